"""``maru-plan`` on bad input, as a user runs it (subprocess): one stderr line, a documented non-zero
exit code, never a traceback; and the same seed gives the same PRM path."""

from __future__ import annotations

import json
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from maru_planner.planning.cli import EXIT_BAD_INPUT, EXIT_FAILED, EXIT_OK, build_parser, main

MARU6 = ["--problem", "maru6"]


def maru_plan(args: list[str], cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "maru_planner.planning.cli", "--quiet", *args],
                          capture_output=True, text=True, cwd=cwd, timeout=300)  # fmt: skip


@pytest.fixture(scope="module")
def files(tmp_path_factory) -> Path:
    root = tmp_path_factory.mktemp("cli")
    (root / "empty.yaml").write_text("")
    (root / "five.yaml").write_text("obstacles: 5\n")
    (root / "broken.yaml").write_text("obstacles: [\n")
    (root / "binary.yaml").write_bytes(b"\x00\xff\xfe")
    (root / "a_file").write_text("not a directory")
    return root


BAD_INPUTS = {
    "nan budget": (["--max-time", "nan"], "--max-time"),
    "negative budget": (["--time", "-1"], "--time"),
    "nan resolution": (["--resolution", "nan"], "--resolution"),
    "negative seed": (["--seed", "-3"], "--seed"),
    "zero attempts": (["--attempts", "0"], "--attempts"),
    "zero scaling": (["--velocity-scaling", "0"], "--velocity-scaling"),
    "unknown option": (["--bogus"], "--bogus"),
    "unknown problem": (["--problem", "maru99"], "maru99"),
    "json under a file": (["--json", "{files}/a_file/out.json"], "a_file/out.json"),
    "json is a directory": (["--json", "{files}"], "is a directory"),
    "png under a file": (["--png", "{files}/a_file/out.png"], "a_file/out.png"),
    "empty scene": (["--scene", "{files}/empty.yaml"], "empty"),
    "obstacles: 5": (["--scene", "{files}/five.yaml"], "obstacles"),
    "scene YAML syntax": (["--scene", "{files}/broken.yaml"], "does not parse"),
    "binary scene": (["--scene", "{files}/binary.yaml"], "decode"),
    "missing scene": (["--scene", "{files}/nope.yaml"], "nope.yaml"),
    "unknown planner": (["--planner", "Dijkstra"], "Dijkstra"),
    "unknown group": (["--group", "legs"], "legs"),
    "wrong joint count": (["--start", "0.1", "0.2"], "6 joints"),
    "nan joint": (["--start", "nan", "1.57", "1.57", "0", "-1.57", "-1.57"], "r_arm_j1"),
    "joint off limits": (["--goal", "9", "1.57", "1.57", "0", "-1.57", "-1.57"], "limits"),
    "unknown robot": (["--robot", "r2d2"], "r2d2"),
    "unknown planner parameter": (["--param", "step=0.1"], "no parameter 'step'"),
    "parameter without value": (["--planner", "RCRRT", "--param", "step"], "NAME=VALUE"),
    "parameter not a number": (["--planner", "RCRRT", "--param", "step=abc"], "step"),
    "parameter out of range": (["--planner", "RCRRT", "--param", "step=-1"], "step"),
}


def run_main(args: list[str], capsys) -> tuple[int, str]:
    """``main`` in this process: (exit code, stderr)."""
    try:
        code = main(["--quiet", *args])
    except SystemExit as exc:  # argparse's own exit for options it rejects
        code = exc.code
    return code, capsys.readouterr().err


def check_one_line(name: str, code: int, stderr: str, words: str) -> None:
    lines = stderr.strip().splitlines()
    assert code == EXIT_BAD_INPUT, (name, code, stderr[-2000:])
    assert len(lines) == 1 and lines[0].startswith("maru-plan: "), (name, stderr[-2000:])
    assert words in lines[0], (name, lines[0])
    assert "Traceback" not in stderr, name


def test_every_bad_input_gets_one_stderr_line_and_exit_2(files, capsys, monkeypatch):
    monkeypatch.chdir(files)
    for name, (args, words) in BAD_INPUTS.items():
        code, stderr = run_main(MARU6 + [a.replace("{files}", str(files)) for a in args], capsys)
        check_one_line(name, code, stderr, words)


AS_A_PROCESS = ["nan budget", "json under a file", "obstacles: 5", "unknown planner"]


def test_bad_input_as_a_process_never_prints_a_traceback(files):
    """A few of the cases above through a real ``maru-plan`` process (exit status, stderr as a user sees them)."""
    cases = [[a.replace("{files}", str(files)) for a in BAD_INPUTS[name][0]] for name in AS_A_PROCESS]
    with ThreadPoolExecutor(max_workers=3) as pool:
        runs = list(pool.map(lambda args: maru_plan(MARU6 + args, files), cases))
    for name, proc in zip(AS_A_PROCESS, runs, strict=True):
        check_one_line(name, proc.returncode, proc.stderr, BAD_INPUTS[name][1])
        assert "Traceback" not in proc.stdout, name


def test_a_failed_plan_exits_1_and_the_exit_codes_are_documented(capsys):
    code, stderr = run_main(MARU6 + ["--time", "1e-6", "--scene", "none"], capsys)
    assert code == EXIT_FAILED, stderr
    assert stderr.strip().startswith("maru-plan: TIMED_OUT: ") and len(stderr.strip().splitlines()) == 1
    help_text = build_parser().format_help()
    for code, meaning in ((EXIT_OK, "a path was found"), (EXIT_FAILED, "planning failed or timed out"),
                          (EXIT_BAD_INPUT, "bad input")):  # fmt: skip
        assert f"  {code}    {meaning}" in help_text


def test_prm_same_seed_same_path_from_the_cli(tmp_path):
    """The issue's check: ``maru-plan --planner PRM --seed 42`` twice gives one path."""
    paths = []
    for run in range(2):
        out = tmp_path / f"prm{run}.json"
        assert main(MARU6 + ["--planner", "PRM", "--seed", "42", "--time", "30", "--json", str(out), "--quiet"]) == 0
        paths.append(json.loads(out.read_text())["path"])
    assert paths[0] == paths[1]

"""Pieces the benchmark scripts share: stderr logging, a progress bar, the data sets and peers they need, writing a
result set, node processes.

The scripts run as ``python bench/<name>.py``, which puts this folder on ``sys.path``. Full runs write the committed
``bench/results/<name>.*``; ``--quick`` runs write under ``bench/results/quick/`` (ignored by git), never over them.
"""

from __future__ import annotations

import importlib.util
import json
import os
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import NoReturn

from maru_planner.paths import benchmarks_dir
from maru_planner.planning.problems import PROBLEMS

ROOT = Path(__file__).resolve().parent.parent
RESULTS = ROOT / "bench" / "results"
QUICK_RESULTS = RESULTS / "quick"  # --quick runs: git ignores it
# planning_node's default group (upper_body, in the SRDF's order) and paper 000's 13-DOF problem over it
UPPER_BODY_JOINTS = ["waist_yaw"] + [f"r_arm_j{i}" for i in range(1, 7)] + [f"l_arm_j{i}" for i in range(1, 7)]
PAPER_START = PROBLEMS["maru13"].start_dict(UPPER_BODY_JOINTS)
PAPER_GOAL = PROBLEMS["maru13"].goal_dict(UPPER_BODY_JOINTS)


def log(message: str) -> None:
    print(message, file=sys.stderr, flush=True)


class Progress:
    """A one-line progress bar on stderr."""

    def __init__(self, total: int):
        self.total, self.done, self.t0 = total, 0, time.monotonic()

    def step(self, label: str) -> None:
        self.done += 1
        frac = self.done / max(self.total, 1)
        bar = "#" * int(30 * frac) + "." * (30 - int(30 * frac))
        elapsed = time.monotonic() - self.t0
        print(f"\r[{bar}] {self.done}/{self.total} {elapsed:7.1f}s {label:<44}", end="", file=sys.stderr, flush=True)
        if self.done == self.total:
            print(file=sys.stderr, flush=True)


def data_dir(*parts: str) -> Path:
    """A public data set (``movingai``, ``barn``, ``motionbenchmaker``, ...) under ``benchmarks_dir()``:
    ``$MARU_BENCHMARKS_DIR``, else ``../shared/benchmarks`` beside the checkout (checked by :func:`require_data`)."""
    return benchmarks_dir().joinpath(*parts)


def require_data(*paths: Path) -> None:
    """Exit 2 with one line naming the first missing data path and what to set (no traceback, no empty results)."""
    for path in paths:
        if not path.exists() or (path.is_dir() and not any(path.iterdir())):
            fail(f"benchmark data not found: {path} (set MARU_BENCHMARKS_DIR to the folder holding movingai/, barn/ "
                 f"and motionbenchmaker/; default: ../shared/benchmarks beside the repository)")  # fmt: skip


def require_peers(*modules: str) -> None:
    """Exit 2 with one line when a peer measured beside us is not installed (``make bench-deps`` installs them)."""
    missing = [m for m in modules if importlib.util.find_spec(m) is None]
    if missing:
        fail(f"peer(s) not installed: {', '.join(missing)} (run: make bench-deps)")


def fail(message: str) -> NoReturn:
    """One line ``<script>: <message>`` on stderr and exit code 2 (the CLIs' convention for bad input)."""
    print(f"{Path(sys.argv[0]).name}: {message}", file=sys.stderr, flush=True)
    raise SystemExit(2)


def results_dir(quick: bool) -> Path:
    """Where a run writes: the committed ``bench/results/`` for full runs, ``bench/results/quick/`` for ``--quick``."""
    return output_dir(RESULTS, quick)


def output_dir(folder: Path, quick: bool) -> Path:
    """``folder``, or ``bench/results/quick/`` when a ``--quick`` run would write into the committed results."""
    folder = Path(folder)
    return QUICK_RESULTS if quick and folder.resolve() == RESULTS.resolve() else folder


def result_path(out: Path, quick: bool) -> Path:
    """The stem ``out`` (``bench/results/<name>``) in :func:`output_dir`."""
    out = Path(out)
    return output_dir(out.parent, quick) / out.name


def write_results(out: Path, results: dict, markdown: str, plot: Callable[[Path], None], *, quick: bool) -> Path:
    """``out``.json, ``out``.md and the figure ``out``.png (under ``bench/results/quick/`` for a ``--quick`` run,
    :func:`result_path`); the markdown also on stdout. Returns the stem written."""
    out = result_path(out, quick)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.with_suffix(".json").write_text(json.dumps(results, indent=1))
    out.with_suffix(".md").write_text(markdown)
    plot(out.with_suffix(".png"))
    print(markdown)
    log(f"wrote {out}.{{json,md,png}}")
    return out


def start_python(args: list[str], log_file) -> subprocess.Popen:
    """``python <args>`` (a node, a helper server) with this environment, its output to ``log_file``."""
    return subprocess.Popen(
        [sys.executable, *args],
        stdout=log_file,
        stderr=subprocess.STDOUT,
        stdin=subprocess.DEVNULL,
        env=dict(os.environ),
    )

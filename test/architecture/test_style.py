"""Style: ``ruff check`` and ``ruff format --check`` clean on every Python file of the repository, and the
pre-commit hooks run the tools pinned in requirements.txt from the venv."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import yaml

REPO_ROOT = Path(__file__).resolve().parents[2]
LINTED_DIRS = ("maru_planner", "bench", "test", "scripts", "launch")


def _ruff(*args: str) -> subprocess.CompletedProcess:
    ruff = Path(sys.executable).parent / "ruff"
    targets = [d for d in LINTED_DIRS if (REPO_ROOT / d).exists()]
    return subprocess.run([str(ruff), *args, *targets, "setup.py"], cwd=REPO_ROOT, capture_output=True, text=True)


def test_ruff_lint_is_clean():
    result = _ruff("check")
    assert result.returncode == 0, result.stdout + result.stderr


def test_ruff_format_is_clean():
    result = _ruff("format", "--check")
    assert result.returncode == 0, result.stdout + result.stderr


def test_pre_commit_hooks_run_the_pinned_tools_from_the_venv():
    config = yaml.safe_load((REPO_ROOT / ".pre-commit-config.yaml").read_text())
    hooks = {hook["id"]: hook for repo in config["repos"] for hook in repo["hooks"]}
    assert {"ruff-check", "ruff-format", "mypy"} <= hooks.keys()
    requirements = (REPO_ROOT / "requirements.txt").read_text().splitlines()
    pinned = {line.split("==")[0].strip().lower() for line in requirements if "==" in line}
    for hook_id, hook in hooks.items():
        tool = Path(hook["entry"].split()[0])
        assert tool.parent == Path(".venv/bin"), f"hook {hook_id} does not run from .venv: {hook['entry']}"
        assert tool.name in pinned, f"hook {hook_id} runs {tool.name}, which requirements.txt does not pin"
        assert (Path(sys.executable).parent / tool.name).is_file(), f"{tool.name} is not installed in the venv"

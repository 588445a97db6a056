"""Pieces the benchmark scripts share: stderr logging, a progress bar, writing a result set, node processes.

The scripts run as ``python bench/<name>.py``, which puts this folder on ``sys.path``.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

from maru_planner.planning.problems import PROBLEMS

ROOT = Path(__file__).resolve().parent.parent
RESULTS = ROOT / "bench" / "results"
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


def write_results(out: Path, results: dict, markdown: str, plot: Callable[[Path], None]) -> None:
    """``out``.json, ``out``.md and the figure ``out``.png; the markdown also on stdout."""
    out.parent.mkdir(parents=True, exist_ok=True)
    out.with_suffix(".json").write_text(json.dumps(results, indent=1))
    out.with_suffix(".md").write_text(markdown)
    plot(out.with_suffix(".png"))
    print(markdown)


def start_python(args: list[str], log_file) -> subprocess.Popen:
    """``python <args>`` (a node, a helper server) with this environment, its output to ``log_file``."""
    return subprocess.Popen(
        [sys.executable, *args],
        stdout=log_file,
        stderr=subprocess.STDOUT,
        stdin=subprocess.DEVNULL,
        env=dict(os.environ),
    )

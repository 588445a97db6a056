"""The package's nodes started as processes of their own by a driver (maru-barn --through-ros, the carry demo).

Each node is ``python -m maru_planner.ros.<name>`` with the driver's environment (its DDS settings), its output
in ``<log_dir>/<name>.log``; :meth:`NodeProcesses.stop` ends them all (SIGTERM, then SIGKILL after 10 s).
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path


class NodeProcesses:
    """The nodes one driver started, by module name (``mujoco_sim_node``, ``planning_node``, ...)."""

    def __init__(self, log_dir: Path):
        self.log_dir = log_dir
        self.procs: dict[str, subprocess.Popen] = {}

    def start(self, name: str, args: list[str]) -> None:
        """Start ``maru_planner.ros.<name>`` with ``args`` (``--ros-args ...``)."""
        log = open(self.log_dir / f"{name}.log", "w")  # noqa: SIM115 -- the child writes it until stop()
        self.procs[name] = subprocess.Popen(
            [sys.executable, "-m", f"maru_planner.ros.{name}", *args], stdout=log, stderr=subprocess.STDOUT,
            stdin=subprocess.DEVNULL, env=dict(os.environ),
        )  # fmt: skip

    def log(self, name: str) -> str:
        return (self.log_dir / f"{name}.log").read_text(errors="replace")

    def dead(self) -> str | None:
        """The name of a node that has exited, if any."""
        return next((name for name, proc in self.procs.items() if proc.poll() is not None), None)

    def last_line(self, name: str) -> str:
        lines = self.log(name).strip().splitlines()
        return lines[-1] if lines else "no output"

    def stop(self) -> None:
        for proc in self.procs.values():
            if proc.poll() is None:
                proc.terminate()
        for proc in self.procs.values():
            try:
                proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait(timeout=5)

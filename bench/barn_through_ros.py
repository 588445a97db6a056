"""The through-ROS half of bench/barn_mujoco.py: the challenge's 50 test worlds (0, 6, ..., 294) x 1, every node
its own process in lock-step (maru_planner.ros.barn_ros_run), and the merge of its summary into the results.

Imported by barn_mujoco.py (--through-ros, --combine); not a script of its own.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from _common import Progress, log

from maru_planner.barn.scoring import RunScore, summarise
from maru_planner.physics.barn_world import optimal_time

TEST_WORLDS = list(range(0, 300, 6))  # the challenge's 50 test worlds
QUICK_TEST_WORLDS = [0, 150]


def run_world(world: int, seed: int, scratch: Path) -> dict:
    """One world through ROS in its own process tree; a run that could not be carried out is an error record."""
    out = scratch / f"world_{world}.json"
    args = ["-m", "maru_planner.ros.barn_ros_run", "--world", str(world), "--seed", str(seed), "--name", str(world)]
    args += ["--optimal-time", repr(optimal_time(world)), "--json", str(out)]
    done = subprocess.run([sys.executable, *args], capture_output=True, text=True, env=dict(os.environ), timeout=900)
    if done.returncode != 0 or not out.is_file():
        reason = (done.stderr.strip().splitlines() or ["no output"])[-1][:300]
        return {"world": str(world), "seed": seed, "error": reason}
    return json.loads(out.read_text())["run"]


def through_ros(worlds: list[int], partial: Path, seed: int = 0) -> dict:
    """The runs and their summary (``errors``: runs the ROS graph could not carry out, counted as failures);
    ``partial`` holds the runs so far after each world (a stopped run can still be merged, its size stated)."""
    progress = Progress(len(worlds))
    runs: list[dict] = []
    errors: list[dict] = []
    t0 = time.time()
    with tempfile.TemporaryDirectory(prefix="barn_ros_") as scratch:
        for world in worlds:
            record = run_world(world, seed, Path(scratch))
            if "error" in record:
                errors.append(record)
                log(f"\nworld {world}: {record['error']}")
                record = RunScore(str(world), seed, False, False, True, None, optimal_time(world), 0.0, 0.0, 0.0,
                                  0.0).to_json()  # fmt: skip
            runs.append(record)
            outcome = "success" if record["success"] else "collision" if record["collision"] else "timeout"
            progress.step(f"world {world}: {outcome} {record['metric']:.3f}")
            partial.write_text(json.dumps(results(runs, errors, len(worlds), t0), indent=1))
    return results(runs, errors, len(worlds), t0)


def results(runs: list[dict], errors: list[dict], planned: int, t0: float) -> dict:
    summary = summarise([RunScore(**r) for r in runs])
    summary["planned_worlds"] = planned
    summary["errors"] = len(errors)
    summary["wall_time_s"] = round(time.time() - t0, 1)
    summary["load_average"] = round(os.getloadavg()[0], 1)
    return {"summary": summary, "runs": runs, "errors": errors}


def merge(results: dict, ros: dict) -> dict:
    """``summary.through_ros`` and the runs under ``runs_through_ros``, plus the target on the success gap."""
    merged = dict(results)
    merged["summary"] = {**results["summary"], "through_ros": ros["summary"]}
    merged["runs_through_ros"] = ros["runs"]
    merged["targets"] = [t for t in results["targets"] if not t["target"].startswith("through-ROS")]
    ours = results["summary"]["in_process"]
    gap = abs(ros["summary"]["success_rate"] - ours["success_rate"])
    merged["targets"].append(
        {"target": "through-ROS success within 3 points of in-process", "hit": gap <= 0.03, "measured": round(gap, 4)}
    )
    return merged

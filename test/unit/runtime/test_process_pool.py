"""ProcessPool: planning in worker processes gives the in-process answers, and the pool stays in control.

Maru-1's upper body on the desk + box scene (the planning node's default), the paper problem.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from maru_planner import errors
from maru_planner.monitor import PlanMonitor
from maru_planner.paths import config_path, urdf_path
from maru_planner.planning import MotionPlanner, MotionRequest, PlannerConfig, PlanStatus
from maru_planner.runtime import ProcessPool, RobotSource
from maru_planner.scene import Scene

GROUP = "upper_body"
JOINTS = ["waist_yaw"] + [f"r_arm_j{i}" for i in range(1, 7)] + [f"l_arm_j{i}" for i in range(1, 7)]
START = dict(zip(JOINTS, (-0.9, -0.7, 1.57, 0.7, 0.7, -0.9, -0.9, -0.8, 1.57, 2.0, 0.7, -1.9, -1.25), strict=True))
GOAL = dict(zip(JOINTS, (0.9, -0.8, 1.57, 1.14, 0.7, -1.24, -1.9, -0.7, 1.57, 2.44, 0.7, -2.24, -1.25), strict=True))
SOURCE = RobotSource(str(urdf_path("maru1_upper_body.urdf")), str(urdf_path("maru1_upper_body.srdf")))
# Seeds whose paths certify without repairs; a generous certification deadline keeps a loaded machine's
# answers the same as a quiet one's (a repaired path is timed within certify_timeout).
SEEDS = (1, 2, 4, 6, 7, 8)
CONFIG = PlannerConfig(certify_timeout=30.0)
LIVENESS_TIMEOUT = 60.0  # s: a bound on waiting for processes to go, never a performance claim


def _scene() -> dict:
    return Scene.from_yaml(config_path("scenes", "maru13_desk_box.yaml")).to_dict()


def _request(**overrides) -> MotionRequest:
    fields = dict(group=GROUP, start=START, goal_joints=GOAL, planner_id="RRTConnect", time_budget=30.0, seed=2)
    return MotionRequest(**{**fields, **overrides})


def _endless_request() -> MotionRequest:
    """Plain RRT on the paper problem: it does not finish within its budget (test_planning_node)."""
    return _request(planner_id="RRT", time_budget=120.0)


def _started_pool(workers: int) -> ProcessPool:
    pool = ProcessPool(SOURCE, _scene(), CONFIG, workers)
    pool.wait_ready()
    return pool


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    with open(f"/proc/{pid}/stat") as stat:  # a zombie is gone for our purposes
        return stat.read().split(") ")[-1][0] != "Z"


def _wait_until_gone(pids: list[int]) -> list[int]:
    deadline = time.monotonic() + LIVENESS_TIMEOUT
    while any(_alive(p) for p in pids) and time.monotonic() < deadline:
        time.sleep(0.05)
    return [p for p in pids if _alive(p)]


class _StageLog:
    """A PlanMonitor sink that records the stages and signals when the search has begun."""

    def __init__(self):
        self.stages: list[str] = []
        self.searching = threading.Event()

    def __call__(self, progress) -> None:
        self.stages.append(progress.stage)
        if progress.stage == "search":
            self.searching.set()


@pytest.fixture(scope="module")
def pool():
    with _started_pool(2) as started:
        yield started


@pytest.fixture(scope="module")
def local():
    return MotionPlanner.from_scene(SOURCE.load(), Scene.from_dict(_scene()), CONFIG)


def test_same_seed_gives_the_in_process_path_and_stages(pool, local):
    here, there = _StageLog(), _StageLog()
    expected = local.plan(_request(), PlanMonitor(here))
    result = pool.plan(_request(), PlanMonitor(there))
    assert expected.success and result.success, (expected.message, result.message)
    np.testing.assert_array_equal(result.path, expected.path)
    np.testing.assert_array_equal(result.trajectory.positions, expected.trajectory.positions)
    assert result.stats.seed == 2 and result.stats.certified
    assert there.stages == here.stages


def test_every_worker_warms_its_kernels_up_before_it_is_ready(pool):
    summaries = pool.warm_ups()
    assert len(summaries) == pool.workers, summaries
    assert all(s.startswith("kernels warmed up") and "RRTConnect in one box: SUCCESS" in s for s in summaries)


def test_errors_keep_their_class_status_and_message(pool, local):
    bad = _request(group="no_such_group")
    expected = local.plan(bad)
    result = pool.plan(bad)
    assert result.status is PlanStatus.INVALID_GROUP is expected.status
    assert type(result.error) is errors.InvalidGroup
    assert result.message == expected.message and "no_such_group" in result.message


def test_concurrent_requests_beyond_the_workers_are_all_answered(pool, local):
    seeds = SEEDS
    futures = [pool.submit(_request(seed=seed)) for seed in seeds]
    results = [future.result() for future in futures]
    for seed, result in zip(seeds, results, strict=True):
        assert result.success, result.message
        np.testing.assert_array_equal(result.path, local.plan(_request(seed=seed)).path)


def test_cancel_reaches_the_worker_and_the_result_says_cancelled(pool):
    log = _StageLog()
    monitor = PlanMonitor(log)
    future = pool.submit(_endless_request(), monitor)
    assert log.searching.wait(LIVENESS_TIMEOUT)
    monitor.cancel()
    result = future.result()
    assert result.status is PlanStatus.PLANNING_FAILED
    assert isinstance(result.error, errors.PlanningCancelled), result.message
    assert pool.plan(_request()).success  # the worker serves the next request


def test_a_cancel_before_the_plan_starts_still_cancels_it(pool):
    monitor = PlanMonitor()
    monitor.cancel()
    result = pool.plan(_endless_request(), monitor)
    assert isinstance(result.error, errors.PlanningCancelled), result.message


def test_scene_and_config_reach_every_worker_before_their_next_request(pool):
    blocked = _scene()
    torso = {"name": "torso", "type": "box", "size": [0.3, 0.3, 0.3], "pose": {"xyz": [0, 0, 0], "rpy": [0, 0, 0]}}
    blocked["obstacles"] = [*blocked["obstacles"], torso]
    try:
        pool.set_scene(blocked, pool.scene_version + 1)
        pool.set_config(PlannerConfig(default_planner="GoalBiasedRRT", certify_timeout=30.0))
        results = [f.result() for f in [pool.submit(_request(planner_id="")) for _ in range(4)]]
        assert {r.status for r in results} == {PlanStatus.START_IN_COLLISION}, [r.message for r in results]
        assert {r.stats.planner_id for r in results} == {"GoalBiasedRRT"}
    finally:
        pool.set_scene(_scene(), pool.scene_version + 1)
        pool.set_config(CONFIG)
    assert pool.plan(_request()).success


def test_an_old_scene_version_is_ignored(pool):
    version = pool.scene_version
    pool.set_scene({"obstacles": [{"name": "everywhere", "type": "sphere", "radius": 9.0}]}, version)
    assert pool.scene_version == version
    assert pool.plan(_request()).success


def test_a_malformed_scene_is_refused_before_any_worker_sees_it(pool):
    version = pool.scene_version
    with pytest.raises(errors.InvalidScene):
        pool.set_scene({"obstacles": [{"name": "bad", "type": "sphere", "radius": -1.0}]}, version + 1)
    assert pool.scene_version == version
    assert pool.plan(_request()).success


def test_a_worker_that_dies_fails_its_request_and_is_replaced():
    with _started_pool(1) as pool:
        log = _StageLog()
        future = pool.submit(_endless_request(), PlanMonitor(log))
        assert log.searching.wait(LIVENESS_TIMEOUT)
        (pid,) = pool.pids
        os.kill(pid, signal.SIGKILL)
        with pytest.raises(
            errors.PlanningFailed, match=rf"worker {pid} died \(signal 9, SIGKILL\) while planning; it was restarted"
        ):
            future.result()
        result = pool.plan(_request())
        assert result.success, result.message
        assert pool.workers == 1 and pool.pids != [pid]


def test_resize_starts_and_retires_workers():
    with _started_pool(1) as pool:
        pool.resize(3)
        pool.wait_ready()
        assert pool.workers == 3 and len(set(pool.pids)) == 3
        pids = pool.pids
        pool.resize(1)
        assert pool.workers == 1
        assert len(_wait_until_gone(pids[1:])) == 0
        assert pool.plan(_request()).success
        with pytest.raises(errors.InvalidParameter, match="workers"):
            pool.resize(0)


def test_close_stops_every_worker_and_fails_what_waits():
    pool = _started_pool(1)
    pids = pool.pids
    running = pool.submit(_endless_request(), PlanMonitor())
    waiting = pool.submit(_endless_request())
    pool.close()
    assert isinstance(running.result().error, errors.PlanningCancelled)
    with pytest.raises(errors.PlanningCancelled):
        waiting.result()
    assert _wait_until_gone(pids) == []
    with pytest.raises(RuntimeError, match="closed"):
        pool.submit(_request())


def test_a_worker_that_cannot_build_its_planner_is_a_start_up_error():
    pool = ProcessPool(RobotSource("/no/such/robot.urdf"), _scene(), CONFIG, 1)
    with pytest.raises(errors.MaruError, match="failed to start"):
        pool.wait_ready()
    assert pool.closed


def test_workers_exit_when_the_pool_process_is_killed(tmp_path):
    script = textwrap.dedent(
        f"""
        import os, signal, sys
        sys.path[:0] = [{os.path.dirname(__file__)!r}, {str(Path(__file__).resolve().parents[2])!r}]
        from test_process_pool import _started_pool
        if __name__ == "__main__":
            pool = _started_pool(2)
            print(*pool.pids, flush=True)
            os.kill(os.getpid(), signal.SIGKILL)
        """
    )
    path = tmp_path / "killed_parent.py"
    path.write_text(script)
    run = subprocess.run([sys.executable, str(path)], capture_output=True, text=True, timeout=600)
    pids = [int(p) for p in run.stdout.split()]
    assert len(pids) == 2, run.stderr
    assert _wait_until_gone(pids) == []


def test_fork_and_zero_workers_are_refused():
    with pytest.raises(errors.InvalidParameter, match="start_method"):
        ProcessPool(SOURCE, _scene(), CONFIG, 1, start_method="fork")
    with pytest.raises(errors.InvalidParameter, match="workers"):
        ProcessPool(SOURCE, _scene(), CONFIG, 0)

"""A planning worker process killed mid-plan: its request gets a typed error at once, a new worker replaces it,
the next requests are served; a worker that cannot be replaced fails what waits instead of hanging.

Maru-1's upper body on the desk + box scene, the paper problem (test_process_pool, test_runtime).
"""

from __future__ import annotations

import os
import shutil
import signal
import threading
import time

import pytest
from conftest import PAPER_GOAL, PAPER_START

from maru_planner import errors
from maru_planner.monitor import PlanMonitor
from maru_planner.paths import config_path, urdf_path
from maru_planner.planning import MotionRequest, PlannerConfig
from maru_planner.runtime import PlanningRuntime, ProcessPool, RobotSource, RuntimeSettings
from maru_planner.scene import Scene

GROUP = "upper_body"
SOURCE = RobotSource(str(urdf_path("maru1_upper_body.urdf")), str(urdf_path("maru1_upper_body.srdf")))
CONFIG = PlannerConfig(certify_timeout=30.0)  # a loaded machine's answers stay a quiet one's (test_process_pool)
ENDLESS_BUDGET = 120.0  # s: plain RRT does not solve the paper problem; the error must come long before this
ANSWER_TIMEOUT = 30.0  # s: a bound on waiting for an answer, never a performance claim
LIVENESS_TIMEOUT = 60.0
KILLED = r"the planning worker {pid} died \(signal 9, SIGKILL\) while planning; it was restarted \(as \d+\)"


def _request(**overrides) -> MotionRequest:
    fields = dict(group=GROUP, start=PAPER_START, goal_joints=PAPER_GOAL, planner_id="RRTConnect", time_budget=30.0,
                  seed=2)  # fmt: skip
    return MotionRequest(**{**fields, **overrides})


def _endless_request() -> MotionRequest:
    return _request(planner_id="RRT", time_budget=ENDLESS_BUDGET)


def _searching_monitor() -> tuple[PlanMonitor, threading.Event]:
    """A monitor and the event set once its plan's search has begun (the plan is in a worker process)."""
    searching = threading.Event()
    return PlanMonitor(lambda progress: progress.stage == "search" and searching.set()), searching


def _gone(pid: int) -> bool:
    deadline = time.monotonic() + LIVENESS_TIMEOUT
    while time.monotonic() < deadline:
        try:
            with open(f"/proc/{pid}/stat") as stat:
                if stat.read().split(") ")[-1][0] == "Z":  # a zombie is gone for our purposes
                    return True
        except FileNotFoundError:
            return True
        time.sleep(0.05)
    return False


def test_a_killed_worker_fails_its_request_at_once_and_the_runtime_serves_on():
    settings = RuntimeSettings(GROUP, workers=1, worker_processes=True, queue_size=2)
    with PlanningRuntime(SOURCE, Scene.from_yaml(config_path("scenes", "maru13_desk_box.yaml")), CONFIG, settings,
                         log=lambda _: None) as runtime:  # fmt: skip
        monitor, searching = _searching_monitor()
        running = runtime.plan(_endless_request(), monitor)
        waiting = runtime.plan(_request(seed=4))  # admitted behind it
        assert searching.wait(LIVENESS_TIMEOUT)
        (pid,) = runtime.worker_pids
        killed_at = time.monotonic()
        os.kill(pid, signal.SIGKILL)

        with pytest.raises(errors.PlanningFailed, match=KILLED.format(pid=pid)) as failure:
            running.result(ANSWER_TIMEOUT)
        assert failure.value.source == "workers"
        assert time.monotonic() - killed_at < ENDLESS_BUDGET / 4  # answered, not timed out
        assert waiting.result(ANSWER_TIMEOUT).success  # served by the new worker
        assert runtime.plan(_request(seed=6)).result(ANSWER_TIMEOUT).success
        (new_pid,) = runtime.worker_pids
        assert new_pid != pid and _gone(pid)
    assert _gone(new_pid)


def test_a_request_waiting_for_the_new_worker_keeps_its_budget():
    scene = Scene.from_yaml(config_path("scenes", "maru13_desk_box.yaml")).to_dict()
    with ProcessPool(SOURCE, scene, CONFIG, workers=1) as pool:
        pool.wait_ready()
        monitor, searching = _searching_monitor()
        running = pool.submit(_endless_request(), monitor)
        assert searching.wait(LIVENESS_TIMEOUT)
        short = pool.submit(_request(time_budget=0.2))  # waits in the pool behind the endless plan
        time.sleep(0.3)  # its whole budget, waiting
        os.kill(pool.pids[0], signal.SIGKILL)
        with pytest.raises(errors.PlanningFailed, match="died"):
            running.result(ANSWER_TIMEOUT)
        with pytest.raises(errors.PlanningTimedOut, match="waited for a planning worker"):
            short.result(ANSWER_TIMEOUT)
        assert pool.plan(_request()).success


def test_when_no_worker_can_be_restarted_requests_fail_instead_of_hanging(tmp_path):
    """The robot's files vanish after start-up: the replacement cannot load them, so nothing is left to plan."""
    urdf, srdf = (shutil.copy(urdf_path(f"maru1_upper_body.{ext}"), tmp_path) for ext in ("urdf", "srdf"))
    scene = Scene.from_yaml(config_path("scenes", "maru13_desk_box.yaml")).to_dict()
    with ProcessPool(RobotSource(str(urdf), str(srdf)), scene, CONFIG, workers=1) as pool:
        pool.wait_ready()
        monitor, searching = _searching_monitor()
        running = pool.submit(_endless_request(), monitor)
        assert searching.wait(LIVENESS_TIMEOUT)
        waiting = pool.submit(_request())
        os.remove(urdf)
        (pid,) = pool.pids
        os.kill(pid, signal.SIGKILL)

        with pytest.raises(errors.PlanningFailed, match=KILLED.format(pid=pid)):
            running.result(ANSWER_TIMEOUT)
        with pytest.raises(errors.PlanningFailed, match="no planning worker is running .*could not start"):
            waiting.result(ANSWER_TIMEOUT)
        with pytest.raises(errors.PlanningFailed, match="no planning worker is running"):
            pool.plan(_request())
        assert pool.workers == 0

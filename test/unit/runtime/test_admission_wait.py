"""Admission by expected wait (maru_planner.runtime.admission) and plans cancelled while they wait for a worker.

A burst that fits its budgets is admitted in full (no fixed count refuses it); a request whose expected wait
exceeds its budget is BUSY at once; a waiting plan whose monitor is cancelled ends at once, the worker still busy.
"""

from __future__ import annotations

import threading
import time

import pytest
from conftest import PAPER_GOAL, PAPER_START

from maru_planner import errors
from maru_planner.monitor import PlanMonitor
from maru_planner.paths import urdf_path
from maru_planner.planning import MotionRequest, PlannerConfig
from maru_planner.runtime import PlanningRuntime, RobotSource, RuntimeSettings, WorkerContext, WorkerPool

GROUP = "upper_body"
SOURCE = RobotSource(str(urdf_path("maru1_upper_body.urdf")), str(urdf_path("maru1_upper_body.srdf")))
LIVENESS_TIMEOUT = 60.0  # s: a bound on waiting, never a performance claim
JOB_TIME = 0.05  # s a budgeted job of the pool tests sleeps


def _pool(workers: int = 1, queue_size: int = 100) -> WorkerPool:
    return WorkerPool([WorkerContext(planner=None, scene_version=0) for _ in range(workers)], queue_size)  # type: ignore[arg-type]


def _run_budgeted_job(pool: WorkerPool) -> None:
    """One budgeted job of JOB_TIME s, run to its end: the pool's recent job time is then >= JOB_TIME."""
    done = threading.Event()
    pool.submit(lambda context: (time.sleep(JOB_TIME), done.set()), budget=10.0)
    assert done.wait(LIVENESS_TIMEOUT)
    while pool.admitted:  # the count drops just after the job returns
        time.sleep(0.001)


def test_a_fresh_pool_admits_a_burst_beyond_any_fixed_count_when_it_fits_its_budgets():
    release = threading.Event()
    pool = _pool(workers=2, queue_size=100)
    try:
        for _ in range(64):
            pool.submit(lambda context: release.wait(), budget=2.0)
        assert pool.admitted == 64
    finally:
        release.set()
        pool.close()


def test_busy_only_when_the_expected_wait_exceeds_the_budget():
    release = threading.Event()
    pool = _pool(workers=1)
    try:
        _run_budgeted_job(pool)
        assert pool.recent_job_time >= JOB_TIME
        pool.submit(lambda context: release.wait(), budget=10.0)  # the worker is busy now
        assert pool.expected_wait(pool.admitted) >= JOB_TIME
        with pytest.raises(errors.Busy, match="expected wait .* exceeds the budget 0.01 s"):
            pool.submit(lambda context: None, budget=0.01)
        pool.submit(lambda context: None, budget=10.0)  # fits: admitted
        pool.submit(lambda context: None)  # no budget (FK, validity): only the count bounds it
        assert pool.admitted == 3
    finally:
        release.set()
        pool.close()


def test_a_job_that_says_it_was_cancelled_is_not_averaged():
    pool = _pool(workers=1)
    try:
        done = threading.Event()

        def cancelled(context) -> bool:
            time.sleep(JOB_TIME)
            done.set()
            return False  # what the runtime's job returns for a cancelled plan

        pool.submit(cancelled, budget=10.0)
        assert done.wait(LIVENESS_TIMEOUT)
        while pool.admitted:
            time.sleep(0.001)
        assert pool.recent_job_time == 0.0
    finally:
        pool.close()


def test_the_count_still_bounds_the_queue():
    release = threading.Event()
    pool = _pool(workers=1, queue_size=2)
    try:
        for _ in range(3):
            pool.submit(lambda context: release.wait(), budget=10.0)
        with pytest.raises(errors.Busy, match="workers 1 \\+ queue_size 2"):
            pool.submit(lambda context: None, budget=10.0)
    finally:
        release.set()
        pool.close()


def _request(**overrides) -> MotionRequest:
    fields = dict(group=GROUP, start=PAPER_START, goal_joints=PAPER_GOAL, planner_id="RRTConnect", time_budget=30.0,
                  seed=2)  # fmt: skip
    return MotionRequest(**{**fields, **overrides})


def test_a_waiting_plan_cancelled_ends_at_once_while_the_worker_plans():
    settings = RuntimeSettings(GROUP, workers=1, worker_processes=False, queue_size=4)
    with PlanningRuntime(SOURCE, "", PlannerConfig(), settings) as runtime:
        searching = threading.Event()
        running_monitor = PlanMonitor(lambda progress: progress.stage == "search" and searching.set())
        running = runtime.plan(_request(planner_id="RRT", time_budget=120.0), running_monitor)  # never solves
        assert searching.wait(LIVENESS_TIMEOUT)
        waiting_monitor = PlanMonitor()
        waiting = runtime.plan(_request(), waiting_monitor)
        waiting_monitor.cancel()
        with pytest.raises(errors.PlanningCancelled, match="waiting for a worker"):
            waiting.result(timeout=LIVENESS_TIMEOUT)
        assert not running.done()  # ended without the worker
        running_monitor.cancel()
        assert isinstance(running.result(LIVENESS_TIMEOUT).error, errors.PlanningCancelled)
        assert runtime.plan(_request()).result(LIVENESS_TIMEOUT).success  # the cancelled one left no trace


def test_freed_memory_is_given_back_once_the_pool_has_been_idle_not_during_a_burst(monkeypatch):
    from maru_planner import heap
    from maru_planner.runtime import admission

    monkeypatch.setattr(admission, "IDLE_RELEASE_DELAY", 0.2)
    pool = _pool(workers=2)
    releases: list[int] = []
    monkeypatch.setattr(heap, "release_free_memory", lambda: releases.append(pool.admitted) or True)
    release = threading.Event()
    try:
        for _ in range(5):
            pool.submit(lambda context: release.wait(), budget=10.0)
        time.sleep(0.5)  # longer than the delay, with every job still admitted
        assert releases == []
        release.set()
        deadline = time.monotonic() + LIVENESS_TIMEOUT
        while not releases and time.monotonic() < deadline:
            time.sleep(0.01)
        time.sleep(0.5)  # both threads have been idle past the delay: still one release for the spell
        assert releases == [0]
    finally:
        release.set()
        pool.close()

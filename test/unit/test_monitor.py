"""PlanMonitor: cancel from another thread ends an OMPL search and Python loops; progress reaches its sink."""

from __future__ import annotations

import threading
import time

import pytest
from ompl import base as ob

from maru_planner.errors import PlanningCancelled
from maru_planner.monitor import PlanMonitor, Progress


def test_check_raises_only_after_cancel():
    monitor = PlanMonitor()
    monitor.check()
    monitor.report("search")
    monitor.cancel()
    with pytest.raises(PlanningCancelled, match="search"):
        monitor.check()


def test_cancel_terminates_attached_condition_from_another_thread():
    monitor = PlanMonitor()
    ptc = ob.timedPlannerTerminationCondition(60.0)
    with monitor.attach(ptc):
        assert not ptc.eval()
        timer = threading.Timer(0.05, monitor.cancel)
        timer.start()
        deadline = time.monotonic() + 5.0
        while not ptc.eval() and time.monotonic() < deadline:
            time.sleep(0.005)
        timer.join()
    assert ptc.eval()


def test_condition_attached_after_cancel_is_terminated_at_once():
    monitor = PlanMonitor()
    monitor.cancel()
    ptc = ob.timedPlannerTerminationCondition(60.0)
    with monitor.attach(ptc):
        assert ptc.eval()


def test_report_feeds_progress_and_survives_a_broken_sink():
    seen: list[Progress] = []
    monitor = PlanMonitor(seen.append)
    monitor.report("search", nodes=10)
    monitor.report("simplify", best_cost=1.5)
    assert [p.stage for p in seen] == ["search", "simplify"]
    assert seen[-1].info == {"nodes": 10, "best_cost": 1.5}
    assert seen[-1].elapsed >= seen[0].elapsed >= 0.0
    assert monitor.snapshot().stage == "simplify"

    def broken(_progress: Progress) -> None:
        raise RuntimeError("sink down")

    PlanMonitor(broken).report("search")  # must not raise

"""The carry demo through the nodes (issue 39, item 5): ``carry_demo --through-ros`` starts arm_sim_node and
planning_node as processes (maru_planner.ros.carry_demo_run), both with the box attached; the carry is a plan_motion
goal with ``execute`` whose start is the arm's /joint_states. One run (~30 s at load 10: two node start-ups, the
approach from home and the carry, at arm real_time_factor 2): the goal SUCCEEDED and was executed, the executed
states touch nothing, the hands' grip held within the dual-arm carry's tolerances, the picture is written.
"""

from __future__ import annotations

import pytest

from maru_planner.execution import carry_demo
from maru_planner.execution.carry_picture import draw_carry
from maru_planner.execution.tolerances import ResultCode

pytestmark = pytest.mark.ros


def test_the_carry_through_the_nodes_succeeds_touching_nothing_and_keeping_the_grip(tmp_path):
    run = carry_demo.run_through_ros(seed=1, real_time_factor=2.0)
    assert run.goal_status == "STATUS_SUCCEEDED" and run.execution is not None, carry_demo.summary(run)
    assert run.execution.code == ResultCode.SUCCESSFUL and run.execution.success
    assert run.execution.contacts == []
    assert run.reported_tracking is not None and 0.0 <= run.reported_tracking <= 0.02
    # arrived (the overrun itself is not checked: the stamps are wall-clock, and a loaded machine runs the arm slower
    # than the real_time_factor that converts them to simulated time)
    assert run.execution.finished_at is not None
    times, rows = run.executed
    assert len(times) > 100 and rows.shape[1] == 13  # /joint_states through the carry (250 Hz)
    translation, rotation = run.grip_error(rows)
    assert translation <= run.problem.position_tolerance and rotation <= run.problem.orientation_tolerance
    line = carry_demo.summary(run)
    assert "SUCCESSFUL" in line and "0 contacts" in line and "\n" not in line
    out = draw_carry(run, tmp_path / "carry.png")
    assert out.is_file() and out.stat().st_size > 10_000

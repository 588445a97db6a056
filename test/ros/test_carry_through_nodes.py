"""The carry demo through the nodes (issue 39, item 5): ``carry_demo --through-ros`` starts arm_sim_node (at the
carry's start, the box weighing BOX_MASS) and planning_node as processes (maru_planner.ros.carry_demo_run), both with
the box attached; the carry is one plan_motion goal with ``execute`` and the hands' relative pose held by
PathConstraints' relative fields (CBiRRT over ROS). One run (~15 s: two node start-ups and the carry, at arm
real_time_factor 2): the goal SUCCEEDED and was executed, the executed states touch nothing, the planned grip is
within the dual-arm carry's tolerances and so is the executed one from the arm's own start, the picture is written.
"""

from __future__ import annotations

import math

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
    assert run.plan.message.startswith("CBiRRT")  # the relative-pose constraint reached the node
    assert run.plan.trajectory is not None
    # per component within the tolerances: the distance and angle within sqrt(3) x them
    bound = (math.sqrt(3) * run.problem.position_tolerance, math.sqrt(3) * run.problem.orientation_tolerance)
    translation, rotation = run.grip_error(run.plan.trajectory.positions)
    assert translation <= bound[0] + 1e-6 and rotation <= bound[1] + 1e-6
    translation, rotation = run.executed_grip_from_its_start()  # the box's weight bends the arm before it moves
    assert translation <= bound[0] and rotation <= bound[1]
    line = carry_demo.summary(run)
    assert "SUCCESSFUL" in line and "0 contacts" in line and "\n" not in line
    out = draw_carry(run, tmp_path / "carry.png")
    assert out.is_file() and out.stat().st_size > 10_000

"""The through-the-nodes carry measured from a recording (carry_demo.carry_from_record), without DDS: a synthetic
record of the waist carry whose stamps are offset and scaled (real_time_factor 2) -- the execution's start is found
from the feedback, the arrival from the states, contacts by replaying the states in MuJoCo, the grip from the states.
"""

from __future__ import annotations

import numpy as np
import pytest

from maru_planner.execution import carry_demo
from maru_planner.robot import RobotModel

OFFSET, RATE = 1000.0, 2.0  # wall-clock stamp of the start; simulated seconds per wall second
DURATION = 1.6


def _goals() -> tuple[dict[str, float], dict[str, float]]:
    """The carry's start, and it with the waist (its first joint) at GOAL_WAIST (the arms held: the grip kept)."""
    problem = carry_demo.carry_problem()
    start = dict(zip(RobotModel.maru1().groups[problem.group], problem.start, strict=True))
    names = list(start)
    return start, {**start, names[0]: carry_demo.GOAL_WAIST}


def _record(end_waist: float, lag: float = 0.0) -> dict:
    start, goal = _goals()
    names = list(start)
    first, last = np.array(list(start.values())), np.array(list(goal.values()))
    last[0] = end_waist
    times = np.linspace(0.0, DURATION, 17)
    positions = first + np.outer(times / DURATION, last - first)
    zeros = np.zeros_like(positions).tolist()

    def at(t: float) -> list[float]:  # the arm: the plan, ``lag`` s late, at rest at the end
        return (first + np.clip((t - lag) / DURATION, 0.0, 1.0) * (last - first)).tolist()

    wall = lambda t: OFFSET + t / RATE  # noqa: E731
    sim_feedback, sim_states = np.arange(0.02, DURATION, 0.04), np.arange(0.0, DURATION + 0.3, 0.004)
    return {
        "goal_status": "STATUS_SUCCEEDED",
        "real_time_factor": RATE,
        "joint_names": names,
        "plan": {"times": times.tolist(), "positions": positions.tolist(), "velocities": zeros,
                 "accelerations": zeros, "planner": "CompiledRRTConnect", "waypoints": 2, "certified": True},
        "execution": {"code": 0, "message": "goal reached", "tracking_error": 0.001, "time": 1.0},
        "feedback": [{"stamp": wall(t), "names": names[::-1], "desired": at(t + lag)[::-1], "actual": at(t)[::-1]}
                     for t in sim_feedback],
        "joint_states": [{"stamp": wall(t), "names": names, "positions": at(t)} for t in sim_states],
    }  # fmt: skip


@pytest.fixture(scope="module")
def run() -> carry_demo.CarryRun:
    return carry_demo.carry_from_record(_record(carry_demo.GOAL_WAIST, lag=0.01))


def test_the_start_is_found_from_the_feedback_and_times_are_simulated_seconds(run):
    times, rows = run.executed
    assert times[0] == pytest.approx(0.0, abs=0.01)
    assert run.execution is not None and run.execution.finished_at is not None
    assert run.execution.finished_at == pytest.approx(DURATION, abs=0.03)  # within 0.01 rad of the goal
    assert run.execution.overrun is not None and run.execution.overrun < 0.02
    assert np.abs(run.execution.error).max() > 0.0  # the feedback's own desired - actual, reordered by name
    assert run.execution.joint_names == run.plan.joint_names == list(RobotModel.maru1().groups["upper_body"])


def test_held_arms_keep_the_grip_and_touch_nothing(run):
    translation, rotation = run.grip_error(run.executed[1])
    assert translation < 1e-9 and rotation < 1e-6
    assert run.execution is not None and run.execution.contacts == []
    assert "0 contacts" in carry_demo.summary(run) and run.goal_status == "STATUS_SUCCEEDED"


def test_a_recorded_motion_into_the_desk_is_reported_as_contacts():
    """The box swung down into the desk at the end (r_arm_j3 - 1.2 rad; replayed, not simulated)."""
    record = _record(carry_demo.GOAL_WAIST)
    for state in record["joint_states"][-40:]:
        state["positions"][3] -= 1.2  # r_arm_j3: the box on the right hand down into the desk
    contacts = carry_demo.carry_from_record(record).execution.contacts
    assert contacts and {(c.link, c.obstacle) for c in contacts} == {("carried_box", "desk")}
    assert max(c.depth for c in contacts) > 0.05

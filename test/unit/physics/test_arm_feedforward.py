"""The servo's acceleration feedforward (physics/arm_model.py ServoGains, arm_sim.py): the torque fed forward is
M(q) a, it cuts the tracking lag and the settling after the end, and it can be switched off."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from maru_planner.execution.executor import ArmController
from maru_planner.execution.interpolation import checked_points
from maru_planner.execution.tolerances import tolerances
from maru_planner.physics.arm_model import ServoGains, build_arm_model
from maru_planner.physics.arm_sim import ArmSim
from maru_planner.trajectory import Limits, parameterize


@pytest.fixture(scope="module")
def motion(maru1):
    names = maru1.groups["right_arm"]
    index = maru1.joint_indices(names)
    q0 = maru1.neutral().copy()
    path = np.stack([q0[index], q0[index] + [0.5, 0.4, 0.5, 0.5, -0.5, -0.5]])
    limits = Limits.scaled(maru1.velocity_limits[index], maru1.acceleration_limits[index])
    trajectory, _ = parameterize(path, names, limits, "toppra", curve_free=lambda q, d: True, max_deviation=0.0)
    points = checked_points(names, trajectory.times, trajectory.positions, trajectory.velocities,
                            trajectory.accelerations)  # fmt: skip
    return q0, points


def executed(maru1, q0, points, feedforward: bool):
    sim = ArmSim(build_arm_model(maru1, q0=q0, gains=ServoGains(acceleration_feedforward=feedforward)))
    sim.reset(q0)
    return sim, ArmController(sim).run(points)


def test_the_feedforward_is_the_arms_inertia_times_the_acceleration(maru1, motion):
    sim, _ = executed(maru1, *motion, feedforward=True)
    acceleration = np.linspace(-2.0, 2.0, maru1.nq)
    full = np.zeros((sim.arm.model.nv, sim.arm.model.nv))
    mujoco.mj_fullM(sim.arm.model, sim.data, full)
    index = sim.arm.qpos_index
    np.testing.assert_allclose(sim.inertia_torques(acceleration), full[np.ix_(index, index)] @ acceleration)
    sim.command(sim.state().positions, np.zeros(maru1.nq), acceleration)
    np.testing.assert_allclose(sim.data.ctrl[2 * maru1.nq :], sim.inertia_torques(acceleration))


def test_the_feedforward_cuts_the_lag_and_the_settling(maru1, motion):
    _, with_it = executed(maru1, *motion, feedforward=True)
    _, without = executed(maru1, *motion, feedforward=False)
    assert with_it.success and without.success
    assert with_it.max_error.max() < without.max_error.max() / 3
    assert with_it.overrun is not None and without.overrun is not None and with_it.overrun <= without.overrun


def test_after_the_last_point_nothing_is_fed_forward(maru1, motion):
    q0, points = motion
    assert np.any(points.accelerations[-1] != 0)  # toppra ends braking at full deceleration
    sim = ArmSim(build_arm_model(maru1, q0=q0))
    sim.reset(q0)
    controller = ArmController(sim)
    unreachable = tolerances(len(points.joint_names), points.duration, goal_position=1e-12, goal_velocity=1e-12)
    controller.start(points, unreachable)  # still running after the last point
    while sim.time < points.duration - 0.01:
        assert controller.step() is None
    assert np.any(sim.data.ctrl[2 * maru1.nq :] != 0)
    while sim.time < points.duration + 0.003:
        assert controller.step() is None
    assert controller.busy
    np.testing.assert_array_equal(sim.data.ctrl[2 * maru1.nq :], 0.0)  # the set-point is the last point, at rest

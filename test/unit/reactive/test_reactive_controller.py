"""ElasticStripController: limits, steering away, reaching a goal, bounded per-update work, arm update."""

from __future__ import annotations

import math

import numpy as np
import pytest

from maru_planner.reactive import ControlOutput, ElasticStripController, LaserScanData, ScanError, StripParams
from maru_planner.sim import Simulator, World
from maru_planner.sim.runner import strip_params_for


def lms200(ranges) -> LaserScanData:
    return LaserScanData(-math.pi / 2, math.radians(0.5), np.asarray(ranges, float), 0.05, 10.0)


def wall_scan(distance: float, lateral: float = 0.0) -> LaserScanData:
    """Ranges of a round obstacle (radius 0.4) ahead of the laser, centred ``lateral`` m to the left."""
    world = World.from_dict(
        {
            "obstacles": [{"type": "circle", "center": [distance + 0.4, lateral], "radius": 0.4}],
            "robot": {"start": [0, 0, 0], "goal": [9, 0, 0], "laser": {"x": 0.0, "noise": 0.0}},
        }
    )
    return Simulator(world).scan()


@pytest.fixture
def params():
    return StripParams(arm_enabled=False, laser_pose=(0.0, 0.0, 0.0))


def test_free_scan_drives_straight_at_full_speed(params):
    ctrl = ElasticStripController(params)
    ctrl.set_goal((5.0, 0.0, 0.0))
    out = ctrl.update((0.0, 0.0, 0.0), lms200(np.full(361, np.inf)))
    assert isinstance(out, ControlOutput)
    assert out.v == pytest.approx(params.max_linear) and out.w == pytest.approx(0.0)
    assert out.strip.shape[1] == 2 and 3 <= len(out.strip) <= params.num_vias and len(out.obstacle_points) == 0
    assert not out.reached_goal


def test_commands_stay_within_limits_for_any_pose(params):
    ctrl = ElasticStripController(params)
    ctrl.set_goal((2.0, 2.0, 0.0))
    rng = np.random.default_rng(0)
    for _ in range(50):
        pose = (rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-3, 3))
        out = ctrl.update(pose, lms200(rng.uniform(0.3, 12.0, 361)))
        assert abs(out.v) <= params.max_linear + 1e-9 and abs(out.w) <= params.max_angular + 1e-9


@pytest.mark.parametrize("lateral, sign", [(0.25, -1.0), (-0.25, 1.0)])
def test_steers_away_from_obstacle_side(params, lateral, sign):
    ctrl = ElasticStripController(params)
    ctrl.set_goal((8.0, 0.0, 0.0))
    for _ in range(5):
        out = ctrl.update((0.0, 0.0, 0.0), wall_scan(0.9, lateral))
    assert np.sign(out.w) == sign
    assert np.sign(out.target[1]) == sign


def test_head_on_plain_does_not_turn_modified_does(params):
    outs = {}
    for strip in ("plain", "modified"):
        ctrl = ElasticStripController(StripParams(strip=strip, arm_enabled=False, laser_pose=(0, 0, 0)))
        ctrl.set_goal((8.0, 0.0, 0.0))
        for _ in range(5):
            outs[strip] = ctrl.update((0.0, 0.0, 0.0), wall_scan(1.0, 0.0))
    bend = {k: np.max(np.abs(o.strip[:, 1])) for k, o in outs.items()}
    assert bend["modified"] > 0.5 and bend["modified"] > 4 * bend["plain"]
    assert abs(outs["modified"].w) > 2 * abs(outs["plain"].w)


def test_reached_goal_stops(params):
    ctrl = ElasticStripController(params)
    ctrl.set_goal((1.0, 0.0, 0.0))
    out = ctrl.update((0.9, 0.05, 0.0), lms200(np.full(361, np.inf)))
    assert out.reached_goal and out.v == 0.0 and out.w == 0.0


def test_rejects_bad_inputs(params):
    ctrl = ElasticStripController(params)
    with pytest.raises(RuntimeError, match="no goal"):
        ctrl.update((0, 0, 0), lms200(np.ones(361)))
    with pytest.raises(ValueError, match="path"):
        ctrl.set_path(np.zeros((3, 4)))
    with pytest.raises(ValueError, match="goal"):
        ctrl.set_goal((np.nan, 0.0))
    ctrl.set_goal((1.0, 0.0))
    with pytest.raises(ValueError, match="pose"):
        ctrl.update((0.0, np.inf, 0.0), lms200(np.ones(361)))
    scan = lms200(np.ones(361))
    scan.angle_increment = 0.0
    with pytest.raises(ScanError):
        ctrl.update((0, 0, 0), scan)
    with pytest.raises(ValueError, match="strip"):
        StripParams(strip="elastic")
    with pytest.raises(ValueError, match="unknown"):
        StripParams.from_dict({"k_rr": 1.0})


def test_set_path_becomes_the_strip(params):
    ctrl = ElasticStripController(params)
    ctrl.set_path(np.array([[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [2.0, 3.0, 1.57]]))
    out = ctrl.update((0.0, 0.0, 0.0), lms200(np.full(361, np.inf)))
    assert out.strip[-1][1] > 0.5  # the strip turns the corner of the path
    assert ctrl.goal == pytest.approx([2.0, 3.0, 1.57])


def test_reaches_goal_in_simple_world_without_collision():
    world = World.from_dict(
        {
            "obstacles": [{"type": "circle", "center": [2.5, 0.3], "radius": 0.3}],
            "robot": {"start": [0, 0, 0], "goal": [5, 0, 0]},
            "max_time": 40.0,
        }
    )
    sim = Simulator(world, seed=1)
    ctrl = ElasticStripController(strip_params_for(world, "modified", arm_enabled=False))
    result = sim.run(ctrl)
    assert result.outcome == "goal" and result.success and result.collisions == 0
    assert result.min_clearance > 0.0
    assert 4.6 <= result.path_length < 7.0


def test_work_per_update_does_not_grow_with_run_length(params):
    """Count work (via x point distances, strip size), not time: update 10 and update 1000 cost the same."""
    ctrl = ElasticStripController(params)
    ctrl.set_path(np.array([[0.0, 0.0], [1000.0, 0.0]]))
    reference_size = len(ctrl.strip.reference)
    scan = wall_scan(3.0, 1.5)
    work = []
    x = 0.0
    for i in range(1000):
        out = ctrl.update((x, 0.0, 0.0), scan)
        x += 0.05
        if i in (10, 999):
            work.append(dict(out.work))
    assert work[0] == work[1]
    bound = params.num_vias * scan.ranges.size * params.iterations
    assert 0 < work[1]["pair_evaluations"] <= bound
    assert work[1]["vias"] <= params.num_vias
    assert len(ctrl.strip.reference) == reference_size, "the reference is fixed at set_path"


def test_arm_update_moves_arm_away_from_close_obstacle():
    from maru_planner.reactive.arm import ArmReactive

    arm = ArmReactive()
    p0 = arm.control_points(arm.q)
    elbow = p0[3]  # left P_4
    obstacle = elbow[:2] + np.array([0.0, 0.1])  # 10 cm outside the left elbow
    steps, forces = arm.step(obstacle[None, :])
    assert np.any(steps != 0.0)
    assert np.all(np.abs(steps) <= arm.max_joint_step + 1e-12)
    assert forces[3][1] < 0  # pushed away (towards -y)
    p1 = arm.control_points(arm.q)
    assert np.hypot(*(p1[3][:2] - obstacle)) > np.hypot(*(elbow[:2] - obstacle))
    assert np.all(arm.q >= arm.lower) and np.all(arm.q <= arm.upper)


def test_arm_torque_is_jacobian_transpose_of_forces():
    import pinocchio as pin

    from maru_planner.reactive.arm import ArmReactive

    arm = ArmReactive(alpha=1e-3, max_joint_step=10.0)
    arm.q = arm.q_nominal + 0.1  # off the planned posture: internal forces only
    q_before = arm.q.copy()
    steps, forces = arm.step(np.zeros((0, 2)))
    q = pin.neutral(arm.model)
    q[arm._q_index] = q_before
    pin.computeJointJacobians(arm.model, arm.data, q)
    pin.updateFramePlacements(arm.model, arm.data)
    tau = np.zeros(arm.model.nv)
    for frame, f in zip(arm._frames, forces, strict=True):
        tau += pin.getFrameJacobian(arm.model, arm.data, frame, pin.LOCAL_WORLD_ALIGNED)[:3].T @ f
    assert steps == pytest.approx(1e-3 * tau[arm._v_index])


def test_controller_reports_arm_steps():
    ctrl = ElasticStripController(StripParams())
    ctrl.set_goal((3.0, 0.0))
    out = ctrl.update((0, 0, 0), lms200(np.full(361, np.inf)))
    assert out.arm_joint_steps.shape == (14,) and out.arm_joint_positions.shape == (14,)


def test_stop_distance_halts_base_in_front_of_close_obstacle():
    free = StripParams(arm_enabled=False, laser_pose=(0.0, 0.0, 0.0), robot_radius=0.3)
    guarded = StripParams(arm_enabled=False, laser_pose=(0.0, 0.0, 0.0), robot_radius=0.3, stop_distance=0.3)
    r = np.full(361, np.inf)
    r[170:191] = 0.5  # a narrow post 0.5 m straight ahead
    outs = []
    for params in (free, guarded):
        ctrl = ElasticStripController(params)
        ctrl.set_goal((5.0, 0.0))
        outs.append(ctrl.update((0.0, 0.0, 0.0), lms200(r)))
    assert outs[1].v == 0.0 and outs[0].v > 0.0


def test_from_dict_converts_lists_and_validates_windows():
    params = StripParams.from_dict({"beam_window": [10, 100], "laser_pose": [0.1, 0.0, 0.0], "strip": "plain"})
    assert params.beam_window == (10, 100) and params.laser_pose == (0.1, 0.0, 0.0)
    with pytest.raises(ValueError, match="beam_window"):
        StripParams(beam_window=(50, 10))
    with pytest.raises(ValueError, match="is_sort_rule"):
        StripParams(is_sort_rule="any")


def test_parameters_are_checked_against_their_declared_ranges():
    from maru_planner.errors import InvalidRequest

    with pytest.raises(InvalidRequest, match="k_r"):
        StripParams(k_r=-1.0)
    with pytest.raises(InvalidRequest, match="num_vias"):
        StripParams(num_vias=2)
    with pytest.raises(InvalidRequest, match="num_vias"):
        StripParams(num_vias=3.5)
    with pytest.raises(InvalidRequest, match="suppress_tangential"):
        StripParams(suppress_tangential="yes")
    with pytest.raises(InvalidRequest, match="laser_pose"):
        StripParams(laser_pose=(0.0, 0.0))
    assert StripParams(num_vias=10.0, k_r=1).num_vias == 10 and isinstance(StripParams(k_r=1).k_r, float)


def test_set_params_applies_from_the_next_update_and_keeps_the_goal(params):
    import dataclasses

    ctrl = ElasticStripController(params)
    ctrl.set_path(np.array([[0.0, 0.0], [3.0, 0.0], [3.0, 3.0]]))
    free = lms200(np.full(361, np.inf))
    assert ctrl.update((0.0, 0.0, 0.0), free).v == pytest.approx(params.max_linear)
    ctrl.set_params(dataclasses.replace(params, max_linear=0.2, num_vias=5, via_spacing=0.5))
    out = ctrl.update((0.1, 0.0, 0.0), free)
    assert out.v == pytest.approx(0.2)
    assert len(out.strip) == 5 and np.all(np.hypot(*np.diff(out.strip, axis=0).T) <= 0.5 + 1e-9)
    assert ctrl.goal == pytest.approx([3.0, 3.0, 0.0]), "the goal and the rest of the path stay"
    assert ctrl.strip.remaining_path()[-1] == pytest.approx([3.0, 3.0])
    ctrl.set_params(dataclasses.replace(params, arm_enabled=True, arm_max_joint_step=0.01))
    assert ctrl.arm is not None and ctrl.arm.max_joint_step == 0.01
    assert ctrl.update((0.2, 0.0, 0.0), free).arm_joint_steps is not None
    ctrl.set_params(params)
    assert ctrl.arm is None and ctrl.update((0.3, 0.0, 0.0), free).arm_joint_steps is None


def test_paths_too_long_for_the_strip_are_refused_before_allocating(params):
    from maru_planner.errors import InvalidRequest
    from maru_planner.reactive.strip import MAX_REFERENCE_POINTS

    ctrl = ElasticStripController(params)
    with pytest.raises(InvalidRequest, match="m long"):
        ctrl.set_path(np.array([[0.0, 0.0], [1e300, 0.0]]))
    too_far = params.via_spacing * MAX_REFERENCE_POINTS * 1.01
    ctrl.set_goal((too_far, 0.0))
    with pytest.raises(InvalidRequest, match="vias"):
        ctrl.update((0.0, 0.0, 0.0), lms200(np.full(361, np.inf)))
    ctrl.set_goal((2.0, 0.0))
    assert ctrl.update((0.0, 0.0, 0.0), lms200(np.full(361, np.inf))).v > 0.0

"""The validation gaps of issue 36, closed in the core and the CLIs (no DDS; the node's cases are in
test_hostile_planning_node.py): each value that was answered SUCCESS or attempted now gets its own code and
one line, refused before any large allocation.

1. a Cartesian ``max_step`` that implies too many interpolated poses (1e-9 m tried to allocate 64.9 GiB);
2. ``num_attempts`` and ``seed`` out of range; a scaling of 0 means 1.0 for the service and the action alike;
3. joint values outside their limits (1e300) or not finite for FK and state validity;
4. obstacle dimensions and positions out of range (a 1e300 m box);
5. planner parameters and PlannerConfig fields without a range (``planners.RCRRT.candidates`` = 1e12);
6. maru-plan on a scene in a frame the robot does not have; maru-reactive-sim on a one-point world path.
"""

from __future__ import annotations

import math
import time
import tracemalloc

import numpy as np
import pytest
import yaml
from hostile_inputs import EASY_GOAL, PAPER_START, cli_outcome, message_problem

from maru_planner import errors
from maru_planner.params import ParamSpec
from maru_planner.planning import cli as plan_cli
from maru_planner.planning.cartesian import MAX_STEPS, CartesianRequest, check_step_count, interpolate_poses
from maru_planner.planning.config import PLANNER_CONFIG_PARAMS, PlannerConfig
from maru_planner.planning.motion_planner import MotionPlanner
from maru_planner.planning.queries import check_state_validity, compute_fk
from maru_planner.planning.registry import PLANNERS
from maru_planner.planning.requests import check_request
from maru_planner.planning.types import MotionRequest, PlanStatus, status_of_error
from maru_planner.robot import RobotModel
from maru_planner.scene import Obstacle, Scene
from maru_planner.scene.poses import MAX_COORDINATE
from maru_planner.scene.shapes import MAX_DIMENSION
from maru_planner.sim import cli as sim_cli

CARTESIAN_LIMIT_MB = 50.0  # traced Python allocations of a refused Cartesian request (64.9 GiB before)


def _one_line(exc: BaseException) -> str:
    message = errors.one_line(exc)
    assert not message_problem(message), message_problem(message)
    return message


@pytest.fixture(scope="module")
def maru() -> RobotModel:
    return RobotModel.maru1()


@pytest.fixture(scope="module")
def planner(maru) -> MotionPlanner:
    return MotionPlanner.from_scene(maru, Scene(), PlannerConfig(collision_model="exact"))


# ---------------------------------------------------------------- 1. Cartesian steps


def _reach(planner: MotionPlanner, dx: float) -> list[np.ndarray]:
    start = np.array([PAPER_START.get(n, 0.0) for n in planner.robot.joint_names])
    pose = planner.robot.frame_pose(start, "r_hand").copy()
    pose[0, 3] += dx
    return [pose]


@pytest.mark.parametrize("max_step", [1e-9, 5e-324])
def test_a_cartesian_step_implying_too_many_poses_is_refused_before_allocating(planner, max_step):
    request = CartesianRequest("right_arm", dict(PAPER_START), _reach(planner, 0.65), max_step=max_step)
    tracemalloc.start()
    try:
        started = time.monotonic()
        result = planner.cartesian_path(request)
        elapsed = time.monotonic() - started
        peak_mb = tracemalloc.get_traced_memory()[1] / 2**20
    finally:
        tracemalloc.stop()
    assert result.status is PlanStatus.INVALID_REQUEST, result.message
    assert "max_step" in result.message and f"more than {MAX_STEPS}" in result.message
    assert not message_problem(result.message) and elapsed < 1.0 and peak_mb < CARTESIAN_LIMIT_MB


def test_the_step_count_is_the_interpolated_poses_count(planner):
    waypoints = _reach(planner, 0.1)
    start = waypoints[0].copy()
    start[0, 3] -= 0.1
    for max_step in (0.01, 0.003, 0.5):
        assert check_step_count(start, waypoints, max_step) == len(interpolate_poses(start, waypoints, max_step))
    assert check_step_count(start, waypoints, 0.1 / (MAX_STEPS - 0.5)) == MAX_STEPS
    with pytest.raises(errors.InvalidRequest, match="max_step"):
        check_step_count(start, waypoints, 0.1 / (MAX_STEPS + 0.5))


def test_cartesian_scalings_are_checked_before_any_work(planner):
    request = CartesianRequest("right_arm", dict(PAPER_START), _reach(planner, 0.05), velocity_scaling=-1.0)
    result = planner.cartesian_path(request)
    assert result.status is PlanStatus.INVALID_REQUEST and "velocity_scaling" in result.message


# ---------------------------------------------------------------- 2. attempts, seeds, scalings


@pytest.mark.parametrize("attempts", [-5, 0, 1001])
def test_attempts_out_of_range_are_refused(attempts):
    request = MotionRequest("right_arm", dict(PAPER_START), dict(EASY_GOAL), attempts=attempts)
    with pytest.raises(errors.InvalidRequest, match="attempts") as caught:
        check_request(request, PlannerConfig())
    _one_line(caught.value)


def _plan_messages():
    from maru_planner_interfaces.action import PlanMotion as PlanMotionAction
    from maru_planner_interfaces.srv import PlanMotion

    return [PlanMotion.Request(), PlanMotionAction.Goal()]


def _motion_request(message, **fields):
    from maru_planner.ros.planning_parameters import NodeSettings
    from maru_planner.ros.planning_requests import motion_request

    message.allowed_planning_time = 1.0
    message.goal_joint_names, message.goal_positions = list(EASY_GOAL), list(EASY_GOAL.values())
    message.start_state.name, message.start_state.position = list(PAPER_START), list(PAPER_START.values())
    for name, value in fields.items():
        setattr(message, name, value)
    return motion_request(message, NodeSettings(), "RRTConnect", dict)


@pytest.mark.parametrize("message", _plan_messages(), ids=["service", "action"])
@pytest.mark.parametrize(("field", "value"), [("num_attempts", -5), ("num_attempts", 1001), ("seed", -2)])
def test_service_and_action_refuse_attempts_and_seeds_out_of_range(message, field, value):
    with pytest.raises(errors.InvalidRequest, match=field) as caught:
        _motion_request(message, **{field: value})
    _one_line(caught.value)


@pytest.mark.parametrize("message", _plan_messages(), ids=["service", "action"])
def test_service_and_action_read_zero_the_same_way(message):
    """0 scalings are 1.0 (the interface's "(0, 1]; 0 = 1.0"), 0 attempts the node's default, seed -1 random."""
    request = _motion_request(message, max_velocity_scaling_factor=0.0, num_attempts=0, seed=-1)
    assert (request.velocity_scaling, request.acceleration_scaling, request.jerk_scaling) == (1.0, 1.0, 1.0)
    assert request.attempts == 1 and request.seed is None


# ---------------------------------------------------------------- 3. joint values


@pytest.mark.parametrize("value", [1e300, -1e300, math.inf, math.nan, "past the limit"])
def test_fk_and_state_validity_refuse_values_outside_limits(maru, planner, value):
    q = np.asarray(maru.neutral(), dtype=float).copy()
    k = maru.joint_names.index("r_arm_j2")
    q[k] = maru.upper_limits[k] + 1e-6 if value == "past the limit" else value
    for query in (lambda: compute_fk(maru, q, ["r_hand"]), lambda: check_state_validity(maru, planner.checker, q)):
        with pytest.raises(errors.InvalidState, match="r_arm_j2") as caught:
            query()
        assert status_of_error(caught.value) is PlanStatus.INVALID_STATE
        _one_line(caught.value)


def test_a_state_at_its_limits_is_still_judged(maru, planner):
    q = np.asarray(maru.upper_limits, dtype=float).copy()
    assert check_state_validity(maru, planner.checker, q).within_limits
    assert "r_hand" in compute_fk(maru, q, ["r_hand"])


# ---------------------------------------------------------------- 4. obstacles

BAD_OBSTACLES = {
    "box 1e300": {"type": "box", "size": [1e300, 1.0, 1.0]},
    "box over the limit": {"type": "box", "size": [1.0, 1.0, 2 * MAX_DIMENSION]},
    "sphere 1e300": {"type": "sphere", "radius": 1e300},
    "cylinder length": {"type": "cylinder", "radius": 0.1, "length": 1e300},
    "mesh scale": {"type": "mesh", "path": "part.stl", "scale": [1e300, 1.0, 1.0]},
    "position 1e300": {"type": "box", "size": [0.1, 0.1, 0.1], "pose": {"xyz": [1e300, 0.0, 0.0]}},
    "position over the limit": {"type": "sphere", "radius": 0.1, "pose": [0.0, 0.0, -2 * MAX_COORDINATE]},
    "4x4 position": {"type": "sphere", "radius": 0.1, "pose": [[1, 0, 0, 1e300], [0, 1, 0, 0], [0, 0, 1, 0],
                                                               [0, 0, 0, 1]]},
}  # fmt: skip


@pytest.mark.parametrize("entry", BAD_OBSTACLES.values(), ids=BAD_OBSTACLES)
def test_obstacles_out_of_range_are_refused(entry):
    with pytest.raises(errors.InvalidScene, match="obstacle 'o'") as caught:
        Obstacle.from_dict({"name": "o", **entry})
    _one_line(caught.value)


def test_obstacles_at_the_limits_are_accepted():
    Obstacle("o", "box", size=(MAX_DIMENSION,) * 3, pose=[MAX_COORDINATE, -MAX_COORDINATE, 0.0])


def test_an_obstacle_message_of_1e300_is_refused():
    from shape_msgs.msg import SolidPrimitive

    from maru_planner.ros.planning_conversions import error_code, matrix_to_pose
    from maru_planner.ros.planning_requests import scene_edit
    from maru_planner_interfaces.msg import PlanningError, SceneObstacle

    for dimensions, xyz in (([1e300, 1.0, 1.0], (0.5, 0.0, 0.0)), ([0.1, 0.1, 0.1], (0.5, 1e300, 0.0))):
        msg = SceneObstacle(name="huge", operation=SceneObstacle.ADD)
        msg.shape = SolidPrimitive(type=SolidPrimitive.BOX, dimensions=dimensions)
        pose = np.eye(4)
        pose[:3, 3] = xyz
        msg.pose = matrix_to_pose(pose)
        with pytest.raises(errors.InvalidScene) as caught:
            scene_edit(msg, "base_link")
        assert error_code(caught.value) == PlanningError.INVALID_SCENE
        _one_line(caught.value)


# ---------------------------------------------------------------- 5. parameter ranges


def _unbounded(specs: dict[str, ParamSpec]) -> list[str]:
    numeric = [s for s in specs.values() if s.value_type in (int, float)]
    return [s.name for s in numeric if s.lower is None or s.upper is None]


def test_every_planner_parameter_and_config_field_has_a_range():
    assert _unbounded(PLANNER_CONFIG_PARAMS) == []
    for planner_id, spec in PLANNERS.items():
        assert _unbounded(dict(spec.params)) == [], planner_id


def test_the_nodes_descriptors_carry_the_ranges():
    from maru_planner.ros.parameters import descriptor
    from maru_planner.ros.planning_parameters import parameter_specs

    specs = parameter_specs()
    assert _unbounded(specs) == []
    candidates = descriptor(specs["planners.RCRRT.candidates"])
    assert (candidates.integer_range[0].from_value, candidates.integer_range[0].to_value) == (1, 1000)
    with pytest.raises(errors.InvalidRequest, match="candidates"):
        specs["planners.RCRRT.candidates"].check(10**12)


def _maru_plan(argv: list[str]):
    return cli_outcome(plan_cli.main, ["--quiet", *argv], "maru-plan", {0, 1, 2, 3, 130}, 2, 3, 5.0)


@pytest.mark.parametrize(("planner_id", "assignment"), [("RCRRT", "candidates=1000000000000"),
                                                         ("RCRRT", "goal_range=1e300"), ("RCRRT", "step=4"),
                                                         ("CompiledRRTConnect", "domain_radius=1e9"),
                                                         ("PRM", "max_nearest_neighbors=100000")])  # fmt: skip
def test_maru_plan_refuses_parameters_out_of_range(planner_id, assignment):
    outcome = _maru_plan(["--problem", "maru6", "--planner", planner_id, "--param", assignment])
    assert outcome.proper_error and "exit 2" in outcome.detail, outcome.detail


# ---------------------------------------------------------------- 6. CLIs: scene frames, world paths


def test_maru_plan_refuses_a_scene_in_a_frame_the_robot_does_not_have(tmp_path):
    scene = tmp_path / "world_frame.yaml"
    scene.write_text(yaml.safe_dump({"frame": "world", "obstacles": [{"name": "b", "type": "sphere", "radius": 0.1,
                                                                      "pose": {"xyz": [2.0, 0.0, 0.0]}}]}))  # fmt: skip
    outcome = _maru_plan(["--problem", "maru6", "--scene", str(scene)])
    assert outcome.proper_error and "exit 2" in outcome.detail and "frame 'world'" in outcome.detail, outcome.detail


def test_a_scene_in_the_root_frame_or_naming_none_is_accepted(maru):
    plan_cli.check_scene_frame(Scene(frame="base_link"), maru)
    plan_cli.check_scene_frame(Scene.from_dict({"obstacles": []}), maru)


def test_maru_reactive_sim_refuses_a_one_point_world_path(tmp_path):
    world = tmp_path / "one_point.yaml"
    world.write_text(yaml.safe_dump({"robot": {"start": [0, 0, 0], "goal": [2, 0, 0]}, "path": [[2, 0]],
                                     "max_time": 1}))  # fmt: skip
    outcome = cli_outcome(sim_cli.main, ["--world", str(world), "--quiet"], "maru-reactive-sim", {0, 2, 130}, 2)
    assert outcome.proper_error and "exit 2" in outcome.detail and "at least 2 points" in outcome.detail, outcome.detail

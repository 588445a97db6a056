"""PathCertifier: continuous validation with a proof (thin obstacles, margins, the motion bound, repair)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pinocchio as pin
import pytest
from conftest import mbm_problem, needs_mbm

from maru_planner import errors
from maru_planner.collision import CollisionChecker
from maru_planner.collision.certify import (
    MIN_ANCHOR_CLEARANCE,
    Certificate,
    PathCertifier,
    SphereCover,
    certify_and_repair,
    chord_deviation,
    joint_levers,
    kernel_primitives,
    without_corners,
)
from maru_planner.collision.checker import convex_hull
from maru_planner.collision.kernels.support_bounds import NO_SHAPE
from maru_planner.collision.shape_records import robot_shape_records
from maru_planner.collision.spheres import densify, verify_path
from maru_planner.paths import config_path
from maru_planner.planning import MotionPlanner, MotionRequest, PlannerConfig, PlanStatus
from maru_planner.planning.config import COLLISION_MODELS
from maru_planner.planning.types import PlanStats
from maru_planner.robot import RobotModel, load_example_robot
from maru_planner.robot.robots.panda import mbm_panda
from maru_planner.scene import Obstacle, Scene

OLD_STEP = 0.02  # rad: the discrete validator's default motion resolution
TIP_RADIUS = 0.002  # m: the toy arm's tip ball
REACH = 0.6  # m: joint 1 to the tip ball's centre (0.3 + 0.3)

TWO_LINK_ARM = """<robot name="two_link">
  <link name="base"/>
  <link name="upper">
    <collision><origin xyz="0.15 0 0"/><geometry><box size="0.3 0.02 0.02"/></geometry></collision>
  </link>
  <link name="fore">
    <collision><origin xyz="0.3 0 0"/><geometry><sphere radius="{tip}"/></geometry></collision>
  </link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="upper"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="j2" type="revolute"><parent link="upper"/><child link="fore"/><origin xyz="0.3 0 0"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
</robot>
"""


@pytest.fixture(scope="module")
def arm(tmp_path_factory) -> RobotModel:
    """Two revolute joints about z; the forearm is a 2 mm ball at 0.6 m from joint 1 (arm stretched)."""
    urdf = tmp_path_factory.mktemp("arm") / "two_link.urdf"
    urdf.write_text(TWO_LINK_ARM.format(tip=TIP_RADIUS))
    return RobotModel.from_urdf(urdf)


def plate_at(angle: float, thickness: float = 0.002, radial: float = 0.05) -> Obstacle:
    """A thin plate across the tip's circle at ``angle`` (rad), ``thickness`` along the circle."""
    pose = np.eye(4)
    pose[:3, :3] = pin.rpy.rpyToMatrix(0.0, 0.0, angle)
    pose[:3, 3] = [REACH * np.cos(angle), REACH * np.sin(angle), 0.0]
    return Obstacle("plate", "box", size=(radial, thickness, 0.05), pose=pose)


def test_thin_plate_between_the_old_validators_states_is_caught(arm):
    # States at every 0.02 rad; the plate sits half-way between two of them, out of reach of both:
    # at 0.02 and 0.04 rad the ball is 6 mm from the plate's centre, 3 mm from its faces.
    checker = CollisionChecker(arm, Scene([plate_at(0.03)]))
    path = np.array([[0.0, 0.0], [0.2, 0.0]])
    assert verify_path(checker, path, OLD_STEP).valid  # every discrete step misses it
    certificate = PathCertifier(arm, checker, safety_margin=0.0).certify_path(path)
    assert not certificate.valid
    assert certificate.reason == "collision" and certificate.first_failing_segment == 0
    assert not checker.is_valid(certificate.witness)
    assert not verify_path(checker, path, 1e-4).valid  # and it is really there


def test_thin_plate_off_the_path_is_certified_clear(arm):
    checker = CollisionChecker(arm, Scene([plate_at(0.3)]))
    certificate = PathCertifier(arm, checker, safety_margin=0.0).certify_path(np.array([[0.0, 0.0], [0.2, 0.0]]))
    assert certificate.valid and certificate.first_failing_segment == -1
    assert certificate.min_clearance > 0.0


def test_margin_is_kept_and_enforced(arm):
    # The ball passes the plate's end 20 mm away (plate radial extent ends 20 mm inside the tip circle).
    plate = Obstacle("plate", "box", size=(0.1, 0.002, 0.05), pose=[REACH - 0.07 - TIP_RADIUS, 0.0, 0.0])
    checker = CollisionChecker(arm, Scene([plate]))
    path = np.array([[-0.2, 0.0], [0.2, 0.0]])
    clearance = 0.02
    for margin in (0.0, 0.5 * clearance):
        certificate = PathCertifier(arm, checker, safety_margin=margin).certify_path(path)
        assert certificate.valid
        assert certificate.margin <= certificate.min_clearance
    certificate = PathCertifier(arm, checker, safety_margin=1.5 * clearance).certify_path(path)
    assert not certificate.valid and certificate.reason == "margin"
    assert 0.0 < checker.clearance(certificate.witness) <= 1.5 * clearance
    with pytest.raises(errors.InvalidRequest, match="safety_margin"):
        PathCertifier(arm, checker, safety_margin=-0.01)


def test_chord_deviation_widens_the_margin(arm):
    assert np.allclose(chord_deviation([0.0, 0.1, 0.3], [8.0, 2.0]), [8.0 * 0.04 / 8, 2.0 * 0.04 / 8])
    plate = Obstacle("plate", "box", size=(0.1, 0.002, 0.05), pose=[REACH - 0.07 - TIP_RADIUS, 0.0, 0.0])
    certifier = PathCertifier(arm, Scene([plate]), safety_margin=0.0)
    path = np.array([[-0.2, 0.0], [0.2, 0.0]])
    # The ball moves at most 0.602 m/rad (joint 1) + 0.302 m/rad (joint 2): 9 mm, then 27 mm off the chords.
    assert certifier.certify_path(path, deviation=[0.01, 0.01]).valid
    assert not certifier.certify_path(path, deviation=[0.03, 0.03]).valid


def test_curves_certified_together_get_each_their_own_answer(arm):
    """certify_curves: one pass, one answer per curve, each as certify_path alone gives it (the straight steps
    between curves are not certified: the last curve ends right of the plate, the next starts left of it)."""
    certifier = PathCertifier(arm, Scene([plate_at(0.03)]), safety_margin=0.0)
    through = np.array([[0.0, 0.0], [0.1, 0.0], [0.2, 0.0]])  # sweeps across the plate
    left, right = np.array([[-0.3, 0.0], [-0.1, 0.0]]), np.array([[0.1, 0.0], [0.3, 0.0]])
    none = np.zeros(2)
    curves = [(right, none), (left, none), (through, none), (right, [0.01, 0.01]), (right, [0.2, 0.2])]
    want = [certifier.certify_path(c, deviation=d).valid for c, d in curves]
    assert want == [True, True, False, True, False]
    assert certifier.certify_curves(curves) == want
    assert certifier.certify_curves([]) == []


def test_bent_segments_are_proven_as_the_parabolas_they_are(arm):
    """certify_curves with bends: segment q(t) = (1 - t) q0 + t q1 + (t² - t) bend. The tip's chord sweeps through
    a 4 mm ball; bending the elbow enough swings the tip inside it. Each answer equals a dense check's."""
    scene = Scene([Obstacle("ball", "sphere", radius=0.004, pose=[REACH, 0.0, 0.0])])
    certifier = PathCertifier(arm, scene, safety_margin=0.0)
    ends = np.array([[-0.2, 0.0], [0.2, 0.0]])
    t = np.linspace(0.0, 1.0, 4001)[:, None]

    def dense_clear(bend: np.ndarray, margin: float) -> bool:
        states = (1.0 - t) * ends[0] + t * ends[1] + (t * t - t) * bend
        return verify_path(CollisionChecker(arm, scene, padding=margin), states, 1.0).valid

    answers = []
    for bend in ([0.0, 0.0], [0.0, 2.0], [0.0, 4.0], [0.0, 6.0], [0.0, -6.0], [2.0, 6.0]):
        for margin in (0.0, 0.003):
            proven = certifier.certify_curves([(ends, np.zeros(2), np.array([bend]))], margin=margin)[0]
            assert proven == dense_clear(np.array(bend), margin), (bend, margin)
            answers.append(proven)
    assert answers == [False, False, False, False, True, False, True, True, True, True, False, False]
    rng = np.random.default_rng(7)
    for bend in rng.uniform(-8.0, 8.0, (30, 2)):  # never a proof of a curve that touches
        if certifier.certify_curves([(ends, np.zeros(2), bend[None])])[0]:
            assert dense_clear(bend, 0.0), bend


def test_scene_edits_are_followed(arm):
    scene = Scene()
    certifier = PathCertifier(arm, CollisionChecker(arm, scene), safety_margin=0.0)
    path = np.array([[0.0, 0.0], [0.2, 0.0]])
    assert certifier.certify_path(path).valid
    scene.add(plate_at(0.1))
    assert not certifier.certify_path(path).valid


def test_levers_bound_the_motion_of_every_vertex():
    """The motion bound the proof rests on: no point of a link moves farther than levers @ |dq|."""
    robot = load_example_robot("panda")
    levers = joint_levers(robot)
    rng = np.random.default_rng(3)
    data = robot.model.createData()
    geometries = robot.collision_model.geometryObjects

    def local_points(geometry) -> np.ndarray:
        if hasattr(geometry, "vertices"):
            return np.asarray(geometry.vertices(), dtype=float)
        corners = np.array(np.meshgrid([-1, 1], [-1, 1], [-1, 1])).reshape(3, -1).T
        return corners * np.asarray(geometry.halfSide)

    def vertices(q):
        pin.forwardKinematics(robot.model, data, q)
        out = []
        for obj in geometries:
            placement = data.oMi[obj.parentJoint] * obj.placement
            out.append(local_points(obj.geometry) @ placement.rotation.T + placement.translation)
        return out

    for _ in range(20):
        q0 = robot.random_configuration(rng)
        q1 = np.clip(q0 + rng.normal(0.0, 0.3, robot.nq), robot.lower_limits, robot.upper_limits)
        for g, (a, b) in enumerate(zip(vertices(q0), vertices(q1), strict=True)):
            moved = np.linalg.norm(b - a, axis=1).max()
            assert moved <= levers[g] @ np.abs(q1 - q0) + 1e-9, geometries[g].name


def test_prismatic_joints_need_finite_limits():
    robot = load_example_robot("panda")
    finger = robot.joint_indices(["panda_finger_joint1"])[0]
    robot.upper_limits[finger] = np.inf
    with pytest.raises(errors.InvalidRequest, match="panda_finger_joint1"):
        joint_levers(robot)


def test_convex_hull_contains_the_mesh():
    mesh = load_example_robot("panda").collision_model.geometryObjects[3].geometry
    hull = convex_hull(mesh)
    points = np.asarray(hull.points(), dtype=float)
    assert len(points) <= mesh.num_vertices
    vertices = np.asarray(mesh.vertices(), dtype=float)
    assert np.allclose(vertices.min(axis=0), points.min(axis=0))
    assert np.allclose(vertices.max(axis=0), points.max(axis=0))


def maru13() -> tuple[RobotModel, CollisionChecker]:
    robot = RobotModel.maru1()
    return robot, CollisionChecker(robot, Scene.from_yaml(config_path("scenes", "maru13_desk_box.yaml")))


def panda_shelf() -> tuple[RobotModel, CollisionChecker]:
    """Meshes (the hull tier) and prismatic fingers, between a shelf's boards and a post."""
    robot = load_example_robot("panda")
    boards = [
        Obstacle(f"board{k}", "box", size=(0.3, 0.8, 0.02), pose=[0.55, 0.0, z]) for k, z in enumerate((0.2, 0.6))
    ]
    post = Obstacle("post", "cylinder", radius=0.03, length=0.8, pose=[0.35, -0.35, 0.4])
    return robot, CollisionChecker(robot, Scene([*boards, post]))


@pytest.mark.parametrize("world", [maru13, panda_shelf])
def test_certified_segments_are_free_at_a_fine_independent_step(world):
    robot, checker = world()
    margin = 0.005
    padded = CollisionChecker(robot, checker.scene, padding=margin)  # valid: more than the margin away
    certifier = PathCertifier(robot, checker, safety_margin=margin)
    rng = np.random.default_rng(7)
    outcomes = {True: 0, False: 0}
    while min(outcomes.values()) < 4:
        q0 = robot.random_configuration(rng)
        q1 = np.clip(q0 + rng.normal(0.0, 2.0, robot.nq), robot.lower_limits, robot.upper_limits)
        if not (padded.is_valid(q0) and padded.is_valid(q1)):
            continue
        certificate = certifier.certify_segment(q0, q1)
        outcomes[certificate.valid] += 1
        if not certificate.valid:
            assert certificate.reason in ("collision", "margin")
            assert not padded.is_valid(certificate.witness)
        elif outcomes[True] <= 6:  # the fine re-check is the slow part
            fine, _ = densify(np.array([q0, q1]), 1e-3)
            assert padded.first_invalid(fine) == -1


class DetourPlanner:
    """A local planner that folds joint 2 while joint 1 sweeps, so the ball passes inside the plate."""

    def __init__(self):
        self.calls = []

    def __call__(self, qa, qb, margin, deadline):
        self.calls.append((qa.copy(), qb.copy(), margin))
        fold = np.array([0.0, 1.2])
        return np.array([qa, qa + fold, qb + fold, qb])


def test_a_failing_segment_is_repaired_locally(arm):
    # Folded by 1.2 rad the ball is 0.495 m from joint 1; unfolding, it crosses the plate's line at 0.573 m.
    plate = Obstacle("plate", "box", size=(0.04, 0.002, 0.05), pose=[REACH + 0.01, 0.0, 0.0])
    certifier = PathCertifier(arm, Scene([plate]), safety_margin=0.005)
    path = np.array([[-0.4, 0.0], [-0.3, 0.0], [0.3, 0.0], [0.4, 0.0]])
    local = DetourPlanner()
    repaired = certify_and_repair(certifier, path, local, deadline=np.inf)
    assert repaired.repairs == 1 and repaired.certificate.valid
    [(qa, qb, margin)] = local.calls
    assert np.allclose(qa, path[1]) and np.allclose(qb, path[2]) and margin == 0.005
    assert np.allclose(repaired.path[0], path[0]) and np.allclose(repaired.path[-1], path[-1])
    assert certifier.certify_path(repaired.path).valid
    assert repaired.certificate.min_clearance >= 0.005


def test_a_repair_never_starts_at_a_waypoint_touching_an_obstacle(arm):
    """Margin 0: waypoint 1 is 1 mm from the plate (more than the margin), segment 1 sweeps through it. The repair
    starts at waypoint 0 instead: every local path from a touching waypoint grazed the obstacle again."""
    tangent_offset = (0.001 + TIP_RADIUS + 0.001) / REACH  # plate's half thickness, the ball, 1 mm of clearance
    certifier = PathCertifier(arm, Scene([plate_at(0.1)]), safety_margin=0.0)
    path = np.array([[-0.2, 0.0], [0.1 - tangent_offset, 0.0], [0.4, 0.0]])
    assert certifier.clearance(path[1]) == pytest.approx(0.001, abs=1e-4)
    assert 0.0 < certifier.clearance(path[1]) < MIN_ANCHOR_CLEARANCE
    local = DetourPlanner()
    certify_and_repair(certifier, path, local, deadline=np.inf, max_repairs=1)
    (qa, qb, _margin), *_ = local.calls
    assert np.array_equal(qa, path[0]) and np.array_equal(qb, path[2])


@pytest.mark.parametrize("model", COLLISION_MODELS)
def test_a_margin_0_repair_is_searched_padded(arm, monkeypatch, model):
    """Twice a margin of 0 is 0: a repair's search is padded by up to MIN_REPAIR_PADDING, half-way to its anchors'
    clearance, so that its edges (checked at states) do not graze what certification just rejected."""
    from maru_planner.planning.stages import repair

    paddings = []
    padded = repair.padded_checker

    def recording(robot, checker, padding):
        paddings.append(padding)
        return padded(robot, checker, padding)

    monkeypatch.setattr(repair, "padded_checker", recording)
    scene = Scene([Obstacle("plate", "box", size=(0.04, 0.002, 0.05), pose=[REACH + 0.01, 0.0, 0.0])])
    request = MotionRequest("all", start={"j1": -0.3, "j2": 0.0}, goal_joints={"j1": 0.4, "j2": 0.0},
                            planner_id="RRTConnect", time_budget=10.0, seed=1)  # fmt: skip
    planner = MotionPlanner.from_scene(arm, scene, PlannerConfig(resolution=0.7, safety_margin=0.0,
                                                                 collision_model=model))  # fmt: skip
    result = planner.plan(request)
    assert result.success and result.stats.certified and result.stats.repairs >= 1, result.message
    assert result.stats.collision_model == model
    assert paddings and all(0.0 < p <= repair.REPAIR_MIN_PADDING for p in paddings)


def test_repair_gives_up_without_a_local_path(arm):
    certifier = PathCertifier(arm, Scene([plate_at(0.0)]), safety_margin=0.0)
    repaired = certify_and_repair(certifier, np.array([[-0.2, 0.0], [0.2, 0.0]]), lambda *_: None, deadline=np.inf)
    assert repaired.path is None and repaired.repairs == 1
    assert not repaired.certificate.valid and repaired.certificate.reason == "collision"


def test_an_end_closer_than_the_margin_lowers_it_to_half_its_clearance(arm):
    plate = Obstacle("plate", "box", size=(0.1, 0.002, 0.05), pose=[REACH - 0.05 - TIP_RADIUS - 0.004, 0.0, 0.0])
    certifier = PathCertifier(arm, Scene([plate]), safety_margin=0.01)  # the ball starts 4 mm from it
    repaired = certify_and_repair(certifier, np.array([[0.0, 0.0], [0.3, 0.0]]), lambda *_: None, deadline=np.inf)
    assert repaired.certificate.valid and repaired.repairs == 0
    assert repaired.certificate.margin == pytest.approx(0.002, abs=1e-5)


@pytest.mark.parametrize("model", COLLISION_MODELS)
def test_motion_planner_returns_only_certified_paths(arm, model):
    # At a 0.7 rad motion step the search checks the goal alone and steps over the plate.
    scene = Scene([Obstacle("plate", "box", size=(0.04, 0.002, 0.05), pose=[REACH + 0.01, 0.0, 0.0])])
    config = PlannerConfig(resolution=0.7, safety_margin=0.005, collision_model=model)
    request = MotionRequest("all", start={"j1": -0.3, "j2": 0.0}, goal_joints={"j1": 0.4, "j2": 0.0},
                            planner_id="RRTConnect", time_budget=10.0, seed=1)  # fmt: skip
    uncertified = MotionPlanner.from_scene(arm, scene, dataclasses.replace(config, certify=False)).plan(request)
    assert uncertified.success and not uncertified.stats.certified
    assert not verify_path(CollisionChecker(arm, scene), np.asarray(uncertified.path), 1e-3).valid
    result = MotionPlanner.from_scene(arm, scene, config).plan(request)
    assert result.success and result.stats.certified and result.stats.repairs >= 1, result.message
    assert result.stats.min_clearance >= 0.005 and result.stats.certify_time > 0
    padded = CollisionChecker(arm, scene, padding=0.005)
    assert verify_path(padded, np.asarray(result.path), 1e-3).valid
    assert result.to_json_dict()["stats"]["certified"]


@pytest.mark.parametrize("model", COLLISION_MODELS)
def test_motion_planner_searches_with_the_margin(arm, model):
    # The tip sweeps past the plate 5 mm away: free, but closer than the 10 mm margin.
    plate = Obstacle("plate", "box", size=(0.04, 0.002, 0.05), pose=[REACH + TIP_RADIUS + 0.005 + 0.02, 0.0, 0.0])
    scene = Scene([plate])
    request = MotionRequest("all", start={"j1": -0.3, "j2": 0.0}, goal_joints={"j1": 0.3, "j2": 0.0},
                            planner_id="RRTConnect", time_budget=10.0, seed=1)  # fmt: skip
    config = PlannerConfig(safety_margin=0.01, collision_model=model)
    uncertified = MotionPlanner.from_scene(arm, scene, dataclasses.replace(config, certify=False)).plan(request)
    assert uncertified.success and len(uncertified.path) == 2  # the search alone takes the straight sweep
    result = MotionPlanner.from_scene(arm, scene, config).plan(request)
    assert result.success and result.stats.certified and result.stats.repairs == 0, result.message
    assert verify_path(CollisionChecker(arm, scene, padding=0.01), np.asarray(result.path), 1e-3).valid
    # A start closer than the margin (~4 mm) is searched padded by 3/4 of that and certified with half of it.
    near = dataclasses.replace(request, start={"j1": 0.0, "j2": 0.0}, goal_joints={"j1": 0.3, "j2": 0.0})
    near_plate = Obstacle("plate", "box", size=(0.1, 0.002, 0.05), pose=[REACH - 0.05 - TIP_RADIUS - 0.004, 0.0, 0.0])
    planner = MotionPlanner.from_scene(arm, Scene([near_plate]), config)
    result = planner.plan(near)
    assert result.success and result.stats.certified, result.message
    clearance = planner.certifier.clearance(np.array([0.0, 0.0]))
    assert planner.context.last_search_checker.padding == pytest.approx(0.75 * clearance)
    assert result.stats.min_clearance > 0.5 * clearance


def test_motion_planner_rejects_a_negative_safety_margin(arm):
    request = MotionRequest("all", start={"j1": 0.0, "j2": 0.0}, goal_joints={"j1": 0.1, "j2": 0.0},
                            safety_margin=-0.01)  # fmt: skip
    result = MotionPlanner.from_scene(arm, Scene()).plan(request)
    assert result.status is PlanStatus.INVALID_REQUEST and "safety_margin" in result.message


def test_planner_stats_message_carries_the_certification():
    conversions = pytest.importorskip("maru_planner.ros.planning_conversions")
    msg = conversions.stats_msg(PlanStats(certified=True, certify_time=0.02, min_clearance=0.004, repairs=2))
    assert msg.certified and msg.repairs == 2
    assert msg.certify_time == pytest.approx(0.02) and msg.min_clearance == pytest.approx(0.004)
    assert conversions.stats_msg(PlanStats()).min_clearance == 0.0  # not certified: inf is sent as 0


def test_clearance_is_the_exact_checkers():
    robot, checker = panda_shelf()
    certifier = PathCertifier(robot, checker)
    rng = np.random.default_rng(5)
    for q in (robot.random_configuration(rng) for _ in range(10)):
        assert certifier.clearance(q) == pytest.approx(checker.clearance(q), abs=1e-5)


def panda_shelf_and_clutter() -> tuple[RobotModel, CollisionChecker]:
    """The shelf plus 120 one-centimetre balls on its boards and in the air around the arm (a point cloud)."""
    robot, shelf = panda_shelf()
    rng = np.random.default_rng(3)
    on_boards = np.c_[rng.uniform(0.42, 0.68, 80), rng.uniform(-0.4, 0.4, 80), np.repeat([0.22, 0.62], 40)]
    in_air = rng.uniform([-0.6, -0.6, 0.0], [0.6, 0.6, 1.0], (40, 3))
    points = np.concatenate([on_boards, in_air])
    balls = [Obstacle(f"pt{k}", "sphere", radius=0.01, pose=p) for k, p in enumerate(points.tolist())]
    return robot, CollisionChecker(robot, Scene([*shelf.scene.obstacles.values(), *balls]))


def test_a_large_scene_certifies_like_its_full_pair_table(monkeypatch):
    """Past NEAR_PATH_MIN_OBSTACLES reachable obstacles each certification only proves the pairs of obstacles
    near its path: the same answers as proving every pair."""
    from maru_planner.collision import certify

    robot, checker = panda_shelf_and_clutter()
    assert len(checker.reachable_obstacles) >= certify.NEAR_PATH_MIN_OBSTACLES
    near = PathCertifier(robot, checker, safety_margin=0.005)
    full = PathCertifier(robot, checker, safety_margin=0.005)
    rng = np.random.default_rng(11)
    outcomes = {True: 0, False: 0}
    while min(outcomes.values()) < 4:
        q0 = robot.random_configuration(rng)
        q1 = np.clip(q0 + rng.normal(0.0, 1.0, robot.nq), robot.lower_limits, robot.upper_limits)
        if not (checker.is_valid(q0) and checker.is_valid(q1)):
            continue
        got = near.certify_segment(q0, q1)
        with monkeypatch.context() as patch:
            patch.setattr(certify, "NEAR_PATH_MIN_OBSTACLES", 10**9)
            want = full.certify_segment(q0, q1)
            assert near.clearance(q0) == pytest.approx(full.clearance(q0), abs=1e-9)
        assert (got.valid, got.first_failing_segment, got.reason) == (want.valid, want.first_failing_segment,
                                                                      want.reason)  # fmt: skip
        assert near.clearance(q0) == pytest.approx(checker.clearance(q0), abs=1e-5)
        outcomes[got.valid] += 1
    tables = near._near_tables.values()  # what the large-scene path proved: fewer obstacles than the scene's
    assert any(len(table.obstacles) < len(checker.reachable_obstacles) for table in tables)


def test_only_a_small_scene_proves_the_straight_pieces_with_the_blends():
    """In a large scene each pass keeps the obstacles near any of its curves: given the straight pieces too, every
    blend would be checked against their obstacles, so the blends go alone and the path is certified after."""
    from maru_planner.trajectory import certified_curve

    robot, clutter = panda_shelf_and_clutter()
    _, shelf = panda_shelf()
    base = robot.neutral()
    large, small = (certified_curve(PathCertifier(robot, checker), base, [0, 1], None, 0.005)
                    for checker in (clutter, shelf))  # fmt: skip
    assert large.certifier.near_path_only and not large.takes_pieces
    assert not small.certifier.near_path_only and small.takes_pieces


def _no_shapes(geometries, hulls) -> tuple:
    """certify's robot shape records with no shape held: the row kernel measures nothing by GJK."""
    kind, *rest = robot_shape_records(geometries, hulls)
    return (np.full_like(kind, NO_SHAPE), *rest)


@pytest.mark.parametrize("world", [panda_shelf, maru13])
def test_rows_get_the_poses_and_centres_of_their_chains_as_full_forward_kinematics_gives_them(world):
    """A later round's few rows per configuration pose only the chains to their pairs' geometries, each as the
    whole configuration's forward kinematics poses it; a first round's many rows pose every joint."""
    from maru_planner.collision.certify import bounds

    robot, checker = world()
    certifier = PathCertifier(robot, checker)
    pairs = certifier._pair_table()
    rng = np.random.default_rng(2)
    configs = np.array([robot.random_configuration(rng) for _ in range(6)])
    tree, joint, local = certifier._tree, certifier._joint, certifier._local
    nj, ng = robot.model.njoints, len(joint)
    want = np.empty((6, nj, 3, 3)), np.empty((6, nj, 3)), np.empty((6, ng, 3))
    bounds.poses_nb(configs, *tree, joint, local, *want)
    for n_rows in (5, 8 * 6):
        pair = rng.integers(len(pairs.first), size=n_rows)
        config_of = rng.integers(6, size=n_rows)
        got = np.full((6, nj, 3, 3), np.nan), np.full((6, nj, 3), np.nan), np.full((6, ng, 3), np.nan)
        posed = np.zeros((6, nj), dtype=bool)
        bounds.place_rows_nb(configs, config_of, pair, pairs.first, pairs.other, *tree, joint, local, *got, posed)
        for c, p in zip(config_of, pair, strict=True):
            for g in (pairs.first[p], pairs.other[p]):
                assert np.allclose(got[2][c, g], want[2][c, g], atol=1e-12)
                chain = certifier._levers[g] > 0.0  # the joints that move it
                assert posed[c, certifier._q_joint[chain]].all()
        assert np.allclose(got[0][posed], want[0][posed], atol=1e-12) and np.allclose(got[1][posed], want[1][posed])
        assert posed.all() == (n_rows >= bounds.ROWS_FOR_ALL * 6)


def test_each_obstacle_finds_its_own_primitive_in_the_kernels_order():
    """Obstacles of mixed kinds in any order: each one's index into the kernel arrays (boxes, spheres, cylinders)
    leads to its own primitive, exact for these shapes."""
    kinds = {"box": {"size": (0.1, 0.2, 0.3)}, "sphere": {"radius": 0.05}, "cylinder": {"radius": 0.04, "length": 0.2}}
    order = ["cylinder", "box", "sphere", "box", "cylinder", "sphere", "box"]
    obstacles = [Obstacle(f"o{i}", kind, pose=[0.1 * i, 0.0, 0.5], **kinds[kind]) for i, kind in enumerate(order)]
    (position, box_c, _, _, sph_c, _, cyl_c, *_), exact = kernel_primitives(obstacles)
    centres = np.concatenate([box_c, sph_c, cyl_c])
    assert np.allclose(centres[position], [[0.1 * i, 0.0, 0.5] for i in range(len(order))])
    assert sorted(position.tolist()) == list(range(len(order))) and exact.all()


def _coal_queries_of_two(robot, checker, want: PathCertifier, got: PathCertifier, seed: int) -> tuple[int, int]:
    """Certify random segments (5 certified, 5 not at least) with both: the same verdicts, every certified one clear
    by the margin; (coal queries of ``want``, of ``got``)."""
    rng = np.random.default_rng(seed)
    outcomes, queries = {True: 0, False: 0}, [0, 0]
    while min(outcomes.values()) < 5:
        q0 = robot.random_configuration(rng)
        q1 = np.clip(q0 + rng.normal(0.0, 1.0, robot.nq), robot.lower_limits, robot.upper_limits)
        if not (checker.is_valid(q0) and checker.is_valid(q1)):
            continue
        a, b = want.certify_segment(q0, q1), got.certify_segment(q0, q1)
        assert (b.valid, b.reason, b.first_failing_segment) == (a.valid, a.reason, a.first_failing_segment)
        assert not b.valid or b.min_clearance >= got.safety_margin
        outcomes[b.valid] += 1
        queries[0] += a.exact_queries + a.hull_queries
        queries[1] += b.exact_queries + b.hull_queries
    return queries[0], queries[1]


@pytest.mark.parametrize("world", [panda_shelf, maru13])
def test_the_kernels_gjk_certifies_like_coal_with_fewer_coal_queries(world, monkeypatch):
    """Pairs of primitives (Maru-1) are measured by GJK in the row kernel, a robot mesh's hull (Panda) bounded
    there: the same verdicts as measuring every such row with coal, with far fewer coal queries."""
    from maru_planner.collision.certify import certifier as certifier_module

    robot, checker = world()
    spheres = load_or_fit_of(robot)
    kernel = PathCertifier(robot, checker, safety_margin=0.005, spheres=spheres)
    with monkeypatch.context() as patch:
        patch.setattr(certifier_module, "robot_shape_records", _no_shapes)
        coal_only = PathCertifier(robot, checker, safety_margin=0.005, spheres=spheres)
    by_coal, by_kernel = _coal_queries_of_two(robot, checker, coal_only, kernel, 17)
    assert by_kernel < 0.5 * by_coal, (by_coal, by_kernel)


@pytest.mark.parametrize("world", [panda_shelf, maru13])
def test_the_sphere_cover_certifies_like_the_bounding_spheres_with_fewer_coal_queries(world, monkeypatch):
    from maru_planner.collision.certify import certifier as certifier_module

    robot, checker = world()
    # coal measures what the bounds leave (not GJK)
    monkeypatch.setattr(certifier_module, "robot_shape_records", _no_shapes)
    with monkeypatch.context() as patch:
        patch.setattr(SphereCover, "of", lambda *_: None)
        plain = PathCertifier(robot, checker, safety_margin=0.005)
    covered = PathCertifier(robot, checker, safety_margin=0.005, spheres=load_or_fit_of(robot))
    assert covered._cover.covered.all()  # Panda: the model's spheres; Maru-1's cylinders and boxes: solid_balls
    by_plain, by_covered = _coal_queries_of_two(robot, checker, plain, covered, 13)
    assert by_covered < 0.6 * by_plain, (by_plain, by_covered)


def load_or_fit_of(robot: RobotModel):
    from maru_planner.collision.sphere_model import load_or_fit

    return load_or_fit(robot.model, robot.collision_model)


def _tip(q: np.ndarray) -> np.ndarray:
    """The toy arm's tip ball centre at joints ``q``."""
    return 0.3 * np.array([np.cos(q[0]), np.sin(q[0]), 0.0]) + 0.3 * np.array([np.cos(q[0] + q[1]),
                                                                                np.sin(q[0] + q[1]), 0.0])  # fmt: skip


def test_corner_blends_leave_out_only_the_ends_a_blend_replaces(arm):
    """A ball on the tip's corner configuration: the path fails there, but with its ends near the corner proven
    elsewhere (a trajectory's blend) the rest is certified; the ends left out never reach past a segment's middle
    of what is asked, and an obstacle on a segment's remaining part still fails it."""
    path = np.array([[-0.3, 0.0], [0.0, 0.4], [0.3, 0.0]])
    ball = Obstacle("ball", "sphere", radius=0.005, pose=list(_tip(path[1])))
    certifier = PathCertifier(arm, Scene([ball]), safety_margin=0.005)
    plain = certifier.certify_path(path)
    assert not plain.valid and plain.first_failing_segment == 0
    blended = certifier.certify_path(path, corner_blends=np.array([0.0, 0.15, 0.0]))
    assert blended.valid and len(blended.segment_clearance) == 2, blended
    assert not certifier.certify_path(path, corner_blends=np.array([0.0, 0.002, 0.0])).valid  # too short a blend
    middle = Obstacle("ball", "sphere", radius=0.005, pose=list(_tip(0.5 * (path[1] + path[2]))))
    on_segment = PathCertifier(arm, Scene([middle]), safety_margin=0.005)
    cert = on_segment.certify_path(path, corner_blends=np.array([0.0, 0.15, 0.0]))
    assert not cert.valid and cert.first_failing_segment == 1 and len(cert.segment_clearance) == 1


def test_a_segment_two_blends_take_whole_is_left_to_them(arm):
    """Blends meeting at a segment's middle leave nothing of it to prove: a ball on that middle does not fail it,
    and the point is not measured again (fewer configurations); the segments' own rests still are."""
    path = np.array([[-0.3, 0.0], [0.0, 0.4], [0.3, 0.0], [0.9, 0.0]])
    middle = 0.5 * (path[1] + path[2])
    ball = Obstacle("ball", "sphere", radius=0.005, pose=list(_tip(middle)))
    certifier = PathCertifier(arm, Scene([ball]), safety_margin=0.005)
    half = 0.5 * np.linalg.norm(path[2] - path[1])
    short = certifier.certify_path(path, corner_blends=np.array([0.0, 0.9 * half, 0.9 * half, 0.0]))
    assert not short.valid and short.first_failing_segment == 1  # a rest of the middle segment is left: it fails
    whole = certifier.certify_path(path, corner_blends=np.array([0.0, half, half, 0.0]))
    assert whole.valid and whole.segment_clearance[1] == np.inf, whole
    assert np.isfinite(whole.segment_clearance[0]) and np.isfinite(whole.segment_clearance[2])


def test_prove_curves_reports_each_certified_curve_s_clearance(arm):
    """A curve proven clear gets the smallest distance measured on it (at least the margin; here every pair is
    proven at once from the segment's middle, so at most the exact distance there); one that is not gets NaN, and
    certify_curves agrees on which is which."""
    ball = Obstacle("ball", "sphere", radius=0.005, pose=list(_tip(np.array([0.0, 0.4]))))
    certifier = PathCertifier(arm, Scene([ball]), safety_margin=0.005)
    clear = (np.array([[0.6, 0.0], [0.9, 0.2]]), np.zeros(2))
    hitting = (np.array([[-0.3, 0.0], [0.0, 0.4], [0.3, 0.0]]), np.zeros(2))
    certified, clearance = certifier.prove_curves([clear, hitting])
    assert certified.tolist() == [True, False] == certifier.certify_curves([clear, hitting])
    assert 0.005 <= clearance[0] <= certifier.clearance(clear[0].mean(axis=0)) and np.isnan(clearance[1])


def test_a_plan_s_min_clearance_includes_its_blends(arm, monkeypatch):
    """stats.min_clearance is the least distance measured on the certified path and on the blends its trajectory
    rounds corners with (these replace the path's corners: the robot moves there)."""
    measured = []
    real_curves, real_path = PathCertifier.prove_curves, PathCertifier.certify_path

    def curves(self, *args, **kwargs):
        certified, clearance = real_curves(self, *args, **kwargs)
        measured.extend(clearance[certified])
        return certified, clearance

    def path(self, *args, **kwargs):
        cert = real_path(self, *args, **kwargs)
        measured.append(cert.min_clearance)
        return cert

    monkeypatch.setattr(PathCertifier, "prove_curves", curves)
    monkeypatch.setattr(PathCertifier, "certify_path", path)
    planner = MotionPlanner.from_scene(arm, Scene([plate_at(0.0)]), PlannerConfig(safety_margin=0.005))
    result = planner.plan(MotionRequest("all", start={"j1": -0.6, "j2": 0.0}, goal_joints={"j1": 0.6, "j2": 0.0},
                                        planner_id="RRTConnect", time_budget=10.0, seed=3))  # fmt: skip
    assert result.success and result.stats.certified, result.message
    assert np.count_nonzero(result.corner_blends) and measured
    assert result.stats.min_clearance == min(measured) >= 0.005


def test_a_curve_certified_with_its_blends_is_not_certified_again(arm, monkeypatch):
    """toppra's blends and the straight parts between them proven in one pass: the path's certification is skipped,
    the plan still certified, and the trajectory's curve proven (chords plus their error bound); ruckig's curve is
    not made of those parts, so its path is certified as before."""
    import maru_planner.collision.certify as certify_module

    calls = []
    real = certify_module.certify_and_repair
    monkeypatch.setattr(certify_module, "certify_and_repair", lambda *a, **k: calls.append(1) or real(*a, **k))
    planner = MotionPlanner.from_scene(arm, Scene([plate_at(0.0)]), PlannerConfig(safety_margin=0.005))
    request = MotionRequest("all", start={"j1": -0.6, "j2": 0.0}, goal_joints={"j1": 0.6, "j2": 0.0},
                            planner_id="RRTConnect", time_budget=10.0, seed=3)  # fmt: skip
    result = planner.plan(request)
    assert result.success and result.stats.certified and result.curve_certified and not calls, result.message
    assert np.count_nonzero(result.corner_blends) and 0.005 <= result.stats.min_clearance < np.inf
    traj = result.trajectory
    acceleration = np.asarray(arm.acceleration_limits, dtype=float)
    assert planner.certifier.certify_path(traj.positions, margin=0.005,
                                          deviation=chord_deviation(traj.times, acceleration)).valid  # fmt: skip
    ruckig = planner.plan(dataclasses.replace(request, time_parameterization="ruckig"))
    assert ruckig.success and ruckig.stats.certified and not ruckig.curve_certified and calls == [1]


def test_without_corners_clips_each_end_to_its_segment():
    path = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 0.5], [3.0, 0.5]])
    ends = without_corners(path, np.array([0.0, 0.3, 2.0, 0.0]))
    np.testing.assert_allclose(ends, [[0.0, 0.0], [0.7, 0.0], [1.0, 0.3], [1.0, 0.3], [3.0, 0.5], [3.0, 0.5]])


def test_certify_and_repair_certifies_all_of_a_repaired_path_again(arm):
    """A repair changes the corners next to it, so the blends the first certification left out are not trusted."""
    path = np.array([[-0.3, 0.0], [0.0, 0.4], [0.3, 0.0], [0.9, 0.0]])
    ball = Obstacle("ball", "sphere", radius=0.005, pose=list(_tip(0.5 * (path[2] + path[3]))))
    certifier = PathCertifier(arm, Scene([ball]), safety_margin=0.005)
    seen = []
    real = certifier.certify_path

    def recording(points, *args, **kwargs):
        seen.append(kwargs.get("corner_blends"))
        return real(points, *args, **kwargs)

    certifier.certify_path = recording
    detour = np.array([[0.3, 0.0], [0.3, -1.2], [0.9, -1.2], [0.9, 0.0]])  # the elbow bent: the tip passes inside
    repaired = certify_and_repair(certifier, path, lambda *_: detour, deadline=np.inf,
                                  corner_blends=np.array([0.0, 0.1, 0.1, 0.0]))  # fmt: skip
    assert repaired.path is not None and repaired.repairs == 1
    assert seen[0] is not None and seen[-1] is None


def test_set_scene_builds_the_pair_table_so_requests_do_not(arm, monkeypatch):
    planner = MotionPlanner.from_scene(arm, Scene(), PlannerConfig(safety_margin=0.005))
    planner.set_scene(Scene([plate_at(1.5)]))

    def rebuilt(*_args):
        raise AssertionError("pair table built inside the request")

    monkeypatch.setattr(PathCertifier, "_build_pairs", rebuilt)
    result = planner.plan(MotionRequest("all", start={"j1": 0.0, "j2": 0.0}, goal_joints={"j1": 0.5, "j2": 0.2},
                                        planner_id="RRTConnect", time_budget=10.0, seed=1))  # fmt: skip
    assert result.success and result.stats.certified, result.message


# table_pick/0032's first path (CompiledRRTConnect, seed 0) and the blends its trajectory rounds two corners with
TABLE_PICK_0032_PATH = [
    [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785, 0.065, 0.065],
    [
        -0.35946044465145166,
        -0.6516321081095878,
        -0.30144916186321,
        -1.8822532858921375,
        -0.4544217041821061,
        1.8227246946624673,
        0.26747778724679117,
        0.065,
        0.065,
    ],
    [
        -0.22843466933248938,
        -0.273506451403041,
        -0.6690281795492115,
        -1.6589918485712294,
        -1.0990985186794773,
        2.0200455117376017,
        0.7150819989148978,
        0.065,
        0.065,
    ],
    [
        -0.09740889401352706,
        0.10461920530350594,
        -1.0366071972352129,
        -1.4357304112503213,
        -1.7437753331768486,
        2.2173663288127363,
        1.1626862105830045,
        0.065,
        0.065,
    ],
    [
        0.03361688130543525,
        0.48274486201005284,
        -1.4041862149212143,
        -1.2124689739294132,
        -2.38845214767422,
        2.4146871458878705,
        1.6102904222511114,
        0.065,
        0.065,
    ],
    [
        0.13262647159495106,
        0.768475408212371,
        -1.68194719631223,
        -1.0437615315748063,
        -2.875602001335856,
        2.5637925658454517,
        1.948522418980287,
        0.065,
        0.065,
    ],
    [
        -0.1054362293336927,
        1.076964073326781,
        -1.033834373191109,
        -1.08025009533616,
        -2.8973,
        2.925467589995654,
        1.40492365067501,
        0.065,
        0.065,
    ],
]
TABLE_PICK_0032_BLENDS = [0.0, 1.0, 0.0, 0.0, 0.0, 0.49257368626932035, 0.0]


@needs_mbm
def test_a_cover_bound_touching_the_margin_goes_to_coal_instead_of_splitting_forever():
    """On this path a sphere-cover bound tends to the margin from above at one point: every piece's middle proved
    less than its piece, so splitting on the cover went on down to 1e-9 rad and failed "unproven". A cover bound
    proving under 1/16 of its piece is measured by coal (the exact distance there is larger)."""
    problem = mbm_problem("table_pick/0032")
    planner = MotionPlanner.from_scene(mbm_panda(), problem.scene, PlannerConfig(collision_model="spheres"))
    cert = planner.certifier.certify_path(np.array(TABLE_PICK_0032_PATH), margin=0.01,
                                          corner_blends=np.array(TABLE_PICK_0032_BLENDS))  # fmt: skip
    assert cert.valid, (cert.reason, cert.first_failing_segment)
    assert cert.exact_queries + cert.hull_queries > 0


def test_a_hull_bound_proving_too_little_of_its_piece_is_measured_on_the_mesh(monkeypatch):
    """A hull distance just above the margin is only split on when it proves enough of the piece: one touching the
    margin at a point would be split on without end (as the cover's was), so the mesh decides."""
    robot = load_example_robot("panda")
    certifier = PathCertifier(robot, Scene([Obstacle("box", "box", size=(0.1, 0.1, 0.1), pose=[0.5, 0.0, 0.3])]))
    pairs = certifier._pair_table()
    row_pair = int(np.flatnonzero(pairs.has_hull & pairs.obstacle)[0])
    hull, mesh = {}, 0.05

    def distance(_pairs, _pair, on_hull, _placed):
        return hull["value"] if on_hull else mesh

    monkeypatch.setattr(certifier, "_distance", distance)
    margin, need = np.array([0.01]), np.array([0.01 + 0.016])  # the piece needs 16 mm more than the margin
    for hull_value, measured_on_mesh in ((0.0105, True), (0.0125, False), (0.009, True)):
        hull["value"], bound = hull_value, np.array([0.0])
        cert = Certificate(valid=True, margin=0.01)
        rows, one = np.array([row_pair]), np.ones(1, dtype=bool)
        exact = certifier._refine(robot.neutral()[None], pairs, np.zeros(1, dtype=int), rows, one, ~one, margin,
                                  bound, need, cert)  # fmt: skip
        assert exact[0] == measured_on_mesh, hull_value
        assert bound[0] == (mesh if measured_on_mesh else hull_value)
    # a row whose hull the row kernel bounded already goes to the mesh at once
    hull["value"], bound = 1.0, np.array([0.0105])
    exact = certifier._refine(robot.neutral()[None], pairs, np.zeros(1, dtype=int), np.array([row_pair]),
                              np.ones(1, dtype=bool), np.ones(1, dtype=bool), margin, bound, need, cert)  # fmt: skip
    assert exact[0] and bound[0] == mesh

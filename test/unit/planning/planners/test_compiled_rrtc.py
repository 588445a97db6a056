"""CompiledRRTConnect: the numba RRT-Connect kernel agrees with the sphere checker, is deterministic, solves the
paper problems through the facade with certified paths, and falls back to OMPL on other checkers."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import mbm_problem, needs_mbm, panda_clutter
from ompl import base as ob
from ompl import geometric as og

from maru_planner.collision import CollisionChecker
from maru_planner.collision.kernels import edge_validity, state_validity
from maru_planner.collision.kernels.bisection import bisection_order
from maru_planner.collision.kernels.edge_validity import bisection_order_into, edge_buffers
from maru_planner.collision.kernels.packing import unpack_robot, unpack_scene
from maru_planner.collision.kernels.primitives import AMBIGUOUS, COLLIDING, VALID
from maru_planner.collision.kernels.sphere_scan import scan_nb
from maru_planner.collision.spheres import SphereCollisionChecker, verify_path
from maru_planner.planning import PLANNERS, MotionPlanner, MotionRequest, PlannerConfig, PlanStatus
from maru_planner.planning.pipeline import Pipeline
from maru_planner.planning.planners.compiled_rrtc import CompiledRRTConnect
from maru_planner.planning.planners.kernels import rrtc as kernel
from maru_planner.planning.problems import PROBLEMS
from maru_planner.planning.space import EdgeChecker, GroupSpace
from maru_planner.robot import RobotModel
from maru_planner.robot.robots.panda import mbm_panda
from maru_planner.scene import Obstacle, Scene

ARM = [f"panda_joint{i}" for i in range(1, 8)]
RESOLUTION = 0.05


@pytest.fixture(scope="module", autouse=True)
def compiled_kernel(panda):
    """numba compiles the kernel on its first call after a change: do that outside the requests' time budgets."""
    gs = arm_space(panda)
    ss = og.SimpleSetup(gs.space)
    ss.setPlanner(CompiledRRTConnect(ss.getSpaceInformation(), EdgeChecker(gs, SphereCollisionChecker(panda), 0.05)))
    ss.setStateValidityChecker(lambda _state: True)
    start = gs.base[gs.indices]
    ss.setStartAndGoalStates(gs.to_state(start), gs.to_state(0.9 * start + 0.05 * (gs.lower + gs.upper)))
    ss.solve(ob.timedPlannerTerminationCondition(60.0))


def arm_space(robot) -> GroupSpace:
    indices = robot.joint_indices(ARM)
    return GroupSpace(ARM, indices, robot.lower_limits[indices], robot.upper_limits[indices], robot.neutral())


def kernel_edge(checker, gs: GroupSpace, qa, qb, exact_near: float = np.inf) -> tuple[int, np.ndarray]:
    """(VALID | COLLIDING | AMBIGUOUS, the ambiguous states) of the kernel's check of qa → qb, ambiguous states
    within ``exact_near`` of qa left to the exact model."""
    st = edge_validity.new_counters()
    amb_states = np.empty((int(np.ceil(np.abs(qb - qa).max() / RESOLUTION)) + 1, gs.dim))
    status = edge_validity.check_edge(np.asarray(qa, float), np.asarray(qb, float), RESOLUTION, gs.base,
                                      gs.indices.astype(np.int64), *checker.kernel_inputs(), checker.confirm,
                                      amb_states, st, np.array([qa, qa], dtype=float), exact_near)  # fmt: skip
    return int(status), amb_states[: st[edge_validity.N_AMB]]


def random_edges(gs: GroupSpace, n: int, seed: int) -> list[tuple[np.ndarray, np.ndarray]]:
    """Edges from random states, half of them short (a few states), half up to 1.5 rad long."""
    rng = np.random.default_rng(seed)
    edges = []
    for i in range(n):
        qa = rng.uniform(gs.lower, gs.upper)
        length = 0.12 if i % 2 else 1.5
        edges.append((qa, np.clip(qa + rng.uniform(-length, length, gs.dim), gs.lower, gs.upper)))
    return edges


# --- the kernel agrees with the sphere checker ---------------------------------------------
@pytest.mark.parametrize("grid", [False, True], ids=["classify", "grid"])
def test_edge_answers_equal_the_pure_sphere_model(panda, grid):
    """Both of the kernel's edge checks: its own classify per state, and the checker's grid scan (large scenes)."""
    checker = SphereCollisionChecker(panda, panda_clutter(1), confirm=False, grid_min_obstacles=1 if grid else 10**6)
    assert checker.uses_grid == grid
    gs = arm_space(panda)
    edges = EdgeChecker(gs, checker, RESOLUTION)
    answers = [kernel_edge(checker, gs, qa, qb)[0] for qa, qb in random_edges(gs, 120, 2)]
    expected = [edges.edge_valid(qa, qb) for qa, qb in random_edges(gs, 120, 2)]
    assert [a == VALID for a in answers] == expected
    assert AMBIGUOUS not in answers and 20 < sum(expected) < 100  # both kinds of edge were tested


def test_single_states_equal_the_sphere_checker(panda):
    checker = SphereCollisionChecker(panda, panda_clutter(3), confirm=False)
    gs = arm_space(panda)
    rng = np.random.default_rng(4)
    states = rng.uniform(gs.lower, gs.upper, (150, gs.dim))
    short = [kernel_edge(checker, gs, q - 0.5 * RESOLUTION, q)[0] == VALID for q in states]  # one state: q
    assert short == checker.are_valid(gs.full(states)).tolist()


def test_with_confirmation_ambiguous_edges_get_the_checkers_exact_answer(panda):
    checker = SphereCollisionChecker(panda, panda_clutter(5))  # confirm=True: near contacts decided by coal
    gs = arm_space(panda)
    edges = EdgeChecker(gs, checker, RESOLUTION)
    seen = set()
    for qa, qb in random_edges(gs, 160, 6):
        status, ambiguous = kernel_edge(checker, gs, qa, qb)
        seen.add(status)
        if status == AMBIGUOUS:
            valid = checker.first_invalid(gs.full(ambiguous)) < 0
        else:
            valid = status == VALID
        assert valid == edges.edge_valid(qa, qb)
    assert seen == {VALID, COLLIDING, AMBIGUOUS}


def test_away_from_the_start_and_goal_ambiguous_states_collide(panda):
    """exact_near 0: only the roots themselves are decided exactly, so the answers are the pure sphere model's."""
    confirmed = SphereCollisionChecker(panda, panda_clutter(5))
    pure = EdgeChecker(arm_space(panda), SphereCollisionChecker(panda, panda_clutter(5), confirm=False), RESOLUTION)
    gs = arm_space(panda)
    for qa, qb in random_edges(gs, 80, 6):
        status = kernel_edge(confirmed, gs, qa, qb, exact_near=0.0)[0]
        assert status != AMBIGUOUS and (status == VALID) == pure.edge_valid(qa, qb)


@pytest.mark.parametrize("robot_name", ["panda", "maru1"])
def test_classify_answers_each_state_like_the_sphere_checker(robot_name, request):
    """VALID / COLLIDING / AMBIGUOUS of every state equal the checker's own scan of it (classify_state), with
    AMBIGUOUS as COLLIDING when the first touch decides, and the numpy path's answers on the pure sphere model."""
    robot = request.getfixturevalue(robot_name)
    checker = SphereCollisionChecker(robot, panda_clutter(9), confirm=False)
    ri, rf, sf, grid_i, grid_f, amb, mark, _shapes = checker.kernel_inputs()
    assert not checker.uses_grid  # classify is the grid-less path
    robot_arrays, scene_arrays = unpack_robot(ri, rf), unpack_scene(sf)
    work = state_validity.work_arrays(robot_arrays, scene_arrays)
    rng = np.random.default_rng(10)
    states = np.array([robot.random_configuration(rng) for _ in range(2000)])
    expected = [scan_nb(q[None], 0, ri, rf, sf, grid_i, grid_f, amb, mark, True)[1] for q in states]
    answers = [state_validity.classify(q, robot_arrays, scene_arrays, work, False) for q in states]
    assert answers == expected
    first_touch = [state_validity.classify(q, robot_arrays, scene_arrays, work, True) for q in states]
    assert first_touch == [VALID if e == VALID else COLLIDING for e in expected]
    numpy_path = SphereCollisionChecker(robot, panda_clutter(9), confirm=False, use_numba=False)  # slow: fewer states
    assert numpy_path.are_valid(states[:150]).tolist() == [e == VALID for e in expected[:150]]
    assert set(expected) == {VALID, COLLIDING, AMBIGUOUS}


@pytest.mark.parametrize(("robot_name", "grid"), [("maru1", False), ("maru1", True), ("panda", False)])
def test_near_contacts_on_primitives_are_cleared_in_the_kernel_only_where_coal_clears_them(robot_name, grid, request):
    """On states the spheres leave in doubt, GJK on the robot's boxes, spheres and cylinders (whole scan, or the
    scan's listed pairs with the grid) clears only states the exact model calls valid: most of them on Maru-1 (all
    primitives), fewer on the Panda (its fingers are boxes; its meshes are left to coal)."""
    robot = request.getfixturevalue(robot_name)
    checker = SphereCollisionChecker(robot, panda_clutter(9), grid_min_obstacles=1 if grid else 10**9)
    assert checker.uses_grid == grid
    ri, rf, sf, grid_i, grid_f, amb, mark, shapes = checker.kernel_inputs()
    robot_arrays, scene_arrays = unpack_robot(ri, rf), unpack_scene(sf)
    work = state_validity.work_arrays(robot_arrays, scene_arrays)
    rng = np.random.default_rng(4)
    in_doubt = valid = cleared = 0
    for _ in range(6000):
        q = robot.random_configuration(rng)
        _row, status, n_pairs = scan_nb(q[None], 0, ri, rf, sf, grid_i, grid_f, amb, mark, True)
        if status != AMBIGUOUS:
            continue
        listed = state_validity.pairs_clear_on_shapes(q, amb[:n_pairs].copy(), robot_arrays, scene_arrays, work, shapes)
        clear = listed if grid else state_validity.clear_on_shapes(q, robot_arrays, scene_arrays, work, shapes)
        assert clear == listed
        exact_valid = checker.first_invalid(q[None]) < 0
        assert exact_valid or not clear
        in_doubt, valid, cleared = in_doubt + 1, valid + exact_valid, cleared + clear
    assert in_doubt > 50 and valid > 20, (in_doubt, valid)
    if robot_name == "maru1":
        assert cleared >= 0.8 * valid, (valid, cleared)
    else:
        assert cleared < 0.8 * valid, (valid, cleared)


def test_edge_states_are_checked_in_bisection_order():
    for n in (1, 2, 3, 7, 64, 100):
        order, queue = edge_buffers(n)
        bisection_order_into(n, order, queue, False)  # compiled, as the edge kernels order their states
        assert np.array_equal(order, bisection_order(n, include_first=False))


# --- through the facade ----------------------------------------------------------------------
def paper_request(robot: RobotModel, name: str, seed: int = 0, **kw) -> MotionRequest:
    problem = PROBLEMS[name]
    names = robot.groups[problem.group]
    rest = {**dict(zip(robot.joint_names, robot.neutral(), strict=True)), **robot.named_states.get("home", {})}
    start = {**rest, **problem.start_dict(names)}
    return MotionRequest(problem.group, start=start, goal_joints=problem.goal_dict(names),
                         planner_id="CompiledRRTConnect", time_budget=kw.pop("time_budget", 10.0), seed=seed,
                         **kw)  # fmt: skip


def full_path(robot: RobotModel, request: MotionRequest, path: np.ndarray) -> np.ndarray:
    """The result's group path as full configurations (the other joints at their start values)."""
    start = np.array([request.start[n] for n in robot.joint_names])
    out = np.repeat(start[None], len(path), axis=0)
    out[:, [robot.joint_names.index(n) for n in robot.groups[request.group]]] = path
    return out


@pytest.mark.parametrize("name", ["maru6", "maru13"])
def test_solves_the_paper_problems_on_spheres_with_certified_paths(maru1, name):
    scene = Scene.from_yaml(PROBLEMS[name].scene_path)
    planner = MotionPlanner.from_scene(maru1, scene, PlannerConfig(collision_model="spheres"))
    request = paper_request(maru1, name)
    res = planner.plan(request)
    assert res.status is PlanStatus.SUCCESS, res.message
    assert res.stats.certified and res.stats.nodes >= 2 and res.stats.collision_checks > 0
    assert verify_path(CollisionChecker(maru1, scene), full_path(maru1, request, res.path), 0.005).valid


def test_same_seed_same_path_and_the_seed_parameter_decides(maru1):
    scene = Scene.from_yaml(PROBLEMS["maru13"].scene_path)

    def plan(seed: int, params: dict | None = None) -> np.ndarray:
        config = PlannerConfig(collision_model="spheres", planner_params={"CompiledRRTConnect": params or {}})
        res = MotionPlanner.from_scene(maru1, scene, config).plan(paper_request(maru1, "maru13", seed, simplify=False))
        assert res.success, res.message
        return res.path

    assert np.array_equal(plan(3), plan(3))
    assert np.array_equal(plan(3, {"seed": 11}), plan(4, {"seed": 11}))


def test_a_goal_inside_an_obstacle_ends_at_the_termination_condition(panda):
    """No edge can reach the goal: the kernel keeps returning to check the time, the trees stay readable."""
    gs = arm_space(panda)
    start = gs.base[gs.indices]
    goal = np.clip(start + 0.8, gs.lower, gs.upper)
    hand = panda.frame_pose(gs.full(goal), "panda_hand")[:3, 3]
    checker = SphereCollisionChecker(panda, Scene([Obstacle("ball", "sphere", radius=0.1, pose=hand)]))
    assert checker.is_valid(gs.full(start)) and not checker.is_valid(gs.full(goal))
    ss = og.SimpleSetup(gs.space)
    planner = CompiledRRTConnect(ss.getSpaceInformation(), EdgeChecker(gs, checker, RESOLUTION))
    ss.setStartAndGoalStates(gs.to_state(start), gs.to_state(goal))
    ss.setStateValidityChecker(lambda _state: True)  # let OMPL pass the goal on to the planner
    ss.setPlanner(planner)
    ss.solve(ob.timedPlannerTerminationCondition(0.3))
    assert not ss.haveSolutionPath()
    nodes, edges = planner.graph_size()
    assert nodes > 2 and edges == nodes - 2
    data = ob.PlannerData(ss.getSpaceInformation())
    planner.getPlannerData(data)
    assert (data.numVertices(), data.numEdges()) == (nodes, edges)


def test_on_the_exact_checker_it_falls_back_to_ompl_rrtconnect(maru1, panda):
    scene = Scene.from_yaml(PROBLEMS["maru13"].scene_path)
    planner = MotionPlanner.from_scene(maru1, scene, PlannerConfig(collision_model="exact"))
    res = planner.plan(paper_request(maru1, "maru13", simplify=False))
    assert res.success, res.message
    assert res.stats.planner_id == "CompiledRRTConnect" and res.stats.nodes > 2
    gs = arm_space(panda)
    si = og.SimpleSetup(gs.space).getSpaceInformation()
    assert not CompiledRRTConnect(si, EdgeChecker(gs, CollisionChecker(panda), RESOLUTION)).compiled
    assert CompiledRRTConnect(si, EdgeChecker(gs, SphereCollisionChecker(panda), RESOLUTION)).compiled
    assert "CompiledRRTConnect" in PLANNERS and PLANNERS["CompiledRRTConnect"].has("tree")


# --- balanced trees and dynamic domains (VAMP's RRTCSettings) --------------------------------
def test_a_failed_extension_gives_its_node_a_dynamic_domain_that_shrinks_and_grows():
    tune = kernel.tuning(True, 4.0, 0.1, 3.5)
    radius = np.full((2, 4), np.inf)
    kernel.update_domain(radius, 1, 0, True, tune)
    assert radius[1, 0] == np.inf  # a success leaves an unbounded domain unbounded
    kernel.update_domain(radius, 1, 0, False, tune)
    assert radius[1, 0] == 4.0
    kernel.update_domain(radius, 1, 0, False, tune)
    assert radius[1, 0] == pytest.approx(3.6)
    kernel.update_domain(radius, 1, 0, False, tune)
    assert radius[1, 0] == 3.5  # not below the smallest domain
    kernel.update_domain(radius, 1, 0, True, tune)
    assert radius[1, 0] == pytest.approx(3.85)
    off = np.full((2, 4), np.inf)
    kernel.update_domain(off, 1, 0, False, kernel.tuning(True, 0.0, 0.1, 3.5))
    assert off[1, 0] == np.inf


def test_extensions_sample_inside_the_dynamic_domain_of_their_nearest_node():
    lower, upper = np.full(3, -np.pi), np.full(3, np.pi)
    nodes, parent, radius, st = kernel.new_state(np.zeros(3), np.full(3, 2.0), 8)
    radius[0, 0] = 0.3
    st[kernel.PHASE], st[kernel.TREE] = kernel.EXTEND, 0
    rng, q_new = kernel.seed_rng(5), np.empty(3)
    proposed = []
    for _ in range(20_000):
        if kernel.propose(nodes, radius, st, q_new, lower, upper, rng, 1.0):
            proposed.append(np.linalg.norm(q_new))
            assert st[kernel.REACHED]
    # a sample lands in the ball of 0.3 rad with probability 4.6e-4: the others are rejected, without an edge
    assert 0 < len(proposed) < 30 and max(proposed) <= 0.3
    radius[0, 0] = np.inf
    far = [np.linalg.norm(q_new) for _ in range(50)
           if kernel.propose(nodes, radius, st, q_new, lower, upper, rng, 1.0)]  # fmt: skip
    assert len(far) == 50 and max(far) == pytest.approx(1.0)  # unbounded: every sample, steered to full range


def test_balancing_extends_the_smaller_tree_until_the_other_has_less_than_twice_its_nodes():
    st = np.zeros(len(kernel.STATE_FIELDS), dtype=np.int64)
    st[kernel.N0], st[kernel.N1] = 2, 1
    balanced, alternating = kernel.tuning(True, 0.0, 0.0, 0.0), kernel.tuning(False, 0.0, 0.0, 0.0)
    assert kernel.next_extension(st, 1, balanced) == 1  # the goal's tree stays stuck at one node: it goes on
    assert kernel.next_extension(st, 1, alternating) == 0
    assert kernel.next_extension(st, 0, balanced) == 1
    st[kernel.N0] = 1
    assert kernel.next_extension(st, 1, balanced) == 0


@needs_mbm
def test_certification_repairs_search_with_the_kernel_on_padded_spheres(monkeypatch):
    """cage/0073: the search's last edge into a goal ~13 mm from the bars passes closer than the 10 mm margin.

    Its repair must search like the request did (the kernel on the padded sphere checker): OMPL's RRTConnect on
    the exact checker spent the whole budget on that narrow approach and failed the request.
    """
    robot = mbm_panda()
    problem = mbm_problem("cage/0073")
    config = PlannerConfig(collision_model="spheres", verify_resolution=0.025, safety_margin=0.01)
    planner = MotionPlanner.from_scene(robot, problem.scene, config)
    searches = []
    run = Pipeline.run

    def recording_run(self, context, request, monitor, t0):
        searches.append((request.planner_id, type(context.checker).__name__, getattr(context.checker, "padding", 0.0)))
        return run(self, context, request, monitor, t0)

    monkeypatch.setattr(Pipeline, "run", recording_run)
    goal = {k: v for k, v in problem.request.goal.items() if k in ARM}
    res = planner.plan(MotionRequest("arm", start=problem.request.start, goal_joints=goal, seed=0, simplify=False,
                                     planner_id="CompiledRRTConnect", time_budget=10.0))  # fmt: skip
    assert res.success and res.stats.certified, res.message
    assert res.stats.repairs >= 1 and len(searches) == 1 + res.stats.repairs
    for planner_id, checker, padding in searches[1:]:
        assert (planner_id, checker) == ("CompiledRRTConnect", "SphereCollisionChecker") and padding > 0.01

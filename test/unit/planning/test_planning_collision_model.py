"""PlannerConfig.collision_model: planning on the sphere checker through the facade and the CLI, every
returned path verified on the exact model; a checker that lies is caught and never reported as success."""

from __future__ import annotations

import json

import numpy as np
import pytest
from planning_toys import BoxWorldChecker, ToyRobot, maze_checker

from maru_planner.collision import CollisionChecker, SphereCollisionChecker, verify_path
from maru_planner.planning import MotionPlanner, MotionRequest, PlannerConfig, PlanStatus
from maru_planner.planning.checkers import make_checkers
from maru_planner.planning.cli import main
from maru_planner.planning.problems import PROBLEMS

FINE = 0.002  # rad: the test's own exact re-check, finer than the planner's (resolution / 4 = 0.005)


@pytest.fixture(scope="module")
def maru():
    from maru_planner.robot import RobotModel

    return RobotModel.maru1()


@pytest.fixture(scope="module")
def maru13(maru):
    from maru_planner.scene import Scene

    prob = PROBLEMS["maru13"]
    names = maru.groups[prob.group]
    start = dict(maru.named_states["home"])
    start.update(prob.start_dict(names))
    return Scene.from_yaml(prob.scene_path), start, prob.goal_dict(names)


def full_path(robot, start: dict, joint_names, path) -> np.ndarray:
    q = np.array([start[n] for n in robot.joint_names])
    out = np.repeat(q[None], len(path), axis=0)
    out[:, robot.joint_indices(list(joint_names))] = np.asarray(path)
    return out


def test_config_rejects_an_unknown_collision_model():
    with pytest.raises(ValueError, match="collision_model"):
        PlannerConfig(collision_model="octomap")
    with pytest.raises(ValueError, match="verify_resolution"):
        PlannerConfig(verify_resolution=0.0)
    assert PlannerConfig(resolution=0.02).verify_step == pytest.approx(0.005)


def test_make_checkers_pairs_the_sphere_checker_with_an_exact_one(maru, maru13):
    scene = maru13[0]
    exact = make_checkers(maru, scene, "exact")
    assert isinstance(exact.checker, CollisionChecker) and exact.exact is None
    fast = make_checkers(maru, scene, "spheres")
    assert isinstance(fast.checker, SphereCollisionChecker) and isinstance(fast.exact, CollisionChecker)
    assert fast.checker.scene is scene and fast.exact.scene is scene
    with pytest.raises(ValueError, match="collision model"):
        make_checkers(maru, scene, "boxes")


@pytest.mark.parametrize("seed", [1, 2])
def test_maru13_on_spheres_returns_a_path_free_on_the_exact_model(maru, maru13, seed):
    scene, start, goal = maru13
    planner = MotionPlanner.from_scene(maru, scene, PlannerConfig(collision_model="spheres"))
    assert isinstance(planner.checker, SphereCollisionChecker)
    res = planner.plan(MotionRequest("upper_body", start=start, goal_joints=goal, time_budget=20.0, seed=seed))
    assert res.success, res.message
    assert res.stats.collision_model == "spheres" and res.stats.verified
    assert res.verification.valid and res.verification.states_checked > len(res.path)
    assert res.stats.verify_time > 0
    assert verify_path(CollisionChecker(maru, scene), full_path(maru, start, res.joint_names, res.path), FINE).valid


def test_a_planner_given_a_sphere_checker_verifies_by_itself(maru, maru13):
    scene, start, goal = maru13
    planner = MotionPlanner(maru, SphereCollisionChecker(maru, scene))  # the pre-existing call shape
    assert isinstance(planner.exact_checker, CollisionChecker)
    res = planner.plan(MotionRequest("upper_body", start=start, goal_joints=goal, time_budget=20.0, seed=3))
    assert res.success and res.stats.verified, res.message


def test_exact_model_plans_are_not_reverified(maru, maru13):
    scene, start, goal = maru13
    planner = MotionPlanner.from_scene(maru, scene, PlannerConfig(collision_model="exact"))
    assert isinstance(planner.checker, CollisionChecker) and planner.exact_checker is None
    res = planner.plan(MotionRequest("upper_body", start=start, goal_joints=goal, time_budget=20.0, seed=1))
    assert res.success and res.stats.collision_model == "exact"
    assert res.stats.planner_id == "CompiledRRTConnect"  # the default id, run as OMPL's RRTConnect on this checker
    assert not res.stats.verified and res.verification is None and res.stats.verify_time == 0
    assert res.stats.certified


def test_the_default_is_compiled_rrtc_on_spheres_verified_on_the_exact_model(maru, maru13):
    config = PlannerConfig()
    assert (config.collision_model, config.default_planner) == ("spheres", "CompiledRRTConnect")
    scene, start, goal = maru13
    assert isinstance(make_checkers(maru, scene).checker, SphereCollisionChecker)
    planner = MotionPlanner.from_scene(maru, scene)
    assert isinstance(planner.checker, SphereCollisionChecker) and isinstance(planner.exact_checker, CollisionChecker)
    res = planner.plan(MotionRequest("upper_body", start=start, goal_joints=goal, time_budget=20.0, seed=1))
    assert res.success, res.message
    assert (res.stats.planner_id, res.stats.collision_model) == ("CompiledRRTConnect", "spheres")
    assert res.stats.verified and res.stats.certified
    assert verify_path(CollisionChecker(maru, scene), full_path(maru, start, res.joint_names, res.path), FINE).valid


def test_cli_plans_maru13_on_spheres(maru, maru13, tmp_path):
    out = tmp_path / "plan.json"
    code = main(["--problem", "maru13", "--collision-model", "spheres", "--seed", "4", "--time", "20",
                 "--json", str(out)])  # fmt: skip
    data = json.loads(out.read_text())
    assert code == 0 and data["success"], data["message"]
    assert data["stats"]["collision_model"] == "spheres" and data["stats"]["verified"]
    scene, start, _goal = maru13
    path = full_path(maru, start, data["joint_names"], data["path"])
    assert verify_path(CollisionChecker(maru, scene), path, FINE).valid


def test_cli_defaults_to_compiled_rrtc_on_spheres_and_plans_on_the_exact_model_when_asked(tmp_path):
    for extra, expected in (
        ([], ("CompiledRRTConnect", "spheres")),
        (["--collision-model", "exact", "--planner", "RRTConnect"], ("RRTConnect", "exact")),
    ):
        out = tmp_path / "plan.json"
        assert main(["--problem", "maru13", "--seed", "2", "--time", "20", "--json", str(out), "--quiet", *extra]) == 0
        stats = json.loads(out.read_text())["stats"]
        assert (stats["planner_id"], stats["collision_model"]) == expected
        assert stats["certified"] and stats["verified"] == (expected[1] == "spheres")


def test_cli_rejects_an_unknown_collision_model(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["--problem", "maru13", "--collision-model", "voxels"])
    assert exc.value.code == 2
    assert "--collision-model" in capsys.readouterr().err


# --- verification failing: a checker that lies -------------------------------------------------
class BlindChecker(BoxWorldChecker):
    """Sees no walls: every edge through the maze's walls is (wrongly) called free."""

    def __init__(self):
        super().__init__([])


def toy_request(**kw):
    return MotionRequest("all", start={"j0": 0.05, "j1": 0.05}, goal_joints={"j0": 0.95, "j1": 0.95},
                         planner_id="RRTConnect", time_budget=3.0, seed=1, **kw)  # fmt: skip


@pytest.mark.parametrize("refinements", [0, 2])
def test_a_path_failing_verification_is_replanned_then_never_returned_as_success(refinements):
    exact = maze_checker()
    config = PlannerConfig(resolution=0.01, max_refinements=refinements)
    res = MotionPlanner(ToyRobot(2), BlindChecker(), config, exact_checker=exact).plan(toy_request())
    assert res.status is PlanStatus.PLANNING_FAILED
    assert "failed verification on the exact model" in res.message
    assert res.path is None and res.trajectory is None
    assert not res.stats.verified and res.stats.replans == refinements
    assert res.verification is not None and not res.verification.valid
    assert exact.check_count > 0


def test_a_path_failing_verification_is_replanned_and_the_replan_returned():
    """The planning checker lies (sees no walls) until the first exact re-check has caught it."""

    class LiesUntilCaught(BoxWorldChecker):
        honest = False

        def _hits(self, Q):
            return super()._hits(Q) if self.honest else np.zeros(len(np.atleast_2d(Q)), dtype=bool)

    liar = LiesUntilCaught(maze_checker().boxes)

    class Exact(BoxWorldChecker):
        def first_invalid(self, Q):
            liar.honest = True
            return super().first_invalid(Q)

    exact = Exact(liar.boxes)
    config = PlannerConfig(resolution=0.01, max_refinements=2)
    res = MotionPlanner(ToyRobot(2), liar, config, exact_checker=exact).plan(toy_request())
    assert res.success, res.message
    assert res.stats.replans == 1 and res.stats.verified and res.verification.valid
    assert verify_path(exact, np.asarray(res.path), 0.001).valid

"""Planning on the sphere checker with verification on the exact model (plan_verified)."""

from __future__ import annotations

import numpy as np
import pytest

from maru_planner.collision import CollisionChecker
from maru_planner.collision.spheres import SphereCollisionChecker, verify_path
from maru_planner.planning import MotionPlanner, MotionRequest, PlannerConfig
from maru_planner.planning.verified import full_path, plan_verified
from maru_planner.robot import load_example_robot
from maru_planner.scene import Obstacle, Scene

ARM = [f"panda_joint{i}" for i in range(1, 8)]


@pytest.fixture(scope="module")
def panda():
    return load_example_robot("panda")


def _problem(panda):
    """Swing joint 1 by 2 rad; a thin plate stands where the hand passes half-way."""
    start = panda.named_state("default")
    goal = start.copy()
    goal[0] += 2.0
    mid = start.copy()
    mid[0] += 1.0
    hand = panda.frame_pose(mid, "panda_hand")[:3, 3]
    plate = np.eye(4)
    plate[:3, 3] = hand
    theta = np.arctan2(hand[1], hand[0])  # plate across the hand's (tangential) path: thin along the tangent
    plate[:3, :3] = np.array([[np.cos(theta), -np.sin(theta), 0], [np.sin(theta), np.cos(theta), 0], [0, 0, 1]])
    scene = Scene([Obstacle("plate", "box", size=(0.12, 0.01, 0.12), pose=plate)])
    names = panda.joint_names
    request = MotionRequest(
        "arm",
        start=dict(zip(names, start)),
        goal_joints={n: goal[i] for i, n in enumerate(names) if n in ARM},
        planner_id="RRTConnect",
        time_budget=10.0,
        seed=1,
        simplify=False,
    )
    return scene, request


def test_coarse_plan_fails_verification_and_is_refined(panda):
    scene, request = _problem(panda)
    fast, exact = SphereCollisionChecker(panda, scene), CollisionChecker(panda, scene)
    # At resolution 2.5 an edge checks its end state only and may step over the plate; with no re-plan
    # allowed, the facade's exact re-check must turn such a path into a failure. Some seeds' coarse
    # paths miss the plate by luck, so take the first seed whose path crosses it.
    config = PlannerConfig(resolution=2.5, verify_resolution=0.01, max_refinements=0)
    for seed in range(40):
        request.seed = seed
        first = MotionPlanner(panda, fast, config, exact_checker=exact).plan(request)
        if not first.success:
            break
    else:
        pytest.fail("no seed in 40 gave a coarse path that crosses the plate")
    assert first.path is None
    assert "failed verification on the exact model" in first.message
    assert first.verification is not None and not first.verification.valid
    assert first.stats.replans == 0 and not first.stats.verified
    out = plan_verified(MotionPlanner(panda, fast, config), exact, request, resolution=0.01, max_refinements=5)
    assert out.fallback_used and out.result.stats.replans >= 1
    assert out.success and out.verification.valid and out.result.stats.verified
    assert verify_path(exact, full_path(panda, request, out.result), 0.005).valid


def test_verified_plan_on_a_free_problem_needs_no_fallback(panda):
    scene, request = _problem(panda)
    scene.remove("plate")
    planner = MotionPlanner(panda, SphereCollisionChecker(panda, scene), PlannerConfig(resolution=0.05))
    out = plan_verified(planner, CollisionChecker(panda, scene), request)
    assert out.success and not out.fallback_used
    assert out.verification.valid and out.verification.states_checked > 2
    path = full_path(panda, request, out.result)
    np.testing.assert_allclose(path[0], panda.named_state("default"))
    assert path.shape[1] == panda.nq

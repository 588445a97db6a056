"""Core state queries: forward kinematics, state validity (collisions, clearance, constraints), planner listing."""

from __future__ import annotations

import math

import numpy as np
import pytest

from maru_planner import errors
from maru_planner.collision import CollisionChecker
from maru_planner.planning.constraints import OrientationConstraint, PathConstraints, PositionConstraint
from maru_planner.planning.links import link_names
from maru_planner.planning.planners.registry import PLANNERS
from maru_planner.planning.queries import check_state_validity, compute_fk, query_planners
from maru_planner.robot import RobotModel
from maru_planner.scene import Obstacle, Scene


@pytest.fixture(scope="module")
def robot():
    return RobotModel.maru1()


def test_fk_matches_the_model_and_defaults_to_every_link(robot):
    q = robot.random_configuration(np.random.default_rng(1))
    poses = compute_fk(robot, q, ["r_hand", "l_hand"])
    assert np.allclose(poses["r_hand"], robot.frame_pose(q, "r_hand"))
    assert np.allclose(poses["l_hand"], robot.frame_pose(q, "l_hand"))
    every = compute_fk(robot, q)
    assert list(every) == link_names(robot) and "torso" in every


def test_fk_rejects_unknown_links_and_bad_states(robot):
    with pytest.raises(errors.InvalidLink, match="no_link"):
        compute_fk(robot, robot.neutral(), ["no_link"])
    with pytest.raises(errors.InvalidState):
        compute_fk(robot, np.full(robot.nq, np.nan))


def test_validity_reports_colliding_pairs_and_clearance(robot):
    q = np.array((-0.9, 0.25, 1.75, 1.66, 1.9, 0.0, -2.55, -0.8, 1.57, 2.0, 0.7, -1.9, -1.25))  # free
    hand = robot.frame_pose(q, "r_hand")[:3, 3]
    free = check_state_validity(robot, CollisionChecker(robot, Scene()), q)
    assert free.valid and free.colliding_pairs == [] and free.clearance > 0 and all(free.closest_pair)
    scene = Scene([Obstacle("ball", "sphere", radius=0.05, pose=hand)])
    hit = check_state_validity(robot, CollisionChecker(robot, scene), q)
    assert not hit.valid and hit.clearance <= 0
    assert any("ball" in pair for pair in hit.colliding_pairs)


def test_validity_measures_constraint_violations(robot):
    q = robot.neutral()
    pose = robot.frame_pose(q, "r_hand")
    tilted = pose[:3, :3] @ np.array([[1, 0, 0], [0, math.cos(0.3), -math.sin(0.3)], [0, math.sin(0.3), math.cos(0.3)]])
    upright = OrientationConstraint("r_hand", tilted, np.array([0.1, 0.1, math.pi]))
    box = PositionConstraint("r_hand", np.eye(4), np.array([0.1, 0.1, 0.1]))
    answer = check_state_validity(robot, CollisionChecker(robot, Scene()), q, PathConstraints(upright, box))
    assert not answer.valid
    assert answer.orientation_violation == pytest.approx(0.2, abs=1e-6)
    local = np.abs(pose[:3, 3])
    assert answer.position_violation == pytest.approx(np.linalg.norm(np.maximum(local - 0.05, 0)), abs=1e-9)


def test_query_planners_lists_the_registry_with_current_values():
    described = {p.id: p for p in query_planners({"RCRRT": {"step": 0.2}})}
    assert list(described) == list(PLANNERS)
    assert "path_constraints" in described["CBiRRT"].capabilities
    assert [i for i in PLANNERS if "path_constraints" in described[i].capabilities] == ["CBiRRT"]
    for planner_id, spec in PLANNERS.items():
        entry = described[planner_id].as_dict()
        assert entry["description"] == spec.description
        assert set(entry["capabilities"]) == set(spec.capabilities)
        assert [p["name"] for p in entry["parameters"]] == list(spec.params)
        for parameter in entry["parameters"]:
            declared = spec.params[parameter["name"]]
            assert parameter["default"] == declared.default
            assert parameter["lower"] == (-math.inf if declared.lower is None else declared.lower)
    rcrrt = {p["name"]: p for p in described["RCRRT"].as_dict()["parameters"]}
    assert rcrrt["step"]["current"] == 0.2

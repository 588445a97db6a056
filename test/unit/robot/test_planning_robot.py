"""Planning on the real Maru-1 model and the paper's scenes (pinocchio + coal checker), and the CLI."""

from __future__ import annotations

import json

import numpy as np
import pytest

from maru_planner.planning import MotionPlanner, MotionRequest, PlannerConfig, PlanStatus
from maru_planner.planning.cli import main
from maru_planner.planning.problems import PROBLEMS
from maru_planner.planning.space import EdgeChecker, GroupSpace


@pytest.fixture(scope="module")
def maru():
    from maru_planner.robot import RobotModel

    return RobotModel.maru1()


def setup_problem(robot, name):
    from maru_planner.collision import CollisionChecker
    from maru_planner.scene import Scene

    prob = PROBLEMS[name]
    checker = CollisionChecker(robot, Scene.from_yaml(prob.scene_path))
    names = robot.groups[prob.group]
    start = dict(robot.named_states["home"])
    start.update(prob.start_dict(names))
    return prob, checker, start, prob.goal_dict(names)


def full(robot, values):
    return np.array([values[n] for n in robot.joint_names])


@pytest.mark.parametrize("name, planner_id", [("maru13", "RRTConnect"), ("maru6", "RRTConnect"), ("maru13", "RCRRT")])
def test_paper_problems_are_solved_collision_free_within_limits(maru, name, planner_id):
    prob, checker, start, goal = setup_problem(maru, name)
    mp = MotionPlanner(maru, checker, PlannerConfig())
    res = mp.plan(
        MotionRequest(group=prob.group, start=start, goal_joints=goal, planner_id=planner_id, time_budget=20.0, seed=3)
    )
    assert res.status is PlanStatus.SUCCESS, res.message
    assert res.joint_names == maru.groups[prob.group]
    assert np.allclose(res.path[0], prob.start) and np.allclose(res.path[-1], prob.goal)
    idx = maru.group_joint_indices(prob.group)
    gs = GroupSpace(res.joint_names, idx, maru.lower_limits[idx], maru.upper_limits[idx], full(maru, start))
    assert EdgeChecker(gs, checker, 0.02).path_valid(res.path)
    traj = res.trajectory
    assert np.all(np.abs(traj.velocities) <= maru.velocity_limits[idx] + 1e-9)
    assert np.all(np.abs(traj.accelerations) <= maru.acceleration_limits[idx] + 1e-9)
    assert np.all(traj.positions >= maru.lower_limits[idx] - 1e-9)
    assert np.all(traj.positions <= maru.upper_limits[idx] + 1e-9)


def test_pose_goal_uses_ik_and_reaches_the_hands(maru):
    prob, checker, start, goal = setup_problem(maru, "maru13")
    q_goal = full(maru, {**start, **goal})
    poses = {f: maru.frame_pose(q_goal, f) for f in ("r_hand", "l_hand")}
    mp = MotionPlanner(maru, checker, PlannerConfig())
    res = mp.plan(MotionRequest(group="upper_body", start=start, goal_poses=poses, time_budget=20.0, seed=1))
    assert res.success, res.message
    assert res.stats.ik_time > 0
    q_end = full(maru, start)
    q_end[maru.group_joint_indices("upper_body")] = res.path[-1]
    for frame, pose in poses.items():
        assert np.allclose(maru.frame_pose(q_end, frame)[:3, 3], pose[:3, 3], atol=1e-4)


def test_unreachable_pose_reports_no_ik_solution(maru):
    prob, checker, start, goal = setup_problem(maru, "maru6")
    far = np.eye(4)
    far[:3, 3] = [3.0, 0.0, 0.0]
    mp = MotionPlanner(maru, checker, PlannerConfig())
    res = mp.plan(MotionRequest(group="right_arm", start=start, goal_poses={"r_hand": far}, time_budget=3.0))
    assert res.status is PlanStatus.NO_IK_SOLUTION, res.message


def test_start_in_collision_names_the_pair(maru):
    prob, checker, start, goal = setup_problem(maru, "maru13")
    rng = np.random.default_rng(0)
    idx = maru.group_joint_indices("upper_body")
    for _ in range(1000):
        q = full(maru, start)
        q[idx] = rng.uniform(maru.lower_limits[idx], maru.upper_limits[idx])
        if not checker.is_valid(q):
            break
    bad = dict(zip(maru.joint_names, q.tolist(), strict=True))
    mp = MotionPlanner(maru, checker, PlannerConfig())
    res = mp.plan(MotionRequest(group="upper_body", start=bad, goal_joints=goal, time_budget=2.0))
    assert res.status is PlanStatus.START_IN_COLLISION
    a, b = res.error.pairs[0]
    assert a in res.message and b in res.message


def test_cli_problem_json_and_png(tmp_path):
    out, png = tmp_path / "out.json", tmp_path / "out.png"
    code = main(
        [
            "--problem",
            "maru6",
            "--planner",
            "RRTConnect",
            "--time",
            "10",
            "--seed",
            "3",
            "--json",
            str(out),
            "--png",
            str(png),
        ]
    )
    assert code == 0
    data = json.loads(out.read_text())
    assert set(data) == {"success", "status", "message", "joint_names", "path", "trajectory", "stats", "seed"}
    assert data["success"] and data["status"] == "SUCCESS" and data["seed"] == 3
    assert len(data["joint_names"]) == 6 and all(len(row) == 6 for row in data["path"])
    assert np.allclose(data["path"][0], PROBLEMS["maru6"].start) and np.allclose(
        data["path"][-1], PROBLEMS["maru6"].goal
    )
    assert {"times", "positions", "velocities", "accelerations"} <= set(data["trajectory"])
    assert data["stats"]["planner_id"] == "RRTConnect" and data["stats"]["collision_checks"] > 0
    assert png.stat().st_size > 10_000


def test_cli_rejects_a_wrong_joint_count(tmp_path):
    out = tmp_path / "bad.json"
    code = main(["--problem", "maru13", "--start", "0.1", "0.2", "--json", str(out)])
    data = json.loads(out.read_text())
    assert code == 2 and data["status"] == "INVALID_JOINT_COUNT" and "13 joints" in data["message"]
    code = main(["--problem", "maru13", "--planner", "Dijkstra", "--json", str(out)])
    assert code == 2 and json.loads(out.read_text())["status"] == "INVALID_PLANNER"

"""``maru-plan``: plan one arm motion from the command line and write JSON (+ a picture).

Examples::

    maru-plan --problem maru13 --planner RCRRT --time 10 --seed 3 --json out.json --png out.png
    maru-plan --robot maru1 --scene config/scenes/maru13_desk_box.yaml --group upper_body \\
        --start -0.9 -0.7 1.57 0.7 0.7 -0.9 -0.9 -0.8 1.57 2.0 0.7 -1.9 -1.25 \\
        --goal 0.9 -0.8 1.57 1.14 0.7 -1.24 -1.9 -0.7 1.57 2.44 0.7 -2.24 -1.25 --planner RRTConnect
    maru-plan --robot panda --group arm --start ... --goal ...     # example-robot-data robots
    maru-plan --problem maru13 --collision-model spheres --seed 1  # fast sphere checker, exact-verified path

``--start``/``--goal`` values follow the group's joint order (``--list-groups`` prints it).
Exit status: 0 on success, 1 when planning failed (the JSON says why), 2 for bad arguments.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

from maru_planner import errors
from maru_planner.planning.config import COLLISION_MODELS, PlannerConfig
from maru_planner.planning.problems import PROBLEMS
from maru_planner.planning.registry import planner_ids
from maru_planner.planning.types import MotionRequest, MotionResult, PlanStatus, status_of_error


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="maru-plan",
        description="Plan an arm motion with OMPL (RRT, RRTConnect, PRM, GoalBiasedRRT, RCRRT) "
        "and write the path, trajectory and stats as JSON.",
    )
    p.add_argument("--problem", choices=sorted(PROBLEMS), help="paper 000 problem: robot, scene, group, start, goal")
    p.add_argument("--robot", default=None, help="maru1 (default) or an example-robot-data name (panda, ur5, ...)")
    p.add_argument("--scene", default=None, help="scene YAML (obstacles); default: none, or the problem's scene")
    p.add_argument("--group", default=None, help="planning group (e.g. upper_body, right_arm)")
    p.add_argument("--start", type=float, nargs="+", help="start values in the group's joint order")
    p.add_argument("--goal", type=float, nargs="+", help="goal values in the group's joint order")
    p.add_argument("--planner", default="RRTConnect", help=f"one of {', '.join(planner_ids())}")
    p.add_argument("--time", type=float, default=5.0, help="time budget in seconds (IK + search + post-processing)")
    p.add_argument("--seed", type=int, default=None, help="random seed (same seed, same path); default random")
    p.add_argument("--attempts", type=int, default=1)
    p.add_argument("--resolution", type=float, default=PlannerConfig.resolution, help="motion-check step (rad)")
    p.add_argument(
        "--collision-model",
        choices=COLLISION_MODELS,
        default="exact",
        help="exact: pinocchio + coal; spheres: batched sphere checker, the path then verified on the exact model",
    )
    p.add_argument("--velocity-scaling", type=float, default=1.0)
    p.add_argument("--acceleration-scaling", type=float, default=1.0)
    p.add_argument("--no-simplify", action="store_true", help="keep the raw planner path")
    p.add_argument("--json", type=Path, default=None, help="write the result JSON here (default: stdout)")
    p.add_argument("--png", type=Path, default=None, help="draw the hand traces over the scene (two views)")
    p.add_argument("--list-groups", action="store_true", help="print the robot's groups and joints, then exit")
    return p


def load_robot(name: str):
    from maru_planner.robot import RobotModel, load_example_robot

    return RobotModel.maru1() if name == "maru1" else load_example_robot(name)


def load_scene(path: str | None):
    from maru_planner.scene import Scene

    if not path or path == "none":
        return Scene()
    return Scene.from_yaml(path)


def _progress(msg: str) -> None:
    print(f"[maru-plan] {msg}", file=sys.stderr, flush=True)


def _fill_from_problem(args) -> None:
    prob = PROBLEMS[args.problem]
    args.robot = args.robot or prob.robot
    args.group = args.group or prob.group
    args.scene = args.scene or str(prob.scene_path)
    args.start = args.start or list(prob.start)
    args.goal = args.goal or list(prob.goal)


def _values(robot, group: str, values, what: str) -> dict[str, float]:
    names = list(robot.groups.get(group, [])) if hasattr(robot, "groups") else []
    if not names:
        robot.group_joint_indices(group)  # raises InvalidGroup with the known groups
    if values is None:
        if what == "start":
            raise errors.NoStartState("no --start given")
        raise errors.InvalidRequest("no --goal given")
    if len(values) != len(names):
        raise errors.InvalidJointCount(
            f"--{what} has {len(values)} value(s) but group {group} has {len(names)} joints: {', '.join(names)}"
        )
    return dict(zip(names, values, strict=True))


def _rest_state(robot) -> dict[str, float]:
    """Joints outside the group: the SRDF "home" state if there is one, else the model's neutral."""
    named = getattr(robot, "named_states", {}) or {}
    values = dict(zip(robot.joint_names, np.asarray(robot.neutral(), float).tolist(), strict=True))
    values.update(named.get("home", {}))
    return values


def run(args) -> MotionResult:
    from maru_planner.planning.motion_planner import MotionPlanner

    if args.problem:
        _fill_from_problem(args)
    args.robot = args.robot or "maru1"
    _progress(f"loading robot {args.robot}")
    robot = load_robot(args.robot)
    if args.list_groups:
        for group, joints in robot.groups.items():
            print(f"{group}: {' '.join(joints)}")
        raise SystemExit(0)
    if not args.group:
        raise errors.InvalidGroup(f"no --group given; known: {', '.join(robot.groups)}")
    scene = load_scene(args.scene)
    config = PlannerConfig(
        resolution=args.resolution, default_planner="RRTConnect", collision_model=args.collision_model
    )
    _progress(f"building the {args.collision_model} collision model")
    planner = MotionPlanner.from_scene(robot, scene, config)
    start = _values(robot, args.group, args.start, "start")
    rest = _rest_state(robot)
    request = MotionRequest(
        group=args.group,
        start={**{n: v for n, v in rest.items() if n not in start}, **start},
        goal_joints=_values(robot, args.group, args.goal, "goal"),
        planner_id=args.planner,
        time_budget=args.time,
        seed=args.seed,
        attempts=args.attempts,
        velocity_scaling=args.velocity_scaling,
        acceleration_scaling=args.acceleration_scaling,
        simplify=not args.no_simplify,
    )
    _progress(f"planning {args.group} with {args.planner} (budget {args.time:g} s)")
    t0 = time.monotonic()
    result = planner.plan(request)
    _progress(f"{result.status.value} in {time.monotonic() - t0:.3f} s: {result.message}")
    if args.collision_model == "spheres":
        _progress(
            f"exact re-check: {'free' if result.stats.verified else 'not passed'}, "
            f"{result.stats.verify_time:.3f} s, {result.stats.replans} re-plan(s)"
        )
    if args.png and result.success:
        from maru_planner.viz.plans import plot_plan

        base_q = np.array([request.start.get(n, 0.0) for n in robot.joint_names])
        plot_plan(robot, scene, result, args.png, title=f"{args.problem or args.group}: {args.planner}", base_q=base_q)
        _progress(f"picture written to {args.png}")
    return result


def main(argv=None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        result = run(args)
    except errors.MaruError as exc:
        result = MotionResult(status=status_of_error(exc), message=exc.message, error=exc)
    except (FileNotFoundError, ValueError, KeyError) as exc:
        result = MotionResult(status=PlanStatus.INVALID_REQUEST, message=f"{type(exc).__name__}: {exc}", error=exc)
    payload = json.dumps(result.to_json_dict(), indent=1, allow_nan=False, default=_json_default)
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(payload + "\n")
        _progress(f"result written to {args.json}")
    else:
        print(payload)
    if result.success:
        return 0
    return 1 if result.status in (PlanStatus.PLANNING_FAILED, PlanStatus.TIMED_OUT) else 2


def _json_default(value):
    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(f"not JSON serialisable: {type(value).__name__}")


if __name__ == "__main__":
    sys.exit(main())

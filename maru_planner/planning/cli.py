"""``maru-plan``: plan one arm motion from the command line and write JSON (+ a picture).

Examples::

    maru-plan --problem maru13 --planner RCRRT --seed 3 --json demo_output/plan.json --png demo_output/plan.png
    maru-plan --robot maru1 --scene config/scenes/maru13_desk_box.yaml --group upper_body \\
        --start -0.9 -0.7 1.57 0.7 0.7 -0.9 -0.9 -0.8 1.57 2.0 0.7 -1.9 -1.25 \\
        --goal 0.9 -0.8 1.57 1.14 0.7 -1.24 -1.9 -0.7 1.57 2.44 0.7 -2.24 -1.25 --planner RRTConnect
    maru-plan --robot panda --group arm --start ... --goal ...     # example-robot-data robots
    maru-plan --robot my_arm.yaml --list-groups                    # your robot: a profile file (docs/your_robot.md)
    maru-plan --problem maru13 --collision-model exact --seed 1    # plan on pinocchio + coal instead of the spheres
    maru-plan --problem maru6 --planner RCRRT --param step=0.2     # a planner parameter

``--start``/``--goal`` values follow the group's joint order (``--list-groups`` prints it). The
planners, their parameters and the exit codes are listed by ``--help`` (from the planner registry).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from maru_planner import errors
from maru_planner.cli_parser import CliError, OneLineParser
from maru_planner.collision import sphere_model
from maru_planner.planning.cartesian import CartesianRequest, CartesianResult, default_link
from maru_planner.planning.config import COLLISION_MODELS, TIME_PARAMETERIZATIONS, PlannerConfig
from maru_planner.planning.links import check_link, link_names
from maru_planner.planning.motion_planner import MotionPlanner
from maru_planner.planning.planners.registry import PLANNERS, get_spec, merged_params
from maru_planner.planning.problems import PROBLEMS
from maru_planner.planning.requests import MAX_ATTEMPTS
from maru_planner.planning.types import MotionRequest, MotionResult, PlanStatus, status_of_error
from maru_planner.robot import RobotModel
from maru_planner.robot.profile_yaml import is_profile_file
from maru_planner.scene import Scene
from maru_planner.scene.planning_scene import DEFAULT_FRAME
from maru_planner.trajectory.limits import MIN_SCALING

PROG = "maru-plan"
EXIT_OK, EXIT_FAILED, EXIT_BAD_INPUT, EXIT_INTERNAL, EXIT_INTERRUPTED = 0, 1, 2, 3, 130
EXIT_CODES = f"""exit codes:
  {EXIT_OK}    a path was found
  {EXIT_FAILED}    planning failed or timed out (the JSON says why)
  {EXIT_BAD_INPUT}    bad input: an option, the robot, scene file, group, joints, planner or a parameter,
       or an output path that cannot be written (one line on stderr; the JSON too once planning started)
  {EXIT_INTERNAL}    internal error (a bug: one line on stderr)
  {EXIT_INTERRUPTED}  interrupted (Ctrl-C)"""


def _positive(text: str) -> float:
    value = float(text)
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"must be a finite number > 0, got {text!r}")
    return value


def _margin(text: str) -> float:
    value = float(text)
    if not (math.isfinite(value) and value >= 0):
        raise argparse.ArgumentTypeError(f"must be a finite number >= 0 (m), got {text!r}")
    return value


def _scaling(text: str) -> float:
    value = float(text)
    if not (math.isfinite(value) and MIN_SCALING <= value <= 1.0):
        raise argparse.ArgumentTypeError(f"must be in [{MIN_SCALING:g}, 1], got {text[:40]!r}")
    return value


def _attempts(text: str) -> int:
    value = int(text)
    if not 1 <= value <= MAX_ATTEMPTS:
        raise argparse.ArgumentTypeError(f"must be in [1, {MAX_ATTEMPTS}], got {text[:40]!r}")
    return value


def _seed(text: str) -> int:
    value = int(text)
    if not 0 <= value < 2**63:
        raise argparse.ArgumentTypeError(f"must be in [0, 2^63), got {text!r}")
    return value


def planners_help() -> str:
    """Every registered planner with its capabilities and parameters (the ``--help`` epilog)."""
    lines = ["planners (--planner ID; parameters as --param NAME=VALUE):"]
    for spec in PLANNERS.values():
        lines.append(f"  {spec.id}: {spec.description} [{', '.join(sorted(spec.capabilities))}]")
        for param in spec.params.values():
            lines.append(f"      {param.name} (default {param.default}): {param.describe()}")
    return "\n".join(lines)


def problems_help() -> str:
    return "problems (--problem NAME):\n" + "\n".join(f"  {p.name}: {p.description}" for p in PROBLEMS.values())


def build_parser() -> argparse.ArgumentParser:
    p = OneLineParser(
        prog=PROG,
        description="Plan an arm motion with OMPL and write the path, trajectory and stats as JSON.",
        epilog="\n\n".join([planners_help(), problems_help(), EXIT_CODES]),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("--problem", choices=sorted(PROBLEMS), help="paper 000 problem: robot, scene, group, start, goal")
    p.add_argument("--robot", default=None,
                   help="maru1 (default), an example-robot-data name (panda, ur5, tiago, talos) or a robot profile "
                   "file (.yaml, docs/your_robot.md)")  # fmt: skip
    p.add_argument("--robot-file", type=Path, default=None, metavar="FILE.yaml",
                   help="a robot profile file (URDF, SRDF, groups, limits...; docs/your_robot.md): "
                   "the same as --robot FILE")  # fmt: skip
    p.add_argument("--scene", default=None, help="scene YAML (obstacles); default: none, or the problem's scene")
    p.add_argument("--group", default=None, help="planning group (e.g. upper_body, right_arm)")
    p.add_argument("--start", type=float, nargs="+", help="start values in the group's joint order")
    p.add_argument("--goal", type=float, nargs="+", help="goal values in the group's joint order")
    p.add_argument("--planner", default=PlannerConfig.default_planner,
                   help=f"one of {', '.join(PLANNERS)} (see below); default: %(default)s")  # fmt: skip
    p.add_argument("--param", action="append", default=[], metavar="NAME=VALUE",
                   help="a parameter of the chosen planner (repeatable; see below)")  # fmt: skip
    p.add_argument("--time", "--max-time", dest="time", type=_positive, default=5.0,
                   help="time budget in seconds (IK + search + post-processing)")  # fmt: skip
    p.add_argument("--seed", type=_seed, default=None, help="random seed (same seed, same path); default random")
    p.add_argument("--attempts", type=_attempts, default=1, help=f"searches until one finds a path (1-{MAX_ATTEMPTS})")
    p.add_argument("--resolution", type=_positive, default=PlannerConfig.resolution, help="motion-check step (rad)")
    p.add_argument(
        "--collision-model",
        choices=COLLISION_MODELS,
        default=PlannerConfig.collision_model,
        help="spheres (default): batched sphere checker, near contacts decided and the path re-checked on the "
        "exact model; exact: pinocchio + coal throughout",
    )
    p.add_argument("--safety-margin", type=_margin, default=PlannerConfig.safety_margin,
                   help="clearance (m) the certified path keeps from obstacles and link pairs (see "
                   "docs/certification.md)")  # fmt: skip
    p.add_argument("--velocity-scaling", type=_scaling, default=1.0)
    p.add_argument("--acceleration-scaling", type=_scaling, default=1.0)
    p.add_argument(
        "--time-parameterization",
        choices=TIME_PARAMETERIZATIONS,
        default="",
        help="toppra: time-optimal through blended corners (default); ruckig: jerk-limited, blended; "
        "trapezoid: rest at every waypoint",
    )
    p.add_argument("--jerk-scaling", type=_scaling, default=1.0, help="scales the jerk limits (ruckig)")
    p.add_argument("--cartesian", type=float, nargs="+", metavar="DX DY DZ",
                   help="instead of --goal: a Cartesian path of --link through these offsets (m, root frame, "
                   "3 per waypoint) from its start position, orientation kept (docs/manipulation.md)")  # fmt: skip
    p.add_argument("--link", default="", help="--cartesian: the link moved (default: the group's end effector)")
    p.add_argument("--max-step", type=_positive, default=0.01, help="--cartesian: task-space step (m)")
    p.add_argument("--jump-threshold", type=_margin, default=0.0,
                   help="--cartesian: largest joint step as a multiple of the mean step (0: no test)")  # fmt: skip
    p.add_argument("--no-simplify", action="store_true", help="keep the raw planner path")
    p.add_argument("--json", type=Path, default=None, help="write the result JSON here (default: stdout)")
    p.add_argument("--png", type=Path, default=None, help="draw the hand traces over the scene (two views)")
    p.add_argument("--list-groups", action="store_true", help="print the robot's groups and joints, then exit")
    p.add_argument("--quiet", action="store_true", help="no progress on stderr")
    return p


# --- checks before anything is loaded ------------------------------------------------------
def planner_params(planner_id: str, assignments: list[str]) -> dict[str, Any]:
    """``--param NAME=VALUE`` strings as checked parameters of ``planner_id`` (InvalidRequest naming the culprit)."""
    spec = get_spec(planner_id)
    values: dict[str, Any] = {}
    for text in assignments:
        name, sep, raw = text.partition("=")
        if not sep:
            raise CliError(f"--param {text!r}: expected NAME=VALUE")
        param = spec.params.get(name)
        if param is None:
            raise CliError(f"--param: planner {planner_id} has no parameter {name!r}; known: {', '.join(spec.params)}")
        values[name] = _parse_value(raw, param.value_type, name)
    merged_params(planner_id, values)
    return values


def _parse_value(raw: str, kind: type, name: str) -> Any:
    if kind is bool:
        if raw.lower() not in ("true", "false"):
            raise CliError(f"--param {name}: expected true or false, got {raw!r}")
        return raw.lower() == "true"
    if kind in (int, float):
        try:
            return int(raw) if kind is int else float(raw)
        except ValueError:
            expected = "an integer" if kind is int else "a number"
            raise CliError(f"--param {name}: expected {expected}, got {raw!r}") from None
    return raw


def check_writable(path: Path, option: str) -> None:
    """CliError unless ``path`` can be created or replaced (its directory is created if missing)."""
    if path.is_dir():
        raise CliError(f"{option} {path}: is a directory")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise CliError(f"{option} {path}: cannot create its directory ({exc.strerror})") from None
    if not os.access(path.parent, os.W_OK) or (path.exists() and not os.access(path, os.W_OK)):
        raise CliError(f"{option} {path}: not writable")


# --- loading and planning ------------------------------------------------------------------
def load_robot(name: str) -> RobotModel:
    """A built-in robot by name, or the robot of a profile file (``.yaml``/``.yml``)."""
    return RobotModel.from_profile(name)


def robot_option(args: argparse.Namespace) -> str:
    """The robot of ``--robot`` / ``--robot-file`` (CliError when both name different robots)."""
    if args.robot_file is None:
        return str(args.robot or "")
    if not is_profile_file(args.robot_file):
        raise CliError(f"--robot-file {args.robot_file}: expected a .yaml or .yml robot profile")
    if args.robot and Path(args.robot) != args.robot_file:
        raise CliError(f"--robot {args.robot} and --robot-file {args.robot_file}: give one robot")
    return str(args.robot_file)


def check_scene_frame(scene: Scene, robot: RobotModel) -> None:
    """InvalidScene unless ``scene`` is in ``robot``'s root frame, where its obstacles are placed (no tf here).

    A scene that names no frame reads as base_link: that is taken as the root of a robot without a base_link.
    """
    root = link_names(robot)[0]
    if scene.frame == root or (scene.frame == DEFAULT_FRAME and not robot.model.existFrame(DEFAULT_FRAME)):
        return
    raise errors.InvalidScene(
        f"--scene: frame {scene.frame[:60]!r} is not the root frame {root!r} of {robot.name}; "
        "obstacles are placed in the root frame (no tf here)"
    )


def load_scene(path: str | None) -> Scene:
    if not path or path == "none":
        return Scene()
    file = Path(path)
    if file.is_file() and not file.read_text().strip():
        raise errors.InvalidScene(f"scene file {path} is empty (use --scene none for no obstacles)")
    return Scene.from_yaml(file)


class _Progress:
    def __init__(self, quiet: bool):
        self.quiet = quiet

    def __call__(self, msg: str) -> None:
        if not self.quiet:
            print(f"[{PROG}] {msg}", file=sys.stderr, flush=True)


def _fill_from_problem(args: argparse.Namespace) -> None:
    prob = PROBLEMS[args.problem]
    args.robot = args.robot or prob.robot
    args.group = args.group or prob.group
    args.scene = args.scene or str(prob.scene_path)
    args.start = args.start or list(prob.start)
    args.goal = args.goal or list(prob.goal)


def _values(robot: RobotModel, group: str, values: list[float] | None, what: str) -> dict[str, float]:
    names = list(robot.groups.get(group, []))
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


def _rest_state(robot: RobotModel) -> dict[str, float]:
    """Joints outside the group: the SRDF "home" state if there is one, else the model's neutral."""
    values = dict(zip(robot.joint_names, np.asarray(robot.neutral(), float).tolist(), strict=True))
    values.update(robot.named_states.get("home", {}))
    return values


def run(args: argparse.Namespace, params: dict[str, Any], progress: _Progress) -> MotionResult | CartesianResult:
    """Load robot and scene, plan (or a Cartesian path), draw; typed errors for bad robots, scenes, groups, joints."""
    progress(f"loading robot {args.robot}")
    robot = load_robot(args.robot)
    if args.list_groups:
        for group, joints in robot.groups.items():
            print(f"{group}: {' '.join(joints)}")
        raise SystemExit(EXIT_OK)
    if not args.group:
        raise errors.InvalidGroup(f"no --group given; known: {', '.join(robot.groups)}")
    start = _values(robot, args.group, args.start, "start")
    goal = _values(robot, args.group, args.goal, "goal") if args.cartesian is None else {}
    scene = load_scene(args.scene)
    check_scene_frame(scene, robot)
    config = PlannerConfig(
        resolution=args.resolution,
        collision_model=args.collision_model,
        planner_params={args.planner: params},
        safety_margin=args.safety_margin,
    )
    if args.collision_model == "spheres":
        notice = sphere_model.first_fit_notice(robot.name, robot.collision_model, robot.sphere_options)
        if notice:
            progress(notice)
    progress(f"building the {args.collision_model} collision model")
    planner = MotionPlanner.from_scene(robot, scene, config)
    rest = _rest_state(robot)
    if args.cartesian is not None:
        return _cartesian(args, planner, {**{n: v for n, v in rest.items() if n not in start}, **start}, progress)
    request = MotionRequest(
        group=args.group,
        start={**{n: v for n, v in rest.items() if n not in start}, **start},
        goal_joints=goal,
        planner_id=args.planner,
        time_budget=args.time,
        seed=args.seed,
        attempts=args.attempts,
        velocity_scaling=args.velocity_scaling,
        acceleration_scaling=args.acceleration_scaling,
        simplify=not args.no_simplify,
        time_parameterization=args.time_parameterization,
        jerk_scaling=args.jerk_scaling,
    )
    progress(f"planning {args.group} with {args.planner} (budget {args.time:g} s)")
    t0 = time.monotonic()
    result = planner.plan(request)
    progress(f"{result.status.value} in {time.monotonic() - t0:.3f} s: {result.message}")
    if args.collision_model == "spheres":
        progress(
            f"exact re-check: {'free' if result.stats.verified else 'not passed'}, "
            f"{result.stats.verify_time:.3f} s, {result.stats.replans} re-plan(s)"
        )
    if args.png and result.success:
        # lazy: matplotlib is only needed for --png
        from maru_planner.viz.plans import plot_plan

        base_q = np.array([request.start.get(n, 0.0) for n in robot.joint_names])  # type: ignore[union-attr]
        plot_plan(robot, scene, result, args.png, title=f"{args.problem or args.group}: {args.planner}", base_q=base_q)
        progress(f"picture written to {args.png}")
    return result


def _cartesian(args: argparse.Namespace, planner: MotionPlanner, start: dict[str, float], progress) -> CartesianResult:
    """The Cartesian path of ``--cartesian`` (offsets of the link from its start position)."""
    offsets = np.asarray(args.cartesian, dtype=float)
    if offsets.size % 3 or not np.all(np.isfinite(offsets)):
        raise CliError(f"--cartesian needs finite values, 3 per waypoint; got {offsets.size}")
    robot = planner.robot
    link = args.link or default_link(robot, args.group)
    check_link(robot, link, "--link")
    begin = robot.frame_pose(np.array([start[n] for n in robot.joint_names]), link)
    waypoints = []
    for offset in offsets.reshape(-1, 3):
        pose = begin.copy()
        pose[:3, 3] += offset
        waypoints.append(pose)
    request = CartesianRequest(
        args.group, start, waypoints, link=link, max_step=args.max_step, jump_threshold=args.jump_threshold,
        velocity_scaling=args.velocity_scaling, acceleration_scaling=args.acceleration_scaling,
        time_parameterization=args.time_parameterization, time_budget=args.time,
    )  # fmt: skip
    progress(f"Cartesian path of {link} through {len(waypoints)} waypoint(s)")
    result = planner.cartesian_path(request)
    progress(f"{result.status.value} in {result.seconds:.3f} s: {result.message}")
    return result


# --- entry point ---------------------------------------------------------------------------
def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        args.robot = robot_option(args)
    except CliError as exc:
        return _fail(EXIT_BAD_INPUT, exc)
    if args.problem:
        _fill_from_problem(args)
    args.robot = args.robot or "maru1"
    try:
        for option in ("json", "png"):
            if getattr(args, option):
                check_writable(getattr(args, option), f"--{option}")
    except CliError as exc:
        return _fail(EXIT_BAD_INPUT, exc)
    progress = _Progress(args.quiet)
    try:
        result = run(args, planner_params(args.planner, args.param), progress)
    except errors.MaruError as exc:
        result = MotionResult(status=status_of_error(exc), message=errors.one_line(exc), error=exc)
    except (OSError, ValueError) as exc:  # robot files that do not load, bad values inside them
        message = errors.one_line(f"{type(exc).__name__}: {exc}")
        result = MotionResult(status=PlanStatus.INVALID_REQUEST, message=message)
    except KeyboardInterrupt:
        print(f"{PROG}: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except Exception as exc:  # a bug: one line, never a traceback
        return _fail(EXIT_INTERNAL, exc, "internal error")
    try:
        _write_json(args, result, progress)
    except OSError as exc:
        return _fail(EXIT_BAD_INPUT, exc, f"--json {args.json}")
    if result.success:
        return EXIT_OK
    code = EXIT_FAILED if result.status in (PlanStatus.PLANNING_FAILED, PlanStatus.TIMED_OUT) else EXIT_BAD_INPUT
    print(f"{PROG}: {result.status.value}: {errors.one_line(result.message)}", file=sys.stderr)
    return code


def _write_json(args: argparse.Namespace, result: MotionResult | CartesianResult, progress: _Progress) -> None:
    payload = json.dumps(result.to_json_dict(), indent=1, allow_nan=False, default=_json_default)
    if args.json:
        args.json.write_text(payload + "\n")
        progress(f"result written to {args.json}")
    else:
        print(payload)


def _fail(code: int, exc: BaseException, what: str = "error") -> int:
    print(f"{PROG}: {what}: {errors.one_line(exc)}", file=sys.stderr)
    return code


def _json_default(value: object) -> object:
    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(f"not JSON serialisable: {type(value).__name__}")


if __name__ == "__main__":
    sys.exit(main())

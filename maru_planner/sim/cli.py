"""maru-reactive-sim: run the elastic strip in a simulated world and report the outcome.

    maru-reactive-sim --world config/worlds/goal_behind_obstacle.yaml --strip modified --seed 0 \\
        --json demo_output/strip.json --png demo_output/strip.png [--gif demo_output/strip.gif]
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

from maru_planner.cli_parser import CliError, OneLineParser
from maru_planner.errors import MaruError, one_line
from maru_planner.sim.runner import run_world
from maru_planner.sim.world import MAX_SIM_TIME, World

PROG = "maru-reactive-sim"
EXIT_OK, EXIT_BAD_INPUT, EXIT_INTERRUPTED = 0, 2, 130
EXIT_CODES = f"""exit codes:
  {EXIT_OK}    the run finished (whatever its outcome: goal, collision or timeout; see the JSON)
  {EXIT_BAD_INPUT}    bad input: an option, the world file (or its map), or an output path that cannot be written
  {EXIT_INTERRUPTED}  interrupted (Ctrl-C)"""


def build_parser() -> argparse.ArgumentParser:
    parser = OneLineParser(
        prog=PROG,
        description=__doc__.splitlines()[0],
        epilog=EXIT_CODES,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--world", required=True, help="world YAML (see docs/reactive.md)")
    parser.add_argument("--strip", choices=("modified", "plain"), default="modified")
    parser.add_argument("--seed", type=int, default=0, help="seeds start jitter, laser noise and mover timing (>= 0)")
    parser.add_argument("--json", help="write the result JSON here")
    parser.add_argument("--png", help="write a picture of the run here")
    parser.add_argument("--gif", help="write an animation of the run here")
    parser.add_argument(
        "--max-time",
        type=float,
        help=f"simulated seconds before a time-out, at most {MAX_SIM_TIME:g} (default: world's)",
    )
    parser.add_argument("--no-jitter", action="store_true", help="exact start pose and mover timing")
    parser.add_argument(
        "--continue-after-collision",
        action="store_true",
        help="count collisions (bumper stop) instead of ending the run at the first one",
    )
    parser.add_argument("--no-arm", action="store_true", help="skip the arm update (eq. 46-49)")
    parser.add_argument("--quiet", action="store_true", help="no progress on stderr")
    return parser


def check_arguments(args: argparse.Namespace) -> None:
    """CliError for values argparse's types let through (negative seed, NaN time) and unwritable outputs."""
    if args.seed < 0:
        raise CliError(f"--seed must be >= 0, got {args.seed}")
    if args.max_time is not None and not 0.0 < args.max_time <= MAX_SIM_TIME:
        raise CliError(f"--max-time must be in (0, {MAX_SIM_TIME:g}] s, got {args.max_time}")
    for option in ("json", "png", "gif"):
        if getattr(args, option):
            check_writable(Path(getattr(args, option)), f"--{option}")
    for option in ("png", "gif"):  # the picture writers pick their format by the suffix
        path = getattr(args, option)
        if path and Path(path).suffix.lower() != f".{option}":
            raise CliError(f"--{option} {path[:80]}: the file name must end in .{option}")


def check_writable(path: Path, option: str) -> None:
    """CliError unless ``path`` can be created or replaced (checked before the run, not after it)."""
    if path.is_dir():
        raise CliError(f"{option} {path}: is a directory")
    parent = path.parent
    if not parent.is_dir():
        raise CliError(f"{option} {path}: directory {parent} does not exist")
    if not os.access(parent, os.W_OK) or (path.exists() and not os.access(path, os.W_OK)):
        raise CliError(f"{option} {path}: not writable")


def run(args: argparse.Namespace) -> None:
    check_arguments(args)
    world = World.from_yaml(args.world)
    if not args.quiet:
        print(f"[{PROG}] {world.name}: strip={args.strip} seed={args.seed} ...", file=sys.stderr)
    want_frames = bool(args.png or args.gif)
    frame_every = max(1, int(world.robot.laser.rate // 2)) if want_frames else 0
    result = run_world(
        world,
        args.strip,
        seed=args.seed,
        jitter=not args.no_jitter,
        strip_every=frame_every,
        stop_on_collision=not args.continue_after_collision,
        max_time=args.max_time,
        arm_enabled=not args.no_arm,
    )
    payload = {"world": world.name, "strip": args.strip, "seed": args.seed, **result.to_json()}
    text = json.dumps(payload, indent=2)
    if args.json:
        Path(args.json).write_text(text + "\n")
    print(text)
    if want_frames:
        # lazy: matplotlib is loaded only when a picture is asked for (a heavy import)
        from maru_planner.viz.reactive import save_run_gif, save_run_picture

        if args.png:
            save_run_picture(args.png, world, {args.strip: result}, title=f"{world.name} ({args.strip})")
        if args.gif:
            save_run_gif(args.gif, world, result, robot_radius=world.robot.bounding_radius)
    if not args.quiet:
        print(f"[{PROG}] {result.outcome} after {result.updates} updates", file=sys.stderr)


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        run(args)
    except (MaruError, OSError) as exc:
        print(f"{PROG}: error: {one_line(exc)}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        print(f"{PROG}: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    return EXIT_OK


if __name__ == "__main__":
    raise SystemExit(main())

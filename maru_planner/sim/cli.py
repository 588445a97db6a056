"""maru-reactive-sim: run the elastic strip in a simulated world and report the outcome.

    maru-reactive-sim --world config/worlds/goal_behind_obstacle.yaml --strip modified --seed 0 \\
        --json out.json --png out.png [--gif out.gif]
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from maru_planner.errors import MaruError
from maru_planner.sim.runner import run_world
from maru_planner.sim.world import World


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="maru-reactive-sim", description=__doc__.splitlines()[0])
    parser.add_argument("--world", required=True, help="world YAML (see docs/reactive.md)")
    parser.add_argument("--strip", choices=("modified", "plain"), default="modified")
    parser.add_argument("--seed", type=int, default=0, help="seeds start jitter, laser noise and mover timing")
    parser.add_argument("--json", help="write the result JSON here")
    parser.add_argument("--png", help="write a picture of the run here")
    parser.add_argument("--gif", help="write an animation of the run here")
    parser.add_argument("--max-time", type=float, help="simulated seconds before a time-out (default: world's)")
    parser.add_argument("--no-jitter", action="store_true", help="exact start pose and mover timing")
    parser.add_argument("--continue-after-collision", action="store_true",
                        help="count collisions (bumper stop) instead of ending the run at the first one")
    parser.add_argument("--no-arm", action="store_true", help="skip the arm update (eq. 46-49)")
    parser.add_argument("--quiet", action="store_true", help="no progress on stderr")
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        world = World.from_yaml(args.world)
    except MaruError as exc:
        print(f"maru-reactive-sim: error: {exc}", file=sys.stderr)
        return 2
    if not args.quiet:
        print(f"[maru-reactive-sim] {world.name}: strip={args.strip} seed={args.seed} ...", file=sys.stderr)
    want_frames = bool(args.png or args.gif)
    frame_every = max(1, int(world.robot.laser.rate // 2)) if want_frames else 0
    result = run_world(world, args.strip, seed=args.seed, jitter=not args.no_jitter, strip_every=frame_every,
                       stop_on_collision=not args.continue_after_collision, max_time=args.max_time,
                       arm_enabled=not args.no_arm)
    payload = {"world": world.name, "strip": args.strip, "seed": args.seed, **result.to_json()}
    text = json.dumps(payload, indent=2)
    if args.json:
        Path(args.json).write_text(text + "\n")
    print(text)
    if args.png or args.gif:
        from maru_planner.viz.reactive import save_run_gif, save_run_picture

        if args.png:
            save_run_picture(args.png, world, {args.strip: result}, title=f"{world.name} ({args.strip})")
        if args.gif:
            save_run_gif(args.gif, world, result, robot_radius=world.robot.bounding_radius)
    if not args.quiet:
        print(f"[maru-reactive-sim] {result.outcome} after {result.updates} updates", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""``maru-base-plan``: plan a mobile-base path on a map_server map.

Example::

    maru-base-plan --map config/maps/paper002_medium.yaml --planner mspp \\
        --start 1 2 0 --goal 5 2 0 --footprint "0.45,0.15 -0.45,0.15 -0.45,-0.15 0.45,-0.15" \\
        --json out.json --png out.png

The footprint is one argument: polygon vertices ``x,y`` in metres (base_link)
separated by spaces or ``;`` (write ``--footprint=...`` if the first is negative), or
``rect:LENGTH:WIDTH``, or ``disc:RADIUS`` (a 16-gon). The JSON is
``{"success", "status", "message", "path": [[x, y, theta], ...], "stats"}``.
Exit code 0 when solved, 1 when no path / timed out, 2 on bad input.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time

import numpy as np

from maru_planner.base import registry
from maru_planner.base.grid import OccupancyGrid
from maru_planner.base.result import jsonable
from maru_planner.base.se2 import rectangle
from maru_planner.errors import MaruError


def parse_footprint(text: str) -> np.ndarray:
    tokens = text.replace(";", " ").split()
    if len(tokens) == 1 and tokens[0].startswith("rect:"):
        _, length, width = tokens[0].split(":")
        return rectangle(float(length), float(width))
    if len(tokens) == 1 and tokens[0].startswith("disc:"):
        radius = float(tokens[0].split(":")[1])
        angles = np.linspace(0.0, 2 * math.pi, 16, endpoint=False)
        # circumscribe the disc so that the polygon contains it
        r = radius / math.cos(math.pi / 16)
        return np.column_stack([r * np.cos(angles), r * np.sin(angles)])
    vertices = []
    for token in tokens:
        x, y = token.split(",")
        vertices.append((float(x), float(y)))
    return np.array(vertices)


def _params(pairs: list[str]) -> dict:
    params = {}
    for pair in pairs:
        key, _, value = pair.partition("=")
        try:
            params[key] = json.loads(value)
        except json.JSONDecodeError:
            params[key] = value
    return params


def result_to_json(result) -> dict:
    return {
        "success": bool(result.success),
        "status": result.status,
        "message": result.message,
        "path": result.path.tolist(),
        "stats": jsonable(result.stats),
    }


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="maru-base-plan", description=__doc__.split("\n")[0])
    parser.add_argument("--map", help="map_server YAML (not needed with --world)")
    parser.add_argument("--world", help="3-D world YAML for biped-track / biped-wall (start/goal default to its own)")
    parser.add_argument("--planner", default=registry.DEFAULT_PLANNER,
                        help=f"one of {', '.join(registry.planner_ids())}")
    parser.add_argument("--start", nargs=3, type=float, metavar=("X", "Y", "THETA"))
    parser.add_argument("--goal", nargs=3, type=float, metavar=("X", "Y", "THETA"))
    parser.add_argument("--footprint", default="rect:0.9:0.3",
                        help="'x,y x,y ...' vertices (use --footprint=... when the first is negative), "
                        "rect:L:W or disc:R (default rect:0.9:0.3)")
    parser.add_argument("--param", action="append", default=[], help="planner parameter key=value (JSON value)")
    parser.add_argument("--unknown-free", action="store_true", help="treat unknown cells as free")
    parser.add_argument("--json", help="write the result here")
    parser.add_argument("--png", help="write a picture here")
    return parser


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    args.planner = args.planner.replace("-", "_")  # biped-track == biped_track
    params, grid = _params(args.param), None
    try:
        footprint = parse_footprint(args.footprint)
        if args.world:
            from maru_planner.base.biped.planners import world_defaults

            args.start, args.goal, params["world"] = world_defaults(args.world, args.start, args.goal)
        if args.map:
            grid = OccupancyGrid.from_yaml(args.map, unknown_is_occupied=not args.unknown_free)
        elif not args.world:
            raise ValueError("--map is required (or --world with a biped planner)")
        if args.start is None or args.goal is None:
            raise ValueError("--start and --goal are required")
    except (OSError, ValueError) as exc:
        print(f"maru-base-plan: {exc}", file=sys.stderr)
        return 2
    where = f"{args.map} ({grid.width} x {grid.height} cells)" if grid is not None else args.world
    print(f"planning with {args.planner} on {where}...", file=sys.stderr)
    t0 = time.perf_counter()
    try:
        result = registry.plan(args.planner, grid, args.start, args.goal, footprint, **params)
    except MaruError as exc:
        print(f"maru-base-plan: {exc}", file=sys.stderr)
        return 2
    print(f"{result.status}: {result.message} ({time.perf_counter() - t0:.3f} s, "
          f"{len(result.path)} poses, stage {result.stats.get('deciding_stage', '')})", file=sys.stderr)
    if args.json:
        with open(args.json, "w") as f:
            json.dump(result_to_json(result), f, indent=1)
    if args.png and "world" in result.layers:
        from maru_planner.viz.biped import save_result_png

        save_result_png(args.png, result, args.planner)
    elif args.png:
        from maru_planner.viz.grids import save_plan_png

        save_plan_png(args.png, grid, result, args.start, args.goal, footprint,
                      f"{args.planner}: {result.status} ({result.stats.get('deciding_stage', '')})")
    if result.status == "invalid_request":
        return 2
    return 0 if result.success else 1


if __name__ == "__main__":
    sys.exit(main())

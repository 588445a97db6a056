"""``maru-base-plan``: plan a mobile-base path on a map_server map.

Example::

    maru-base-plan --map config/maps/paper002_medium.yaml --planner mspp \\
        --start 1 2 0 --goal 5 2 0 --footprint "0.45,0.15 -0.45,0.15 -0.45,-0.15 0.45,-0.15" \\
        --json demo_output/base.json --png demo_output/base.png   # demo_output/ must exist (mkdir -p)

The footprint is one argument: polygon vertices ``x,y`` in metres (base_link)
separated by spaces or ``;`` (write ``--footprint=...`` if the first is negative), or
``rect:LENGTH:WIDTH``, or ``disc:RADIUS`` (a 16-gon). The JSON is
``{"success", "status", "message", "path": [[x, y, theta], ...], "stats", "clearance": {"min_m", "mean_m"}}``:
the clearance is the path's exact distance to the nearest obstacle cell centre of the map it was planned
on (the minimum along the path and the mean over its length; null without a path).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path
from typing import NoReturn

import numpy as np

from maru_planner.base import registry
from maru_planner.base.biped.planners import world_defaults
from maru_planner.base.budget import DEFAULT_TIME_LIMIT
from maru_planner.base.clearance import path_clearance
from maru_planner.base.footprint import disc, rectangle
from maru_planner.base.grid import OccupancyGrid
from maru_planner.base.result import BasePlanResult, PlanStatus
from maru_planner.errors import InvalidRequest, MaruError, one_line

PROG = "maru-base-plan"
EXIT_SOLVED, EXIT_NO_PATH, EXIT_BAD_INPUT, EXIT_OUTPUT = 0, 1, 2, 3
EXIT_CODES = f"""exit codes:
  {EXIT_SOLVED}  solved
  {EXIT_NO_PATH}  no path (searched or proven), timed out, start or goal outside the map or in collision
  {EXIT_BAD_INPUT}  bad input: arguments, map/world file, footprint, planner parameter, a size limit
  {EXIT_OUTPUT}  the --json/--png output could not be written"""


class _Parser(argparse.ArgumentParser):
    """argparse with a one-line error (no usage dump) and the bad-input exit code."""

    def error(self, message: str) -> NoReturn:
        self.exit(EXIT_BAD_INPUT, f"{PROG}: {one_line(message)}\n")


def parse_footprint(text: str) -> np.ndarray:
    """``x,y x,y ...`` vertices, ``rect:L:W`` or ``disc:R``; InvalidRequest naming the bad part."""
    tokens = text.replace(";", " ").split()
    kind = tokens[0].split(":")[0] if len(tokens) == 1 and ":" in tokens[0] else "polygon"
    try:
        if kind == "rect":
            _, length, width = tokens[0].split(":")
            numbers = [float(length), float(width)]
        elif kind == "disc":
            _, radius = tokens[0].split(":")
            numbers = [float(radius)]
        else:
            numbers = [float(v) for token in tokens for v in _pair(token)]
    except ValueError:
        raise InvalidRequest(f"--footprint {text[:60]!r}: expected 'x,y x,y ...', rect:L:W or disc:R") from None
    if kind == "rect":
        return rectangle(*numbers)
    if kind == "disc":
        return disc(numbers[0])
    return np.array(numbers).reshape(-1, 2)


def _pair(token: str) -> tuple[str, str]:
    x, y = token.split(",")
    return x, y


def _params(pairs: list[str]) -> dict:
    params = {}
    for pair in pairs:
        key, sep, value = pair.partition("=")
        if not sep or not key:
            raise InvalidRequest(f"--param {pair[:60]!r}: expected key=value")
        try:
            params[key] = json.loads(value)
        except json.JSONDecodeError:
            params[key] = value
    return params


def result_to_json(result: BasePlanResult, grid: OccupancyGrid | None = None) -> dict:
    return {
        "success": bool(result.success),
        "status": result.status.value,
        "message": result.message,
        "path": result.path.tolist(),
        "stats": result.stats.to_dict(),
        "clearance": result_clearance(result, grid),
    }


def result_clearance(result: BasePlanResult, grid: OccupancyGrid | None) -> dict | None:
    """``{"min_m", "mean_m"}`` of the path on the map it was planned on (a biped's 2-D map, else ``grid``)."""
    if len(result.path) == 0:
        return None
    planned = result.layers.get("map")
    if planned is not None and not isinstance(planned, OccupancyGrid):  # a biped planner's own 2-D map
        grid = OccupancyGrid(planned.occupied, planned.resolution, (planned.origin[0], planned.origin[1], 0.0))
    if grid is None:
        return None
    return path_clearance(grid, result.path).to_dict()


def _planners_help() -> str:
    lines = ["planners (--planner) and their --param names:"]
    for spec in (registry.SPECS[i] for i in registry.planner_ids()):
        lines.append(f"  {spec.id}: {spec.description}")
        for name, param in spec.params.items():
            lines.append(f"      {name} (default {param.default}): {param.describe()}")
    return "\n".join(lines)


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog=PROG,
        description=__doc__.split("\n")[0],
        epilog=_planners_help() + "\n\n" + EXIT_CODES,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--map", help="map_server YAML (not needed with --world)")
    parser.add_argument("--world", help="3-D world YAML for a world_3d planner (start/goal default to its own)")
    parser.add_argument(
        "--planner",
        default=registry.DEFAULT_PLANNER,
        help=f"one of {', '.join(registry.planner_ids())} ('-' may replace '_')",
    )
    parser.add_argument("--start", nargs=3, type=float, metavar=("X", "Y", "THETA"))
    parser.add_argument("--goal", nargs=3, type=float, metavar=("X", "Y", "THETA"))
    parser.add_argument(
        "--footprint",
        default="rect:0.9:0.3",
        help="'x,y x,y ...' vertices (use --footprint=... when the first is negative), "
        "rect:L:W or disc:R (default rect:0.9:0.3)",
    )
    parser.add_argument("--param", action="append", default=[], help="planner parameter key=value (JSON value)")
    parser.add_argument(
        "--time-limit",
        type=float,
        default=DEFAULT_TIME_LIMIT,
        help=f"planning budget in seconds (default {DEFAULT_TIME_LIMIT:g})",
    )
    parser.add_argument("--unknown-free", action="store_true", help="treat unknown cells as free")
    parser.add_argument("--json", help="write the result here")
    parser.add_argument("--png", help="write a picture here")
    return parser


def _check_writable(path: str | None, option: str) -> None:
    """InvalidRequest unless ``path`` can be created or overwritten (checked before planning)."""
    if path is None:
        return
    target = Path(path)
    parent = target.parent if str(target.parent) else Path(".")
    if target.is_dir():
        raise InvalidRequest(f"{option} {path}: is a directory")
    if not parent.is_dir():
        raise InvalidRequest(f"{option} {path}: directory {parent} does not exist")
    if not os.access(target if target.exists() else parent, os.W_OK):
        raise InvalidRequest(f"{option} {path}: not writable")


def _request(args: argparse.Namespace) -> tuple:
    """(spec, grid or None, footprint, params) from the arguments; MaruError/OSError/ValueError when bad."""
    spec = registry.spec(args.planner.replace("-", "_"))
    params = _params(args.param)
    footprint = parse_footprint(args.footprint)
    for path, option in ((args.json, "--json"), (args.png, "--png")):
        _check_writable(path, option)
    if not (args.time_limit > 0):
        raise InvalidRequest(f"--time-limit must be > 0 s, got {args.time_limit}")
    if args.world:
        if not spec.has(registry.WORLD_3D):
            raise InvalidRequest(f"--world needs a world_3d planner, not {spec.id!r}")
        args.start, args.goal, params["world"] = world_defaults(args.world, args.start, args.goal)
    grid = None
    if args.map:
        grid = OccupancyGrid.from_yaml(args.map, unknown_is_occupied=not args.unknown_free)
    elif not args.world:
        raise InvalidRequest("--map is required (or --world with a world_3d planner)")
    if args.start is None or args.goal is None:
        raise InvalidRequest("--start and --goal are required")
    return spec, grid, footprint, params


def _write_outputs(args: argparse.Namespace, spec_id: str, grid, footprint, result: BasePlanResult) -> None:
    if args.json:
        with open(args.json, "w") as f:
            json.dump(result_to_json(result, grid), f, indent=1)
    if args.png:
        _write_png(args, spec_id, grid, footprint, result)


def _write_png(args: argparse.Namespace, spec_id: str, grid, footprint, result: BasePlanResult) -> None:
    # lazy: matplotlib takes about half a second to import; only --png loads it
    from maru_planner.viz.biped import save_result_png
    from maru_planner.viz.grids import save_plan_png

    if "world" in result.layers:
        save_result_png(args.png, result, spec_id)
    else:
        save_plan_png(
            args.png,
            grid,
            result,
            args.start,
            args.goal,
            footprint,
            f"{spec_id}: {result.status.value} ({result.stats.deciding_stage})",
        )


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        spec, grid, footprint, params = _request(args)
        planner = registry.make_planner(spec.id, footprint, **params)
    except (MaruError, OSError, ValueError) as exc:
        print(f"{PROG}: {one_line(exc)}", file=sys.stderr)
        return EXIT_BAD_INPUT
    where = f"{args.map} ({grid.width} x {grid.height} cells)" if grid is not None else args.world
    print(f"planning with {spec.id} on {where}...", file=sys.stderr)
    t0 = time.perf_counter()
    result = planner.plan(grid, args.start, args.goal, time_limit=args.time_limit)
    print(
        f"{result.status.value}: {result.message} ({time.perf_counter() - t0:.3f} s, "
        f"{len(result.path)} poses, stage {result.stats.deciding_stage})",
        file=sys.stderr,
    )
    try:
        _write_outputs(args, spec.id, grid, footprint, result)
    except OSError as exc:
        print(f"{PROG}: cannot write the output: {exc}", file=sys.stderr)
        return EXIT_OUTPUT
    if result.status is PlanStatus.INVALID_REQUEST:
        return EXIT_BAD_INPUT
    return EXIT_SOLVED if result.success else EXIT_NO_PATH


if __name__ == "__main__":
    sys.exit(main())

"""``maru-view``: the interactive planning view in a browser (no ROS needed).

``maru-view --robot panda --scene my_scene.yaml`` prints the URL to open; Ctrl-C stops it. ``maru-view --bag DIR
[--map YAML | --barn N]`` replays a base run instead (path, trace, base, laser points); ``--barn N`` alone draws
BARN world N. Bound to 127.0.0.1 unless ``--host`` names another address. A bad robot, scene, bag, map, world or
port: one line on stderr, exit 2.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Sequence
from typing import TYPE_CHECKING

from maru_planner import errors
from maru_planner.cli_parser import OneLineParser
from maru_planner.planning.config import COLLISION_MODELS, PlannerConfig
from maru_planner.robot.robot_profile import PROFILES
from maru_planner.web.server import ViewApp, ViewSettings
from maru_planner.web.serving import DEFAULT_HOST, serve

if TYPE_CHECKING:
    from maru_planner.web.base_live import LiveBaseView
    from maru_planner.web.base_view import BaseView

EXIT_OK, EXIT_BAD_INPUT = 0, 2
#: robots planned with the exact checker unless --collision-model says otherwise: the first fit of TIAGo's sphere
#: model (its base and torso meshes) ran over 7 minutes, and the view is to plan within seconds of the page
EXACT_BY_DEFAULT = {"tiago": "its first sphere-model fit takes minutes"}


def parser() -> argparse.ArgumentParser:
    p = OneLineParser(
        prog="maru-view", description="The interactive planning view (or a base run's replay) in a browser."
    )
    p.add_argument("--robot", default="maru1", help=f"robot profile: {', '.join(sorted(PROFILES))} (default maru1)")
    p.add_argument(
        "--scene", default="", help="scene YAML (default: the package's desk scene for maru1, none for other robots)"
    )
    p.add_argument(
        "--host", default=DEFAULT_HOST, help=f"address to serve on (default {DEFAULT_HOST}: this machine only)"
    )
    p.add_argument("--port", type=int, default=8080, help="port (default 8080, the next free one if taken; 0: any)")
    p.add_argument(
        "--collision-model",
        choices=COLLISION_MODELS,
        help=f"the planner's checker (default {PlannerConfig.collision_model}; exact for "
        f"{', '.join(sorted(EXACT_BY_DEFAULT))}, whose sphere fit takes minutes)",
    )
    p.add_argument("--bag", help="replay the base run of this rosbag2 directory (/odom, /scan, /plan, /goal_pose)")
    p.add_argument("--map", help="with --bag: the occupancy grid's map YAML to draw under the run")
    p.add_argument("--barn", type=int, metavar="N", help="draw BARN world N's cylinders (alone, or under --bag's run)")
    return p


def settings_of(args: argparse.Namespace) -> ViewSettings:
    """The view's settings; InvalidRequest for a port out of range."""
    if not 0 <= args.port <= 65535:
        raise errors.InvalidRequest(f"--port must be in [0, 65535], got {args.port}")
    scene = args.scene or ("" if args.robot == "maru1" else "none")
    return ViewSettings(args.robot, scene, args.host, args.port, collision_model(args))


def collision_model(args: argparse.Namespace) -> str:
    """``--collision-model``, or when it is not given the default for the robot (one line on stderr saying why)."""
    if args.collision_model:
        return str(args.collision_model)
    if args.robot in EXACT_BY_DEFAULT:
        print(f"maru-view: {args.robot} plans with --collision-model exact ({EXACT_BY_DEFAULT[args.robot]})",
              file=sys.stderr)  # fmt: skip
        return "exact"
    return PlannerConfig.collision_model


def base_view(args: argparse.Namespace) -> BaseView | LiveBaseView:
    """The replay of ``--bag`` (over ``--map`` or ``--barn``), or BARN world ``--barn`` alone, on its own server."""
    # lazy: the base side (scipy, rosbags, BARN worlds) costs the robot view ~1 s of start-up it does not need
    from maru_planner.base.grid import OccupancyGrid
    from maru_planner.physics import barn_world
    from maru_planner.web.base_live import LiveBaseView
    from maru_planner.web.base_view import BaseView, read_base_run

    settings = settings_of(args)
    run = read_base_run(args.bag) if args.bag else None
    try:
        grid = OccupancyGrid.from_yaml(args.map) if args.map else None
    except (OSError, ValueError) as exc:
        raise errors.InvalidRequest(f"--map {args.map}: {errors.one_line(exc, 160)}") from None
    world = getattr(args, "barn", None)  # (a Namespace made by hand may lack it)
    barn = barn_world.world_grid(world) if world is not None else None
    server = serve(settings.host, settings.port)
    return BaseView(server, run, grid, barn) if run is not None else LiveBaseView(server, grid, barn)


def main(argv: Sequence[str] | None = None) -> int:
    args = parser().parse_args(argv)
    try:
        base = args.bag or args.barn is not None
        view: ViewApp | BaseView | LiveBaseView = base_view(args) if base else ViewApp(settings_of(args))
    except errors.MaruError as exc:
        print(f"maru-view: {exc.message}", file=sys.stderr)
        return EXIT_BAD_INPUT
    server = view.server
    what = view.robot.name if isinstance(view, ViewApp) else f"the base run of {args.bag}" if args.bag else None
    what = what or f"BARN world {args.barn}"
    print(f"maru-view: {what} at http://{server.get_host()}:{server.get_port()}", flush=True)
    try:
        while True:
            time.sleep(1.0)
    except KeyboardInterrupt:
        return EXIT_OK
    finally:
        if isinstance(view, ViewApp):
            view.close()
        else:
            server.stop()


if __name__ == "__main__":
    sys.exit(main())

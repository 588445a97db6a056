"""Record rosbag2 bags of simulated paper-001 runs for the reactive_node replay tests.

Each bag holds one window of a closed-loop run of the elastic strip in a
scenario world: ``/goal_pose`` and ``/plan`` (the straight initial path) at the
window's start, then per laser tick ``/tf`` (odom -> base_link -> laser_link),
``/odom``, ``/scan`` and ``/cmd_vel`` — the command the core controller gave
for exactly those messages (inputs go through the same message conversions
the node uses), so a replay through the node can be compared with it.

The run before the window (``--skip`` s) is driven by its own controller and
not recorded; the recorded window starts a fresh controller, as a node
started at that moment would be.

    .venv/bin/python scripts/record_reactive_bags.py                      # the committed test bags
    .venv/bin/python scripts/record_reactive_bags.py --world config/worlds/multiple_static.yaml \\
        --skip 2 --duration 6 --storage mcap --out /tmp/bags
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path

import numpy as np
from rclpy.serialization import deserialize_message, serialize_message

from maru_planner.bag import TF_MSGTYPE, BagWriter, planar_transform, read_messages, summarize, tf_message
from maru_planner.paths import config_path
from maru_planner.reactive import ElasticStripController, scan_to_points, to_world
from maru_planner.ros import reactive_conversions as conv
from maru_planner.ros.reactive_node import strip_params_from_config
from maru_planner.sim import Simulator, World

STAMP_BASE = 1000.0  # s added to simulator time, so that no stamp is 0 ("unset" in ROS)
ODOM, BASE, LASER = "odom", "base_link", "laser_link"
TOPICS = {
    "/goal_pose": "geometry_msgs/msg/PoseStamped",
    "/plan": "nav_msgs/msg/Path",
    "/tf": TF_MSGTYPE,
    "/odom": "nav_msgs/msg/Odometry",
    "/scan": "sensor_msgs/msg/LaserScan",
    "/cmd_vel": "geometry_msgs/msg/Twist",
}
#: (world, skip s, duration s, storage) of the bags committed under test/data/
DEFAULT_BAGS = [
    ("single_static", 4.5, 4.0, "sqlite3"),
    ("goal_behind_obstacle", 4.5, 4.0, "sqlite3"),
    ("walking_person", 3.5, 4.0, "mcap"),
    ("multiple_static", 2.5, 4.0, "sqlite3"),
    ("irregular_scattered", 2.0, 4.0, "mcap"),
]


def _ns(stamp_s: float) -> int:
    return round(stamp_s * 1e9)


def _warm_up(sim: Simulator, params, goal, until: float, dt: float) -> None:
    """Drive the robot with its own controller up to ``until`` s (not recorded)."""
    ctrl = ElasticStripController(params)
    ctrl.set_goal(goal)
    while sim.time < until - 1e-9 and not sim.collided:
        out = ctrl.update(sim.robot_pose, sim.scan())
        sim.step(out.v, out.w, dt)


def _wire(msg) -> tuple[bytes, object]:
    """The CDR bytes of a message and the message as a subscriber gets it back from them.

    rclpy keeps float32 scalars (e.g. LaserScan.angle_increment) as Python
    floats until serialization; the core must see the rounded values the node sees.
    """
    raw = serialize_message(msg)
    return raw, deserialize_message(raw, type(msg))


def _tf(pose, stamp_s: float, laser_pose) -> object:
    return tf_message(
        [
            planar_transform(ODOM, BASE, _ns(stamp_s), *pose),
            planar_transform(BASE, LASER, _ns(stamp_s), *laser_pose),
        ]
    )


def record_world(
    world_path: Path,
    out: Path,
    *,
    seed: int = 0,
    skip: float = 0.0,
    duration: float = 4.0,
    rate: float | None = None,
    storage: str = "sqlite3",
    params_file: Path | None = None,
) -> dict:
    """Record one window of a run in ``world_path`` to the bag directory ``out``; returns a summary.

    Receive timestamps are the header stamps plus 0..3 ns, so that readers order the messages of one
    tick as they happened (goal, plan; then tf, odom, scan, cmd_vel) whatever they do with ties.

    ``rate``: laser ticks per second, by default the world's laser rate (the controller's steps are
    per update, so the rate is part of the scenario).
    """
    world = World.from_yaml(world_path)
    params = strip_params_from_config(params_file or config_path("reactive.yaml"))
    sim = Simulator(world, seed=seed)
    dt = 1.0 / (rate or world.robot.laser.rate)
    goal = tuple(float(g) for g in world.robot.goal)
    _warm_up(sim, params, goal, skip, dt)

    start = STAMP_BASE + sim.time
    waypoints = world.path[:, :2] if world.path is not None else np.array([goal[:2]])
    plan = _wire(conv.path_msg(np.vstack([sim.robot_pose[:2], waypoints]), ODOM, start))
    ctrl = ElasticStripController(params)
    ctrl.set_path(conv.path_points_from_msg(plan[1]))
    v = w = 0.0
    ticks, outcome, strips = 0, "window", []
    with BagWriter(out, storage=storage) as bag:
        for topic, msgtype in TOPICS.items():
            bag.add_topic(topic, msgtype)
        bag.write("/goal_pose", _ns(start), _wire(conv.pose_stamped_msg(goal, ODOM, start))[0])
        bag.write("/plan", _ns(start) + 1, plan[0])
        while sim.time < skip + duration - 1e-9:
            stamp = STAMP_BASE + sim.time
            odom = _wire(conv.odom_msg(sim.robot_pose, v, w, stamp, ODOM, BASE))
            scan = _wire(conv.scan_msg(dataclasses.replace(sim.scan(), stamp=stamp), LASER, scan_time=dt))
            out_cmd = ctrl.update(conv.pose_from_odom(odom[1]), conv.scan_from_msg(scan[1]))
            v, w = out_cmd.v, out_cmd.w
            if ticks % 10 == 0:
                strips.append(np.asarray(out_cmd.strip).copy())
            bag.write("/tf", _ns(stamp), _tf(sim.robot_pose, stamp, params.laser_pose))
            bag.write("/odom", _ns(stamp) + 1, odom[0])
            bag.write("/scan", _ns(stamp) + 2, scan[0])
            bag.write("/cmd_vel", _ns(stamp) + 3, serialize_message(conv.twist_msg(v, w)))
            ticks += 1
            if out_cmd.reached_goal:
                outcome = "goal"
                break
            if sim.step(v, w, dt):
                outcome = "collision"
                break
    summary = summarize(out)
    size = sum(f.stat().st_size for f in out.iterdir())
    return {
        "world": world.name,
        "bag": str(out),
        "storage": storage,
        "ticks": ticks,
        "outcome": outcome,
        "duration_s": round(summary.duration_s, 3),
        "bytes": size,
        "counts": summary.counts,
        "world_obj": world,
        "strips": strips,
    }


def save_picture(path: Path, recordings: list[dict]) -> None:
    """One panel per bag, drawn from what the bag holds: odometry path, scan points, and the core's strips."""
    # lazy: matplotlib is loaded only when a picture is asked for (a heavy import)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from maru_planner.viz.reactive import draw_world

    cols = 2 if len(recordings) > 1 else 1
    rows = -(-len(recordings) // cols)
    fig, axes = plt.subplots(rows, cols, figsize=(6.5 * cols, 3.6 * rows), squeeze=False)
    for ax in axes.flat[len(recordings) :]:
        ax.axis("off")
    for ax, rec in zip(axes.flat, recordings):
        draw_world(ax, rec["world_obj"], show_movers=False)
        poses, points = [], []
        pose = None
        for record in read_messages(rec["bag"], topics=["/odom", "/scan"]):
            msg = conv.decode_bag_record(record.msgtype, record.rawdata)
            if record.topic == "/odom":
                pose = conv.pose_from_odom(msg)
                poses.append(pose)
            elif pose is not None and len(poses) % 5 == 1:
                local = scan_to_points(conv.scan_from_msg(msg), (0.22, 0.0, 0.0), max_range=3.0)
                points.append(to_world(local, pose))
        if points:
            cloud = np.vstack(points)
            ax.plot(cloud[:, 0], cloud[:, 1], ".", ms=1.5, color="tab:red", label="/scan points")
        for i, strip in enumerate(rec["strips"]):
            ax.plot(
                strip[:, 0],
                strip[:, 1],
                "-o",
                ms=2,
                lw=0.8,
                color="tab:blue",
                alpha=0.6,
                label="strip (core)" if i == 0 else None,
            )
        path_xy = np.array(poses)
        ax.plot(path_xy[:, 0], path_xy[:, 1], "-", lw=2, color="k", label="/odom")
        ax.set_title(f"{rec['world']}: {rec['ticks']} ticks, {rec['storage']}, {rec['bytes'] / 1024:.0f} KiB")
        ax.legend(loc="lower right", fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--world", type=Path, help="one world YAML (default: the committed test bags)")
    parser.add_argument("--out", type=Path, default=Path("test/data"), help="directory for the bag directories")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--skip", type=float, default=0.0, help="seconds driven before recording starts")
    parser.add_argument("--duration", type=float, default=4.0, help="seconds recorded")
    parser.add_argument("--rate", type=float, help="laser ticks per second (default: the world's laser rate)")
    parser.add_argument("--storage", choices=["sqlite3", "mcap"], default="sqlite3")
    parser.add_argument("--params", type=Path, help="reactive_node params file (default config/reactive.yaml)")
    parser.add_argument("--force", action="store_true", help="replace existing bag directories")
    parser.add_argument("--png", type=Path, help="picture of the recorded windows")
    args = parser.parse_args(argv)

    if args.world is not None:
        jobs = [(args.world, args.skip, args.duration, args.storage)]
    else:
        jobs = [(config_path("worlds", f"{name}.yaml"), skip, dur, st) for name, skip, dur, st in DEFAULT_BAGS]
    args.out.mkdir(parents=True, exist_ok=True)
    print(f"{'world':<24}{'storage':<9}{'ticks':>6}{'outcome':>11}{'KiB':>8}  bag")
    recordings = []
    for world_path, skip, duration, storage in jobs:
        out = args.out / f"reactive_{Path(world_path).stem}"
        if out.exists():
            if not args.force:
                print(f"{out} exists (use --force to replace)", file=sys.stderr)
                return 1
            for f in out.iterdir():
                f.unlink()
            out.rmdir()
        print(f"recording {world_path} ...", file=sys.stderr)
        s = record_world(
            Path(world_path),
            out,
            seed=args.seed,
            skip=skip,
            duration=duration,
            rate=args.rate,
            storage=storage,
            params_file=args.params,
        )
        print(f"{s['world']:<24}{s['storage']:<9}{s['ticks']:>6}{s['outcome']:>11}{s['bytes'] / 1024:>8.0f}  {out}")
        recordings.append(s)
    if args.png is not None:
        save_picture(args.png, recordings)
        print(f"picture: {args.png}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

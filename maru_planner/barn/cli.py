"""maru-barn: the BARN Challenge in MuJoCo -- our base stack on one world, scored like the challenge.

maru-barn --world 0 --trials 3 --seed 0 --json out.json --png out.png
maru-barn --grid my_grid.npy            (any 30 x 30 uint8 grid, 1 = cylinder)
maru-barn --world 0 --through-ros       (every node its own process, lock-step over ROS topics)
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from maru_planner.barn.scoring import RunScore, RunTrace, grid_optimal_time, summarise
from maru_planner.cli_parser import CliError, OneLineParser
from maru_planner.errors import MaruError, one_line
from maru_planner.physics.barn_world import WORLD_COUNT, cylinder_centres, load_grid, optimal_time, world_grid
from maru_planner.sim.cli import check_writable

PROG = "maru-barn"
EXIT_OK, EXIT_RUN_FAILED, EXIT_BAD_INPUT, EXIT_INTERRUPTED = 0, 1, 2, 130
MAX_TRIALS = 100
EXIT_CODES = f"""exit codes:
  {EXIT_OK}    every run finished (whatever its outcome; see the JSON)
  {EXIT_RUN_FAILED}    --through-ros: the ROS graph could not carry a run out (a node died, a timeout)
  {EXIT_BAD_INPUT}    bad input: an option, the grid file (shape, dtype, no free path) or an output path
  {EXIT_INTERRUPTED}  interrupted (Ctrl-C)"""


def build_parser() -> argparse.ArgumentParser:
    parser = OneLineParser(
        prog=PROG,
        description=__doc__.splitlines()[0],
        epilog=EXIT_CODES,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    source = parser.add_mutually_exclusive_group(required=True)
    source.add_argument("--world", type=int, help=f"public BARN world 0..{WORLD_COUNT - 1}")
    source.add_argument("--grid", help="a 30 x 30 uint8 .npy grid (the dataset's grid_files format, 1 = cylinder)")
    parser.add_argument("--trials", type=int, default=1, help=f"runs per world, seeds S, S+1, ... (1..{MAX_TRIALS})")
    parser.add_argument("--seed", type=int, default=0, help="first seed (laser and odometry noise), >= 0")
    parser.add_argument("--json", help="write the runs and their summary here")
    parser.add_argument("--png", help="write a top view of the runs here (world, global path, trajectory, contacts)")
    parser.add_argument(
        "--through-ros",
        action="store_true",
        help="mujoco_sim_node, base_planner_node and reactive_node as processes, lock-step over topics "
        "(default: in-process, the same core code without DDS)",
    )
    parser.add_argument("--quiet", action="store_true", help="no progress on stderr")
    return parser


def check_arguments(args: argparse.Namespace) -> None:
    if not 1 <= args.trials <= MAX_TRIALS:
        raise CliError(f"--trials must be in 1..{MAX_TRIALS}, got {args.trials}")
    if args.seed < 0:
        raise CliError(f"--seed must be >= 0, got {args.seed}")
    for option in ("json", "png"):
        if getattr(args, option):
            check_writable(Path(getattr(args, option)), f"--{option}")
    if args.png and Path(args.png).suffix.lower() != ".png":
        raise CliError(f"--png {args.png[:80]}: the file name must end in .png")


def run(args: argparse.Namespace) -> dict:
    check_arguments(args)
    if args.world is not None:
        grid, name, optimal = world_grid(args.world), f"world_{args.world}", optimal_time(args.world)
    else:
        grid, name = load_grid(args.grid), Path(args.grid).name
        optimal = grid_optimal_time(grid)
    runs: list[RunScore] = []
    traces: list[RunTrace] = []
    for seed in range(args.seed, args.seed + args.trials):
        if not args.quiet:
            print(f"[{PROG}] {name} seed {seed} ...", file=sys.stderr, flush=True)
        if args.through_ros:
            score, trace = run_through_ros(args, optimal, seed, name)
        else:
            # lazy: the stack (numba's A*, the strip) is not needed when the nodes run it (--through-ros)
            from maru_planner.barn.stack import run_barn

            score, trace = run_barn(grid, optimal, seed=seed, world_name=name)
        runs.append(score)
        traces.append(trace)
        if not args.quiet:
            outcome = "success" if score.success else "collision" if score.collision else "timeout"
            print(
                f"[{PROG}] {name} seed {seed}: {outcome} T={score.time_s or 0:.2f} s metric={score.metric:.3f} "
                f"({score.sim_time_s / max(score.wall_time_s, 1e-9):.1f}x real time)",
                file=sys.stderr,
                flush=True,
            )
    payload = {"world": name, "optimal_time_s": round(optimal, 4), "summary": summarise(runs)}
    payload["runs"] = [r.to_json() for r in runs]
    if args.json:
        Path(args.json).write_text(json.dumps(payload, indent=2) + "\n")
    if args.png:
        save_picture(args.png, grid, runs, traces)
    return payload


def run_through_ros(args: argparse.Namespace, optimal: float, seed: int, name: str) -> tuple[RunScore, RunTrace]:
    """One run by ``maru_planner.ros.barn_ros_run`` in a process of its own (this layer imports no ROS)."""
    source = ["--world", str(args.world)] if args.world is not None else ["--grid", str(Path(args.grid).resolve())]
    with tempfile.TemporaryDirectory(prefix="maru_barn_") as scratch:
        out = Path(scratch) / "run.json"
        command = [sys.executable, "-m", "maru_planner.ros.barn_ros_run", *source, "--seed", str(seed)]
        command += ["--name", name, "--optimal-time", repr(optimal), "--json", str(out)]
        done = subprocess.run(command, capture_output=True, text=True)
        if done.returncode != 0 or not out.is_file():
            reason = (done.stderr.strip().splitlines() or ["no output"])[-1]
            raise RosRunFailed(f"the run through ROS failed: {reason}")
        payload = json.loads(out.read_text())
    trace = RunTrace(
        np.array(payload["trajectory"]).reshape(-1, 3),
        np.array(payload["global_path"]).reshape(-1, 2),
        [tuple(c) for c in payload["contacts"]],
    )
    return RunScore(**payload["run"]), trace


class RosRunFailed(MaruError):
    """The ROS graph could not carry the run out (a node died, a timeout)."""

    source = "ros"


def save_picture(path: str, grid, runs: list[RunScore], traces: list[RunTrace]) -> None:
    # lazy: matplotlib is loaded only when a picture is asked for (a heavy import)
    from maru_planner.viz.barn import save_barn_runs

    centres = cylinder_centres(grid)
    panels = [
        dict(
            cylinders=centres,
            trajectory=trace.trajectory,
            global_path=trace.global_path,
            contacts=trace.contacts,
            title=f"{run.world} seed {run.seed}: metric {run.metric:.3f}",
        )
        for run, trace in zip(runs, traces, strict=True)
    ]
    save_barn_runs(path, panels)


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        payload = run(args)
    except RosRunFailed as exc:
        print(f"{PROG}: error: {one_line(exc)}", file=sys.stderr)
        return EXIT_RUN_FAILED
    except (MaruError, OSError) as exc:
        print(f"{PROG}: error: {one_line(exc)}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        print(f"{PROG}: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    print(json.dumps(payload["summary"]))
    return EXIT_OK


if __name__ == "__main__":
    raise SystemExit(main())

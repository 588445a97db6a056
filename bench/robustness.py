"""Robustness benchmark (issue 18): the hostile-input suite's generators at a larger scale.

Runs the generators of ``test/hostile_inputs.py`` against planning_node, base_planner_node and
reactive_node (each its own process, real rclpy clients on loopback DDS) and against maru-plan,
maru-base-plan and maru-reactive-sim (their loaders and ``main`` in this process), then:

- the table per target: inputs / accepted / proper errors / crashes / tracebacks / internal
  errors / late answers (past budget + 0.5 s) / lost, and whether a known-good request
  succeeded after every batch;
- RSS of each node before and after 10,000 junk messages on its subscribed topic;
- a burst of 64 simultaneous plan_motion calls on a planning_node with its shipped settings:
  answered / BUSY / lost and the latency distribution (p50, p95, max).

Writes bench/results/robustness.{json,md,png}. ``--quick`` runs a quarter of the test suite's
examples (a smoke run, no files written unless ``--write``); the default is 5x the suite.

    .venv/bin/python bench/robustness.py [--quick] [--scale 5] [--seed 18]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import random
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "test"))  # the suite's generators and node helpers

import hostile_inputs as hostile  # noqa: E402
from _common import results_dir  # noqa: E402
from conftest import NodeProcess, SpinningNode  # noqa: E402

from maru_planner.errors import MaruError  # noqa: E402
from maru_planner.paths import config_path  # noqa: E402
from maru_planner.ros.env import configure_loopback_dds  # noqa: E402

RESULTS = ROOT / "bench" / "results"
NAME = "robustness"
JUNK_MESSAGES = 10_000
BURST_CLIENTS = 64
BURST_BUDGET = 5.0
TARGETS = ["planning_node", "base_planner_node", "reactive_node", "maru-plan", "maru-base-plan", "maru-reactive-sim"]


def log(message: str) -> None:
    print(message, file=sys.stderr, flush=True)


class Bench:
    """Runs batches with progress, keeps the known-good checks and the measurements."""

    def __init__(self, scale: float, seed: int, workdir: Path):
        self.scale, self.seed, self.workdir = scale, seed, workdir
        self.good_after_batch: dict[str, list[bool]] = {target: [] for target in TARGETS}
        self.rss: dict[str, dict] = {}
        self.batches = 0

    def examples(self, batch: str) -> int:
        return max(1, round(hostile.SUITE_EXAMPLES[batch] * self.scale))

    def batch(self, target: str, batch: str, strategy, send: Callable, good: Callable[[], bool] | None = None) -> None:
        total = self.examples(batch)
        started, done = time.monotonic(), hostile.tally(target).inputs

        def progress(inputs: int) -> None:
            if (inputs - done) % 25 == 0 or inputs - done == total:
                log(f"  [{target}] {batch}: {inputs - done}/{total} ({time.monotonic() - started:.0f} s)")

        self.batches += 1
        hostile.run_batch(target, strategy, send, total, strict=False, seed_value=self.seed + self.batches,
                          progress=progress)  # fmt: skip
        if good is not None:
            ok = good()
            self.good_after_batch[target].append(ok)
            log(f"  [{target}] known-good request after {batch}: {'ok' if ok else 'FAILED'}")

    def measure_rss(self, target: str, pid: int, flood: Callable[[], None], recovered: Callable[[], bool]) -> None:
        before = hostile.rss_mb(pid)
        started = time.monotonic()
        flood()
        ok = recovered()
        after = hostile.rss_mb(pid)
        self.rss[target] = {"before_mb": round(before, 1), "after_mb": round(after, 1),
                            "growth_mb": round(after - before, 1), "messages": JUNK_MESSAGES,
                            "seconds": round(time.monotonic() - started, 1), "serving_after": ok}  # fmt: skip
        log(f"  [{target}] RSS {before:.1f} -> {after:.1f} MB over {JUNK_MESSAGES} junk messages")


def node(module: str, args: list[str], workdir: Path) -> NodeProcess:
    return NodeProcess(module, args, workdir / f"{module.rsplit('.', 1)[-1]}_{time.monotonic_ns()}.log")


def stopped_alive(process: NodeProcess) -> bool:
    """Whether the process was still alive when we stopped it (then stops it)."""
    alive = process.alive()
    if not alive:
        log(f"  node died; log tail:\n{process.log()[-2000:]}")
    process.stop()
    return alive


def run_planning_node(bench: Bench) -> None:
    from maru_planner.robot import RobotModel

    log("planning_node")
    arguments = hostile.params_file_arguments("planner.yaml", hostile.PLANNING_LIMITS)
    process = node("maru_planner.ros.planning_node", arguments, bench.workdir)
    spinning = SpinningNode("robustness_planning")
    target = hostile.PlanningNodeTarget(spinning, process, RobotModel.maru1())
    try:
        target.connect()

        def good() -> bool:
            return target.good_plan().error.code == hostile.PlanningError.SUCCESS

        def restored_good() -> bool:
            target.restore_scene()
            return good()

        name = "planning_node"
        bench.batch(name, "plan_motion", target.plan_requests(), target.send_plan, good)
        bench.batch(name, "compute_ik", target.ik_requests(), target.send_ik, good)
        bench.batch(name, "apply_scene", hostile.apply_scene_requests(), target.send_scene, restored_good)
        bench.batch(name, "scene_topic", hostile.scene_obstacles(["fuzz_a", "fuzz_b", "desk", "box"]),
                    lambda m: target.publish(target.scene_topic, m), restored_good)  # fmt: skip
        bench.batch(name, "joint_states", target.joint_state_messages(),
                    lambda m: target.publish(target.joint_states, m), target.good_state_is_used)  # fmt: skip
        bench.measure_rss(name, process.proc.pid, lambda: target.junk_joint_states(JUNK_MESSAGES),
                          target.good_state_is_used)  # fmt: skip
    finally:
        spinning.destroy()
        bench.good_after_batch["planning_node"].append(stopped_alive(process))


def run_base_node(bench: Bench) -> None:
    log("base_planner_node")
    arguments = hostile.params_file_arguments("base_planner.yaml", hostile.BASE_LIMITS)
    process = node("maru_planner.ros.base_planner_node", arguments, bench.workdir)
    spinning = SpinningNode("robustness_base")
    target = hostile.BaseNodeTarget(spinning, process)
    try:
        target.connect()

        def good() -> bool:
            response = target.good_request()
            return response is not None and response.error_code == 0

        name = "base_planner_node"
        bench.batch(name, "plan_base_path", target.requests(), target.send, good)
        bench.batch(name, "make_plan", target.get_plan_requests(), target.send_get_plan, good)
        bench.batch(name, "map", hostile.occupancy_grids(), target.publish_map, target.restore_map)
        bench.measure_rss(name, process.proc.pid, lambda: target.junk_maps(JUNK_MESSAGES), target.restore_map)
    finally:
        spinning.destroy()
        bench.good_after_batch["base_planner_node"].append(stopped_alive(process))


def run_reactive_node(bench: Bench) -> None:
    log("reactive_node")
    process = node("maru_planner.ros.reactive_node", hostile.ReactiveNodeTarget.node_arguments(bench.workdir),
                   bench.workdir)  # fmt: skip
    spinning = SpinningNode("robustness_reactive")
    target = hostile.ReactiveNodeTarget(spinning, process)
    try:
        target.connect()

        def good() -> bool:
            target.settle()
            target.send_good_goal()
            return target.good_step() and spinning.wait_for(lambda: target.callback_errors() == 0, timeout=30)

        for _ in range(hostile.REACTIVE_BATCHES):
            bench.batch("reactive_node", "reactive", hostile.reactive_messages(), target.send, good)
        bench.measure_rss("reactive_node", process.proc.pid, lambda: target.junk_scans(JUNK_MESSAGES), good)
    finally:
        spinning.destroy()
        bench.good_after_batch["reactive_node"].append(stopped_alive(process))


def run_files(bench: Bench) -> None:
    from maru_planner.base.biped.world import load_world
    from maru_planner.base.grid import OccupancyGrid
    from maru_planner.planning.cli import load_scene
    from maru_planner.sim import World

    log("files (scene, map, biped world, simulator world)")
    files = hostile.Files(Path(tempfile.mkdtemp(dir=bench.workdir)))
    typed = (MaruError, OSError)

    def loader(write: Callable, load: Callable, what: str) -> Callable:
        return lambda generated: hostile.loader_outcome(lambda: load(write(generated)), what, typed)

    bench.batch("maru-plan", "scene_files", hostile.scene_documents(), loader(files.document, load_scene, "scene"))
    bench.batch("maru-base-plan", "map_files", hostile.map_files(),
                loader(files.map_file, OccupancyGrid.from_yaml, "map"))  # fmt: skip
    bench.batch("maru-base-plan", "biped_files", hostile.biped_worlds(),
                loader(files.document, load_world, "biped world"))  # fmt: skip
    bench.batch("maru-reactive-sim", "sim_files", hostile.sim_worlds(),
                loader(files.document, World.from_yaml, "sim world"))  # fmt: skip


def run_clis(bench: Bench) -> None:
    from maru_planner.base import cli as base_cli
    from maru_planner.planning import cli as plan_cli
    from maru_planner.sim import cli as sim_cli

    clis = {
        "maru-plan": (plan_cli.main, hostile.maru_plan_argv, {0, 1, 2, 3, 130}, 3, "--time"),
        "maru-base-plan": (base_cli.main, hostile.maru_base_plan_argv, {0, 1, 2, 3}, None, "--time-limit"),
        "maru-reactive-sim": (sim_cli.main, hostile.maru_reactive_sim_argv, {0, 2, 130}, None, "--max-time"),
    }
    for prog, (main, argv, codes, internal, budget_option) in clis.items():
        log(prog)
        workdir = Path(tempfile.mkdtemp(dir=bench.workdir))

        def run(args: list[str], main=main, prog=prog, codes=codes, internal=internal, option=budget_option):
            budget = hostile.number_or_zero(hostile.option_value(args, option, "0"))
            return hostile.cli_outcome(main, args, prog, codes, 2, internal, budget)

        bench.batch(prog, prog, argv(workdir), run)


def run_burst(bench: Bench) -> tuple[dict, list[float]]:
    log(f"burst: {BURST_CLIENTS} simultaneous plan_motion calls (shipped settings)")
    process = node("maru_planner.ros.planning_node",
                   ["--ros-args", "--params-file", str(config_path("planner.yaml"))], bench.workdir)  # fmt: skip
    spinning = SpinningNode("robustness_burst")
    try:
        from maru_planner.ros.planning_client import PlanningClient

        client = PlanningClient(node=spinning.node)
        assert client.plan_client.wait_for_service(timeout_sec=120.0), "plan_motion never appeared"
        client.wait_until_ready(timeout=120.0)
        burst = hostile.plan_burst(spinning, BURST_CLIENTS, BURST_BUDGET)
    finally:
        spinning.destroy()
        node_alive = stopped_alive(process)
    result = {**burst.summary(), "node_alive": node_alive}
    log(
        f"  answered {result['answered']}/{BURST_CLIENTS} (plans {result['success']}, BUSY {result['busy']}), "
        f"lost {result['lost']}; p50 {result['p50_s']:.2f} s, p95 {result['p95_s']:.2f} s, max {result['max_s']:.2f} s"
    )
    return result, burst.latencies


# ---------------------------------------------------------------- report

COLUMNS = ["inputs", "accepted", "proper_errors", "crashes", "tracebacks", "internal_errors", "late_answers", "lost"]


def table_rows(bench: Bench) -> list[dict]:
    rows = []
    for target in TARGETS:
        record = hostile.tally(target)
        checks = bench.good_after_batch[target]
        good = all(checks) if checks else None  # None: a CLI, every run a new process (nothing to check after)
        rows.append({"target": target, **record.row(), "good_after_every_batch": good,
                     "failures": record.failures[:5]})  # fmt: skip
    return rows


def markdown(rows: list[dict], rss: dict, burst: dict, meta: dict) -> str:
    header = "| target | " + " | ".join(c.replace("_", " ") for c in COLUMNS) + " | good request after every batch |"
    lines = [f"# Robustness (issue 18): {meta['total_inputs']} hostile inputs", "",
             f"`{meta['command']}` — scale {meta['scale']}, seed {meta['seed']}, {meta['seconds']:.0f} s.", "",
             header, "|" + "---|" * (len(COLUMNS) + 2)]  # fmt: skip
    for row in rows:
        good = {True: "yes", False: "**no**", None: "— (a new process per run)"}[row["good_after_every_batch"]]
        lines.append(f"| {row['target']} | " + " | ".join(str(row[c]) for c in COLUMNS) + f" | {good} |")
    lines += ["", "Topic messages (/joint_states, /planning_scene_obstacles, /map, reactive_node's inputs) have no",
              "answer: they count as proper when the node survived them with no traceback.", "",
              "## RSS over 10,000 junk messages", "",
              "| node | before (MB) | after (MB) | growth (MB) | serving after |", "|---|---|---|---|---|"]  # fmt: skip
    for name, r in rss.items():
        lines.append(f"| {name} | {r['before_mb']} | {r['after_mb']} | {r['growth_mb']} | {r['serving_after']} |")
    lines += ["", f"## Burst: {burst['clients']} simultaneous plan_motion calls (budget {BURST_BUDGET:g} s)", "",
              "| answered | plans | BUSY | other | lost | p50 (s) | p95 (s) | max (s) |",
              "|---|---|---|---|---|---|---|---|",
              f"| {burst['answered']} | {burst['success']} | {burst['busy']} | {burst['other']} | {burst['lost']} | "
              f"{burst['p50_s']:.3f} | {burst['p95_s']:.3f} | {burst['max_s']:.3f} |", ""]  # fmt: skip
    return "\n".join(lines)


def picture(rows: list[dict], burst_latencies: list[float], path: Path) -> None:
    import matplotlib  # lazy: only the report needs it

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (left, right) = plt.subplots(1, 2, figsize=(12, 4.5))
    names = [row["target"] for row in rows]
    accepted = [row["accepted"] for row in rows]
    proper = [row["proper_errors"] for row in rows]
    broken = [row["inputs"] - row["accepted"] - row["proper_errors"] for row in rows]
    left.barh(names, accepted, label="accepted")
    left.barh(names, proper, left=accepted, label="proper error")
    left.barh(names, broken, left=[a + p for a, p in zip(accepted, proper, strict=True)], label="broken", color="red")
    left.set_xlabel("hostile inputs")
    left.legend(loc="lower right")
    left.set_title("answers per target")
    right.hist(burst_latencies, bins=20)
    right.set_xlabel("seconds to the answer")
    right.set_ylabel("calls")
    right.set_title(f"{BURST_CLIENTS} simultaneous plan_motion calls")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def print_table(rows: list[dict]) -> None:
    widths = [max(len("target"), *(len(r["target"]) for r in rows))] + [max(len(c), 6) for c in COLUMNS]
    print("  ".join(h.ljust(w) for h, w in zip(["target", *COLUMNS], widths, strict=True)))
    for row in rows:
        cells = [row["target"], *(str(row[c]) for c in COLUMNS)]
        print("  ".join(c.ljust(w) for c, w in zip(cells, widths, strict=True)))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="a quarter of the test suite's examples (smoke run)")
    parser.add_argument("--scale", type=float, default=5.0, help="examples per batch x the test suite's (default 5)")
    parser.add_argument("--seed", type=int, default=hostile.SEED)
    parser.add_argument("--write", action="store_true", help="write the results also after --quick")
    args = parser.parse_args(argv)
    global RESULTS
    RESULTS = results_dir(args.quick)  # --quick: bench/results/quick/, never the committed results
    scale = 0.25 if args.quick else args.scale
    if not (math.isfinite(scale) and scale > 0):
        parser.error(f"--scale must be > 0, got {scale}")
    user_domain = os.environ.get("ROS_DOMAIN_ID")
    configure_loopback_dds(domain_id=None if user_domain else random.SystemRandom().randint(101, 200))

    import rclpy  # lazy: after the DDS environment is set

    rclpy.init()
    started = time.monotonic()
    with tempfile.TemporaryDirectory(prefix="robustness_") as tmp:
        bench = Bench(scale, args.seed, Path(tmp))
        try:
            run_files(bench)
            run_clis(bench)
            run_planning_node(bench)
            run_base_node(bench)
            run_reactive_node(bench)
            burst, latencies = run_burst(bench)
        finally:
            rclpy.try_shutdown()
    rows = table_rows(bench)
    command = "bench/robustness.py " + " ".join(argv if argv is not None else sys.argv[1:])
    meta = {"command": command.strip(), "scale": scale, "seed": args.seed, "seconds": time.monotonic() - started,
            "total_inputs": sum(row["inputs"] for row in rows)}  # fmt: skip
    print_table(rows)
    for row in rows:
        for failure in row["failures"]:
            print(f"  {row['target']}: {failure}")
    print(f"total {meta['total_inputs']} inputs; RSS: {json.dumps(bench.rss)}; burst: {json.dumps(burst)}")
    if args.quick and not args.write:
        return 0
    RESULTS.mkdir(parents=True, exist_ok=True)
    payload = {"meta": meta, "targets": rows, "rss": bench.rss, "burst": burst, "burst_latencies": latencies}
    (RESULTS / f"{NAME}.json").write_text(json.dumps(payload, indent=1) + "\n")
    (RESULTS / f"{NAME}.md").write_text(markdown(rows, bench.rss, burst, meta) + "\n")
    picture(rows, latencies, RESULTS / f"{NAME}.png")
    log(f"wrote {RESULTS / NAME}.{{json,md,png}}")
    broken = sum(row["inputs"] - row["accepted"] - row["proper_errors"] for row in rows)
    return 0 if broken == 0 and burst["lost"] == 0 else 1


if __name__ == "__main__":
    sys.exit(main())

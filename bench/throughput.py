"""Throughput of planning_node under concurrent clients: one worker against several, processes against threads.

For each configuration a planning_node process starts (config/planner.yaml, ``-p workers:=K -p
worker_processes:=B``, a queue deep enough that nothing is BUSY), then ``--clients`` client threads (each its own
plan_motion client, one rclpy node spun in this process) send the same list of requests: the 13-DOF desk-and-box
problem with RC-RRT (~80 ms of search: planning keeps the cores busy) or RRTConnect (~10 ms), each request its own
seed (the same work in every configuration). Requests/s = answered requests / wall time
from the first send to the last answer. Start-up = node process start until its first answer.

Target (issue 16): N process workers >= 1.8x one worker's requests/s with 8 clients on this 2-core machine, judged
on RC-RRT's requests; RRTConnect's, which the node's own per-request work bounds, are measured beside them.

    .venv/bin/python bench/throughput.py [--requests 96] [--clients 8] [--workers 2] [--quick]

Writes bench/results/throughput.{json,md,png}.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np
from _common import PAPER_GOAL, PAPER_START, RESULTS, log, start_python, write_results

from maru_planner.paths import config_path
from maru_planner.ros.env import configure_loopback_dds

NAME = "throughput"
TARGET_RATIO = 1.8
# Seeds of this problem, the same for every configuration and planner.
SEEDS = (1, 2, 4, 6, 7, 8, 12, 13, 18, 24, 25, 26, 27, 28)
BUDGET = 20.0  # s per request: far above what a request needs, so none times out
CALL_TIMEOUT = 600.0


def configurations(workers: int, quick: bool) -> list[dict]:
    """(label, planner, workers, worker_processes). The target is judged on RC-RRT, whose requests keep a core busy
    (~80 ms of search each); an RRTConnect request plans in ~10 ms, so there the node's own per-request work and the
    clients, on the same two cores, bound the rate."""
    configs = []
    for planner in ("RCRRT",) if quick else ("RCRRT", "RRTConnect"):
        kinds = (True,) if quick or planner == "RRTConnect" else (True, False)
        for processes in kinds:
            one, many = ("process", "processes") if processes else ("thread", "threads")
            configs += [
                {"label": f"{planner}: 1 worker ({one})", "planner": planner, "workers": 1, "processes": processes},
                {"label": f"{planner}: {workers} workers ({many})", "planner": planner, "workers": workers,
                 "processes": processes},
            ]  # fmt: skip
    return configs


def start_node(config: dict, requests: int, log_file) -> subprocess.Popen:
    args = [
        "-m", "maru_planner.ros.planning_node", "--ros-args", "--params-file", str(config_path("planner.yaml")),
        "-p", f"workers:={config['workers']}", "-p", f"worker_processes:={str(config['processes']).lower()}",
        "-p", f"queue_size:={requests}",
    ]  # fmt: skip
    return start_python(args, log_file)


def stop_node(node: subprocess.Popen) -> None:
    node.terminate()
    try:
        node.wait(timeout=20)
    except subprocess.TimeoutExpired:
        node.kill()
        node.wait()


def make_request(seed: int, planner: str):
    from maru_planner.ros.planning_client import plan_request  # ROS loads after main's configure_loopback_dds

    return plan_request(
        PAPER_GOAL, start=PAPER_START, group="upper_body", planner_id=planner, time_budget=BUDGET, seed=seed
    )


def drive(clients: list, seeds: list[int], planner: str) -> dict:
    """Send ``seeds`` (one request each) from every client thread, taking the next seed when free."""
    from maru_planner.ros.planning_client import call_service  # ROS loads after main's configure_loopback_dds
    from maru_planner_interfaces.msg import PlanningError

    todo = iter(seeds)
    lock = threading.Lock()
    latencies: list[float] = []
    core: list[float] = []
    failures: list[str] = []

    def client_loop(client) -> None:
        while True:
            with lock:
                seed = next(todo, None)
            if seed is None:
                return
            t0 = time.perf_counter()
            response = call_service(client, make_request(seed, planner), CALL_TIMEOUT)
            with lock:
                latencies.append(time.perf_counter() - t0)
                core.append(response.planning_time)
                if response.error.code != PlanningError.SUCCESS:
                    failures.append(response.error.message)

    threads = [threading.Thread(target=client_loop, args=(c,)) for c in clients]
    t0 = time.perf_counter()
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    wall = time.perf_counter() - t0
    return {
        "requests": len(latencies),
        "failures": len(failures),
        "failure_example": failures[0] if failures else "",
        "wall_s": wall,
        "requests_per_s": len(latencies) / wall,
        "latency_median_ms": float(np.median(latencies) * 1e3),
        "latency_p90_ms": float(np.percentile(latencies, 90) * 1e3),
        "core_median_ms": float(np.median(core) * 1e3),
        "raw_latency_ms": [x * 1e3 for x in latencies],
    }


def measure(config: dict, clients_count: int, requests: int, client_node, logs: Path) -> dict:
    from maru_planner.ros.planning_client import call_until_answered  # ROS loads after configure_loopback_dds
    from maru_planner_interfaces.srv import PlanMotion

    label = config["label"]
    log_path = logs / f"node_{config['planner']}_{config['workers']}_{int(config['processes'])}.log"
    with open(log_path, "w") as node_log:
        t_start = time.perf_counter()
        node = start_node(config, requests, node_log)
        clients = [client_node.create_client(PlanMotion, "plan_motion") for _ in range(clients_count)]
        try:
            for client in clients:
                if not client.wait_for_service(timeout_sec=300.0):
                    raise RuntimeError(f"{label}: plan_motion never appeared; node log:\n{log_path.read_text()}")
            call_until_answered(clients[0], make_request(SEEDS[0], config["planner"]), CALL_TIMEOUT)
            startup = time.perf_counter() - t_start
            for client in clients[1:]:  # both directions matched for every client: no answer gets lost
                call_until_answered(client, make_request(SEEDS[0], config["planner"]), CALL_TIMEOUT)
            log(f"{label}: ready after {startup:.1f} s; {requests} requests from {clients_count} clients ...")
            seeds = [SEEDS[i % len(SEEDS)] for i in range(requests)]
            result = drive(clients, seeds, config["planner"])
        finally:
            for client in clients:
                client_node.destroy_client(client)
            stop_node(node)
    log(f"{label}: {result['requests_per_s']:.2f} requests/s, {result['failures']} failed")
    return {**config, "startup_s": startup, **result}


def run(configs: list[dict], clients: int, requests: int) -> dict:
    import rclpy  # ROS loads after main's configure_loopback_dds
    from rclpy.executors import MultiThreadedExecutor

    rclpy.init()
    client_node = rclpy.create_node("throughput_clients")
    executor = MultiThreadedExecutor(num_threads=2)
    executor.add_node(client_node)
    threading.Thread(target=executor.spin, daemon=True).start()
    try:
        with tempfile.TemporaryDirectory(prefix="throughput_") as logs:
            rows = [measure(config, clients, requests, client_node, Path(logs)) for config in configs]
    finally:
        executor.shutdown(timeout_sec=2.0)
        client_node.destroy_node()
        rclpy.shutdown()
    reference = {row["planner"]: row["requests_per_s"] for row in rows if row["processes"] and row["workers"] == 1}
    for row in rows:
        row["speedup_vs_1_process_worker"] = row["requests_per_s"] / reference[row["planner"]]
    return {
        "clients": clients,
        "requests": requests,
        "cpus": os.cpu_count(),
        "target_ratio": TARGET_RATIO,
        "rows": rows,
    }


def table(results: dict) -> str:
    lines = [
        f"# planning_node throughput ({results['clients']} concurrent clients, {results['requests']} requests, "
        f"{results['cpus']} CPUs)",
        "",
        "Each request: the 13-DOF desk-and-box problem on the default config (sphere checker), RC-RRT or RRTConnect,",
        "its own seed (the same requests in every configuration). Start-up: node process start until its first",
        "answer.",
        "",
        "| configuration | requests/s | x 1 process worker (same planner) | latency median ms | p90 ms "
        "| core median ms | failed | start-up s |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for row in results["rows"]:
        lines.append(
            f"| {row['label']} | {row['requests_per_s']:.2f} | {row['speedup_vs_1_process_worker']:.2f} | "
            f"{row['latency_median_ms']:.0f} | {row['latency_p90_ms']:.0f} | {row['core_median_ms']:.0f} | "
            f"{row['failures']} | {row['startup_s']:.1f} |"
        )
    lines.append("")
    for planner in dict.fromkeys(row["planner"] for row in results["rows"]):
        best = max(row["speedup_vs_1_process_worker"] for row in results["rows"]
                   if row["planner"] == planner and row["processes"] and row["workers"] > 1)  # fmt: skip
        if planner == "RCRRT":
            verdict = "met" if best >= results["target_ratio"] else "missed"
            lines.append(f"Target (RC-RRT: planning keeps the cores busy): process workers >= "
                         f"{results['target_ratio']}x one worker: **{verdict}** ({best:.2f}x).")  # fmt: skip
        else:
            lines.append(f"{planner}: process workers {best:.2f}x one worker; a request plans in ~10 ms, so the node's "
                         "own per-request work and the clients, on the same two cores, bound the rate.")  # fmt: skip
    return "\n".join(lines) + "\n"


def plot(results: dict, path: Path) -> None:
    import matplotlib  # only for the picture

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = results["rows"]
    fig, ax = plt.subplots(figsize=(8, 4))
    colors = ["tab:blue" if row["processes"] else "tab:gray" for row in rows]
    ax.bar([row["label"] for row in rows], [row["requests_per_s"] for row in rows], color=colors)
    reference = rows[0]["requests_per_s"]  # RC-RRT's one process worker
    ax.axhline(TARGET_RATIO * reference, color="tab:red", linestyle="--",
               label=f"target {TARGET_RATIO}x one worker (RC-RRT)")  # fmt: skip
    ax.tick_params(axis="x", labelrotation=20, labelsize=7)
    ax.set_ylabel("requests / s")
    ax.set_title(f"planning_node throughput, {results['clients']} concurrent clients ({results['cpus']} CPUs)")
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--requests", type=int, default=96, help="requests per configuration")
    parser.add_argument("--clients", type=int, default=8, help="concurrent client threads")
    parser.add_argument("--workers", type=int, default=2, help="workers of the parallel configurations")
    parser.add_argument("--quick", action="store_true", help="16 requests, process workers only (a smoke run)")
    args = parser.parse_args(argv)
    if min(args.requests, args.clients, args.workers) < 1:
        print("throughput: --requests, --clients and --workers must be >= 1", file=sys.stderr)
        return 2
    configure_loopback_dds(random_domain=True)
    results = run(configurations(args.workers, args.quick), args.clients, 16 if args.quick else args.requests)
    write_results(RESULTS / NAME, results, table(results), lambda path: plot(results, path), quick=args.quick)
    return 0


if __name__ == "__main__":
    sys.exit(main())

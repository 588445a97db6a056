"""MovingAI grid benchmark: our 2-D A* (JPS, no corner cutting) beside pyastar2d, pathfinding, python-motion-planning.

Every one of our paths is scored against the scenario's optimal length (the
tolerance is one unit of the last printed digit -- the dao/random files give
6 significant digits, truncated, room/maze/street 8 decimals -- or 1e-6 relative,
whichever is larger: the long maze lengths carry float rounding of the
generator in their 8th digit). Peers run on the same
queries in the same run: pyastar2d (C++; unit-cost diagonals and corner
cutting allowed, so its lengths are not the MovingAI ones: we report how
many differ), pathfinding (pure Python, octile, no corner cutting) and
python-motion-planning (AStar on its Grid) on a spread subset (they are slow).

    .venv/bin/python bench/movingai.py [--quick] [--sets dao room ...] [--peer-queries N]

Writes bench/results/movingai.{json,md,png}.
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
import sys
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from _common import RESULTS, data_dir, log, require_data, require_peers, results_dir  # noqa: E402

from maru_planner.base.astar import astar_2d, path_cost  # noqa: E402

DATA = data_dir("movingai")
SETS = ("dao", "room", "maze", "street", "random")
PEER_MODULES = {"pathfinding": "pathfinding", "pmp": "python_motion_planning"}


def load_map(path: Path) -> np.ndarray:
    """(H, W) bool, True = blocked; row = y, col = x as in the .scen files."""
    lines = path.read_text().replace("\r", "").split("\n")
    header = {}
    i = 0
    while lines[i].strip() != "map":
        key, _, value = lines[i].partition(" ")
        header[key] = value.strip()
        i += 1
    h, w = int(header["height"]), int(header["width"])
    rows = lines[i + 1 : i + 1 + h]
    return np.array([[ch not in ".GS" for ch in row[:w]] for row in rows], dtype=bool)


def load_scenarios(path: Path) -> list[dict]:
    out = []
    for line in path.read_text().replace("\r", "").split("\n")[1:]:
        parts = line.split("\t")
        if len(parts) < 9:
            continue
        length_text = parts[8].strip()
        decimals = len(length_text.split(".")[1]) if "." in length_text else 0
        out.append(
            {
                "bucket": int(parts[0]),
                "start": (int(parts[5]), int(parts[4])),  # (row, col) = (y, x)
                "goal": (int(parts[7]), int(parts[6])),
                "optimal": float(length_text),
                # one unit of the last printed digit (dao/random print 6 significant digits, truncated:
                # 235.764 for 235.76450) or 1e-6 relative (the long maze/room lengths were summed in
                # floating point by the generator and differ from the exact sums in the 7th-8th digit)
                "tol": max(10.0**-decimals, 1e-6 * float(length_text)) + 1e-9,
            }
        )
    return out


def spread(items: list, count: int) -> list:
    """``count`` items evenly spread over the list (all buckets represented)."""
    if count >= len(items):
        return list(items)
    idx = np.linspace(0, len(items) - 1, count).round().astype(int)
    return [items[i] for i in idx]


def corner_cuts(path: np.ndarray, blocked: np.ndarray) -> bool:
    for (r0, c0), (r1, c1) in zip(path[:-1], path[1:], strict=False):
        if r0 != r1 and c0 != c1 and (blocked[r1, c0] or blocked[r0, c1]):
            return True
    return False


# ------------------------------------------------------------------- runners
def run_ours(blocked, scen):
    t = time.perf_counter()
    path, cost, _ = astar_2d(blocked, scen["start"], scen["goal"])
    dt = time.perf_counter() - t
    ok = len(path) > 0 and abs(cost - scen["optimal"]) <= scen["tol"] and abs(path_cost(path) - cost) < 1e-9
    return dt, cost, ok


def run_pyastar2d(weights, blocked, scen):
    import pyastar2d

    t = time.perf_counter()
    path = pyastar2d.astar_path(weights, scen["start"], scen["goal"], allow_diagonal=True)
    dt = time.perf_counter() - t
    length = path_cost(path) if path is not None else math.inf
    return dt, length, abs(length - scen["optimal"]) <= scen["tol"], path is not None and corner_cuts(path, blocked)


class PathfindingPeer:
    def __init__(self, blocked):
        from pathfinding.core.diagonal_movement import DiagonalMovement
        from pathfinding.core.grid import Grid
        from pathfinding.finder.a_star import AStarFinder

        self.grid = Grid(matrix=(~blocked).astype(int).tolist())
        self.finder = AStarFinder(diagonal_movement=DiagonalMovement.only_when_no_obstacle)

    def run(self, scen):
        (sr, sc), (gr, gc) = scen["start"], scen["goal"]
        self.grid.cleanup()
        t = time.perf_counter()
        path, _ = self.finder.find_path(self.grid.node(sc, sr), self.grid.node(gc, gr), self.grid)
        dt = time.perf_counter() - t
        length = path_cost(np.array([(n.y, n.x) for n in path])) if path else math.inf
        return dt, length, abs(length - scen["optimal"]) <= scen["tol"]


class PmpPeer:
    def __init__(self, blocked):
        from python_motion_planning.common import TYPES, Grid
        from python_motion_planning.path_planner.graph_search.a_star import AStar

        h, w = blocked.shape
        type_map = np.where(blocked.T, TYPES.OBSTACLE, TYPES.FREE).astype(np.int8)  # indexed (x, y)
        self.planner = AStar(
            map_=Grid(bounds=[[0, w], [0, h]], resolution=1.0, type_map=type_map), start=(0, 0), goal=(0, 0)
        )

    def run(self, scen):
        (sr, sc), (gr, gc) = scen["start"], scen["goal"]
        self.planner.start, self.planner.goal = (sc, sr), (gc, gr)
        t = time.perf_counter()
        _, info = self.planner.plan()
        dt = time.perf_counter() - t
        length = float(info["length"]) if info["success"] else math.inf
        return dt, length, abs(length - scen["optimal"]) <= scen["tol"]


# --------------------------------------------------------------------- main
def bench_map(map_path: Path, per_map: int | None, peer_queries: int, peers: list[str], peer_max_length: float) -> dict:
    blocked = load_map(map_path)
    scens = load_scenarios(Path(str(map_path) + ".scen"))
    chosen = spread(scens, per_map) if per_map else scens
    weights = np.where(blocked, np.inf, 1.0).astype(np.float32)
    ours, py = [], []
    for scen in chosen:
        ours.append(run_ours(blocked, scen))
        py.append(run_pyastar2d(weights, blocked, scen))
    record = {
        "map": map_path.stem,
        "set": map_path.parent.name,
        "size": list(blocked.shape),
        "queries": len(chosen),
        "ours_exact": sum(ok for _, _, ok in ours),
        "ours_ms": [1e3 * dt for dt, _, _ in ours],
        "ours_max_abs_err": max(abs(c - s["optimal"]) for (_, c, _), s in zip(ours, chosen, strict=True)),
        "pyastar2d_ms": [1e3 * dt for dt, _, _, _ in py],
        "pyastar2d_exact": sum(ok for _, _, ok, _ in py),
        "pyastar2d_corner_cuts": sum(cc for *_, cc in py),
    }
    short = [i for i, s in enumerate(chosen) if s["optimal"] <= peer_max_length]
    peer_idx = [short[int(i)] for i in np.linspace(0, len(short) - 1, min(peer_queries, len(short))).round()]
    record["peer_idx"] = peer_idx
    for name, cls in (("pathfinding", PathfindingPeer), ("pmp", PmpPeer)):
        if name not in peers or not peer_idx:
            continue
        peer = cls(blocked)
        runs = [peer.run(chosen[i]) for i in peer_idx]
        record[f"{name}_ms"] = [1e3 * dt for dt, _, _ in runs]
        record[f"{name}_exact"] = sum(ok for _, _, ok in runs)
    return record


def summarise(records: list[dict]) -> dict:
    def med(values):
        return statistics.median(values) if values else math.nan

    rows = {}
    groups = {s: [r for r in records if r["set"] == s] for s in SETS}
    groups["all"] = records
    for name, recs in groups.items():
        if not recs:
            continue
        ours = [t for r in recs for t in r["ours_ms"]]
        py = [t for r in recs for t in r["pyastar2d_ms"]]
        row = {
            "queries": len(ours),
            "ours_exact": sum(r["ours_exact"] for r in recs),
            "ours_median_ms": med(ours),
            "pyastar2d_median_ms": med(py),
            "ratio_vs_pyastar2d": med(ours) / med(py),
            "pyastar2d_exact": sum(r["pyastar2d_exact"] for r in recs),
            "pyastar2d_corner_cuts": sum(r["pyastar2d_corner_cuts"] for r in recs),
            "ours_max_abs_err": max(r["ours_max_abs_err"] for r in recs),
        }
        for peer in ("pathfinding", "pmp"):
            peer_ms = [t for r in recs for t in r.get(f"{peer}_ms", [])]
            if peer_ms:
                ours_same = [r["ours_ms"][i] for r in recs if f"{peer}_ms" in r for i in r["peer_idx"]]
                row[f"{peer}_queries"] = len(peer_ms)
                row[f"{peer}_median_ms"] = med(peer_ms)
                row[f"{peer}_exact"] = sum(r.get(f"{peer}_exact", 0) for r in recs)
                row[f"speedup_vs_{peer}"] = med(peer_ms) / med(ours_same)
        rows[name] = row
    return rows


def write_outputs(summary: dict, records: list[dict], args) -> None:
    out = results_dir(args.quick)  # --quick: bench/results/quick/, never the committed results
    out.mkdir(parents=True, exist_ok=True)
    with open(out / "movingai.json", "w") as f:
        json.dump(
            {
                "quick": args.quick,
                "summary": summary,
                "maps": [
                    {k: v for k, v in r.items() if not k.endswith("_ms") and k != "peer_idx"}
                    | {
                        k.replace("_ms", "_median_ms"): statistics.median(v)
                        for k, v in r.items()
                        if k.endswith("_ms") and v
                    }
                    for r in records
                ],
            },
            f,
            indent=1,
        )
    lines = [
        "# MovingAI benchmark (2-D A*, 8-connected, octile, no corner cutting)",
        "",
        f"Run: {'--quick' if args.quick else 'full'}; median time per query in ms; exact = path length equal to",
        "the scenario's optimal length (to one unit of its last printed digit, or 1e-6 relative when larger).",
        "pyastar2d allows corner cutting and costs",
        "diagonals 1, so its lengths are not the MovingAI ones. Peers' speed-ups are on their own query subset",
        "(ours timed on the same queries, restricted to shorter queries: see --peer-max-length).",
        "",
        "| set | queries | ours exact | ours ms | pyastar2d ms | ours / pyastar2d | pyastar2d exact (cuts) "
        "| pathfinding ms (n) | vs pathfinding | pmp ms (n) | vs pmp |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for name, r in summary.items():
        lines.append(
            f"| {name} | {r['queries']} | {r['ours_exact']}/{r['queries']} | {r['ours_median_ms']:.3f} | "
            f"{r['pyastar2d_median_ms']:.3f} | {r['ratio_vs_pyastar2d']:.2f} | {r['pyastar2d_exact']} "
            f"({r['pyastar2d_corner_cuts']}) | {r.get('pathfinding_median_ms', math.nan):.1f} "
            f"({r.get('pathfinding_queries', 0)}) | {r.get('speedup_vs_pathfinding', math.nan):.0f}x | "
            f"{r.get('pmp_median_ms', math.nan):.1f} ({r.get('pmp_queries', 0)}) | "
            f"{r.get('speedup_vs_pmp', math.nan):.0f}x |"
        )
    (out / "movingai.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))

    plot(summary, out / "movingai.png")
    log(f"wrote {out}/movingai.{{json,md,png}}")


def plot(summary: dict, path: Path) -> None:
    """Median ms per set (log scale); the slow peers' bars are on their short-query subset."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = list(summary)
    fig, ax = plt.subplots(figsize=(8, 4))
    width = 0.2
    bars = [
        ("ours_median_ms", "ours (JPS, numba), all queries"),
        ("pyastar2d_median_ms", "pyastar2d, all queries"),
        ("pathfinding_median_ms", "pathfinding, short-query subset"),
        ("pmp_median_ms", "python-motion-planning, short-query subset"),
    ]
    for i, (key, label) in enumerate(bars):
        values = [summary[n].get(key, math.nan) for n in names]
        ax.bar(np.arange(len(names)) + (i - 1.5) * width, values, width, label=label)
    ax.set_yscale("log")
    ax.set_xticks(np.arange(len(names)), names)
    ax.set_ylabel("median ms per query")
    total = summary.get("all", {})
    ax.set_title(
        f"MovingAI: median time per query (log scale); our paths exact: "
        f"{total.get('ours_exact', 0)}/{total.get('queries', 0)}",
        fontsize=10,
    )
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="40 queries per map, 4 for the slow peers")
    parser.add_argument("--sets", nargs="+", default=list(SETS), choices=SETS)
    parser.add_argument("--per-map", type=int, help="queries per map (default: all, 40 with --quick)")
    parser.add_argument("--peer-queries", type=int, help="queries per map for pathfinding / pmp (default 4 / 12)")
    parser.add_argument("--peers", nargs="*", default=["pathfinding", "pmp"], choices=list(PEER_MODULES))
    parser.add_argument(
        "--peer-max-length",
        type=float,
        help="peers only get queries up to this optimal length (default 150, 400 full): pure "
        "Python A* takes minutes on the longest maze queries",
    )
    parser.add_argument("--replot", action="store_true", help="only redraw the picture from the JSON")
    args = parser.parse_args(argv)
    if args.replot:
        plot(json.loads((RESULTS / "movingai.json").read_text())["summary"], RESULTS / "movingai.png")
        return 0
    require_data(*(DATA / s for s in args.sets))
    require_peers("pyastar2d", *(PEER_MODULES[p] for p in args.peers))
    per_map = args.per_map or (40 if args.quick else None)
    peer_queries = args.peer_queries or (4 if args.quick else 12)
    astar_2d(np.zeros((3, 3), bool), (0, 0), (2, 2))  # compile / load the numba cache outside the timings
    records = []
    maps = sorted(p for s in args.sets for p in (DATA / s).glob("*.map"))
    for i, map_path in enumerate(maps):
        t = time.perf_counter()
        peer_max = args.peer_max_length or (150.0 if args.quick else 400.0)
        records.append(bench_map(map_path, per_map, peer_queries, args.peers, peer_max))
        r = records[-1]
        print(
            f"[{i + 1}/{len(maps)}] {r['set']}/{r['map']}: {r['queries']} queries, exact {r['ours_exact']}, "
            f"ours {statistics.median(r['ours_ms']):.3f} ms, pyastar2d {statistics.median(r['pyastar2d_ms']):.3f} ms "
            f"({time.perf_counter() - t:.1f} s)",
            file=sys.stderr,
        )
    write_outputs(summarise(records), records, args)
    return 0


if __name__ == "__main__":
    sys.exit(main())

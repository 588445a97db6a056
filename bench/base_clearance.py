"""Issue 37: base paths that keep their distance -- Nav2-style inflation costs and smoothing for the grid A*.

On MovingAI maps (one per family, scenarios spread over the buckets) and the 300 BARN worlds, each query is
planned by our 2-D A* plain (``cost_travel_multiplier=0``: the shortest path, JPS), cost-aware, and
cost-aware + smoothed, beside python-motion-planning's and pathfinding's A* on the same grown map (and
pathfinding's A* with the same cost as node weights: the same objective, so the same optimal cost).
Each path gets its length over the shortest path's, its exact clearance (min and mean, ``clearance.py``),
whether it touches a lethal cell (cost >= 253: within the inscribed radius), and the plan time (the best of
``--repeats`` runs of ``planner.plan``, cost layer included; peers: their search only).

Settings (Nav2's scaled to the map): BARN 0.15 m cells, the challenge's costmap (Jackal footprint
0.42 x 0.33 m, ``inflation_radius`` 0.30 m, Nav2's ``cost_scaling_factor`` 10), the robot a disc of the
footprint's circumradius (0.267 m); MovingAI cells of 1 unit, a point robot, inflation of 5 cells, scaling 3.
``--multiplier`` sets ``cost_travel_multiplier`` (default 2.0, Smac 2D's and our A*'s default).

    .venv/bin/python bench/base_clearance.py [--quick] [--multiplier M] [--repeats N]

Writes bench/results/base_clearance.{json,md,png}; the JSON's ``summary`` holds ``mean_clearance_ratio``,
``length_ratio``, ``lethal_paths``, ``plan_time_ratio`` per data set for the cost-aware planners.
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))

from _common import RESULTS, Progress, data_dir, log, require_data, require_peers, write_results  # noqa: E402
from movingai import load_map, load_scenarios, spread  # noqa: E402

from maru_planner.base.astar import GridAStarPlanner, astar_2d  # noqa: E402
from maru_planner.base.clearance import distance_transform, path_clearance, resample, to_cell_units  # noqa: E402
from maru_planner.base.costmap import INSCRIBED_INFLATED_OBSTACLE, cost_layer  # noqa: E402
from maru_planner.base.footprint import footprint_radii, rectangle  # noqa: E402
from maru_planner.base.grid import OccupancyGrid  # noqa: E402

DATA = data_dir()
MOVINGAI_MAPS = ["dao/den312d", "room/32room_000", "maze/maze512-16-0", "street/Berlin_0_256", "random/random512-20-0"]
BARN_RESOLUTION = 0.15
BARN_START, BARN_GOAL = (14, 19), (14, 86)  # full_grid cells (README: start and goal of the challenge)
JACKAL = rectangle(0.42, 0.33)
OURS = ("plain", "cost", "cost_smooth")
PEERS = ("pmp", "pathfinding", "pathfinding_cost")
PEER_MODULES = {"pmp": "python_motion_planning", "pathfinding": "pathfinding", "pathfinding_cost": "pathfinding"}


@dataclass
class Case:
    """One query: the map, start/goal cells, the robot radius and the cost-layer settings."""

    family: str
    name: str
    grid: OccupancyGrid
    start: tuple[int, int]
    goal: tuple[int, int]
    robot_radius: float
    inflation_radius: float
    cost_scaling_factor: float
    optimal: float = 0.0  # the scenario's optimal length (cells; 0 for BARN)


def movingai_cases(per_map: int, inflation: float = 5.0, scaling: float = 3.0) -> list[Case]:
    cases = []
    for entry in MOVINGAI_MAPS:
        path = DATA / "movingai" / f"{entry}.map"
        grid = OccupancyGrid(load_map(path), 1.0)
        for i, scen in enumerate(spread(load_scenarios(Path(f"{path}.scen")), per_map)):
            cases.append(
                Case(
                    entry.split("/")[0],
                    f"{path.stem}#{i}",
                    grid,
                    scen["start"],
                    scen["goal"],
                    0.0,
                    inflation,
                    scaling,
                    scen["optimal"],
                )
            )
    return cases


def barn_cases(
    worlds: list[int], inflation: float = 0.30, scaling: float = 10.0, robot: str = "circumscribed"
) -> list[Case]:
    r_in, r_out = footprint_radii(JACKAL)
    radius = r_out if robot == "circumscribed" else r_in
    cases = []
    for n in worlds:
        occupied = np.load(DATA / "barn" / "full_grid_files" / f"full_grid_{n}.npy").astype(bool)
        grid = OccupancyGrid(occupied, BARN_RESOLUTION)
        cases.append(Case("barn", f"world_{n}", grid, BARN_START, BARN_GOAL, radius, inflation, scaling))
    return cases


# ---------------------------------------------------------------------------------------------- ours
def our_planners(case: Case, multiplier: float) -> dict[str, GridAStarPlanner]:
    costs = dict(inflation_radius=case.inflation_radius, cost_scaling_factor=case.cost_scaling_factor)
    return {
        "plain": GridAStarPlanner(robot_radius=case.robot_radius, cost_travel_multiplier=0.0, **costs),
        "cost": GridAStarPlanner(robot_radius=case.robot_radius, cost_travel_multiplier=multiplier, **costs),
        "cost_smooth": GridAStarPlanner(
            robot_radius=case.robot_radius, cost_travel_multiplier=multiplier, smooth=True, **costs
        ),
    }


def run_ours(planner: GridAStarPlanner, case: Case, repeats: int) -> tuple[np.ndarray, float, str]:
    start = (*case.grid.cell_to_world(*case.start), 0.0)
    goal = (*case.grid.cell_to_world(*case.goal), 0.0)
    best, result = math.inf, None
    for _ in range(repeats):
        t = time.perf_counter()
        result = planner.plan(case.grid, start, goal)
        best = min(best, time.perf_counter() - t)
    assert result is not None
    return (result.path[:, :2] if result.success else np.zeros((0, 2))), best, result.status.value


# --------------------------------------------------------------------------------------------- peers
def run_pmp(grown: np.ndarray, case: Case) -> tuple[np.ndarray, float]:
    from python_motion_planning.common import TYPES, Grid
    from python_motion_planning.path_planner.graph_search.a_star import AStar

    h, w = grown.shape
    type_map = np.where(grown.T, TYPES.OBSTACLE, TYPES.FREE).astype(np.int8)  # indexed (x, y)
    planner = AStar(
        map_=Grid(bounds=[[0, w], [0, h]], resolution=1.0, type_map=type_map),
        start=(case.start[1], case.start[0]),
        goal=(case.goal[1], case.goal[0]),
    )
    t = time.perf_counter()
    path, info = planner.plan()
    dt = time.perf_counter() - t
    cells = np.array([(p[1], p[0]) for p in path], dtype=float) if info["success"] else np.zeros((0, 2))
    return cells, dt


def run_pathfinding(grown: np.ndarray, case: Case, weights: np.ndarray | None) -> tuple[np.ndarray, float]:
    from pathfinding.core.diagonal_movement import DiagonalMovement
    from pathfinding.core.grid import Grid
    from pathfinding.finder.a_star import AStarFinder

    matrix = np.where(grown, 0.0, 1.0 if weights is None else 1.0 + weights)
    grid = Grid(matrix=matrix.tolist())
    finder = AStarFinder(diagonal_movement=DiagonalMovement.only_when_no_obstacle)
    (sr, sc), (gr, gc) = case.start, case.goal
    t = time.perf_counter()
    path, _ = finder.find_path(grid.node(sc, sr), grid.node(gc, gr), grid)
    dt = time.perf_counter() - t
    return (np.array([(n.y, n.x) for n in path], dtype=float) if path else np.zeros((0, 2))), dt


# ------------------------------------------------------------------------------------------- scoring
def length(xy: np.ndarray) -> float:
    return float(np.sum(np.linalg.norm(np.diff(xy, axis=0), axis=1))) if len(xy) > 1 else 0.0


def touches_lethal(grid: OccupancyGrid, xy: np.ndarray, cost: np.ndarray) -> bool:
    """Does the polyline (sampled every quarter cell) enter a cell of cost >= 253?"""
    samples, _ = resample(to_cell_units(grid, xy))
    rows = np.clip(np.floor(samples[:, 0]).astype(int), 0, grid.height - 1)
    cols = np.clip(np.floor(samples[:, 1]).astype(int), 0, grid.width - 1)
    return bool(np.any(cost[rows, cols] >= INSCRIBED_INFLATED_OBSTACLE))


def score(case: Case, xy: np.ndarray, seconds: float, edt: np.ndarray, cost: np.ndarray) -> dict:
    if len(xy) == 0:
        return {"solved": False, "time_ms": 1e3 * seconds}
    clearance = path_clearance(case.grid, xy, edt)
    return {
        "solved": True,
        "time_ms": 1e3 * seconds,
        "length_m": length(xy),
        "min_clearance_m": clearance.min_m,
        "mean_clearance_m": clearance.mean_m,
        "lethal": touches_lethal(case.grid, xy, cost),
        "xy": xy,
    }


def bench_case(case: Case, multiplier: float, repeats: int, peers: list[str], peer_max: float = math.inf) -> dict:
    grid = case.grid
    layer = cost_layer(grid, case.robot_radius, case.robot_radius, case.inflation_radius, case.cost_scaling_factor)
    edt = distance_transform(grid.occupied)
    row = {"family": case.family, "case": case.name, "paths": {}}
    for name, planner in our_planners(case, multiplier).items():
        xy, seconds, status = run_ours(planner, case, repeats)
        row["paths"][name] = score(case, xy, seconds, edt, layer.cost) | {"status": status}
    grown = grid.inflate(case.robot_radius).occupied
    weights = layer.traversal_weights(multiplier)
    row["search_ms"] = search_times(grown, case, weights, repeats)
    runners = {
        "pmp": lambda: run_pmp(grown, case),
        "pathfinding": lambda: run_pathfinding(grown, case, None),
        "pathfinding_cost": lambda: run_pathfinding(grown, case, weights),
    }
    for name in peers if case.optimal <= peer_max else []:
        cells, seconds = runners[name]()
        xy = grid.cells_to_world(cells) if len(cells) else np.zeros((0, 2))
        row["paths"][name] = score(case, xy, seconds, edt, layer.cost)
    for name in ("cost", "pathfinding_cost"):  # the same objective: the same optimum
        entry = row["paths"].get(name)
        if entry and entry["solved"]:
            entry["objective"] = objective(grid, entry["xy"], weights)
    shortest = row["paths"]["plain"].get("length_m")
    for entry in row["paths"].values():
        if entry["solved"] and shortest:
            entry["length_ratio"] = entry["length_m"] / shortest
    return row


def search_times(grown: np.ndarray, case: Case, weights: np.ndarray, repeats: int) -> dict[str, float]:
    """Search only (ms, best of ``repeats``) on the grown map: JPS, plain A*, and plain A* with the weights."""
    out = {}
    for name, kwargs in (("jps", {}), ("astar", {"method": "astar"}), ("weighted", {"cell_weight": weights})):
        best = math.inf
        for _ in range(repeats):
            t = time.perf_counter()
            astar_2d(grown, case.start, case.goal, **kwargs)
            best = min(best, time.perf_counter() - t)
        out[name] = 1e3 * best
    return out


def objective(grid: OccupancyGrid, xy: np.ndarray, weights: np.ndarray) -> float:
    """Length + multiplier x cost of a cell-centre path (cells), as the cost-aware search counts it."""
    cells = np.array([grid.world_to_cell(x, y) for x, y in xy])
    steps = np.linalg.norm(np.diff(cells, axis=0), axis=1)
    return float(np.sum(steps * (1.0 + weights[cells[1:, 0], cells[1:, 1]])))


# ------------------------------------------------------------------------------------------- summary
def summarise(rows: list[dict], names: list[str]) -> dict:
    """Per planner: ratios to the plain (shortest) path on the queries both solved."""
    out = {}
    for name in names:
        pairs = [
            (r["paths"]["plain"], r["paths"][name])
            for r in rows
            if name in r["paths"] and r["paths"]["plain"]["solved"] and r["paths"][name]["solved"]
        ]
        if not pairs:
            continue
        clear = [p["mean_clearance_m"] / b["mean_clearance_m"] for b, p in pairs if b["mean_clearance_m"] > 0]
        min_clear = [p["min_clearance_m"] / b["min_clearance_m"] for b, p in pairs if b["min_clearance_m"] > 0]
        lengths = [p["length_ratio"] for _, p in pairs]
        times = [p["time_ms"] / b["time_ms"] for b, p in pairs]
        out[name] = {
            "queries": len(pairs),
            "unsolved": sum(1 for r in rows if name in r["paths"] and not r["paths"][name]["solved"]),
            "mean_clearance_ratio": statistics.fmean(clear) if clear else math.nan,
            "median_clearance_ratio": statistics.median(clear) if clear else math.nan,
            "min_clearance_ratio": statistics.fmean(min_clear) if min_clear else math.nan,
            "length_ratio": statistics.fmean(lengths),
            "max_length_ratio": max(lengths),
            "lethal_paths": sum(p["lethal"] for _, p in pairs),
            "plan_time_ratio": statistics.median(times),
            "median_time_ms": statistics.median(p["time_ms"] for _, p in pairs),
            "mean_clearance_m": statistics.fmean(p["mean_clearance_m"] for _, p in pairs),
            "min_clearance_m": min(p["min_clearance_m"] for _, p in pairs),
        }
        if name == "pathfinding_cost":  # the same objective as our cost-aware search: the same optimum?
            same = [
                abs(r["paths"][name]["objective"] - r["paths"]["cost"]["objective"])
                <= 1e-6 * r["paths"]["cost"]["objective"]
                for r in rows
                if r["paths"].get(name, {}).get("solved") and r["paths"]["cost"]["solved"]
            ]
            out[name]["same_optimum"] = f"{sum(same)}/{len(same)}"
    return out


def search_summary(rows: list[dict]) -> dict:
    """Medians of the search-only time ratios: what the costs cost, what losing JPS costs."""
    ratio = {
        "weighted_over_jps": [r["search_ms"]["weighted"] / r["search_ms"]["jps"] for r in rows],
        "weighted_over_astar": [r["search_ms"]["weighted"] / r["search_ms"]["astar"] for r in rows],
        "astar_over_jps": [r["search_ms"]["astar"] / r["search_ms"]["jps"] for r in rows],
    }
    return {k: statistics.median(v) for k, v in ratio.items() if v}


# (label, multiplier, MovingAI (inflation, scaling), BARN (inflation, scaling), BARN robot): what the targets take
SWEEP = [
    ("issue's settings", 5.0, (5.0, 3.0), (0.30, 10.0), "circumscribed"),
    ("issue's settings", 10.0, (5.0, 3.0), (0.30, 10.0), "circumscribed"),
    ("issue's settings", 20.0, (5.0, 3.0), (0.30, 10.0), "circumscribed"),
    ("gentle decay, BARN inscribed disc", 2.0, (5.0, 0.6), (0.30, 10.0), "inscribed"),
    ("gentle decay, BARN inscribed disc", 10.0, (5.0, 0.6), (0.30, 10.0), "inscribed"),
    ("wide gentle decay", 10.0, (10.0, 0.3), (0.60, 3.0), "inscribed"),
    ("wide, steep weight", 100.0, (20.0, 0.2), (0.90, 2.0), "inscribed"),
    ("wide, extreme weight", 1000.0, (15.0, 0.4), (0.90, 2.0), "inscribed"),
]

TARGETS = {
    "mean_clearance_ratio": (">=", 2.0),
    "length_ratio": ("<=", 1.15),
    "plan_time_ratio": ("<=", 2.0),
    "lethal_paths": ("<=", 0),
}


def verdicts(stats: dict) -> dict:
    return {key: (stats[key] >= bound if op == ">=" else stats[key] <= bound) for key, (op, bound) in TARGETS.items()}


def sweep(per_map: int, worlds: list[int]) -> list[dict]:
    """The cost-aware planners under other settings (one plan per query, no peers)."""
    out = []
    progress = Progress(len(SWEEP))
    for label, multiplier, movingai, barn, robot in SWEEP:
        cases = movingai_cases(per_map, *movingai) + barn_cases(worlds, *barn, robot)
        rows = [bench_case(case, multiplier, 1, []) for case in cases]
        out.append(
            {
                "label": label,
                "multiplier": multiplier,
                "movingai": list(movingai),
                "barn": list(barn),
                "barn_robot": robot,
                "movingai_summary": summarise([r for r in rows if r["family"] != "barn"], list(OURS)),
                "movingai_families": {
                    family: summarise([r for r in rows if r["family"] == family], list(OURS))
                    for family in sorted({r["family"] for r in rows if r["family"] != "barn"})
                },
                "barn_summary": summarise([r for r in rows if r["family"] == "barn"], list(OURS)),
            }
        )
        progress.step(f"{label} x{multiplier:g}")
    return out


def sweep_markdown(rows: list[dict]) -> str:
    lines = [
        "",
        "## What the targets take: the cost-aware + smoothed planner under other settings",
        "",
        "One plan per query, the same queries. MovingAI (inflation cells, scaling per cell); BARN (inflation m, "
        "scaling 1/m, the disc the grown map uses).",
        "",
        "| settings | multiplier | MovingAI | BARN | MovingAI clearance ratio / length ratio | "
        "BARN clearance ratio / length ratio | lethal | MovingAI per family: clearance / length |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        m, b = r["movingai_summary"].get("cost_smooth", {}), r["barn_summary"].get("cost_smooth", {})
        lines.append(
            f"| {r['label']} | {r['multiplier']:g} | {r['movingai'][0]:g} / {r['movingai'][1]:g} | "
            f"{r['barn'][0]:g} / {r['barn'][1]:g}, {r['barn_robot']} | "
            f"{m.get('mean_clearance_ratio', math.nan):.2f} / {m.get('length_ratio', math.nan):.3f} | "
            f"{b.get('mean_clearance_ratio', math.nan):.2f} / {b.get('length_ratio', math.nan):.3f} | "
            f"{m.get('lethal_paths', 0) + b.get('lethal_paths', 0)} | {per_family(r)} |"
        )
    lines += [
        "",
        "Random maps (20 % of cells blocked, scattered) bound what any setting reaches: their free space leaves "
        "no room to keep away from obstacles, so their clearance ratio stays near 1 at any weight.",
    ]
    return "\n".join(lines) + "\n"


def per_family(row: dict) -> str:
    return ", ".join(
        f"{family} {s.get('cost_smooth', {}).get('mean_clearance_ratio', math.nan):.2f} / "
        f"{s.get('cost_smooth', {}).get('length_ratio', math.nan):.2f}"
        for family, s in row.get("movingai_families", {}).items()
    )


def summary_markdown(summary: dict) -> str:
    """Ours on each data set as a whole (the rows above): the table docs/base.md quotes."""
    lines = [
        "",
        "## Summary: ours against the shortest path",
        "",
        "| data set | planner | mean clearance ratio | min "
        "clearance ratio | length ratio (max) | lethal paths | plan time ratio | targets missed |",
        "|---" * 8 + "|",
    ]
    for family, name in [(f, n) for f in ("movingai", "barn") for n in OURS[1:] if n in summary.get(f, {})]:
        s = summary[family][name]
        missed = ", ".join(k for k, ok in verdicts(s).items() if not ok) or "none"
        lines.append(f"| {family} | {name} | {s['mean_clearance_ratio']:.2f} | {s['min_clearance_ratio']:.2f} | "
                     f"{s['length_ratio']:.3f} ({s['max_length_ratio']:.3f}) | {s['lethal_paths']} | "
                     f"{s['plan_time_ratio']:.2f} | {missed} |")  # fmt: skip
    return "\n".join(lines) + "\n"


def markdown(summary: dict, searches: dict, args, context: str) -> str:
    lines = [
        "# Base paths that keep their distance (issue 37): cost-aware 2-D A* vs the shortest path",
        "",
        f"Run: {'--quick' if args.quick else 'full'}, cost_travel_multiplier {args.multiplier:g}, best of "
        f"{args.repeats} plan(s) per query; {context}.",
        "Ratios are to our plain A* (the shortest path on the same grown map), per query, then averaged "
        "(plan time: median). Clearance: exact distance from the path to the nearest obstacle cell centre.",
        "Targets: mean clearance >= 2x, length <= 1.15x, plan time <= 2x the plain planner's, 0 lethal paths.",
        "",
        "| data set | planner | queries | mean clearance ratio | min clearance ratio | length ratio (max) "
        "| lethal paths | plan time ratio | median ms | targets met |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for family, per in summary.items():
        for name, s in per.items():
            met = verdicts(s) if name in OURS else {}
            flags = ", ".join(k for k, ok in met.items() if ok) or "-"
            lines.append(
                f"| {family} | {name} | {s['queries']} | {s['mean_clearance_ratio']:.2f} | "
                f"{s['min_clearance_ratio']:.2f} | {s['length_ratio']:.3f} ({s['max_length_ratio']:.3f}) | "
                f"{s['lethal_paths']} | {s['plan_time_ratio']:.2f} | {s['median_time_ms']:.2f} | {flags} |"
            )
    lines += [
        "",
        "Peers' times are their search only, on the grown map we hand them; ours include the grown map and "
        "the cost layer. pathfinding_cost runs pathfinding's A* with weights 1 + multiplier x cost / 252 "
        "(our objective), so its optimum must equal ours: "
        + ", ".join(
            f"{f} {per['pathfinding_cost']['same_optimum']}"
            for f, per in summary.items()
            if "pathfinding_cost" in per and "/" not in f
        )
        + " queries with the same optimal cost.",
        "",
        "Search only (median ratio over queries): "
        + "; ".join(
            f"{f}: weighted A* / JPS {s['weighted_over_jps']:.1f}, weighted / plain A* "
            f"{s['weighted_over_astar']:.2f}, plain A* / JPS {s['astar_over_jps']:.1f}"
            for f, s in searches.items()
        )
        + " (JPS gives way to plain A* once cells cost differently).",
    ]
    return "\n".join(lines) + "\n" + summary_markdown(summary)


def plot(rows: list[dict], cases: dict[str, Case], path: Path, multiplier: float) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    picks = []
    for family in ("barn", "maze", "room"):
        candidates = [r for r in rows if r["family"] == family and r["paths"]["cost_smooth"]["solved"]]
        if candidates:
            picks.append(
                max(
                    candidates,
                    key=lambda r: (
                        r["paths"]["cost_smooth"]["mean_clearance_m"]
                        / max(r["paths"]["plain"]["mean_clearance_m"], 1e-9)
                    ),
                )
            )
    fig, axes = plt.subplots(1, len(picks) + 1, figsize=(5 * (len(picks) + 1), 4.6))
    axes = np.atleast_1d(axes)
    for ax, row in zip(axes, picks, strict=False):
        case = cases[row["case"]]
        layer = cost_layer(
            case.grid, case.robot_radius, case.robot_radius, case.inflation_radius, case.cost_scaling_factor
        )
        ox, oy, _ = case.grid.origin
        extent = (ox, ox + case.grid.width * case.grid.resolution, oy, oy + case.grid.height * case.grid.resolution)
        ax.imshow(layer.cost, origin="lower", cmap="magma_r", extent=extent, vmin=0, vmax=254)
        for name, colour in (("plain", "tab:blue"), ("cost_smooth", "tab:green")):
            entry = row["paths"][name]
            ax.plot(
                entry["xy"][:, 0],
                entry["xy"][:, 1],
                color=colour,
                lw=1.4,
                label=f"{name}: mean clearance {entry['mean_clearance_m']:.2f}, length {entry['length_m']:.1f}",
            )
        both = np.concatenate([row["paths"][n]["xy"] for n in ("plain", "cost_smooth")])
        pad = max(0.15 * float(np.ptp(both, axis=0).max()), 8 * case.grid.resolution)
        ax.set_xlim(both[:, 0].min() - pad, both[:, 0].max() + pad)
        ax.set_ylim(both[:, 1].min() - pad, both[:, 1].max() + pad)
        ax.set_title(f"{row['case']} over its cost map (black: lethal)", fontsize=9)
        ax.legend(fontsize=7, loc="best")
        ax.set_aspect("equal")
    ax = axes[-1]
    for family, marker in (("barn", "o"), ("dao", "s"), ("room", "^"), ("maze", "v"), ("street", "D"), ("random", "x")):
        pts = [
            (
                r["paths"]["cost_smooth"]["length_ratio"],
                r["paths"]["cost_smooth"]["mean_clearance_m"] / r["paths"]["plain"]["mean_clearance_m"],
            )
            for r in rows
            if r["family"] == family
            and r["paths"]["cost_smooth"]["solved"]
            and r["paths"]["plain"]["mean_clearance_m"] > 0
        ]
        if pts:
            ax.scatter(*np.array(pts).T, s=10, marker=marker, label=family, alpha=0.7)
    ax.axhline(2.0, color="grey", ls=":", lw=1)
    ax.axvline(1.15, color="grey", ls=":", lw=1)
    ax.set_xlabel("length / shortest")
    ax.set_ylabel("mean clearance / shortest path's")
    ax.set_title(f"cost-aware + smoothed A* (multiplier {multiplier:g}) per query", fontsize=9)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="4 queries per MovingAI map, 30 BARN worlds, 1 repeat")
    parser.add_argument("--multiplier", type=float, default=2.0, help="cost_travel_multiplier (default 2.0)")
    parser.add_argument("--repeats", type=int, help="plans per query, the best time kept (default 3, 1 quick)")
    parser.add_argument("--per-map", type=int, help="MovingAI queries per map (default 20, 4 quick)")
    parser.add_argument("--peers", nargs="*", default=list(PEERS), choices=PEERS)
    parser.add_argument("--barn-worlds", type=int, help="BARN worlds, spread over 0..299 (default 300, 30 quick)")
    parser.add_argument(
        "--peer-max-length",
        type=float,
        default=150.0,
        help="peers get MovingAI queries up to this optimal length in cells (pure Python A* takes minutes on the "
        "longest; default 150)",
    )
    parser.add_argument("--no-sweep", action="store_true", help="skip the settings sweep (done in full runs)")
    parser.add_argument("--out", default=str(RESULTS / "base_clearance"), help="output stem (json/md/png)")
    parser.add_argument(
        "--movingai",
        nargs=2,
        type=float,
        default=(5.0, 3.0),
        metavar=("INFLATION", "SCALING"),
        help="MovingAI inflation_radius (cells) and cost_scaling_factor (default 5 3)",
    )
    parser.add_argument(
        "--barn",
        nargs=2,
        type=float,
        default=(0.30, 10.0),
        metavar=("INFLATION", "SCALING"),
        help="BARN inflation_radius (m) and cost_scaling_factor (default 0.30 10)",
    )
    parser.add_argument(
        "--barn-robot",
        choices=("circumscribed", "inscribed"),
        default="circumscribed",
        help="BARN disc: the Jackal's circumradius (valid at any heading, default) or its "
        "inscribed radius (Nav2's lethal cells, the rest only costed)",
    )
    args = parser.parse_args(argv)
    require_data(DATA / "movingai", DATA / "barn")
    require_peers(*sorted({PEER_MODULES[p] for p in args.peers}))
    args.repeats = args.repeats or (1 if args.quick else 3)
    per_map = args.per_map or (4 if args.quick else 20)
    count = args.barn_worlds or (30 if args.quick else 300)
    worlds = sorted({int(i) for i in np.linspace(0, 299, count).round()})
    cases = movingai_cases(per_map, *args.movingai) + barn_cases(worlds, *args.barn, args.barn_robot)
    our_planners(cases[0], args.multiplier)["cost_smooth"].plan(
        cases[0].grid,
        (*cases[0].grid.cell_to_world(*cases[0].start), 0),
        (*cases[0].grid.cell_to_world(*cases[0].goal), 0),
    )  # load the compiled kernels outside the timings
    progress = Progress(len(cases))
    rows = []
    t0 = time.perf_counter()
    for case in cases:
        rows.append(bench_case(case, args.multiplier, args.repeats, args.peers, args.peer_max_length))
        progress.step(case.name)
    log(f"{len(cases)} queries in {time.perf_counter() - t0:.0f} s")
    names = list(OURS) + list(args.peers)
    families = sorted({c.family for c in cases if c.family != "barn"})
    summary = {
        "movingai": summarise([r for r in rows if r["family"] in families], names),
        "barn": summarise([r for r in rows if r["family"] == "barn"], names),
    }
    for family in families:
        summary[f"movingai/{family}"] = summarise([r for r in rows if r["family"] == family], names)
    searches = {
        "movingai": search_summary([r for r in rows if r["family"] in families]),
        "barn": search_summary([r for r in rows if r["family"] == "barn"]),
    }
    swept = [] if args.quick or args.no_sweep else sweep(per_map, worlds)
    context = (
        f"{len(rows) - len(worlds)} MovingAI queries ({', '.join(MOVINGAI_MAPS)}), {len(worlds)} BARN worlds; "
        f"peers: {', '.join(args.peers) or 'none'} (on MovingAI the queries up to {args.peer_max_length:g} cells)"
    )
    results = {
        "quick": args.quick,
        "multiplier": args.multiplier,
        "repeats": args.repeats,
        "targets": TARGETS,
        "summary": summary,
        "search_time_ratios": searches,
        "sweep": swept,
        "verdicts": {f: {n: verdicts(s) for n, s in per.items() if n in OURS} for f, per in summary.items()},
        "queries": [
            {
                **{k: v for k, v in r.items() if k != "paths"},
                "paths": {n: {k: v for k, v in p.items() if k != "xy"} for n, p in r["paths"].items()},
            }
            for r in rows
        ],
    }
    by_name = {c.name: c for c in cases}
    text = markdown(summary, searches, args, context) + (sweep_markdown(swept) if swept else "")
    write_results(
        Path(args.out), results, text, lambda png: plot(rows, by_name, png, args.multiplier), quick=args.quick
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())

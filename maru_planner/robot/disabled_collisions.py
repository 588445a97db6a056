"""Which link pairs an SRDF should exclude from self-collision checks.

Like MoveIt's setup assistant: a pair is disabled when the links are
``Adjacent`` (parent and child link, skipping links without geometry), ``Always`` colliding
(in at least 95 % of random configurations: checking it only says "invalid"),
or ``Never`` colliding in ``n_samples`` random configurations within limits --
and, to keep rare-but-possible contacts checked, never closer than
``NEVER_MARGIN`` either.

    python -m maru_planner.robot.disabled_collisions robot.urdf [--samples N]

prints the ``<disable_collisions>`` lines for any URDF.
"""

from __future__ import annotations

import argparse
import sys
from itertools import combinations
from pathlib import Path

import numpy as np
import pinocchio as pin

ALWAYS_FRACTION = 0.95
NEVER_MARGIN = 0.03  # m


def _link_of_geometry(model: pin.Model, geom_model: pin.GeometryModel) -> list[str]:
    return [model.frames[g.parentFrame].name for g in geom_model.geometryObjects]


def _parent_link(model: pin.Model, link: str, with_geometry: set[str]) -> str | None:
    """The nearest ancestor link that has geometry (links without geometry are skipped, as in MoveIt)."""
    frame = model.frames[model.getFrameId(link, pin.FrameType.BODY)]
    while True:
        parent = model.frames[frame.parentFrame]
        if parent.type == pin.FrameType.BODY and parent.name in with_geometry:
            return parent.name
        if frame.parentFrame == 0:
            return None
        frame = parent


def _ordered(a: str, b: str, order: dict[str, int]) -> tuple[str, str]:
    """The pair (a, b) in link order, as the reasons are keyed."""
    return (a, b) if order[a] <= order[b] else (b, a)


def _random_configuration(model: pin.Model, rng: np.random.Generator) -> np.ndarray:
    lo, hi = model.lowerPositionLimit.copy(), model.upperPositionLimit.copy()
    finite = np.isfinite(lo) & np.isfinite(hi) & (hi - lo < 1e3)
    lo[~finite], hi[~finite] = -np.pi, np.pi
    return rng.uniform(lo, hi)


def compute_disabled_collisions(
    urdf_text: str, *, n_samples: int = 20000, seed: int = 0, package_dirs: list[str] | None = None
) -> list[tuple[str, str, str]]:
    """(link1, link2, reason) for every link pair to exclude, sorted."""
    model = pin.buildModelFromXML(urdf_text)
    geom_model = pin.buildGeomFromUrdfString(model, urdf_text, pin.COLLISION, package_dirs=package_dirs or [])
    links = _link_of_geometry(model, geom_model)
    link_names = sorted(set(links), key=links.index)
    parent = {name: _parent_link(model, name, set(link_names)) for name in link_names}

    reasons: dict[tuple[str, str], str] = {}
    for a, b in combinations(link_names, 2):
        if parent[a] == b or parent[b] == a:
            reasons[(a, b)] = "Adjacent"
    order = {name: i for i, name in enumerate(link_names)}
    for i, j in combinations(range(len(links)), 2):
        if links[i] != links[j] and _ordered(links[i], links[j], order) not in reasons:
            geom_model.addCollisionPair(pin.CollisionPair(i, j))
    geom_data = pin.GeometryData(geom_model)
    data = model.createData()
    pair_links = [_ordered(links[p.first], links[p.second], order) for p in geom_model.collisionPairs]
    hits = dict.fromkeys(pair_links, 0)
    closest = dict.fromkeys(pair_links, np.inf)
    rng = np.random.default_rng(seed)
    for _ in range(n_samples):
        pin.computeDistances(model, data, geom_model, geom_data, _random_configuration(model, rng))
        seen = set()
        for pair, result in zip(pair_links, geom_data.distanceResults):
            closest[pair] = min(closest[pair], result.min_distance)
            if result.min_distance <= 0.0:
                seen.add(pair)
        for pair in seen:
            hits[pair] += 1
    for pair, count in hits.items():
        if count == 0 and closest[pair] > NEVER_MARGIN:
            reasons[pair] = "Never"
        elif count >= ALWAYS_FRACTION * n_samples:
            reasons[pair] = "Always"
    return sorted(((a, b, r) for (a, b), r in reasons.items()), key=lambda t: (order[t[0]], order[t[1]]))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description="Print SRDF <disable_collisions> lines for a URDF.")
    parser.add_argument("urdf", type=Path)
    parser.add_argument("--samples", type=int, default=20000)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--package-dir", action="append", default=[])
    args = parser.parse_args(argv)
    disabled = compute_disabled_collisions(
        args.urdf.read_text(), n_samples=args.samples, seed=args.seed, package_dirs=args.package_dir
    )
    for a, b, reason in disabled:
        print(f'  <disable_collisions link1="{a}" link2="{b}" reason="{reason}"/>')
    print(f"{len(disabled)} pairs disabled", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""certify_and_repair: certify a path and re-plan each failing segment locally until it is certified."""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from maru_planner.collision.certify.certifier import Certificate, PathCertifier

# m: a repair starts and ends at waypoints at least this clear even when the margin is less (a margin of 0 let it
# start at waypoints touching an obstacle, from which every local path grazed it again)
MIN_ANCHOR_CLEARANCE = 0.0025

LocalPlanner = Callable[[np.ndarray, np.ndarray, float, float], np.ndarray | None]


@dataclass
class CertifiedPath:
    """Result of :func:`certify_and_repair`: the certified path (None if none could be made) and its cost."""

    path: np.ndarray | None
    certificate: Certificate  # the last certification; checks, exact queries and seconds summed over all
    repairs: int = 0  # local re-plans


def certify_and_repair(
    certifier: PathCertifier,
    path: np.ndarray,
    local_planner: LocalPlanner,
    deadline: float,
    *,
    margin: float | None = None,
    max_repairs: int = 3,
    certify_deadline: float | None = None,
    corner_blends: np.ndarray | None = None,
) -> CertifiedPath:
    """Certify ``path``; re-plan each failing segment locally (``local_planner``) until certified or out of tries.

    ``corner_blends`` (per waypoint, as :meth:`PathCertifier.certify_path` takes it): the corners a trajectory
    rounds with blends proven elsewhere are left out, until a repair changes the path (then all of it is certified
    again: its blends are to be proven anew).

    ``local_planner(qa, qb, margin, deadline)`` returns full configurations from ``qa`` to ``qb`` (None if it
    finds none); its path is certified like the rest. A failing segment is re-planned between the nearest
    waypoints around it that keep the margin, and at least :data:`MIN_ANCHOR_CLEARANCE`. ``margin`` (m; None =
    ``certifier.safety_margin``): a start or goal closer than that lowers the margin of this path to half its
    clearance (nothing nearer can be certified). Repairs stop at ``deadline``; certification itself at
    ``certify_deadline`` (None: no limit).
    """
    path = np.atleast_2d(np.asarray(path, dtype=float))
    margin = certifier.safety_margin if margin is None else float(margin)
    done, repairs, relaxed = 0, 0, False
    total = Certificate(valid=False, margin=margin)
    while True:
        blends = None if corner_blends is None else corner_blends[done:]
        cert = certifier.certify_path(path[done:], certify_deadline, margin=margin, corner_blends=blends)
        _accumulate(total, cert, done)
        if cert.valid:
            return CertifiedPath(path, total, repairs)
        if cert.reason == "margin" and not relaxed:
            relaxed = True
            ends = min(certifier.clearance(path[0]), certifier.clearance(path[-1]))
            if ends <= margin:
                margin, done = 0.5 * max(ends, 0.0), 0
                total.margin = margin
                continue
        if cert.reason == "timeout" or repairs >= max_repairs or time.monotonic() >= deadline:
            return CertifiedPath(None, total, repairs)
        a, b = _repair_anchors(certifier, path, total.first_failing_segment, max(margin, MIN_ANCHOR_CLEARANCE))
        repairs += 1
        local = local_planner(path[a], path[b], margin, deadline)
        if local is None:
            return CertifiedPath(None, total, repairs)
        path, done = np.vstack([path[:a], np.atleast_2d(local), path[b + 1 :]]), a
        if corner_blends is not None:  # the corners certified without their blends' ends change: all of it again
            corner_blends, done = None, 0


def _repair_anchors(certifier: PathCertifier, path: np.ndarray, segment: int, margin: float) -> tuple[int, int]:
    """Waypoint indices around ``segment`` that keep more than ``margin`` (the path's ends at the latest)."""
    a, b = segment, segment + 1
    while a > 0 and certifier.clearance(path[a]) <= margin:
        a -= 1
    while b < len(path) - 1 and certifier.clearance(path[b]) <= margin:
        b += 1
    return a, b


def _accumulate(total: Certificate, cert: Certificate, offset: int) -> None:
    """Fold the certificate of ``path[offset:]`` into ``total`` (the whole path's; costs summed)."""
    total.valid, total.reason, total.witness = cert.valid, cert.reason, cert.witness
    total.first_failing_segment = cert.first_failing_segment + offset if not cert.valid else -1
    total.segment_clearance = total.segment_clearance[:offset] + cert.segment_clearance
    total.min_clearance = min(total.segment_clearance, default=math.inf) if cert.valid else cert.min_clearance
    total.checks += cert.checks
    total.exact_queries += cert.exact_queries
    total.hull_queries += cert.hull_queries
    total.seconds += cert.seconds

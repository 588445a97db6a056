"""Certified collision-free arm paths: continuous validation of straight joint-space segments.

The validation of ``hpp-core`` (HPP's continuous validation), on Pinocchio + coal. For every pair
the exact :class:`~maru_planner.collision.checker.CollisionChecker` checks (robot geometry vs
obstacle, and its SRDF-filtered self-collision pairs) two numbers decide:

- a lower bound ``d`` on the pair's distance at a configuration: a bounding-volume bound first
  (the geometry's bounding sphere against the obstacle's oriented bounding box, or two bounding
  spheres), then coal's distance to a mesh's convex hull, the exact coal distance only where the
  hull is within the margin;
- an upper bound ``M`` on how fast that distance can change along a segment:
  ``M = sum_j c_j |q1_j - q0_j|`` over the joints that move one body of the pair but not the other,
  ``c_j`` the largest distance from joint ``j``'s axis to any point of the body (revolute; a bound
  from the joint offsets down the chain plus the geometry's bounding radius, tightened on each piece
  with the configuration at its middle) or 1 (prismatic).

On ``q(t) = q0 + t (q1 - q0)``, a pair whose distance at ``t_m`` is ``d`` keeps more than
``margin`` of clearance for ``|t - t_m| < (d - margin) / M``. Each segment is bisected until those
intervals cover it (a proof) or the exact distance at a checked configuration is within the margin
(a counter-example). Bounding volumes only ever prove; exact geometry decides every failure.

With the search's sphere model (``spheres``; every triangle of a mesh lies in one of its spheres) a mesh's
pairs get a tighter bound before coal: its spheres' distance to the obstacle's primitive or to the other
mesh's spheres. Unproven pieces are split into dyadic pieces, so all pairs share their configurations.

Large scenes (``NEAR_PATH_MIN_OBSTACLES`` reachable obstacles or more, e.g. a point cloud as 1 cm
balls): each certification first keeps the obstacles some moving geometry may come within its margin
of -- on each segment, the geometry's bounding sphere at the middle grown by half the segment's motion
times its levers -- and proves only their pairs; obstacle pairs are measured by coal directly.
:func:`certify_and_repair` re-plans a failing segment locally. See ``docs/certification.md``.

Modules: :mod:`.certifier` (:class:`PathCertifier`, :class:`Certificate`), :mod:`.repair`
(:func:`certify_and_repair`), :mod:`.levers` (the rate bounds), :mod:`.pairs` (the pair tables), :mod:`.bounds` and
:mod:`.rounds` (the numba row kernels and a certification's rounds), :mod:`.cover` (the sphere cover's bound).
"""

from maru_planner.collision.certify.bounds import (
    COVER_SLACK_SPLIT,
    MEASURE_BOUND,
    MEASURE_EXACT,
    MEASURE_NONE,
    ROWS_FOR_ALL,
    proves_too_little,
)
from maru_planner.collision.certify.certifier import (
    CLEARANCE_WINDOW,
    DEFAULT_SAFETY_MARGIN,
    NEAR_PATH_MIN_OBSTACLES,
    NEAR_TABLES,
    SHARED_END,
    Certificate,
    PathCertifier,
    without_corners,
)
from maru_planner.collision.certify.cover import DISTANCE_TOLERANCE, NO_COVER, SphereCover
from maru_planner.collision.certify.levers import PRISMATIC, REVOLUTE, bounding_sphere, chord_deviation, joint_levers
from maru_planner.collision.certify.pairs import UNBOUNDED, kernel_primitives
from maru_planner.collision.certify.repair import (
    MIN_ANCHOR_CLEARANCE,
    CertifiedPath,
    LocalPlanner,
    certify_and_repair,
)
from maru_planner.collision.certify.rounds import FAILURE_REASONS, MAX_SPLIT, MIN_INTERVAL

__all__ = [
    "CLEARANCE_WINDOW", "COVER_SLACK_SPLIT", "DEFAULT_SAFETY_MARGIN", "DISTANCE_TOLERANCE", "FAILURE_REASONS",
    "MAX_SPLIT", "MEASURE_BOUND", "MEASURE_EXACT", "MEASURE_NONE", "MIN_ANCHOR_CLEARANCE", "MIN_INTERVAL",
    "NEAR_PATH_MIN_OBSTACLES", "NEAR_TABLES", "NO_COVER", "PRISMATIC", "REVOLUTE", "ROWS_FOR_ALL", "SHARED_END",
    "UNBOUNDED", "Certificate", "CertifiedPath", "LocalPlanner", "PathCertifier", "SphereCover", "bounding_sphere",
    "certify_and_repair", "chord_deviation", "joint_levers", "kernel_primitives", "proves_too_little",
    "without_corners",
]  # fmt: skip

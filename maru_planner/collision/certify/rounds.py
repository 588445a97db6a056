"""A certification's rounds: the configurations at the middles of the pending pieces, and after their bounds, the
failures and the pieces still unproven (numba); :class:`CertificationRun` holds one certification's state."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from maru_planner.collision.certify.pairs import PairTable

MIN_INTERVAL = 1e-9  # rad: a piece of segment this short that is still unproven fails as "unproven"
# An unproven end is split into up to this many dyadic pieces at once, each no longer than twice the radius its
# piece's middle proved (bisecting one level per round took ~10 rounds a path, each a batch's fixed cost; 16 rather
# than 8: in-process A/B, 8 rounds, median plan -0.10 ms on MotionBenchMaker and -0.11 ms on Maru-1)
MAX_SPLIT = 16


FAILURE_REASONS = ("collision", "margin", "unproven", "timeout")  # Certificate.reason by the round kernels' codes


@njit(cache=True)
def round_configs_nb(path, delta, bend, seg, a, b):
    """The middle of each row's piece: (distinct configurations in key order, each row's configuration, half
    the piece). Rows at the same segment and middle share one configuration (as ``np.unique`` would sort them).
    Segment s at t is ``path[s] + t * delta[s] + t² * bend[s]``."""
    n = seg.shape[0]
    half = np.empty(n)
    keys = np.empty(n)
    in_order = True
    for r in range(n):
        half[r] = 0.5 * (b[r] - a[r])
        keys[r] = seg[r] + 0.25 * (a[r] + b[r])
        in_order = in_order and (r == 0 or keys[r] >= keys[r - 1])
    # a first round's rows come segment by segment: sorting them would take 4x the rest of this kernel
    order = np.arange(n) if in_order else np.argsort(keys, kind="mergesort")
    config_of = np.empty(n, dtype=np.int64)
    firsts = np.empty(n, dtype=np.int64)
    count = 0
    for i in range(n):
        r = order[i]
        if i == 0 or keys[r] != keys[order[i - 1]]:
            firsts[count] = r
            count += 1
        config_of[r] = count - 1
    configs = np.empty((count, path.shape[1]))
    for c in range(count):
        r = firsts[c]
        mid = 0.5 * (a[r] + b[r])
        for j in range(path.shape[1]):
            configs[c, j] = path[seg[r], j] + mid * delta[seg[r], j] + mid * mid * bend[seg[r], j]
    return configs, config_of, half


@njit(cache=True)
def _fail_nb(segment, reason, config, alive, curve, failure, witness):
    """Segment ``segment`` fails: the rest of its curve needs no more proof; the first failure is kept
    (``failure``: [segment, reason code], ``witness``: its configuration)."""
    for s in range(segment, alive.shape[0]):
        if curve[s] == curve[segment]:
            alive[s] = False
    if segment < failure[0]:
        failure[0], failure[1] = segment, reason
        witness[:] = config


@njit(cache=True)
def finish_round_nb(configs, config_of, seg, pair, a, b, half, margin, bound, rate, need, refine, exact, span,
                     timed_out, min_interval, max_split, alive, curve, clearance, failure, witness):  # fmt: skip
    """After a round's bounds (:meth:`PathCertifier._check_rows`): each segment's clearance, the failures, and the
    rows still unproven, as (seg, pair, a, b) of the next round.

    At the middle of its piece ``[a, b]`` a row's pair is proven for ``|t - m| <= (bound - margin) / rate``; each
    unproven end of the piece is widened to the dyadic piece that holds it, so that the pieces of all pairs share
    their middles, hence their forward kinematics (4x fewer configurations), and cut into up to ``max_split`` equal
    dyadic pieces, none longer than twice that radius where it can (a row near an obstacle skips the levels that
    one halving per round would spend a round each on).
    """
    n = seg.shape[0]
    for r in range(n):
        if refine[r] or bound[r] >= need[r]:
            clearance[seg[r]] = min(clearance[seg[r]], bound[r])
    for r in range(n):
        if exact[r] and bound[r] - margin[r] <= 0.0:
            _fail_nb(seg[r], 0 if bound[r] <= 0.0 else 1, configs[config_of[r]], alive, curve, failure, witness)
    reach = np.empty(n)
    open_ = np.zeros(n, dtype=np.bool_)
    for r in range(n):
        slack = max(bound[r] - margin[r], 0.0)
        reach[r] = slack / rate[r] if rate[r] > 0.0 else np.inf
        open_[r] = reach[r] < half[r] and alive[seg[r]]
    for r in range(n):
        if open_[r]:
            short = half[r] * span[seg[r]] < min_interval
            if short or timed_out:
                _fail_nb(seg[r], 2 if short else 3, configs[config_of[r]], alive, curve, failure, witness)
    size, step = np.empty(n), np.empty(n)
    count = 0
    for r in range(n):
        if open_[r] and alive[seg[r]]:
            size[r] = min(half[r], 2.0 ** np.ceil(np.log2(half[r] - reach[r])))
            step[r] = size[r]
            while step[r] > 2.0 * reach[r] and step[r] > size[r] / max_split:
                step[r] *= 0.5
            count += 2 * int(round(size[r] / step[r]))
    seg2, pair2 = np.empty(count, dtype=np.int64), np.empty(count, dtype=np.int64)
    a2, b2 = np.empty(count), np.empty(count)
    k = 0
    for r in range(n):
        if open_[r] and alive[seg[r]]:
            for start in (a[r], b[r] - size[r]):
                for i in range(int(round(size[r] / step[r]))):
                    seg2[k], pair2[k] = seg[r], pair[r]
                    a2[k] = start + i * step[r]
                    b2[k] = a2[k] + step[r]
                    k += 1
    return seg2, pair2, a2, b2


class CertificationRun:
    """The state of one :meth:`PathCertifier.certify_path` call."""

    def __init__(self, path: np.ndarray, pairs: PairTable, pair_margin: np.ndarray, deadline: float, downstream,
                 curve: np.ndarray, bend: np.ndarray):  # fmt: skip
        """``pair_margin`` (segments, pairs); ``curve`` (segments,): the curve each segment belongs to, -1 for a
        segment not to certify (between two curves); ``bend`` (segments, nq): segment s at t in [0, 1] is
        ``(1 - t) * path[s] + t * path[s + 1] + (t² - t) * bend[s]`` (zeros: straight)."""
        self.path, self.pairs, self.pair_margin, self.deadline = path, pairs, pair_margin, deadline
        self.curve = curve
        self.n_segments = len(path) - 1
        self.bend = np.ascontiguousarray(bend, dtype=float)
        self.delta = np.diff(path, axis=0) - self.bend  # segment s at t: path[s] + t * delta[s] + t² * bend[s]
        # (segments, nq): the largest |dq_j / dt| on each segment (at one of its ends: dq/dt is linear in t)
        self.motion = np.maximum(np.abs(self.delta), np.abs(self.delta + 2.0 * self.bend))
        self.span = self.motion.max(axis=1, initial=0.0)
        self.rate = self.motion @ pairs.rate.T  # (segments, pairs): configuration-free bound on distance change
        # (segments, geometries, nq): how fast a geometry can move relative to each joint's axis (joints below it)
        g, nq = downstream.shape[:2]
        self.downstream = (downstream.reshape(g * nq, nq) @ self.motion.T).T.reshape(-1, g, nq)  # einsum: 20x slower
        self.arrays = tuple(np.ascontiguousarray(a, dtype=float)
                            for a in (pair_margin, self.rate, self.motion, self.downstream))  # fmt: skip
        self.clearance = np.full(self.n_segments, math.inf)
        self.failure = np.array([self.n_segments, -1], dtype=np.int64)  # first failing segment, reason code
        self.witness_config = np.zeros(path.shape[1])
        self.alive = curve >= 0  # segments still worth proving: not after a failure on their curve
        n_pairs = len(pairs.first)
        # Pending work, one row per (segment, pair, piece [a, b] of the segment not yet proven for the pair).
        live = np.flatnonzero(self.alive)
        self.seg = np.repeat(live, n_pairs)
        self.pair = np.tile(np.arange(n_pairs), len(live))
        self.a, self.b = np.zeros(len(self.seg)), np.ones(len(self.seg))

    @property
    def failed(self) -> int:
        """The first failing segment (``n_segments``: none)."""
        return int(self.failure[0])

    @property
    def reason(self) -> str:
        return FAILURE_REASONS[self.failure[1]] if self.failure[1] >= 0 else ""

    @property
    def witness(self) -> np.ndarray | None:
        return self.witness_config.copy() if self.failure[1] >= 0 else None

    def failed_curves(self, n_curves: int) -> np.ndarray:
        """(n_curves,) bool: whether each curve has a failing segment."""
        out = np.zeros(n_curves, dtype=bool)
        done = (self.curve >= 0) & ~self.alive
        out[self.curve[done]] = True
        return out

"""The curve check a blended trajectory is proven with: ``curve_free(states, chord deviation)``.

A blend is re-checked by ``curve_free(states, deviation)``: its samples at most ``certify_step`` apart (default
:data:`CERTIFY_STEP`) and, per joint, how far the curve leaves the chords between them (exact for a parabola:
``|p''|·h²/8``), for a checker that certifies the chords continuously with that much more margin; a checker of the
states alone needs the fine default step. A check whose ``takes_bends`` is True (:class:`CertifiedCurve`) takes the
parabolas as bent segments instead, and one whose ``takes_pieces`` is True the straight pieces between them too.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

CERTIFY_STEP = 0.005  # rad: joint step of the collision re-check of blends

CurveFree = Callable[[np.ndarray, np.ndarray], bool]  # (states, chord deviation per joint) -> collision-free
# (states, chord deviation per joint), or with a third element, bends (states - 1, joints): segment i is the parabola
# (1 - t)·q_i + t·q_i+1 + (t² - t)·bend_i -- only for a curve check whose ``takes_bends`` is True
Curve = tuple


@dataclass(frozen=True)
class CertifiedCurve:
    """A :data:`CurveFree` proving a group curve clear by ``margin`` on ``certifier`` (a ``PathCertifier``), each
    joint's margin grown by how far the curve leaves the chords; the joints outside ``indices`` stay at ``base``.
    ``many`` proves several curves in one certification pass (the blends of a path, and its straight pieces:
    ``takes_pieces``)."""

    certifier: Any
    base: np.ndarray
    indices: Sequence[int]
    deadline: float | None
    margin: float
    clearance: list[float] = field(default_factory=list, compare=False)  # m: least distance on each curve proven
    takes_bends = True  # the certifier proves parabolic segments as they are

    @property
    def takes_pieces(self) -> bool:
        """Worth giving the straight pieces too (then the path's certification has nothing left), except in a large
        scene: a pass keeps the obstacles near any of its curves, so every blend would be checked against the pieces'
        obstacles too (10,000-ball clutter around Maru-1: 129 -> 220 ms a plan)."""
        return not self.certifier.near_path_only

    def __call__(self, states: np.ndarray, chord_deviation: np.ndarray) -> bool:
        return self.many([(states, chord_deviation)])[0]

    def many(self, curves: Sequence[Curve]) -> list[bool]:
        certified, clearance = self.certifier.prove_curves(list(curves), self.deadline, margin=self.margin,
                                                           base=self.base, joints=self.indices)  # fmt: skip
        self.clearance.extend(clearance[certified].tolist())
        return certified.tolist()


def certified_curve(certifier: Any, base: np.ndarray, indices, deadline: float | None, margin: float) -> CurveFree:
    """:class:`CertifiedCurve` of these arguments."""
    return CertifiedCurve(certifier, base, indices, deadline, margin)


@dataclass(frozen=True)
class WatchedCurve:
    """``curve_free`` with ``before()`` called ahead of every check (a monitor's cancellation point); keeps
    ``curve_free``'s ``many``."""

    curve_free: CurveFree
    before: Callable[[], None]

    @property
    def takes_bends(self) -> bool:
        return takes_bends(self.curve_free)

    @property
    def takes_pieces(self) -> bool:
        return takes_pieces(self.curve_free)

    @property
    def clearance(self) -> list[float]:
        return getattr(self.curve_free, "clearance", [])

    def __call__(self, states: np.ndarray, chord_deviation: np.ndarray) -> bool:
        self.before()
        return self.curve_free(states, chord_deviation)

    def many(self, curves: Sequence[Curve]) -> list[bool]:
        self.before()
        return curves_free(self.curve_free, curves)


@dataclass(frozen=True)
class Check:
    """The caller's curve check, its sample step, and the deadline after which nothing is certified."""

    curve_free: CurveFree
    step: float
    deadline: float | None

    def __call__(self, states: np.ndarray, deviation: np.ndarray) -> bool:
        return self.many([(states, deviation)])[0]

    def many(self, curves: Sequence[Curve]) -> list[bool]:
        if self.deadline is not None and time.monotonic() >= self.deadline:
            return [False] * len(curves)
        return curves_free(self.curve_free, curves)


def certified_clearance(curve_free: CurveFree) -> float:
    """The smallest distance (m) measured on the curves ``curve_free`` (a :class:`CertifiedCurve`, maybe watched)
    certified; inf if none, or if it is no certifier."""
    return min(getattr(curve_free, "clearance", None) or [math.inf])


def takes_bends(curve_free: CurveFree) -> bool:
    """Whether ``curve_free`` proves curves given with bends (:data:`Curve`), else only sampled chords."""
    return bool(getattr(curve_free, "takes_bends", False))


def takes_pieces(curve_free: CurveFree) -> bool:
    """Whether ``curve_free`` should get the straight pieces of a blended curve too (a :class:`CertifiedCurve`, maybe
    watched): proven with the blends, they spare the path's certification (``TimingReport.curve_certified``)."""
    return bool(getattr(curve_free, "takes_pieces", False))


def curves_free(curve_free: CurveFree, curves: Sequence[Curve]) -> list[bool]:
    """``curve_free`` of each curve: in one call when it has ``many``, else one by one."""
    many = getattr(curve_free, "many", None)
    if many is not None:
        return list(many(curves))
    return [curve_free(states, deviation) for states, deviation in curves]

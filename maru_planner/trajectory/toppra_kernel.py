"""TOPP-RA's stage linear programs in closed form, one numba call per path: the kernel of the toppra profile
(:mod:`~maru_planner.trajectory.toppra`).

At stage ``i`` of the grid toppra solves a linear program over ``(u, x)`` = (path acceleration, squared path speed
ṡ²) whose rows ``alpha u + beta x <= gamma`` come from its canonical linear constraints (joint velocity limits give
bounds on ``x``, joint acceleration limits rows at grid points ``i`` and ``i + 1``: toppra's interpolated
discretisation), with the next point's ``x + 2 delta u`` kept within ``[0, highest[i + 1]]``. Only two programs
occur in a rest-to-rest profile, and both have a closed form:

* the highest controllable ``x`` (backward pass): Fourier–Motzkin elimination of ``u`` pairs every lower bound of
  ``u`` with every upper bound, leaving bounds on ``x`` alone;
* the largest ``u`` at a given ``x`` (forward pass): the least upper bound of ``u`` where it is not below the
  greatest lower bound.

toppra's Seidel solver answers the same programs one Python call per stage (~2 µs each, plus its wrapper's set-up):
the whole profile here costs about what two of its calls do. The rows are those of toppra's constraint objects
(``compute_constraint_params``), with its retry rule; the tests compare the profiles with toppra's.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

TINY = 1e-10  # a row coefficient at most this is zero (toppra's Seidel solver's own threshold)


@njit(cache=True, inline="always")
def _row(alpha, beta, gamma, i, k, delta, next_high):
    """Row ``k`` of stage ``i``: a constraint row, or (last two) ``x + 2 delta u`` within ``[0, next_high]``."""
    n = alpha.shape[1]
    if k < n:
        return alpha[i, k], beta[i, k], gamma[i, k]
    if k == n:
        return -2.0 * delta, -1.0, 0.0
    return 2.0 * delta, 1.0, next_high


@njit(cache=True, inline="always")
def _bounded(lo, hi, coef, rhs):
    """``[lo, hi]`` cut by ``coef * v <= rhs`` (``coef`` within :data:`TINY` of 0: ``0 <= rhs``, else empty)."""
    if coef > TINY:
        return lo, min(hi, rhs / coef)
    if coef < -TINY:
        return max(lo, rhs / coef), hi
    return (lo, hi) if rhs >= -TINY else (math.inf, hi)


@njit(cache=True)
def highest_x(alpha, beta, gamma, i, x_high, delta, next_high):
    """The largest ``x`` of stage ``i`` for which some ``u`` meets every row (NaN: none); ``x`` in
    ``[0, x_high]``. A row whose ``|alpha|`` is at most :data:`TINY` bounds ``x`` alone."""
    lo, hi = 0.0, x_high
    rows = alpha.shape[1] + 2
    for k in range(rows):
        ak, bk, ck = _row(alpha, beta, gamma, i, k, delta, next_high)
        if ak > TINY:
            continue
        if ak >= -TINY:  # no u in it: b x <= c
            lo, hi = _bounded(lo, hi, bk, ck)
            continue
        for m in range(rows):  # ak < 0: u >= (ck - bk x) / ak; pair it with each upper bound u <= (cm - bm x) / am
            am, bm, cm = _row(alpha, beta, gamma, i, m, delta, next_high)
            if am > TINY:
                lo, hi = _bounded(lo, hi, am * bk - ak * bm, am * ck - ak * cm)
    return hi if lo <= hi else math.nan


@njit(cache=True)
def largest_u(alpha, beta, gamma, i, x, delta, next_high):
    """The largest ``u`` of stage ``i`` at squared speed ``x`` that meets every row (NaN: none)."""
    lo, hi = -math.inf, math.inf
    for k in range(alpha.shape[1] + 2):
        a, b, c = _row(alpha, beta, gamma, i, k, delta, next_high)
        lo, hi = _bounded(lo, hi, a, c - b * x)
    return hi if lo <= hi else math.nan


@njit(cache=True, inline="always")
def _limit_rows(alpha, beta, gamma, i, column, a, b, limit):
    """``|a u + b x| <= limit`` as two rows of stage ``i``: at ``column`` and one joint count (a quarter row) on."""
    other = column + alpha.shape[1] // 4
    alpha[i, column], beta[i, column], gamma[i, column] = a, b, limit
    alpha[i, other], beta[i, other], gamma[i, other] = -a, -b, limit


@njit(cache=True)
def stage_rows_nb(ps, pss, deltas, velocity, acceleration):
    """toppra's rows of joint velocity and acceleration limits over a grid: (alpha, beta, gamma) (points, 4 dof) and
    the highest ``x`` per point. ``ps``/``pss``: the path's first and second derivatives at the grid points.

    Velocity: ``x <= (v_j / p'_j)²``. Acceleration, interpolated: ``|p'_j u + p''_j x| <= a_j`` at the point and,
    with the next point's ``x + 2 delta u``, ``|(p'_j + 2 delta p''_j) u + p''_j x| <= a_j`` there (the last point
    repeats its own rows, as toppra does).
    """
    points, dof = ps.shape
    alpha, beta, gamma = np.empty((points, 4 * dof)), np.empty((points, 4 * dof)), np.empty((points, 4 * dof))
    x_high = np.full(points, math.inf)
    for i in range(points):
        n = i + 1 if i + 1 < points else i
        step = 2.0 * deltas[i] if i + 1 < points else 0.0
        for j in range(dof):
            if ps[i, j] != 0.0:
                x_high[i] = min(x_high[i], (velocity[j] / ps[i, j]) ** 2)
            _limit_rows(alpha, beta, gamma, i, j, ps[i, j], pss[i, j], acceleration[j])
            _limit_rows(alpha, beta, gamma, i, 2 * dof + j, ps[n, j] + step * pss[n, j], pss[n, j], acceleration[j])
    return alpha, beta, gamma, x_high


@njit(cache=True)
def rest_to_rest_nb(ps, pss, deltas, velocity, acceleration, step_down, max_tries):
    """Squared path speeds (grid points,) of toppra's rest-to-rest profile under joint ``velocity`` and
    ``acceleration`` limits; empty where toppra fails. ``ps``/``pss``: :func:`stage_rows_nb`; ``deltas`` (stages,).

    Backward: the highest controllable ``x`` per point (rest at the end). Forward: from rest, each stage's largest
    ``u``; where rounding leaves none, ``x`` is lowered a little (by ``step_down`` or 0.1 %) and tried again, at most
    ``max_tries`` times in a row, as toppra does.
    """
    alpha, beta, gamma, x_high = stage_rows_nb(ps, pss, deltas, velocity, acceleration)
    stages = deltas.shape[0]
    highest = np.zeros(stages + 1)
    for i in range(stages - 1, -1, -1):
        high = highest_x(alpha, beta, gamma, i, x_high[i], deltas[i], highest[i + 1])
        if math.isnan(high):
            return np.empty(0)
        highest[i] = max(high, 0.0)
    x = np.zeros(stages + 1)
    i = tries = 0
    while i < stages:
        u = largest_u(alpha, beta, gamma, i, x[i], deltas[i], highest[i + 1])
        if math.isnan(u):
            if tries == max_tries:
                return np.empty(0)
            x[i] = max(x[i] - step_down, 0.999 * x[i])
            tries += 1
            continue
        tries = 0
        x_next = x[i] + 2.0 * deltas[i] * u
        x[i + 1] = min(highest[i + 1], max(0.0, x_next - step_down, 0.9999 * x_next))
        i += 1
    return x


@njit(cache=True)
def profile_states_nb(t, times, grid, sd, pieces, starts, p0, v0, dd):
    """Joint positions, velocities and accelerations (len(t), dof) at times ``t`` of a path-velocity profile: ṡ
    ``sd`` at the ``grid`` points (reached at ``times``), constant s̈ between them, on the pieces ``p0 + v0·σ +
    ½·dd·σ²`` (σ from the piece's start in ``starts``) that ``pieces`` gives per grid interval."""
    n, dof, last = t.shape[0], p0.shape[1], sd.shape[0] - 2
    q, qd, qdd = np.empty((n, dof)), np.empty((n, dof)), np.empty((n, dof))
    for r in range(n):
        k = min(max(np.searchsorted(times, t[r], side="right") - 1, 0), last)
        sdd = (sd[k + 1] ** 2 - sd[k] ** 2) / (2.0 * (grid[k + 1] - grid[k]))
        tau = t[r] - times[k]
        s = min(max(grid[k] + sd[k] * tau + 0.5 * sdd * tau**2, grid[k]), grid[k + 1])
        speed = max(sd[k] + sdd * tau, 0.0)
        p = pieces[k]
        sigma = s - starts[p]
        for j in range(dof):
            slope = v0[p, j] + dd[p, j] * sigma
            q[r, j] = p0[p, j] + v0[p, j] * sigma + 0.5 * dd[p, j] * sigma**2
            qd[r, j] = slope * speed
            qdd[r, j] = dd[p, j] * speed**2 + slope * sdd
    return q, qd, qdd


@njit(cache=True)
def peak_ratios_nb(grid, sd, pieces, starts, v0, dd, velocity, acceleration):
    """Exact maxima over a profile (as :func:`profile_states_nb` takes it) of |joint velocity| / limit and |joint
    acceleration| / limit: on a grid interval ``p'(s) = b + c·σ`` and ``ṡ² = x + 2·u·σ``, so the acceleration
    ``c·ṡ² + p'·u`` is linear in σ (extremes at the ends) and the squared velocity ``(b + c·σ)²·(x + 2·u·σ)`` a cubic
    whose one interior extremum is at ``σ* = −(c·x + u·b) / (3·u·c)``."""
    velocity2, peak_acceleration = 0.0, 0.0
    for k in range(sd.shape[0] - 1):
        delta = grid[k + 1] - grid[k]
        x0, x1 = sd[k] ** 2, sd[k + 1] ** 2
        u = (x1 - x0) / (2.0 * delta)
        p = pieces[k]
        for j in range(v0.shape[1]):
            c = dd[p, j]
            b = v0[p, j] + c * (grid[k] - starts[p])
            b1 = b + c * delta
            denominator = 3.0 * u * c
            star = -(c * x0 + u * b) / denominator if denominator != 0.0 else 0.0
            star = min(max(star, 0.0), delta) if math.isfinite(star) else 0.0
            top = max(b * b * x0, b1 * b1 * x1, (b + c * star) ** 2 * (x0 + 2.0 * u * star))
            velocity2 = max(velocity2, top / velocity[j] ** 2)
            peak_acceleration = max(peak_acceleration, max(abs(c * x0 + b * u), abs(c * x1 + b1 * u)) / acceleration[j])
    return math.sqrt(velocity2), peak_acceleration

"""Path constraints: a link's orientation within tolerances and/or its origin inside a box, all along a motion.

After MoveIt's ``OrientationConstraint`` / ``PositionConstraint``:

- orientation: ``r = log(R_target^T R_link)`` (the rotation from the target to the link, as a rotation
  vector in the target frame) must satisfy ``|r_i| <= tolerance_i`` for each axis i; a tolerance >= pi
  leaves that axis free (a cup kept upright: tolerances (0.1, 0.1, pi) about a z-up target);
- position: the link origin, expressed in the box frame, must lie within the box's half sides.

:meth:`PathConstraints.violation` measures how far outside a state is (0 = inside);
:meth:`PathConstraints.project` pulls a state onto the allowed region by damped least squares on the
violated components (the projection step of constrained sampling planners).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from maru_planner import errors
from maru_planner.planning.links import check_link

LOCAL = pin.ReferenceFrame.LOCAL
PROJECTION_ITERATIONS = 30
PROJECTION_TOLERANCE = 1e-4  # rad / m: how far inside each bound projection aims (then the bound holds)


@dataclass(frozen=True)
class OrientationConstraint:
    link: str
    target: np.ndarray  # (3, 3) rotation in the root frame
    tolerance: np.ndarray  # (3,) rad about the target's x, y, z

    def __post_init__(self) -> None:
        _check_matrix(self.target, (3, 3), f"orientation constraint on {self.link!r}: target")
        _check_positive3(self.tolerance, f"orientation constraint on {self.link!r}: tolerance", "rad")

    def excess(self, pose: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(rotation vector r in the target frame, per-axis amount outside the tolerance)."""
        r = pin.log3(self.target.T @ pose[:3, :3])
        return r, np.maximum(np.abs(r) - self.tolerance, 0.0)


@dataclass(frozen=True)
class PositionConstraint:
    link: str
    box_pose: np.ndarray  # (4, 4) box frame in the root frame
    box_size: np.ndarray  # (3,) full side lengths (m)

    def __post_init__(self) -> None:
        _check_matrix(self.box_pose, (4, 4), f"position constraint on {self.link!r}: box pose")
        _check_positive3(self.box_size, f"position constraint on {self.link!r}: box size", "m")

    def excess(self, pose: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(link origin in the box frame, per-axis amount outside the box)."""
        local = self.box_pose[:3, :3].T @ (pose[:3, 3] - self.box_pose[:3, 3])
        return local, np.maximum(np.abs(local) - 0.5 * np.asarray(self.box_size), 0.0)


@dataclass(frozen=True)
class RelativePoseConstraint:
    """``link_b``'s pose in ``link_a``'s frame kept at ``relative`` (two hands carrying one object).

    The error is ``e = log6(relative^-1 T_a^-1 T_b)`` (translation; rotation vector, in ``link_b``'s frame);
    each translation component must stay within ``position_tolerance`` m, each rotation component within
    ``orientation_tolerance`` rad.
    """

    link_a: str
    link_b: str
    relative: np.ndarray  # (4, 4)
    position_tolerance: float = 1e-3
    orientation_tolerance: float = 1e-2

    def __post_init__(self) -> None:
        _check_matrix(self.relative, (4, 4), f"relative pose constraint {self.link_a!r}-{self.link_b!r}")
        for name in ("position_tolerance", "orientation_tolerance"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise errors.InvalidRequest(f"relative pose constraint: {name} must be finite and > 0, got {value}")

    @property
    def tolerance(self) -> np.ndarray:
        return np.r_[np.full(3, self.position_tolerance), np.full(3, self.orientation_tolerance)]

    def error(self, pose_a: np.ndarray, pose_b: np.ndarray) -> np.ndarray:
        """The 6-vector e (module doc)."""
        actual = np.linalg.solve(pose_a, pose_b)
        return pin.log6(pin.SE3(np.linalg.solve(self.relative, actual))).vector

    @classmethod
    def held(cls, robot, q: np.ndarray, link_a: str, link_b: str, **tolerances: float) -> RelativePoseConstraint:
        """The relative pose the two links have at ``q``, to be kept."""
        pose_a, pose_b = robot.frame_pose(q, link_a).copy(), robot.frame_pose(q, link_b)
        return cls(link_a, link_b, np.linalg.solve(pose_a, pose_b), **tolerances)


@dataclass(frozen=True)
class PathConstraints:
    """An orientation, a position and/or a relative-pose constraint (each may be None)."""

    orientation: OrientationConstraint | None = None
    position: PositionConstraint | None = None
    relative: RelativePoseConstraint | None = None

    @property
    def empty(self) -> bool:
        return self.orientation is None and self.position is None and self.relative is None

    def links(self) -> list[str]:
        links = [c.link for c in (self.orientation, self.position) if c is not None]
        return links + ([self.relative.link_a, self.relative.link_b] if self.relative is not None else [])

    def check_links(self, robot) -> None:
        """InvalidLink for a constrained link the robot does not have."""
        for link in self.links():
            check_link(robot, link, "path constraint link")

    def violation(self, robot, q: np.ndarray) -> tuple[float, float]:
        """(orientation violation in rad, position violation in m) at ``q``: how far outside; 0 = satisfied."""
        orientation = position = 0.0
        if self.orientation is not None:
            orientation = float(self.orientation.excess(robot.frame_pose(q, self.orientation.link))[1].max())
        if self.position is not None:
            position = float(np.linalg.norm(self.position.excess(robot.frame_pose(q, self.position.link))[1]))
        if self.relative is not None:
            c = self.relative
            excess = np.abs(c.error(robot.frame_pose(q, c.link_a).copy(), robot.frame_pose(q, c.link_b))) - c.tolerance
            position, orientation = max(position, excess[:3].max(), 0.0), max(orientation, excess[3:].max(), 0.0)
        return orientation, position

    def satisfied(self, robot, q: np.ndarray, slack: float = 0.0) -> bool:
        orientation, position = self.violation(robot, q)
        return orientation <= slack and position <= slack

    def project(self, robot, q: np.ndarray, indices: np.ndarray, inset: float = 0.0) -> np.ndarray | None:
        """``q`` moved (only the joints ``indices``, within limits) until the constraints hold; None if it fails.

        A violated component is pulled to ``1 - inset`` of its bound, so straight motions between projected
        states keep some room before they leave the region.
        """
        q = np.array(q, dtype=float)
        lo, hi = robot.lower_limits[indices], robot.upper_limits[indices]
        for _ in range(PROJECTION_ITERATIONS):
            rows, residual = self._residual(robot, q, indices, 1.0 - inset)
            if not len(residual):
                return q
            step = rows.T @ np.linalg.solve(rows @ rows.T + 1e-6 * np.eye(len(residual)), residual)
            q[indices] = np.clip(q[indices] - step, lo, hi)
        return q if self.satisfied(robot, q) else None

    def _residual(self, robot, q: np.ndarray, indices: np.ndarray, keep: float) -> tuple[np.ndarray, np.ndarray]:
        """Jacobian rows and signed excess of the components outside ``keep`` x their bound (aiming just inside)."""
        rows: list[np.ndarray] = []
        residual: list[float] = []
        if self.orientation is not None:
            _orientation_rows(self.orientation, robot, q, indices, keep, rows, residual)
        if self.position is not None:
            _position_rows(self.position, robot, q, indices, keep, rows, residual)
        if self.relative is not None:
            _relative_rows(self.relative, robot, q, indices, keep, rows, residual)
        return np.array(rows).reshape(len(rows), len(indices)), np.array(residual)


def _check_matrix(value: np.ndarray, shape: tuple[int, int], what: str) -> None:
    value = np.asarray(value, dtype=float)
    if value.shape != shape or not np.all(np.isfinite(value)):
        raise errors.InvalidRequest(f"{what} must be a finite {shape[0]}x{shape[1]} matrix")


def _check_positive3(value: np.ndarray, what: str, unit: str) -> None:
    values = np.asarray(value, dtype=float)
    if values.shape != (3,) or not np.all(np.isfinite(values)) or np.any(values <= 0):
        raise errors.InvalidRequest(f"{what} must be 3 finite values > 0 {unit}, got {values}")


def _pull(J: np.ndarray, value: np.ndarray, bound: np.ndarray, rows: list, residual: list) -> None:
    """Rows and residuals of the components of ``value`` beyond ``+-bound``, aimed just inside it."""
    for i in np.flatnonzero(np.abs(value) > bound):
        rows.append(J[i])
        residual.append(value[i] - math.copysign(bound[i] - PROJECTION_TOLERANCE, value[i]))


def _orientation_rows(c: OrientationConstraint, robot, q, indices, keep: float, rows: list, residual: list) -> None:
    fid = robot.frame_id(c.link)
    r = c.excess(robot.frame_pose(q, fid))[0]
    J = c.target.T @ robot.frame_jacobian(q, fid)[3:, indices]  # angular rate in the target frame
    _pull(pin.Jlog3(pin.exp3(r)) @ J, r, np.minimum(c.tolerance * keep, math.pi), rows, residual)


def _position_rows(c: PositionConstraint, robot, q, indices, keep: float, rows: list, residual: list) -> None:
    fid = robot.frame_id(c.link)
    local = c.excess(robot.frame_pose(q, fid))[0]
    J = c.box_pose[:3, :3].T @ robot.frame_jacobian(q, fid)[:3, indices]
    _pull(J, local, 0.5 * np.asarray(c.box_size) * keep, rows, residual)


def _relative_rows(c: RelativePoseConstraint, robot, q, indices, keep: float, rows: list, residual: list) -> None:
    """Rows of the relative-pose error: d e = Jlog6 (J_b - Ad(T_b^-1 T_a) J_a) dq, all in the local frames."""
    data = robot.model.createData()
    pin.computeJointJacobians(robot.model, data, q)
    fa, fb = robot.frame_id(c.link_a), robot.frame_id(c.link_b)
    oMa, oMb = pin.updateFramePlacement(robot.model, data, fa), pin.updateFramePlacement(robot.model, data, fb)
    J_a = pin.getFrameJacobian(robot.model, data, fa, LOCAL)[:, indices]
    J_b = pin.getFrameJacobian(robot.model, data, fb, LOCAL)[:, indices]
    error = pin.SE3(c.relative).actInv(oMa.actInv(oMb))
    J = pin.Jlog6(error) @ (J_b - oMb.actInv(oMa).action @ J_a)
    _pull(J, pin.log6(error).vector, c.tolerance * keep, rows, residual)


GOAL_REGION_ATTEMPTS = 50  # random restarts of the projection before a goal region is declared unreachable


def goal_in_region(
    robot, region: PathConstraints, start: np.ndarray, indices: np.ndarray, is_valid, rng: np.random.Generator,
    deadline: float,
) -> np.ndarray:  # fmt: skip
    """A collision-free full configuration inside the pose ``region`` (its constraints hold at the goal only).

    First the start projected onto the region (the nearest goal in effect), then projections of random
    configurations of the group; NoIKSolution when none lands free before ``deadline`` or the attempts run out.
    """
    region.check_links(robot)
    candidate = start.copy()
    for _ in range(GOAL_REGION_ATTEMPTS):
        goal = region.project(robot, candidate, indices, inset=0.1)
        if goal is not None and is_valid(goal):
            return goal
        if time.monotonic() > deadline:
            break
        candidate = start.copy()
        candidate[indices] = rng.uniform(robot.lower_limits[indices], robot.upper_limits[indices])
    raise errors.NoIKSolution(f"no collision-free state found in the goal region of {', '.join(region.links())}")

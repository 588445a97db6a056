"""What the reactive layer accepts from outside: poses, orientations and paths within stated limits.

Every limit is a named constant; a value outside it raises :class:`InputError` naming the field and
quoting at most a short excerpt of the value, so a node can drop the message and keep serving.
"""

from __future__ import annotations

import math

from maru_planner.errors import InvalidRequest

MAX_COORDINATE = 1e5  # m: |x| and |y| of a pose, goal or path point (100 km from the odometry origin)
MAX_PATH_POSES = 100_000  # poses in one initial path
UNIT_QUATERNION_TOLERANCE = 0.05  # accepted | |q| - 1 | of an orientation

Pose2D = tuple[float, float, float]


class InputError(InvalidRequest):
    """A pose, goal, path or odometry message is outside what the reactive layer accepts."""

    source = "input"


def yaw_from_quaternion(x: float, y: float, z: float, w: float, what: str = "orientation") -> float:
    """Heading (rad) of a unit quaternion; InputError for NaN/inf, zero or far-from-unit ones."""
    x, y, z, w = float(x), float(y), float(z), float(w)
    if not all(math.isfinite(v) for v in (x, y, z, w)):
        raise InputError(f"{what} is not finite ({_excerpt((x, y, z, w))})")
    norm = math.hypot(x, y, z, w)  # scaled: no overflow for huge components
    if abs(norm - 1.0) > UNIT_QUATERNION_TOLERANCE:
        raise InputError(f"{what} is not a unit quaternion (norm {norm:.3g})")
    return math.atan2(2.0 * (w * z + x * y), w * w + x * x - y * y - z * z)


def planar_pose(x: float, y: float, yaw: float, what: str = "pose") -> Pose2D:
    """(x, y, yaw) as floats; InputError if a value is not finite or a coordinate exceeds MAX_COORDINATE."""
    pose = (float(x), float(y), float(yaw))
    if not all(math.isfinite(v) for v in pose):
        raise InputError(f"{what} is not finite ({_excerpt(pose)})")
    if max(abs(pose[0]), abs(pose[1])) > MAX_COORDINATE:
        raise InputError(f"{what} is farther than {MAX_COORDINATE:g} m from the origin ({_excerpt(pose[:2])})")
    return pose


def check_path_size(count: int, what: str = "path") -> None:
    """InputError unless a path of ``count`` poses fits MAX_PATH_POSES (checked before converting them)."""
    if count > MAX_PATH_POSES:
        raise InputError(f"{what} has {count} poses (at most {MAX_PATH_POSES})")


def _excerpt(values: tuple[float, ...]) -> str:
    """At most four floats, 4 significant digits each: short whatever their size."""
    return ", ".join(f"{v:.4g}" for v in values)

"""The knobs of a robot's sphere model (:mod:`maru_planner.collision.sphere_model` fits it).

Plain data, so that a robot profile (:class:`maru_planner.robot.robot_profile.RobotProfile`, its YAML key
``sphere_model``) can carry them; ``maru_planner.collision.sphere_model`` re-exports the class.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class SphereFitOptions:
    """Knobs of the fit. Lengths in metres."""

    max_protrusion: float = 0.015  # how far a sphere may stick out of the link's hull (grown where needed)
    max_edge: float = 0.025  # surface triangles are split until no edge is longer than this
    grid_step: float = 0.012  # spacing of the candidate centres inside the hull
    cylinder_sides: int = 16  # circumscribed prism used to cover a cylinder
    cluster_size: int = 6  # spheres per cluster (the middle level of the bounding hierarchy)


# Accepted ranges of a profile's values (profile_yaml checks them): below them a fit takes minutes and memory
# grows without bound, above them the spheres stop resembling the links.
SPHERE_OPTION_RANGES: dict[str, tuple[float, float]] = {
    "max_protrusion": (0.001, 0.1),
    "max_edge": (0.005, 0.2),
    "grid_step": (0.004, 0.1),
    "cylinder_sides": (6, 64),
    "cluster_size": (1, 64),
}

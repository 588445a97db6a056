"""Moved: the kinematic tree and its numpy forward kinematics to :mod:`maru_planner.collision.kinematic_tree`, the numba
kernels to :mod:`maru_planner.collision.kernels.fk`; this path is kept for existing imports."""

from maru_planner.collision.kernels.fk import (
    FIXED,
    PRISMATIC,
    REVOLUTE,
    REVOLUTE_UNBOUNDED,
    frame_placements_nb,
    joint_pose_nb,
    joint_poses_nb,
    place_members,
    place_points,
    point_in_world,
    root_pose_nb,
    row_distance,
    sphere_centers_nb,
)
from maru_planner.collision.kinematic_tree import KinematicTree, batch_joint_poses, tree_arrays

__all__ = [
    "FIXED", "PRISMATIC", "REVOLUTE", "REVOLUTE_UNBOUNDED", "KinematicTree", "batch_joint_poses",
    "frame_placements_nb", "joint_pose_nb", "joint_poses_nb", "place_members", "place_points", "point_in_world",
    "root_pose_nb", "row_distance", "sphere_centers_nb", "tree_arrays",
]  # fmt: skip

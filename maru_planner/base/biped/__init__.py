"""Biped planning among 3-D obstacles (paper 004): 3-D → 2-D mapping, track following, virtual wall."""

from maru_planner.base.biped.mapping import BipedMap2D, classify, map_3d_to_2d, wheeled_map
from maru_planner.base.biped.track import TrackFollowingPlanner, TrackParams, turn_allowed
from maru_planner.base.biped.wall import VirtualWallPlanner, WallParams
from maru_planner.base.biped.world import BipedRobot, BipedWorld, Box3D, load_world, world_from_dict

__all__ = [
    "BipedMap2D",
    "BipedRobot",
    "BipedWorld",
    "Box3D",
    "TrackFollowingPlanner",
    "TrackParams",
    "VirtualWallPlanner",
    "WallParams",
    "classify",
    "load_world",
    "map_3d_to_2d",
    "turn_allowed",
    "wheeled_map",
    "world_from_dict",
]

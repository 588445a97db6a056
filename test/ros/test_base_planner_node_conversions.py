"""base_conversions: nav_msgs maps, poses and paths <-> core (no DDS)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from maru_planner.base.grid import OccupancyGrid
from maru_planner.base.result import PlanStats, PlanStatus, jsonable
from maru_planner.base.tunnel import TunnelStats
from maru_planner.errors import (
    GoalOccupied,
    InvalidMap,
    InvalidPlanner,
    InvalidRequest,
    NoPath,
    NoPathProven,
    PlanningTimedOut,
    StartOutsideMap,
    TooLarge,
)

conv = pytest.importorskip("maru_planner.ros.base_conversions")


def test_map_message_round_trip_keeps_geometry_and_unknown():
    from builtin_interfaces.msg import Time

    occ = np.zeros((4, 5), bool)
    occ[1, 3] = True
    grid = OccupancyGrid(occ, 0.05, (1.0, -2.0, 0.4))
    msg = conv.grid_to_msg(grid, grid.occupied, Time(), "map")
    msg.data[4 * 5 - 1] = -1
    back = conv.grid_from_msg(msg)
    assert back.resolution == 0.05 and back.origin == pytest.approx((1.0, -2.0, 0.4))
    assert back.occupied[1, 3] and back.unknown[3, 4] and back.occupied[3, 4]
    assert not conv.grid_from_msg(msg, unknown_is_occupied=False).occupied[3, 4]
    msg.info.resolution = 0.0
    with pytest.raises(InvalidMap, match="resolution"):
        conv.grid_from_msg(msg)
    msg.info.resolution, msg.info.width, msg.info.height = 0.05, 5000, 5000
    with pytest.raises(TooLarge, match="5000 x 5000 cells is over the limit"):
        conv.grid_from_msg(msg)


def test_pose_and_path_messages():
    from builtin_interfaces.msg import Time

    path = np.array([[0.0, 1.0, 0.3], [0.1, 1.0, -2.5]])
    msg = conv.path_to_msg(path, Time(), "map")
    assert [conv.pose_from_msg(p) for p in msg.poses] == [pytest.approx(tuple(r)) for r in path]
    assert math.isnan(conv.pose_from_msg(type(msg.poses[0])())[2]) is False  # identity quaternion -> yaw 0


def test_every_status_has_an_error_code_and_stats_are_json():
    assert set(conv.STATUS_TO_ERROR) == set(PlanStatus)
    value = {"a": np.int64(3), "b": np.array([1.5]), "c": float("inf"), "d": [{"e": np.float64(2)}]}
    assert jsonable(value) == {"a": 3, "b": [1.5], "c": None, "d": [{"e": 2.0}]}
    stats = TunnelStats(expansions=np.int64(4), planning_time=0.5, deciding_stage="tunnel b=3", attempts=2)
    assert json.loads(conv.stats_json(stats)) == {
        "expansions": 4,
        "collision_checks": 0,
        "planning_time": 0.5,
        "deciding_stage": "tunnel b=3",
        "tfp_expansions": 0,
        "lcrp_cells": 0,
        "pfp_expansions": 0,
        "attempts": 2,
        "virtual_obstacles": 0,
    }
    assert "cost" not in json.loads(conv.stats_json(PlanStats()))  # None fields are left out
    assert conv.footprint_from_param([1, 2, 3, 4, 5, 6]).shape == (3, 2)
    with pytest.raises(InvalidRequest, match="pairs"):
        conv.footprint_from_param([1, 2, 3])


@pytest.mark.parametrize(
    "error, code",
    [
        (InvalidPlanner("unknown base planner 'rrt'"), "INVALID_PLANNER"),
        (InvalidRequest("start pose has a NaN"), "INVALID_REQUEST"),
        (TooLarge("too big"), "INVALID_REQUEST"),
        (StartOutsideMap("start outside"), "START_OUTSIDE_MAP"),
        (GoalOccupied("goal in collision"), "GOAL_OCCUPIED"),
        (NoPath("no path"), "NO_VALID_PATH"),
        (NoPathProven("enclosed"), "NO_PATH_PROVEN"),
        (PlanningTimedOut("timed out"), "TIMEOUT"),
    ],
)
def test_errors_map_to_codes_once(error, code):
    assert conv.error_code(error) == getattr(conv.E, code)

"""Property-based hostile inputs for the reactive layer (hypothesis, derandomized, bounded).

Whatever a LaserScan, a goal, a plan or a world file holds, the conversions and the world reader
either accept it or raise their typed error; an accepted scan gives a bounded, finite command.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from reactive_helpers import laser_scans

from maru_planner.errors import InvalidRequest, InvalidScene
from maru_planner.reactive import ElasticStripController, StripParams

pytestmark = pytest.mark.ros  # the conversions need the message packages

SETTINGS = settings(max_examples=200, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
FLOAT32 = st.floats(width=32)  # LaserScan fields are float32 on the wire: any of them, NaN and inf included
ANY_FLOAT = st.floats()


@SETTINGS
@given(laser_scans())
def test_any_scan_is_rejected_with_scan_error_or_gives_a_bounded_command(msg):
    from maru_planner.reactive import ScanError
    from maru_planner.ros import reactive_conversions as conv

    try:
        scan = conv.scan_from_msg(msg)
    except ScanError:
        return
    params = StripParams(arm_enabled=False, beam_window=None)
    controller = ElasticStripController(params)
    controller.set_goal((3.0, 0.5, 0.0))
    out = controller.update((0.0, 0.0, 0.0), scan)
    assert math.isfinite(out.v) and math.isfinite(out.w)
    assert abs(out.v) <= params.max_linear + 1e-9 and abs(out.w) <= params.max_angular + 1e-9
    assert np.all(np.isfinite(out.strip))


@SETTINGS
@given(st.tuples(ANY_FLOAT, ANY_FLOAT, ANY_FLOAT), st.tuples(ANY_FLOAT, ANY_FLOAT, ANY_FLOAT, ANY_FLOAT))
def test_any_goal_is_rejected_with_input_error_or_accepted_by_the_controller(position, quaternion):
    from geometry_msgs.msg import PoseStamped

    from maru_planner.reactive.inputs import InputError
    from maru_planner.ros import reactive_conversions as conv

    msg = PoseStamped()
    msg.pose.position.x, msg.pose.position.y, msg.pose.position.z = position
    o = msg.pose.orientation
    o.x, o.y, o.z, o.w = quaternion
    try:
        goal = conv.pose_from_pose_stamped(msg)
    except InputError:
        return
    assert all(math.isfinite(v) for v in goal) and -math.pi <= goal[2] <= math.pi
    ElasticStripController(StripParams(arm_enabled=False)).set_goal(goal)


@pytest.mark.filterwarnings("ignore:invalid value encountered:RuntimeWarning")  # building headings from inf
@SETTINGS
@given(st.lists(st.tuples(ANY_FLOAT, ANY_FLOAT), min_size=0, max_size=6))
def test_any_plan_is_rejected_with_a_typed_error_or_becomes_the_strip(points):
    from maru_planner.ros import reactive_conversions as conv

    plan = conv.path_msg(np.array(points, dtype=float).reshape(-1, 2), "odom", 0.0)
    try:
        path = conv.path_points_from_msg(plan)
        ElasticStripController(StripParams(arm_enabled=False)).set_path(path)
    except InvalidRequest:
        return
    assert np.all(np.isfinite(path))


JSON_LEAVES = st.one_of(st.none(), st.booleans(), st.integers(-(10**6), 10**6), ANY_FLOAT, st.text(max_size=8))
JSON_VALUES = st.recursive(
    JSON_LEAVES,
    lambda inner: st.one_of(st.lists(inner, max_size=4), st.dictionaries(st.text(max_size=8), inner, max_size=4)),
    max_leaves=12,
)
WORLD_KEYS = ["name", "obstacles", "movers", "robot", "path", "goal_tolerance", "max_time", "bounds"]


@st.composite
def world_dicts(draw):
    """Mappings shaped like world files, with any value in any field (sometimes a valid robot)."""
    world = draw(st.dictionaries(st.sampled_from(WORLD_KEYS), JSON_VALUES, max_size=5))
    if draw(st.booleans()):
        laser = draw(
            st.dictionaries(
                st.sampled_from(["range_min", "range_max", "fov_deg", "resolution_deg", "rate", "noise", "x"]),
                JSON_LEAVES,
                max_size=3,
            )
        )
        world["robot"] = {"start": [0, 0, 0], "goal": [1, 0, 0], "laser": laser}
    if draw(st.booleans()):
        world["obstacles"] = draw(
            st.lists(
                st.fixed_dictionaries(
                    {"type": st.sampled_from(["circle", "box", "polygon", "cone"])},
                    optional={
                        "center": JSON_VALUES,
                        "radius": JSON_VALUES,
                        "size": JSON_VALUES,
                        "yaw": JSON_VALUES,
                        "points": JSON_VALUES,
                    },
                ),
                max_size=3,
            )
        )
    return world


@SETTINGS
@given(world_dicts())
def test_any_world_mapping_is_a_world_or_a_world_error(data):
    from maru_planner.sim import World

    try:
        World.from_dict(data)
    except InvalidScene:
        return

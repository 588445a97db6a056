"""The obstacle shape table: a new shape is one entry, and scene YAML, both checkers, the MoveIt reader,
the message conversions, the markers and the pictures pick it up with no other edit."""

from __future__ import annotations

import coal
import numpy as np
import pytest
from geometry_msgs.msg import Pose
from shape_msgs.msg import SolidPrimitive
from visualization_msgs.msg import Marker

from maru_planner.collision import CollisionChecker, SphereCollisionChecker
from maru_planner.errors import InvalidScene
from maru_planner.robot import RobotModel
from maru_planner.ros import markers
from maru_planner.ros import planning_conversions as conv
from maru_planner.scene import Obstacle, Scene, shapes
from maru_planner.scene.moveit import primitive_obstacle

CONE = shapes.ShapeSpec(  # a toy entry: not in the package's table
    name="cone",
    dimensions=(shapes.Dimension("radius"), shapes.Dimension("length")),
    geometry=lambda d: coal.Cone(d["radius"], d["length"]),
    kernel_primitive=lambda d, pose: shapes.KernelPrimitive(
        "cylinder", pose[:3, 3], pose[:3, :3], np.array([d["radius"], d["radius"], d["length"] / 2]), exact=False
    ),
    faces=lambda d: shapes.prism_faces(shapes.ring(d["radius"], -d["length"] / 2), shapes.ring(0.0, d["length"] / 2)),
    marker=lambda d: shapes.MarkerShape("CYLINDER", (2 * d["radius"], 2 * d["radius"], d["length"])),
    primitive_type="CONE",
    primitive_dimensions=("length", "radius"),  # SolidPrimitive: CONE_HEIGHT = 0, CONE_RADIUS = 1
)


@pytest.fixture
def cone_shape():
    shapes.register(CONE)
    yield CONE
    shapes.unregister("cone")


@pytest.fixture(scope="module")
def robot():
    return RobotModel.maru1()


def cone_at(point, name: str = "cone") -> Obstacle:
    xyz = [float(v) for v in point]
    text = f"obstacles: [{{name: {name}, type: cone, radius: 0.05, length: 0.2, pose: {{xyz: {xyz}}}}}]"
    return Scene.from_yaml(text).obstacles[name]


def test_scene_yaml_reads_validates_and_writes_a_new_shape(cone_shape):
    cone = cone_at([0.5, 0.0, 0.1])
    assert cone.type == "cone" and cone.radius == 0.05 and cone.length == 0.2
    again = Scene.from_yaml(Scene([cone]).to_yaml()).obstacles["cone"]
    assert again.dimensions == cone.dimensions
    with pytest.raises(InvalidScene, match="'tip'.*'length'"):
        Scene.from_dict({"obstacles": [{"name": "tip", "type": "cone", "radius": 0.1}]})
    with pytest.raises(InvalidScene, match="'tip'.*'radius'"):
        Obstacle("tip", "cone", radius=-1.0, length=0.1)
    assert isinstance(cone.geometry(), coal.Cone) and cone.faces()


def test_unregistered_shape_is_refused():
    with pytest.raises(InvalidScene, match="'tip'.*type"):
        Obstacle("tip", "cone", radius=0.1, length=0.1)


def test_both_checkers_see_a_new_shape(cone_shape, robot):
    home = robot.named_state("home")
    hand = robot.frame_pose(home, "r_hand")[:3, 3]
    scene = Scene([cone_at(hand)])
    exact = CollisionChecker(robot, scene)
    fast = SphereCollisionChecker(robot, scene)
    assert not exact.is_valid(home) and not fast.is_valid(home)
    assert ("r_hand", "cone") in exact.colliding_pairs(home)
    scene.move("cone", hand - [0.0, 0.0, 1.0])  # below the hand, which points down
    assert exact.is_valid(home) and fast.is_valid(home)
    # near contacts with the bounding cylinder are left to the exact model: same answers, never guessed
    deferred = 0
    for dz in np.linspace(0.0, 0.3, 31):  # the cone's tip points up at the hand
        scene.move("cone", hand - [0.0, 0.0, dz])
        fast.reset_count()
        assert fast.is_valid(home) == exact.is_valid(home), dz
        deferred += fast.exact_pair_checks
    assert deferred > 0


def test_moveit_conversions_and_markers_pick_up_a_new_shape(cone_shape):
    pose = np.eye(4)
    pose[:3, 3] = [0.4, 0.1, 0.2]
    obstacle = primitive_obstacle("cap", {"type": "cone", "dimensions": [0.3, 0.05]}, pose)
    assert obstacle.type == "cone" and obstacle.length == pytest.approx(0.3) and obstacle.radius == 0.05
    as_dict = Scene([obstacle]).to_dict()["obstacles"][0]
    msg = conv.obstacle_to_msg(as_dict, "base_link")
    assert msg.shape.type == SolidPrimitive.CONE and list(msg.shape.dimensions) == pytest.approx([0.3, 0.05])
    back = conv.primitive_to_obstacle("cap", msg.shape, msg.pose)
    assert back["type"] == "cone" and back["length"] == pytest.approx(0.3)
    marker = markers.scene_markers({"obstacles": [as_dict]}, "base_link", None).markers[1]
    assert marker.type == Marker.CYLINDER
    assert [marker.scale.x, marker.scale.y, marker.scale.z] == pytest.approx([0.1, 0.1, 0.3])


def test_primitive_form_of_every_registered_shape_round_trips():
    examples = {"box": {"size": [0.1, 0.2, 0.3]}, "sphere": {"radius": 0.1}, "cylinder": {"radius": 0.1, "length": 0.4}}
    pose = Pose()
    pose.orientation.w = 1.0
    for name, spec in shapes.SHAPES.items():
        if spec.primitive_type is None:
            with pytest.raises(InvalidScene, match="no SolidPrimitive"):
                conv.primitive_msg(name, [1.0], "obstacle 'x'")
            continue
        values = spec.primitive_values(examples[name])
        obstacle = conv.primitive_to_obstacle("x", conv.primitive_msg(name, values), pose)
        assert obstacle["type"] == name
        for key, value in examples[name].items():
            assert obstacle[key] == pytest.approx(value)

"""Scene: YAML schema, validation errors naming obstacle and field, edits bump the version."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

from maru_planner.errors import InvalidScene
from maru_planner.paths import config_path
from maru_planner.scene import Obstacle, Scene

YAML = """
frame: base_link
obstacles:
  - {name: desk, type: box, size: [0.6, 1.2, 0.8], pose: {xyz: [0.5, 0, -0.4], rpy: [0, 0, 0.3]}}
  - {name: ball, type: sphere, radius: 0.1, pose: {xyz: [0.3, 0.2, 0.5]}}
  - {name: post, type: cylinder, radius: 0.05, length: 1.0, pose: {xyz: [0.4, -0.4, 0], rpy: [1.5707963, 0, 0]}}
"""


def test_load_and_roundtrip():
    scene = Scene.from_yaml(YAML)
    assert list(scene.obstacles) == ["desk", "ball", "post"]
    desk = scene.obstacles["desk"]
    assert desk.size == (0.6, 1.2, 0.8)
    np.testing.assert_allclose(desk.pose[:3, 3], [0.5, 0, -0.4])
    np.testing.assert_allclose(desk.pose[:2, 0], [np.cos(0.3), np.sin(0.3)])
    again = Scene.from_yaml(scene.to_yaml())
    for name, obstacle in scene.obstacles.items():
        np.testing.assert_allclose(again.obstacles[name].pose, obstacle.pose, atol=1e-12)
    assert again.to_dict() == Scene.from_dict(scene.to_dict()).to_dict()


@pytest.mark.parametrize(
    "entry, words",
    [
        ({"name": "a", "type": "cone", "radius": 1}, ["'a'", "type"]),
        ({"name": "b", "type": "box"}, ["'b'", "size"]),
        ({"name": "c", "type": "box", "size": [1, -1, 1]}, ["'c'", "size"]),
        ({"name": "d", "type": "sphere", "radius": float("nan")}, ["'d'", "radius"]),
        ({"name": "e", "type": "cylinder", "radius": 0.1}, ["'e'", "length"]),
        ({"name": "f", "type": "box", "size": [1, 1, 1], "pose": {"xyz": [0, float("nan"), 0]}}, ["'f'", "xyz"]),
        ({"name": "g", "type": "box", "size": [1, 1]}, ["'g'", "size"]),
        ({"name": "h", "type": "sphere", "radius": 0.1, "colour": "red"}, ["'h'", "colour"]),
        ({"name": "i", "type": "mesh"}, ["'i'", "path"]),
    ],
)
def test_malformed_obstacles_are_rejected(entry, words):
    with pytest.raises(InvalidScene) as err:
        Scene.from_dict({"obstacles": [entry]})
    for word in words:
        assert word in str(err.value)


def test_scene_level_errors():
    with pytest.raises(InvalidScene, match="duplicate"):
        Scene.from_dict({"obstacles": [{"name": "a", "type": "sphere", "radius": 1}] * 2})
    with pytest.raises(InvalidScene, match="parse"):
        Scene.from_yaml("obstacles: [unclosed")
    with pytest.raises(InvalidScene, match="not in the scene"):
        Scene().remove("ghost")


def test_edits_bump_version():
    scene = Scene()
    versions = [scene.version]
    scene.add(Obstacle("ball", "sphere", radius=0.1))
    versions.append(scene.version)
    scene.move("ball", [0.1, 0.2, 0.3])
    np.testing.assert_allclose(scene.obstacles["ball"].pose[:3, 3], [0.1, 0.2, 0.3])
    versions.append(scene.version)
    scene.move("ball", {"xyz": [0, 0, 1], "rpy": [0, 0, 1]})
    versions.append(scene.version)
    scene.remove("ball")
    versions.append(scene.version)
    scene.add(Obstacle("b", "box", size=(1, 1, 1)))
    scene.clear()
    versions.append(scene.version)
    assert versions == sorted(set(versions)) and len(scene) == 0


def test_paper_scene_files_load():
    for name in ("maru6_desk.yaml", "maru13_desk_box.yaml"):
        scene = Scene.from_yaml(config_path("scenes", name))
        assert scene.frame == "base_link" and "desk" in scene


def test_one_line_yaml_string_and_file_path(tmp_path):
    long_line = "{obstacles: [" + ", ".join(f"{{name: b{i}, type: sphere, radius: 0.1}}" for i in range(20)) + "]}"
    assert len(Scene.from_yaml(long_line)) == 20
    path = tmp_path / "scene.txt"
    path.write_text(YAML)
    assert list(Scene.from_yaml(str(path)).obstacles) == ["desk", "ball", "post"]
    with pytest.raises(InvalidScene, match="not found"):
        Scene.from_yaml(str(tmp_path / "missing.yaml"))


def test_obstacles_pickle_as_plain_data():
    scene = Scene.from_yaml(YAML)
    again = pickle.loads(pickle.dumps(scene))
    assert again.to_dict() == scene.to_dict() and again.obstacles["post"].length == 1.0


@pytest.mark.parametrize("pose", [["\u00a8F\u00dd\x910qx"], [[1, 2], [3]], [None, "a"]])
def test_a_pose_list_of_text_or_uneven_rows_is_an_invalid_scene(pose):
    """bench/robustness.py found a scene file whose pose was a list holding text: a ValueError escaped maru-plan."""
    box = {"name": "a", "type": "box", "size": [0.1, 0.1, 0.1], "pose": pose}
    with pytest.raises(InvalidScene, match="pose must be"):
        Scene.from_dict({"obstacles": [box]})

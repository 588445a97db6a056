"""Robot profiles as YAML files: the built-in robots are such files, a bad file is one line naming the key, and a
robot the package ships no profile for (example-robot-data's xArm 7, docs/your_robot.md) plans from its file."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest

from maru_planner import errors
from maru_planner.planning import cli
from maru_planner.robot import RobotModel, profiles, robots
from maru_planner.robot.profile_yaml import load_profile, profile_from_mapping
from maru_planner.robot.robot_profile import InvalidRobotProfile
from maru_planner.robot.robots import maru1, tiago, ur5
from maru_planner.runtime.robot_loading import DescriptionFiles, RobotDescription, description_source

HERE = Path(__file__).resolve().parent
XARM7 = HERE / "xarm7.yaml"  # the profile docs/your_robot.md writes
XARM7_SCENE = HERE / "xarm7_scene.yaml"
YOUR_ROBOT_PAGE = HERE.parents[2] / "docs" / "your_robot.md"
ROBOTS_DIR = Path(robots.__path__[0])
UR5_FILES = {"source": "example-robot-data", "urdf": "ur_description/urdf/ur5_robot.urdf"}


@pytest.mark.parametrize("path", sorted(ROBOTS_DIR.glob("*.yaml")), ids=lambda p: p.stem)
def test_every_built_in_robot_is_a_yaml_profile_of_the_table(path):
    assert profiles.PROFILES[path.stem] == load_profile(path)


def test_a_built_in_robot_is_one_yaml_file(tmp_path, monkeypatch):
    (tmp_path / "ur5_slow.yaml").write_text(
        (ROBOTS_DIR / "ur5.yaml").read_text().replace("name: ur5", "name: ur5_slow").replace("3.0", "0.5")
    )
    monkeypatch.setattr(robots, "__path__", [*robots.__path__, str(tmp_path)])
    found = {p.name: p for p in profiles.built_in_profiles()}
    assert list(found) == sorted(found) and set(found) == {"maru1", "panda", "talos", "tiago", "ur5", "ur5_slow"}
    assert found["ur5_slow"].acceleration_limits == 0.5 and found["ur5_slow"].groups == found["ur5"].groups


def test_the_robot_modules_keep_their_public_names():
    assert ur5.UR5_JOINTS == profiles.UR5_JOINTS == profiles.PROFILES["ur5"].groups["manipulator"]
    assert tiago.TIAGO_ARM == [f"arm_{i}_joint" for i in range(1, 8)]
    assert profiles.PROFILES["maru1"].ik_strategies == (maru1.one_arm_strategy, maru1.two_hands_strategy)
    assert maru1.ACCELERATION_LIMIT == 4.0


@pytest.mark.parametrize(
    "text, key",
    [
        ("name: a\n", "urdf: required"),
        ("urdf: x.urdf\n", "name: required"),
        ("[1, 2]\n", "expected a mapping"),
        ("name: a\nurdf: x.urdf\ncolour: red\n", "unknown key.*colour"),
        ("name: a.yaml\nurdf: x.urdf\n", "name: expected a name"),
        ("name: a\nurdf: x.urdf\nacceleration_limits: fast\n", "acceleration_limits: expected a finite number"),
        ("name: a\nurdf: x.urdf\nacceleration_limits: [1.0, -2.0]\n", "acceleration_limits: expected a positive"),
        ("name: a\nurdf: x.urdf\ngroups: {arm: []}\n", "groups: group 'arm': expected a non-empty list"),
        ("name: a\nurdf: x.urdf\nignore_links_touching_at_rest: yes please\n", "ignore_links.*true or false"),
        ("name: a\nurdf: x.urdf\nik_strategies: [no_such_module:f]\n", "ik_strategies: no_such_module:f: cannot"),
        ("name: a\nurdf: x.urdf\nik_strategies: [math:no_such]\n", "ik_strategies: .*math has no function"),
        ("name: a\nurdf: x.urdf\nlocked_joints: {j: .nan}\n", "locked_joints: expected a finite number"),
        ("name: a\nurdf: no_such.urdf\n", "urdf: no such file"),
        ("name: a\nurdf: [unclosed\n", "not valid YAML at line \\d"),
    ],
)
def test_a_bad_profile_file_is_one_line_naming_the_key(tmp_path, text, key):
    path = tmp_path / "robot.yaml"
    path.write_text(text)
    with pytest.raises(InvalidRobotProfile, match=f"robot file {re.escape(str(path))}: .*{key}") as raised:
        load_profile(path)
    assert "\n" not in str(raised.value) and isinstance(raised.value, errors.InvalidRequest)


@pytest.mark.parametrize(
    "fields, key",
    [
        ({"acceleration_limits": [3.0, 3.0]}, "acceleration_limits: 2 values for the 6 joints"),
        ({"groups": {"arm": ["shoulder_pan_joint", "wrist_9_joint"]}}, "groups: arm: unknown joint.*wrist_9_joint"),
        ({"end_effectors": {"tool": "no_such_link"}}, "end_effectors: no such frame"),
        ({"locked_joints": {"no_such_joint": 0.0}}, "locked_joints: .*no_such_joint"),
    ],
)
def test_a_profile_that_does_not_fit_its_urdf_names_the_key(fields, key):
    profile = profile_from_mapping({"name": "ur5_bad", **UR5_FILES, **fields}, HERE)
    with pytest.raises(InvalidRobotProfile, match=f"robot ur5_bad: {key}"):
        RobotModel.from_profile(profile)


def test_an_srdf_that_is_not_xml_is_one_line(tmp_path):
    (tmp_path / "not.srdf").write_text("frame: world\n")
    profile = profile_from_mapping({"name": "ur5_bad", **UR5_FILES, "srdf": str(tmp_path / "not.srdf")}, HERE)
    with pytest.raises(ValueError, match=r"^SRDF .*not\.srdf: not valid XML \(.*\)$"):
        RobotModel.from_profile(profile)


def test_locked_joints_and_added_groups_shape_the_model():
    fields = {"locked_joints": {"wrist_3_joint": 0.5}, "groups": {"wrist": ["wrist_1_joint"]}}
    profile = profile_from_mapping({"name": "ur5_five", **UR5_FILES, **fields}, HERE)
    robot = RobotModel.from_profile(profile)
    assert robot.nq == 5 and "wrist_3_joint" not in robot.joint_names
    assert robot.groups["wrist"] == ["wrist_1_joint"] and "all" in robot.groups


def test_the_docs_page_writes_the_fixture_profile():
    """docs/your_robot.md's heredoc is this directory's xarm7.yaml, so the test plans with what the page shows."""
    page = YOUR_ROBOT_PAGE.read_text()
    written = re.search(r"cat > xarm7\.yaml <<'EOF'\n(.*?)\nEOF\n", page, re.S)
    scene = re.search(r"cat > xarm7_scene\.yaml <<'EOF'\n(.*?)\nEOF\n", page, re.S)
    assert written and scene, "docs/your_robot.md no longer writes xarm7.yaml and xarm7_scene.yaml"
    assert written.group(1) + "\n" == XARM7.read_text()
    assert scene.group(1) + "\n" == XARM7_SCENE.read_text()


def test_a_robot_without_a_built_in_profile_plans_a_certified_path_from_its_file(tmp_path, capsys):
    """example-robot-data's xArm 7 from its profile file through maru-plan (--robot-file), as the docs page does."""
    out = tmp_path / "plan.json"
    argv = ["--robot-file", str(XARM7), "--scene", str(XARM7_SCENE), "--group", "arm", "--collision-model", "exact",
            "--start", "-1.0", "0.6", "0", "1.0", "0", "0.4", "0", "--goal", "1.0", "0.6", "0", "1.0", "0", "0.4", "0",
            "--seed", "1", "--time", "5", "--json", str(out), "--quiet"]  # fmt: skip
    assert cli.main(argv) == cli.EXIT_OK
    result = json.loads(out.read_text())
    assert result["success"] and result["stats"]["certified"] and result["stats"]["min_clearance"] > 0.0
    assert result["joint_names"] == [f"joint{i}" for i in range(1, 8)]
    accelerations = np.abs(np.asarray(result["trajectory"]["accelerations"]))
    assert accelerations.max() <= 20.0 + 1e-6 and accelerations.max() > 4.0  # the profile's limit, not the default
    assert cli.main(["--robot", str(XARM7), "--robot-file", str(HERE / "other.yaml"), "--list-groups"]) == 2
    assert "give one robot" in capsys.readouterr().err


def test_the_planning_runtime_loads_a_robot_file():
    files = DescriptionFiles("maru_robot_yaml_test_")
    source, origin = description_source(RobotDescription(robot_file=str(XARM7)), files)
    assert source.profile == str(XARM7) and Path(source.urdf).name == "xarm7.urdf" and "robot xarm7" in origin
    robot = source.load()
    assert robot.name == "xarm7" and robot.end_effectors == {"tool": "link_eef"} and "arm" in robot.groups
    assert load_profile(XARM7).urdf_name == robot.model.name == "UF_ROBOT"
    with pytest.raises(errors.InvalidParameter, match="'robot_file' is set, and so are robot_urdf"):
        description_source(RobotDescription(robot_file=str(XARM7), urdf_file="x.urdf"), files)
    with pytest.raises(errors.InvalidParameter, match="parameter 'robot_file': robot file .*: no such file"):
        description_source(RobotDescription(robot_file="/nonexistent/robot.yaml"), files)

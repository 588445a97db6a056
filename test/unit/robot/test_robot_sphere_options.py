"""A robot profile's ``sphere_model`` options: parsed and checked from YAML, carried by the robot, used by the fit."""

from __future__ import annotations

import re

import numpy as np
import pytest

from maru_planner.collision import sphere_model
from maru_planner.collision.spheres import SphereCollisionChecker
from maru_planner.robot import RobotModel, robot_profile
from maru_planner.robot.profile_yaml import load_profile
from maru_planner.robot.robot_profile import InvalidRobotProfile
from maru_planner.robot.sphere_options import SphereFitOptions

# Two box links: small enough that a fit takes a fraction of a second.
URDF = """<robot name="two_boxes">
  <link name="base"><collision><geometry><box size="0.06 0.06 0.04"/></geometry></collision></link>
  <link name="arm"><collision><origin xyz="0 0 0.06"/><geometry><box size="0.03 0.03 0.08"/></geometry></collision>
  </link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="arm"/><origin xyz="0 0 0.05"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" velocity="1" effort="10"/></joint>
</robot>
"""


@pytest.fixture
def robot_dir(tmp_path, monkeypatch):
    monkeypatch.setenv("MARU_PLANNER_CACHE", str(tmp_path / "cache"))
    (tmp_path / "two_boxes.urdf").write_text(URDF)
    return tmp_path


def write_profile(directory, extra: str = "") -> object:
    path = directory / "two_boxes.yaml"
    path.write_text(f"name: two_boxes\nurdf: two_boxes.urdf\n{extra}")
    return path


def test_without_the_key_a_profile_keeps_the_default_fit(robot_dir):
    robot = RobotModel.from_profile(write_profile(robot_dir))
    assert load_profile(write_profile(robot_dir)).sphere_model == SphereFitOptions()
    assert robot.sphere_options == SphereFitOptions()


def test_sphere_options_in_the_profile_change_the_fit(robot_dir):
    default = RobotModel.from_profile(write_profile(robot_dir))
    coarse = RobotModel.from_profile(
        write_profile(robot_dir, "sphere_model: {max_protrusion: 0.04, max_edge: 0.1, grid_step: 0.03}\n")
    )
    assert coarse.sphere_options == SphereFitOptions(max_protrusion=0.04, max_edge=0.1, grid_step=0.03)
    fine_fit = SphereCollisionChecker(default, use_numba=False).spheres
    coarse_fit = SphereCollisionChecker(coarse, use_numba=False).spheres
    assert coarse_fit.n_spheres < fine_fit.n_spheres
    # the checker fitted with the profile's options, and the runtime's pre-fit (load_or_fit) finds that same model
    again = sphere_model.load_or_fit(coarse.model, coarse.collision_model, coarse.sphere_options)
    assert np.array_equal(again.radius, coarse_fit.radius) and np.array_equal(again.center, coarse_fit.center)
    assert sphere_model.first_fit_notice("two_boxes", coarse.collision_model, coarse.sphere_options) is None


def test_a_urdf_loaded_by_path_takes_the_options_of_its_profile(robot_dir, monkeypatch):
    """A robot_description whose <robot name> is a profile's urdf_name fits its spheres as that profile says."""
    profile = load_profile(write_profile(robot_dir, "urdf_name: two_boxes\nsphere_model: {cluster_size: 3}\n"))
    monkeypatch.setitem(robot_profile.PROFILES, profile.name, profile)
    robot = RobotModel.from_urdf(robot_dir / "two_boxes.urdf")
    assert robot.sphere_options == SphereFitOptions(cluster_size=3)


def test_the_class_keeps_its_old_import_path():
    assert sphere_model.SphereFitOptions is SphereFitOptions


@pytest.mark.parametrize(
    "value, message",
    [
        ("0.01", "sphere_model: expected a mapping of max_protrusion"),
        ("{radius: 0.1}", "sphere_model: unknown key.*radius; known: max_protrusion"),
        ("{max_edge: -0.1}", r"sphere_model: max_edge: expected a value in \[0.005, 0.2\], got -0.1"),
        ("{grid_step: 0.0001}", r"sphere_model: grid_step: expected a value in \[0.004, 0.1\]"),
        ("{max_protrusion: .inf}", "sphere_model: max_protrusion: expected a finite number"),
        ("{max_protrusion: thin}", "sphere_model: max_protrusion: expected a finite number"),
        ("{cylinder_sides: 12.5}", "sphere_model: cylinder_sides: expected a whole number"),
        ("{cluster_size: true}", "sphere_model: cluster_size: expected a whole number"),
        ("{cluster_size: 0}", r"sphere_model: cluster_size: expected a value in \[1, 64\], got 0"),
    ],
)
def test_a_bad_sphere_option_is_one_line_naming_the_key(robot_dir, value, message):
    path = write_profile(robot_dir, f"sphere_model: {value}\n")
    with pytest.raises(InvalidRobotProfile, match=f"robot file {re.escape(str(path))}: {message}") as raised:
        load_profile(path)
    assert "\n" not in str(raised.value)

"""maru_planner.ros.parameters through real rclpy nodes: descriptors, start-up reading, on-set validation."""

from __future__ import annotations

import itertools
import math

import pytest
from rcl_interfaces.msg import ParameterType
from rclpy.parameter import Parameter

from maru_planner.errors import InvalidParameter
from maru_planner.params import ParamSpec
from maru_planner.ros import parameters

SPECS = {
    "resolution": ParamSpec("resolution", 0.02, "edge check step (rad)", lower=1e-4, upper=1.0),
    "workers": ParamSpec("workers", 2, "planning threads", lower=1, upper=16),
    "collision_model": ParamSpec("collision_model", "exact", "checker", choices=("exact", "spheres")),
    "robot_urdf": ParamSpec("robot_urdf", "", "URDF path", read_only=True),
    "publish": ParamSpec("publish", True, "publish markers"),
    "verify_resolution": ParamSpec("verify_resolution", None, "re-check step", lower=1e-5, optional=True),
    "package_dirs": ParamSpec("package_dirs", [], "mesh search dirs"),
    "weights": ParamSpec("weights", (1.0, 2.5), "cost weights"),
}

_names = itertools.count()


@pytest.fixture
def make_node(rclpy_session):
    created = []

    def make(**overrides):
        node = rclpy_session.create_node(
            f"param_test_{next(_names)}",
            parameter_overrides=[Parameter(name, value=value) for name, value in overrides.items()],
        )
        created.append(node)
        return node

    yield make
    for node in created:
        node.destroy_node()


def test_descriptors_carry_type_range_description_and_read_only(make_node):
    node = make_node()
    parameters.declare_parameters(node, SPECS)
    resolution, workers, model, urdf, verify, dirs, weights = node.describe_parameters(
        ["resolution", "workers", "collision_model", "robot_urdf", "verify_resolution", "package_dirs", "weights"]
    )
    assert resolution.type == ParameterType.PARAMETER_DOUBLE and not resolution.dynamic_typing
    assert (resolution.floating_point_range[0].from_value, resolution.floating_point_range[0].to_value) == (1e-4, 1.0)
    assert "edge check step" in resolution.description and "range [0.0001, 1]" in resolution.description
    assert workers.type == ParameterType.PARAMETER_INTEGER
    assert (workers.integer_range[0].from_value, workers.integer_range[0].to_value) == (1, 16)
    assert model.additional_constraints == "one of: exact, spheres"
    assert urdf.read_only and not resolution.read_only
    assert verify.dynamic_typing and verify.floating_point_range[0].to_value == math.inf
    assert dirs.type == ParameterType.PARAMETER_STRING_ARRAY
    assert weights.type == ParameterType.PARAMETER_DOUBLE_ARRAY


def test_start_up_values_are_defaults_or_overrides_checked(make_node):
    node = make_node(resolution=0.05, verify_resolution=0.001, package_dirs=["/meshes"], weights=[3.0, 4.0])
    values = parameters.declare_parameters(node, SPECS)
    assert values == {
        "resolution": 0.05,
        "workers": 2,
        "collision_model": "exact",
        "robot_urdf": "",
        "publish": True,
        "verify_resolution": 0.001,
        "package_dirs": ["/meshes"],
        "weights": (3.0, 4.0),
    }
    defaults = parameters.declare_parameters(make_node(), SPECS)
    assert defaults["verify_resolution"] is None and defaults["package_dirs"] == []
    assert defaults["weights"] == (1.0, 2.5)


@pytest.mark.parametrize(
    ("overrides", "words"),
    [
        ({"resolution": "fine"}, ["'resolution'", "must be a double", "fine"]),
        ({"workers": 2.5}, ["'workers'", "must be a integer"]),
        ({"resolution": 5.0}, ["'resolution'", "out of range", "range [0.0001, 1]"]),
        ({"workers": 0}, ["'workers'", "out of range"]),
        ({"collision_model": "bogus"}, ["'collision_model'", "bogus", "exact, spheres"]),
        ({"verify_resolution": "x"}, ["'verify_resolution'", "must be a number"]),
        ({"verify_resolution": 0.0}, ["'verify_resolution'", "out of range", "value: 0.0"]),
    ],
)
def test_bad_start_up_value_is_one_line_naming_the_parameter(make_node, overrides, words):
    with pytest.raises(InvalidParameter) as caught:
        parameters.declare_parameters(make_node(**overrides), SPECS)
    message = str(caught.value)
    assert "\n" not in message
    for word in words:
        assert word in message


def test_on_set_applies_checked_changes_and_rejects_the_rest_with_a_reason(make_node):
    node = make_node()
    parameters.declare_parameters(node, SPECS)
    applied: list[dict] = []

    def apply(changes):
        if changes.get("publish") is False and "resolution" in changes:
            raise InvalidParameter("publish and resolution cannot change together")
        applied.append(changes)

    parameters.add_on_set_parameters_callback(node, SPECS, apply)

    ok = node.set_parameters([Parameter("resolution", value=0.1), Parameter("collision_model", value="spheres")])
    assert all(r.successful for r in ok)
    assert applied == [{"resolution": 0.1}, {"collision_model": "spheres"}]
    assert node.get_parameter("resolution").value == 0.1

    rejected = {
        "robot_urdf": node.set_parameters([Parameter("robot_urdf", value="/other.urdf")])[0],
        "collision_model": node.set_parameters([Parameter("collision_model", value="bogus")])[0],
        "resolution": node.set_parameters([Parameter("resolution", value=2.0)])[0],
        "verify_resolution": node.set_parameters([Parameter("verify_resolution", value="x")])[0],
    }
    assert all(not r.successful for r in rejected.values())
    assert "read-only" in rejected["robot_urdf"].reason
    assert "bogus" in rejected["collision_model"].reason and "exact, spheres" in rejected["collision_model"].reason
    assert "out of range" in rejected["resolution"].reason
    assert "verify_resolution" in rejected["verify_resolution"].reason

    together = node.set_parameters_atomically([Parameter("publish", value=False), Parameter("resolution", value=0.2)])
    assert not together.successful and together.reason == "publish and resolution cannot change together"
    assert node.get_parameter("resolution").value == 0.1 and node.get_parameter("publish").value is True
    assert node.get_parameter("collision_model").value == "spheres"
    assert len(applied) == 2


def test_an_optional_parameter_cannot_be_unset_at_run_time(make_node):
    node = make_node(verify_resolution=0.01)
    parameters.declare_parameters(node, SPECS)
    parameters.add_on_set_parameters_callback(node, SPECS, lambda changes: None)
    result = node.set_parameters([Parameter("verify_resolution", Parameter.Type.NOT_SET)])[0]
    assert not result.successful and "cannot be unset" in result.reason
    assert node.has_parameter("verify_resolution") and node.get_parameter("verify_resolution").value == 0.01


def test_prefixed_specs_are_declared_under_their_namespace(make_node):
    planner = {"goal_bias": ParamSpec("goal_bias", 0.05, "goal sampling share", lower=0.0, upper=1.0)}
    specs = parameters.prefixed(planner, "planners.RRT")
    assert list(specs) == ["planners.RRT.goal_bias"]
    assert specs["planners.RRT.goal_bias"].name == "planners.RRT.goal_bias"
    node = make_node(**{"planners.RRT.goal_bias": 1.5})
    with pytest.raises(InvalidParameter, match="'planners.RRT.goal_bias'"):
        parameters.declare_parameters(node, specs)

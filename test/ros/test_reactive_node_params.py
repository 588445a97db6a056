"""reactive_node's parameters as Nav2's: descriptors, the params file under a namespace, run-time changes
applied from the next command or rejected with a reason (through the node's parameter services)."""

from __future__ import annotations

import itertools

import pytest
from reactive_helpers import (
    OBSTACLE,
    client_with_goal,
    odom,
    start_namespaced_node,
    synthetic_scan,
)

pytestmark = pytest.mark.ros

NS = "/params_ns"
NODE = f"{NS}/reactive_node"
FILE_MAX_LINEAR = 0.4  # set by the params file (keyed /**), which must apply under the namespace
_stamps = (10.0 + 0.1 * k for k in itertools.count())


@pytest.fixture(scope="module")
def node(node_process, tmp_path_factory):
    return start_namespaced_node(
        node_process, tmp_path_factory.mktemp("params_params"), NS, scan_timeout=600.0, max_linear=FILE_MAX_LINEAR
    )


@pytest.fixture(scope="module")
def client(node, rclpy_session):
    yield from client_with_goal("params_client", NS, node)


def call(client, service_type, name: str, request):
    service = client.spinning.node.create_client(service_type, f"{NODE}/{name}")
    try:
        return client.spinning.call(service, request)
    finally:
        client.spinning.node.destroy_client(service)


def get(client, *names):
    from rcl_interfaces.srv import GetParameters
    from rclpy.parameter import parameter_value_to_python

    response = call(client, GetParameters, "get_parameters", GetParameters.Request(names=list(names)))
    return [parameter_value_to_python(v) for v in response.values]


def set_parameter(client, name: str, value):
    from rcl_interfaces.srv import SetParameters
    from rclpy.parameter import Parameter

    request = SetParameters.Request(parameters=[Parameter(name, value=value).to_parameter_msg()])
    return call(client, SetParameters, "set_parameters", request).results[0]


def step(client):
    stamp = next(_stamps)
    return stamp, client.step(odom((0.0, 0.0, 0.0), stamp), synthetic_scan(stamp, [OBSTACLE]))


def test_params_file_keyed_for_any_namespace_applies(client):
    assert get(client, "max_linear") == [FILE_MAX_LINEAR]
    _, twist = step(client)
    assert 0.0 < twist.linear.x <= FILE_MAX_LINEAR + 1e-9


def test_every_parameter_has_a_descriptor_with_type_description_and_range(client):
    from rcl_interfaces.msg import ParameterType
    from rcl_interfaces.srv import DescribeParameters, ListParameters

    from maru_planner.ros.reactive_node import NODE_SPECS, STRIP_SPECS

    names = call(client, ListParameters, "list_parameters", ListParameters.Request()).result.names
    assert set(STRIP_SPECS) | set(NODE_SPECS) <= set(names)
    declared = sorted(set(STRIP_SPECS) | set(NODE_SPECS))
    described = call(client, DescribeParameters, "describe_parameters", DescribeParameters.Request(names=declared))
    by_name = {d.name: d for d in described.descriptors}
    assert all(d.description and d.type != ParameterType.PARAMETER_NOT_SET for d in by_name.values())
    k_r = by_name["k_r"]
    assert k_r.type == ParameterType.PARAMETER_DOUBLE and "repulsion gain" in k_r.description
    assert (k_r.floating_point_range[0].from_value, k_r.floating_point_range[0].to_value) == (1e-3, 100.0)
    assert by_name["num_vias"].type == ParameterType.PARAMETER_INTEGER
    assert by_name["num_vias"].integer_range[0].from_value == 3
    assert by_name["beam_window"].type == ParameterType.PARAMETER_INTEGER_ARRAY
    assert by_name["strip"].additional_constraints == "one of: modified, plain"
    assert by_name["scan_reliability"].read_only and not k_r.read_only


def test_run_time_changes_apply_from_the_next_command(client):
    from maru_planner.ros import reactive_conversions as conv

    assert set_parameter(client, "max_linear", 0.1).successful
    _, twist = step(client)
    assert 0.0 < twist.linear.x <= 0.1 + 1e-9, "max_linear (accepted and ignored before) limits the next command"

    assert set_parameter(client, "num_vias", 5).successful
    stamp, _ = step(client)
    assert client.spinning.wait_for(lambda: any(conv.stamp_to_s(s.header.stamp) == stamp for s in client.strips))
    strip = next(s for s in client.strips if conv.stamp_to_s(s.header.stamp) == stamp)
    assert 2 <= len(strip.poses) <= 5

    assert set_parameter(client, "publish_arm", False).successful
    silent, _ = step(client)
    assert set_parameter(client, "publish_arm", True).successful
    loud, _ = step(client)
    arm_stamps = lambda: {conv.stamp_to_s(a.header.stamp) for a in client.arm}  # noqa: E731
    assert client.spinning.wait_for(lambda: loud in arm_stamps()), "arm commands again once publish_arm is true"
    assert silent not in arm_stamps(), "no arm command while publish_arm is false"
    assert get(client, "max_linear", "num_vias", "publish_arm") == [0.1, 5, True]


@pytest.mark.parametrize(
    ("name", "value", "reason"),
    [
        ("scan_reliability", "reliable", "read-only"),
        ("k_r", -1.0, "k_r"),
        ("strip", "elastic", "strip"),
        ("num_vias", 2.5, "type"),
        ("beam_window", [50, 10], "beam_window"),
        ("laser_pose", [0.2, 0.0], "laser_pose"),
        ("scan_timeout", 0.0, "scan_timeout"),
    ],
)
def test_changes_that_cannot_apply_are_rejected_with_a_reason(client, name, value, reason):
    before = get(client, name)
    result = set_parameter(client, name, value)
    assert not result.successful and reason in result.reason, result.reason
    assert get(client, name) == before
    _, twist = step(client)
    assert twist.linear.x > 0.0, "the node keeps serving with its previous parameters"


def _another_value(spec):
    """A valid value of ``spec`` other than its default."""
    if spec.choices:
        return next(c for c in spec.choices if c != spec.default)
    if isinstance(spec.default, bool):
        return not spec.default
    if isinstance(spec.default, (int, float)):
        upper = spec.upper if spec.upper is not None else spec.default + 10
        value = min(upper, spec.default + max(abs(spec.default) * 0.5, 1 if isinstance(spec.default, int) else 0.1))
        return type(spec.default)(value)
    if isinstance(spec.default, tuple):
        return [v + 1 for v in spec.default]
    return spec.default + "_2"


def test_every_run_time_parameter_is_applied_or_rejected_with_a_reason(client):
    from maru_planner.ros.reactive_node import NODE_SPECS, STRIP_SPECS

    for name, spec in {**STRIP_SPECS, **NODE_SPECS}.items():
        before = get(client, name)[0]
        value = _another_value(spec)
        result = set_parameter(client, name, value)
        if spec.read_only:
            assert not result.successful and "read-only" in result.reason, name
            continue
        assert result.successful, f"{name} = {value!r}: {result.reason}"
        assert get(client, name) == [value]
        assert set_parameter(client, name, before).successful, name
    _, twist = step(client)
    assert twist.linear.x > 0.0, "the node serves on with its parameters restored"

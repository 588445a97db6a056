"""planning_node's parameters and networking, through a real node process under a namespace.

The node runs as ``/arm/planning_node`` with config/planner.yaml plus an override file (both keyed
``/**/planning_node``) and a user Fast DDS profile (a copy of ours) in its environment. Tests run in
file order; each one that changes a parameter restores it.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import subprocess
import sys

import pytest
from conftest import PAPER_GOAL, PAPER_START, connected_planning_client

pytestmark = pytest.mark.ros

NAMESPACE = "/arm"
NODE = f"{NAMESPACE}/planning_node"
OVERRIDES = """\
/**/planning_node:
  ros__parameters:
    scene_file: none
    resolution: 0.03
    queue_size: 4
    planners:
      RCRRT:
        seed: 11
"""


def _goal(delta: float = 0.3) -> dict[str, float]:
    goal = dict(PAPER_START)
    goal["r_arm_j4"] += delta
    return goal


@pytest.fixture(scope="module")
def user_profile(tmp_path_factory):
    from maru_planner.paths import config_path

    copy = tmp_path_factory.mktemp("user_dds") / "my_profile.xml"
    shutil.copy(config_path("fastdds_loopback.xml"), copy)
    return copy


@pytest.fixture(scope="module")
def arm_node(node_process, rclpy_session, tmp_path_factory, user_profile):
    from maru_planner.paths import config_path

    overrides = tmp_path_factory.mktemp("params") / "overrides.yaml"
    overrides.write_text(OVERRIDES)
    saved = os.environ.get("FASTRTPS_DEFAULT_PROFILES_FILE")
    os.environ["FASTRTPS_DEFAULT_PROFILES_FILE"] = str(user_profile)  # the process inherits it
    try:
        proc = node_process(
            "maru_planner.ros.planning_node",
            ["--ros-args", "-r", f"__ns:={NAMESPACE}", "--params-file", str(config_path("planner.yaml")),
             "--params-file", str(overrides)],
        )  # fmt: skip
    finally:
        os.environ["FASTRTPS_DEFAULT_PROFILES_FILE"] = saved or ""
    yield proc
    assert proc.alive(), "planning_node died:\n" + proc.log()


@pytest.fixture(scope="module")
def client(arm_node, tester):
    return connected_planning_client(tester, arm_node, namespace=NAMESPACE)


@pytest.fixture(scope="module")
def params(client, tester):
    """Get / set / describe parameters of the node, synchronously."""
    from rclpy.parameter_client import AsyncParameterClient

    remote = AsyncParameterClient(tester.node, NODE)
    assert remote.wait_for_services(timeout_sec=60.0)
    return RemoteParameters(remote, tester)


class RemoteParameters:
    def __init__(self, remote, tester):
        self.remote, self.tester = remote, tester

    def _result(self, future):
        assert self.tester.wait_for(future.done, timeout=60.0), "no answer from the parameter service"
        return future.result()

    def get(self, name: str):
        """The value of ``name``; None while unset (an empty array default: rclpy cannot type ``[]``)."""
        from rclpy.parameter import parameter_value_to_python

        values = self._result(self.remote.get_parameters([name])).values
        return parameter_value_to_python(values[0]) if values else None

    def set(self, name: str, value):
        """The SetParametersResult of setting ``name`` alone."""
        from rclpy.parameter import Parameter

        return self._result(self.remote.set_parameters([Parameter(name, value=value)])).results[0]

    def describe(self, name: str):
        return self._result(self.remote.describe_parameters([name])).descriptors[0]


def _codes():
    from maru_planner_interfaces.msg import PlanningError

    return PlanningError


def _assert_success(response):
    from maru_planner.ros.planning_conversions import code_name

    assert response.error.code == _codes().SUCCESS, f"{code_name(response.error.code)}: {response.error.message}"


# ---------------------------------------------------------------- networking, files, descriptors


def test_the_users_dds_profile_is_kept(arm_node, client, user_profile):
    log = arm_node.log()
    assert "DDS networking from the environment" in log, log
    assert f"FASTRTPS_DEFAULT_PROFILES_FILE={user_profile}" in log, log
    assert client.get_scene() is not None  # and the node talks through it


def test_params_file_is_honoured_under_a_namespace(params, client):
    assert params.get("resolution") == 0.03
    assert params.get("queue_size") == 4
    assert params.get("planners.RCRRT.seed") == 11
    assert params.get("workers") == 2  # from config/planner.yaml
    assert list(client.get_scene().obstacles) == []  # scene_file: none


def test_parameters_carry_descriptors(params):
    from rcl_interfaces.msg import ParameterType

    resolution = params.describe("resolution")
    assert resolution.type == ParameterType.PARAMETER_DOUBLE
    assert resolution.floating_point_range[0].from_value == pytest.approx(1e-4)
    assert "motion-check step" in resolution.description
    assert params.describe("robot_urdf").read_only
    assert params.describe("collision_model").additional_constraints == "one of: exact, spheres"
    assert params.describe("planners.PRM.max_nearest_neighbors").integer_range[0].from_value == 1
    step = params.describe("planners.CBiRRT.step")  # CBiRRT is registered like every planner
    assert step.floating_point_range[0].to_value == pytest.approx(1.0) and "projected" in step.description


def _flattened(params: dict, prefix: str = "") -> dict:
    """``{"planners": {"RRT": {"range": 0.0}}}`` as ``{"planners.RRT.range": 0.0}`` (ROS's parameter names)."""
    flat = {}
    for key, value in params.items():
        if isinstance(value, dict):
            flat.update(_flattened(value, f"{prefix}{key}."))
        else:
            flat[f"{prefix}{key}"] = value
    return flat


def test_config_planner_yaml_restates_only_declared_defaults():
    import yaml

    from maru_planner.paths import config_path
    from maru_planner.ros.planning_node import parameter_specs

    section = yaml.safe_load(config_path("planner.yaml").read_text())["/**/planning_node"]["ros__parameters"]
    specs = parameter_specs()
    for name, value in _flattened(section).items():
        assert name in specs, f"config/planner.yaml: {name} is not a parameter of planning_node"
        assert specs[name].check(value) == specs[name].default, f"config/planner.yaml: {name} is not its default"


# ---------------------------------------------------------------- run-time changes


def _another_value(spec):
    """A valid value of ``spec`` other than its default (an optional one: a harmless setting)."""
    kind = spec.value_type
    if spec.name == "default_group":
        return "right_arm"
    if spec.choices:
        return next(c for c in spec.choices if c != spec.default)
    if kind is bool:
        return not spec.default
    if kind is str:
        return "/elsewhere"
    if kind is list:
        return ["/elsewhere"]
    if spec.default is None:
        return kind(0.01 if kind is float else 1)
    candidate = kind(spec.default * 2 if spec.default else 1)
    return candidate if spec.upper is None or candidate <= spec.upper else kind(spec.lower)


def test_every_parameter_change_is_applied_or_rejected_with_a_reason(params):
    from maru_planner.ros.planning_node import parameter_specs

    for name, spec in parameter_specs().items():
        before = params.get(name)
        value = _another_value(spec)
        result = params.set(name, value)
        if spec.read_only:
            assert not result.successful and "read-only" in result.reason, (name, result)
            assert params.get(name) == before
            continue
        assert result.successful, (name, value, result.reason)
        assert params.get(name) == pytest.approx(value), name
        if before is not None:  # an unset optional one cannot be unset again (rclpy would undeclare it)
            restored = params.set(name, before)
            assert restored.successful, (name, restored.reason)


@contextlib.contextmanager
def changed(params, **values):
    """Parameters set to ``values`` (each accepted) for the ``with`` block, then set back."""
    before = {name: params.get(name) for name in values}
    try:
        for name, value in values.items():
            result = params.set(name, value)
            assert result.successful, (name, value, result.reason)
        yield
    finally:
        for name, value in before.items():
            assert params.set(name, value).successful, name


def test_default_planner_and_group_changes_show_in_the_next_plan(params, client):
    with changed(params, default_planner="GoalBiasedRRT"):
        response = client.plan(_goal(), start=PAPER_START, planner_id="", time_budget=5.0, seed=3)
        _assert_success(response)
        assert response.stats.planner_id == "GoalBiasedRRT"
    right_goal = {f"r_arm_j{i}": PAPER_START[f"r_arm_j{i}"] for i in range(1, 7)}
    right_goal["r_arm_j4"] += 0.3
    with changed(params, default_group="right_arm"):
        response = client.plan(right_goal, start=PAPER_START, group="", time_budget=5.0, seed=3)
        _assert_success(response)
        assert list(response.trajectory.joint_names) == [f"r_arm_j{i}" for i in range(1, 7)]


def test_resolution_and_budget_changes_show_in_the_next_plan(params, client):
    coarse = client.plan(_goal(), start=PAPER_START, time_budget=5.0, seed=3)
    with changed(params, resolution=0.003):
        fine = client.plan(_goal(), start=PAPER_START, time_budget=10.0, seed=3)
    _assert_success(coarse)
    _assert_success(fine)
    assert fine.stats.collision_checks > 3 * coarse.stats.collision_checks
    with changed(params, max_planning_time=2.0):
        response = client.plan(_goal(), start=PAPER_START, time_budget=3.0)
    assert response.error.code == _codes().INVALID_REQUEST and "max_planning_time 2.0" in response.error.message


def test_a_planner_parameter_change_shows_in_the_next_plan(params, client):
    default = client.plan(_goal(), start=PAPER_START, planner_id="RRTConnect", time_budget=5.0, seed=3)
    with changed(params, **{"planners.RRTConnect.range": 0.01}):  # 0.3 rad in steps of at most 0.01 rad
        short_edges = client.plan(_goal(), start=PAPER_START, planner_id="RRTConnect", time_budget=10.0, seed=3)
    _assert_success(default)
    _assert_success(short_edges)
    assert short_edges.stats.nodes >= 30 > default.stats.nodes


def test_collision_model_change_rebuilds_the_planning_contexts(params, client, arm_node):
    assert params.get("collision_model") == "spheres"  # the default (config/planner.yaml)
    logged = len(arm_node.log())
    with changed(params, collision_model="exact"):
        _assert_success(client.plan(_goal(0.2), start=PAPER_START, time_budget=10.0, seed=3))
    log = arm_node.log()[logged:]
    assert "collision_model='exact' (planning contexts rebuilt" in log, log
    assert "CompiledRRTConnect on exact" in log, log  # the default planner id, run as OMPL's RRTConnect there


def test_a_full_queue_answers_busy_after_workers_and_queue_size_change(params, client, tester):
    from maru_planner.ros.planning_client import plan_request

    with changed(params, workers=1, queue_size=0):
        # plain RRT cannot solve the paper problem: it holds the only worker for its whole budget
        long_plan = client.plan_client.call_async(
            plan_request(PAPER_GOAL, start=PAPER_START, planner_id="RRT", time_budget=4.0)
        )
        busy = None
        while not long_plan.done() and busy is None:
            response = client.plan(_goal(), start=PAPER_START, time_budget=2.0)
            if response.error.code == _codes().BUSY:
                busy = response
        assert busy is not None, "never answered BUSY while the only worker was planning"
        assert "queue_size 0" in busy.error.message
        assert tester.wait_for(long_plan.done, timeout=60.0)
        assert long_plan.result().error.code == _codes().TIMED_OUT
    _assert_success(client.plan(_goal(), start=PAPER_START, time_budget=5.0))


@pytest.mark.parametrize(
    ("name", "value", "words"),
    [
        ("robot_urdf", "/other.urdf", ["read-only"]),
        ("scene_file", "scenes/maru6_desk.yaml", ["read-only"]),
        ("collision_model", "bogus", ["bogus", "exact, spheres"]),
        ("workers", 0, ["out of range"]),
        ("resolution", "fine", ["type"]),
        ("default_group", "legs", ["legs", "upper_body"]),
        ("default_planner", "Foo", ["Foo", "RRTConnect"]),
        ("planners.RCRRT.goal_bias", 2.0, ["out of range"]),
        ("planners.RCRRT.seed", "x", ["seed"]),
    ],
)
def test_bad_run_time_values_are_rejected_with_a_reason(params, client, name, value, words):
    before = params.get(name)
    result = params.set(name, value)
    assert not result.successful
    for word in words:
        assert word in result.reason, result.reason
    assert params.get(name) == before
    _assert_success(client.plan(_goal(), start=PAPER_START, time_budget=5.0))


# ---------------------------------------------------------------- start-up errors


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (["-p", "resolution:=fine"], ["resolution", "double"]),
        (["-p", "workers:=0"], ["workers", "out of range"]),
    ],
)
def test_a_bad_start_up_parameter_is_one_line_and_a_non_zero_exit(args, words):
    run = subprocess.run(
        [sys.executable, "-m", "maru_planner.ros.planning_node", "--ros-args", *args],
        capture_output=True,
        text=True,
        timeout=180,
    )
    output = (run.stdout + run.stderr).strip()
    assert run.returncode == 2, output
    assert "Traceback" not in output
    assert len(output.splitlines()) == 1, output
    for word in words:
        assert word in output


def test_a_bad_params_file_value_is_one_line(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("/**:\n  ros__parameters:\n    collision_model: octomap\n")
    run = subprocess.run(
        [sys.executable, "-m", "maru_planner.ros.planning_node", "--ros-args", "--params-file", str(bad)],
        capture_output=True,
        text=True,
        timeout=180,
    )
    output = (run.stdout + run.stderr).strip()
    assert run.returncode == 2, output
    assert len(output.splitlines()) == 1 and "octomap" in output and "exact, spheres" in output, output

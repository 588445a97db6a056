"""The three nodes as managed nodes, driven through their real lifecycle services (lifecycle_msgs).

Each node runs in its own process with ``autostart:=false`` in a namespace of its own, and the test
moves it through configure, activate, deactivate, re-activate, cleanup and shutdown with
``<node>/change_state``, reading ``<node>/get_state`` after each step, and checks what it serves
in between: requests answered INACTIVE (or goals rejected) unless active, a zero ``cmd_vel`` when
the reactive node is deactivated, a failed configure that leaves the node unconfigured.
"""

from __future__ import annotations

import time

import pytest

from maru_planner.paths import config_path

pytestmark = pytest.mark.ros


class Lifecycle:
    """``ros2 lifecycle get/set`` for one node, through the test's spinning client node."""

    def __init__(self, spinning, node: str):
        from lifecycle_msgs.srv import ChangeState, GetState

        self.spinning = spinning
        self._change = spinning.node.create_client(ChangeState, f"{node}/change_state")
        self._get = spinning.node.create_client(GetState, f"{node}/get_state")

    def state(self) -> str:
        """The node's state label. GetState only reads: a request lost while the node's reply path is still being
        discovered (the first call after start-up; seen once in CI) is sent again."""
        from lifecycle_msgs.srv import GetState

        deadline = time.monotonic() + 120.0
        while True:
            try:
                return self.spinning.call(self._get, GetState.Request(), timeout=10.0).current_state.label
            except TimeoutError:
                if time.monotonic() > deadline:
                    raise

    def set(self, transition: str) -> bool:
        """Trigger ``transition`` by label (configure, activate, deactivate, cleanup, shutdown); its success."""
        from lifecycle_msgs.srv import ChangeState

        request = ChangeState.Request()
        request.transition.label = transition
        return self.spinning.call(self._change, request, timeout=300.0).success


@pytest.fixture(scope="module")
def tester(rclpy_session):
    from conftest import SpinningNode

    spinning = SpinningNode("lifecycle_tests")
    yield spinning
    spinning.destroy()


def _manual_start(namespace: str, *args: str) -> list[str]:
    return ["--ros-args", "-r", f"__ns:=/{namespace}", "-p", "autostart:=false", *args]


# ---------------------------------------------------------------- planning_node


def test_planning_node_serves_only_while_active(node_process, tester):
    from maru_planner.ros.planning_client import PlanningClient, plan_goal
    from maru_planner_interfaces.msg import PlanningError
    from maru_planner_interfaces.srv import GetScene, PlanMotion

    process = node_process(
        "maru_planner.ros.planning_node",
        _manual_start("lc_arm", "--params-file", str(config_path("planner.yaml")), "-p", "workers:=1"),
    )
    lifecycle = Lifecycle(tester, "/lc_arm/planning_node")
    assert lifecycle.state() == "unconfigured", process.log()
    client = PlanningClient(node=tester.node, namespace="/lc_arm")

    def plan_code() -> int:  # an empty request: INVALID_REQUEST from an active node
        return tester.call(client.plan_client, PlanMotion.Request(), timeout=120.0).error.code

    def scene_names() -> list[str]:
        return [o.name for o in tester.call(client.scene_client, GetScene.Request(), timeout=120.0).obstacles]

    def goal_accepted() -> bool:
        assert client.plan_action_client.wait_for_server(timeout_sec=120.0)
        future = client.plan_action_client.send_goal_async(plan_goal({"waist_yaw": 0.1}, time_budget=1.0))
        assert tester.wait_for(future.done, timeout=120.0)
        handle = future.result()
        if handle.accepted:
            result = handle.get_result_async()
            assert tester.wait_for(result.done, timeout=120.0)
        return handle.accepted

    assert lifecycle.set("configure") and lifecycle.state() == "inactive", process.log()
    assert plan_code() == PlanningError.INACTIVE
    assert scene_names() == []
    assert not goal_accepted()
    for _ in range(2):  # activation, then re-activation after a deactivation
        assert lifecycle.set("activate") and lifecycle.state() == "active", process.log()
        assert plan_code() == PlanningError.INVALID_REQUEST
        assert scene_names() == ["desk", "box"]
        assert goal_accepted()
        assert lifecycle.set("deactivate") and lifecycle.state() == "inactive"
        assert plan_code() == PlanningError.INACTIVE
    assert lifecycle.set("cleanup") and lifecycle.state() == "unconfigured"
    assert lifecycle.set("configure") and lifecycle.set("activate") and lifecycle.state() == "active"
    assert plan_code() == PlanningError.INVALID_REQUEST
    assert lifecycle.set("shutdown") and lifecycle.state() == "finalized"
    assert process.alive(), process.log()
    assert "Traceback" not in process.log()


# ---------------------------------------------------------------- base_planner_node


def _set_parameter(tester, node: str, name: str, value: str) -> bool:
    from rcl_interfaces.msg import Parameter, ParameterType, ParameterValue
    from rcl_interfaces.srv import SetParameters

    client = tester.node.create_client(SetParameters, f"{node}/set_parameters")
    value_msg = ParameterValue(type=ParameterType.PARAMETER_STRING, string_value=value)
    request = SetParameters.Request(parameters=[Parameter(name=name, value=value_msg)])
    return tester.call(client, request, timeout=120.0).results[0].successful


def test_base_planner_node_transitions_and_a_failed_configure(node_process, tester):
    from nav_msgs.srv import GetPlan

    from maru_planner_interfaces.srv import PlanBasePath

    node = "/lc_base/base_planner_node"
    process = node_process("maru_planner.ros.base_planner_node", _manual_start("lc_base"))
    lifecycle = Lifecycle(tester, node)
    assert lifecycle.state() == "unconfigured", process.log()
    # accepted while unconfigured (a string), refused by configure: the node stays unconfigured
    assert _set_parameter(tester, node, "planner_id", "no_such_planner")
    assert not lifecycle.set("configure")
    assert lifecycle.state() == "unconfigured"
    assert "configure failed" in process.log() and "no_such_planner" in process.log()
    assert _set_parameter(tester, node, "planner_id", "mspp")
    assert lifecycle.set("configure") and lifecycle.state() == "inactive", process.log()

    plan_client = tester.node.create_client(PlanBasePath, "/lc_base/plan_base_path")
    make_plan = tester.node.create_client(GetPlan, "/lc_base/make_plan")

    def plan_code() -> int:
        return tester.call(plan_client, PlanBasePath.Request(), timeout=120.0).error_code

    assert plan_code() == PlanBasePath.Response.INACTIVE
    assert "inactive" in tester.call(plan_client, PlanBasePath.Request(), timeout=120.0).error_msg
    assert list(tester.call(make_plan, GetPlan.Request(), timeout=120.0).plan.poses) == []
    assert lifecycle.set("activate") and lifecycle.state() == "active"
    assert plan_code() == PlanBasePath.Response.NO_MAP  # served: no map was published
    assert lifecycle.set("deactivate") and plan_code() == PlanBasePath.Response.INACTIVE
    assert lifecycle.set("activate") and plan_code() == PlanBasePath.Response.NO_MAP
    assert lifecycle.set("deactivate") and lifecycle.set("cleanup") and lifecycle.state() == "unconfigured"
    assert lifecycle.set("shutdown") and lifecycle.state() == "finalized"
    assert process.alive() and "Traceback" not in process.log(), process.log()


# ---------------------------------------------------------------- reactive_node


def test_reactive_node_commands_only_while_active_and_stops_the_base_on_deactivate(node_process, tester, tmp_path):
    from reactive_helpers import OBSTACLE, ReactiveClient, reactive_params_file, synthetic_scan

    from maru_planner.ros import reactive_conversions as conv

    overrides = reactive_params_file(tmp_path, scan_reliability="reliable", use_sim_time=True, scan_timeout=600.0)
    args = ["--params-file", str(config_path("reactive.yaml")), "--params-file", str(overrides)]
    process = node_process(
        "maru_planner.ros.reactive_node", _manual_start("lc_reactive", "-r", "/clock:=/lc_reactive/clock", *args)
    )
    lifecycle = Lifecycle(tester, "/lc_reactive/reactive_node")
    assert lifecycle.state() == "unconfigured", process.log()
    assert lifecycle.set("configure") and lifecycle.set("activate") and lifecycle.state() == "active"
    client = ReactiveClient(tester, namespace="/lc_reactive", process=process)
    goal = conv.pose_stamped_msg((4.0, 0.0, 0.0), "odom", 1.05)

    def command(stamp: float):
        return client.step(conv.odom_msg((0.0, 0.0, 0.0), 0.0, 0.0, stamp, "odom", "base_link"),
                           synthetic_scan(stamp, [OBSTACLE]))  # fmt: skip

    client.wait_connected()
    client.send_and_confirm(client.goal_pub, goal, process, "goal (")
    assert command(1.1).linear.x > 0.0, "an active node with a free goal moves the base"

    moving = client.twist_count()
    assert lifecycle.set("deactivate") and lifecycle.state() == "inactive"
    assert tester.wait_for(lambda: client.twist_count() > moving, timeout=60.0), process.log()
    last = client.twists[-1]
    assert (last.linear.x, last.angular.z) == (0.0, 0.0), "deactivation publishes a zero cmd_vel"

    assert lifecycle.set("activate") and lifecycle.state() == "active"
    client.wait_connected()  # new subscriptions: matched again
    held = command(1.3)
    assert (held.linear.x, held.angular.z) == (0.0, 0.0), "the goal is forgotten on deactivation"
    client.send_and_confirm(client.goal_pub, goal, process, "goal (")
    assert command(1.4).linear.x > 0.0, "re-activated with a new goal, the node moves the base again"

    assert lifecycle.set("deactivate") and lifecycle.set("cleanup") and lifecycle.state() == "unconfigured"
    assert lifecycle.set("shutdown") and lifecycle.state() == "finalized"
    assert process.alive() and "Traceback" not in process.log(), process.log()

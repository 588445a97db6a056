"""Lifecycle misuse (issue 36): every ``change_state`` request in every primary state is answered, none kills a node.

Each of the three nodes runs once for the whole module, as its own process with ``autostart:=false``, driven by
real rclpy clients of ``<node>/change_state``, ``get_state`` and ``get_available_transitions``. In each primary
state (unconfigured, inactive, active, finalized) the node lists exactly the transitions of the ROS 2 managed-node
design, answers ``success: false`` to every other transition id and label (configure while active, the callback
ids 97-99, the transition states' ids, unknown ids and labels, a valid id behind an unknown label), stays in its
state and alive, and keeps serving: plan_motion / plan_base_path answer (INACTIVE unless active), reactive_node
answers a scan with a command while active. The valid transitions are taken by id and by label in turn.
"""

from __future__ import annotations

import itertools
import time
from collections.abc import Callable
from dataclasses import dataclass

import pytest
from conftest import NodeProcess, SpinningNode
from lifecycle_msgs.msg import Transition
from lifecycle_msgs.srv import ChangeState, GetAvailableTransitions, GetState
from rcl_interfaces.srv import GetParameters

from maru_planner.paths import config_path
from maru_planner.ros.planning_client import call_service, call_until_answered

pytestmark = pytest.mark.ros

CONFIGURE, CLEANUP = Transition.TRANSITION_CONFIGURE, Transition.TRANSITION_CLEANUP
ACTIVATE, DEACTIVATE = Transition.TRANSITION_ACTIVATE, Transition.TRANSITION_DEACTIVATE
# state -> {id: label} of the transitions that start from it, per the ROS 2 managed-node design
DESIGN: dict[str, dict[int, str]] = {
    "unconfigured": {CONFIGURE: "configure", Transition.TRANSITION_UNCONFIGURED_SHUTDOWN: "shutdown"},
    "inactive": {CLEANUP: "cleanup", ACTIVATE: "activate", Transition.TRANSITION_INACTIVE_SHUTDOWN: "shutdown"},
    "active": {DEACTIVATE: "deactivate", Transition.TRANSITION_ACTIVE_SHUTDOWN: "shutdown"},
    "finalized": {},
}
# every id lifecycle_msgs names (public, transition-state and callback ids) and some it does not; ids are uint8
PROBE_IDS = sorted({getattr(Transition, n) for n in dir(Transition) if n.startswith("TRANSITION_")} | {9, 100, 255})
PROBE_LABELS = [
    "create", "configure", "cleanup", "activate", "deactivate", "shutdown", "destroy",
    "transition_success", "transition_failure", "transition_error",  # labels of the transition states' ways out
    "unconfigured_shutdown", "Activate", " configure", "bogus", "\u00e4ktivieren", "x" * 10_000,
]  # fmt: skip
START_TIMEOUT = 120.0  # s for the first answer: the node may still be starting
ANSWER_TIMEOUT = 30.0  # s for any later answer to a request that changes nothing
TRANSITION_TIMEOUT = 300.0  # s: planning_node's configure warms its kernels up


class Lifecycle:
    """The lifecycle services of one node, and its parameter service, called from the test's spinning node."""

    def __init__(self, spinning: SpinningNode, node: str, process: NodeProcess):
        self.process = process
        self._parameters = spinning.node.create_client(GetParameters, f"{node}/get_parameters")
        self._change = spinning.node.create_client(ChangeState, f"{node}/change_state")
        self._get = spinning.node.create_client(GetState, f"{node}/get_state")
        self._transitions = spinning.node.create_client(GetAvailableTransitions, f"{node}/get_available_transitions")
        self._timeout = START_TIMEOUT

    def answer(self, client, request):
        """The answer to a request that changes nothing, sent again until answered (an answer proves that the
        node has matched this client's reply reader); no answer is a failure that says whether the node died."""
        try:
            response = call_until_answered(client, request, self._timeout)
        except TimeoutError as exc:
            alive = "alive" if self.process.alive() else "dead"
            raise AssertionError(f"{exc} (the node is {alive}):\n{self.process.log()[-3000:]}") from None
        self._timeout = ANSWER_TIMEOUT
        return response

    def state(self) -> str:
        return self.answer(self._get, GetState.Request()).current_state.label

    def autostart(self) -> bool:
        """The node's ``autostart`` parameter, read through its parameter service (served in every state)."""
        return self.answer(self._parameters, GetParameters.Request(names=["autostart"])).values[0].bool_value

    def available(self) -> dict[int, str]:
        answer = self.answer(self._transitions, GetAvailableTransitions.Request())
        return {t.transition.id: t.transition.label for t in answer.available_transitions}

    def refused(self, transition_id: int, label: str = "") -> bool:
        """Whether a request the node must refuse is refused (refused, it changes nothing: sent until answered)."""
        request = ChangeState.Request(transition=Transition(id=transition_id, label=label))
        return not self.answer(self._change, request).success

    def take(self, transition_id: int = 0, label: str = "") -> bool:
        """Whether a valid transition succeeded: sent once (``refused`` has proven the reply path), as sending it
        again while the first is still running (a slow configure) would be refused."""
        request = ChangeState.Request(transition=Transition(id=transition_id, label=label))
        return call_service(self._change, request, TRANSITION_TIMEOUT).success


@dataclass
class Target:
    """One node under test: its process, its lifecycle and a check of its normal service in a given state."""

    process: NodeProcess
    lifecycle: Lifecycle
    serves: Callable[[str], None]


# ---------------------------------------------------------------- the three nodes and their normal service


def planning_node(start: Callable[..., NodeProcess], spinning: SpinningNode, _tmp) -> Target:
    from maru_planner.ros.planning_client import PlanningClient
    from maru_planner_interfaces.msg import PlanningError
    from maru_planner_interfaces.srv import PlanMotion

    args = ["--params-file", str(config_path("planner.yaml")), "-p", "workers:=1", "-p", "worker_processes:=false"]
    process = start("maru_planner.ros.planning_node", _unconfigured("misuse_arm", *args))
    plan_client = PlanningClient(node=spinning.node, namespace="/misuse_arm").plan_client

    def serves(state: str) -> None:  # an empty request: INVALID_REQUEST from an active node
        if state not in ("inactive", "active"):
            return  # configure creates the services, cleanup and shutdown destroy them
        expected = PlanningError.INVALID_REQUEST if state == "active" else PlanningError.INACTIVE
        assert call_until_answered(plan_client, PlanMotion.Request(), START_TIMEOUT).error.code == expected

    return Target(process, Lifecycle(spinning, "/misuse_arm/planning_node", process), serves)


def base_planner_node(start: Callable[..., NodeProcess], spinning: SpinningNode, _tmp) -> Target:
    from maru_planner_interfaces.srv import PlanBasePath

    process = start("maru_planner.ros.base_planner_node", _unconfigured("misuse_base"))
    plan_client = spinning.node.create_client(PlanBasePath, "/misuse_base/plan_base_path")

    def serves(state: str) -> None:  # no map was published: NO_MAP from an active node
        if state not in ("inactive", "active"):
            return  # configure creates the services, cleanup and shutdown destroy them
        expected = PlanBasePath.Response.NO_MAP if state == "active" else PlanBasePath.Response.INACTIVE
        assert call_until_answered(plan_client, PlanBasePath.Request(), START_TIMEOUT).error_code == expected

    return Target(process, Lifecycle(spinning, "/misuse_base/base_planner_node", process), serves)


def reactive_node(start: Callable[..., NodeProcess], spinning: SpinningNode, tmp) -> Target:
    from reactive_helpers import ReactiveClient, odom, reactive_params_file, synthetic_scan

    from maru_planner.ros.reactive_conversions import stamp_to_ns

    params = reactive_params_file(tmp, scan_reliability="reliable", use_sim_time=True, scan_timeout=600.0)
    args = ["-r", "/clock:=/misuse_reactive/clock", "--params-file", str(params)]
    process = start("maru_planner.ros.reactive_node", _unconfigured("misuse_reactive", *args))
    client = ReactiveClient(spinning, namespace="/misuse_reactive", process=process)
    stamps = (1.0 + 0.1 * k for k in itertools.count())

    def serves(state: str) -> None:
        """While active, a scan is answered by a command; sent again (new stamp) until the node has matched us."""
        if state != "active":
            return  # it answers no scan then
        deadline = time.monotonic() + START_TIMEOUT
        while time.monotonic() < deadline:
            stamp = next(stamps)
            scan = synthetic_scan(stamp)
            answer_key = stamp_to_ns(scan.header.stamp)
            client.publish_clock(answer_key)
            client.odom_pub.publish(odom((0.0, 0.0, 0.0), stamp))
            client.scan_pub.publish(scan)
            if spinning.wait_for(lambda key=answer_key: key in client.stamped, timeout=1.0):
                return
        raise AssertionError(f"reactive_node answered no scan while active:\n{process.log()[-3000:]}")

    return Target(process, Lifecycle(spinning, "/misuse_reactive/reactive_node", process), serves)


NODES = {"planning_node": planning_node, "base_planner_node": base_planner_node, "reactive_node": reactive_node}


def _unconfigured(namespace: str, *args: str) -> list[str]:
    return ["--ros-args", "-r", f"__ns:=/{namespace}", *args, "-p", "autostart:=false"]


@pytest.fixture(scope="module")
def targets(node_process, tester, tmp_path_factory) -> dict[str, Target]:
    """The three nodes, started together at once (they boot in parallel while the first is driven)."""
    return {name: make(node_process, tester, tmp_path_factory.mktemp(name)) for name, make in NODES.items()}


# ---------------------------------------------------------------- the test


def refuses_everything_else(target: Target, state: str) -> None:
    """In ``state``: the design's transitions listed, every other id and label refused, the node alive, its
    parameters and its normal service answering."""
    lifecycle, valid = target.lifecycle, DESIGN[state]
    assert lifecycle.state() == state, target.process.log()[-3000:]
    assert lifecycle.available() == valid
    a_valid_id = next(iter(valid), CONFIGURE)  # behind an unknown label: the label names the transition
    requests = [(i, "") for i in PROBE_IDS if i not in valid]
    requests += [(a_valid_id, label) for label in PROBE_LABELS if label not in valid.values()]
    accepted = [(i, label[:20]) for i, label in requests if not lifecycle.refused(i, label)]
    assert not accepted, f"accepted while {state}: {accepted}"
    assert target.process.alive(), target.process.log()[-3000:]
    assert lifecycle.state() == state
    assert lifecycle.autostart() is False  # the parameter service answers
    target.serves(state)


@pytest.mark.parametrize("name", NODES)
def test_invalid_transitions_are_refused_in_every_state_and_the_node_keeps_serving(targets, name):
    target = targets[name]
    lifecycle, process = target.lifecycle, target.process
    refuses_everything_else(target, "unconfigured")
    assert lifecycle.take(CONFIGURE), process.log()[-3000:]
    refuses_everything_else(target, "inactive")
    assert lifecycle.take(label="activate"), process.log()[-3000:]
    refuses_everything_else(target, "active")
    assert lifecycle.take(DEACTIVATE) and lifecycle.state() == "inactive"
    assert lifecycle.take(label="cleanup") and lifecycle.state() == "unconfigured"
    # a label names the transition whatever the id (as in rclcpp: `ros2 service call` leaves the id 0)
    assert lifecycle.take(Transition.TRANSITION_CALLBACK_ERROR, label="configure")
    assert lifecycle.take(ACTIVATE) and lifecycle.state() == "active"
    target.serves("active")
    assert lifecycle.take(label="shutdown"), process.log()[-3000:]
    refuses_everything_else(target, "finalized")
    log = process.log()
    assert "Traceback" not in log, log[-3000:]
    assert "change_state id 1 refused: not allowed while active (allowed: deactivate (4), shutdown (7))" in log

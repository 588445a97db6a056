"""A planning node killed and restarted mid-burst (issue 36): every client call returns -- an answer, an error or
its timeout -- never a hang; the retry of an unanswered call is answered by the restarted node; the killed node's
worker processes (and their fork server) end with it instead of planning on for nobody."""

from __future__ import annotations

import os
import signal
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest
from conftest import PAPER_START, connected_planning_client

from maru_planner.paths import config_path

pytestmark = pytest.mark.ros

BURST = 12
BUDGET = 1.0  # s, each call's time_budget
CALL_TIMEOUT = BUDGET + 2.0  # s a client waits for an answer before giving up on the call
NODE_ARGS = ["--ros-args", "--params-file", str(config_path("planner.yaml")), "-p", "workers:=1"]


def _move(i: int) -> dict[str, float]:
    """The i-th small right-arm move from the paper start (clear of the desk)."""
    return dict(PAPER_START, r_arm_j4=PAPER_START["r_arm_j4"] + 0.1 + 0.01 * i)


def _descendants(pid: int) -> set[int]:
    """Every living process below ``pid`` (from /proc: the worker processes and their fork server)."""
    children: dict[int, list[int]] = {}
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / "stat").read_text()
        except OSError:  # ended meanwhile
            continue
        parent = int(stat.rsplit(")", 1)[1].split()[1])
        children.setdefault(parent, []).append(int(entry.name))
    found: set[int] = set()
    todo = [pid]
    while todo:
        for child in children.get(todo.pop(), []):
            found.add(child)
            todo.append(child)
    return found


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


def test_a_node_killed_mid_burst_leaves_no_call_hanging_and_the_retry_is_answered(node_process, tester):
    from maru_planner.ros.planning_client import PlanningClient

    first = node_process("maru_planner.ros.planning_node", NODE_ARGS)
    # the replacement starts now, unconfigured (no services yet), so its imports overlap the first's start-up;
    # after the kill a lifecycle manager's configure + activate bring it up, as a respawn would
    second = node_process("maru_planner.ros.planning_node", [*NODE_ARGS, "-p", "autostart:=false"])
    client: PlanningClient = connected_planning_client(tester, first)
    workers = _descendants(first.proc.pid)
    assert workers, "planning_node started no worker processes (worker_processes: true in planner.yaml)"

    def plan(i: int):
        return client.plan_async(_move(i), start=PAPER_START, planner_id="RRTConnect", time_budget=BUDGET, seed=i)

    sent_at = time.monotonic()
    burst = [plan(i) for i in range(BURST)]
    burst[0].result(CALL_TIMEOUT)  # the first answered, the rest planning or waiting for the one worker
    os.kill(first.proc.pid, signal.SIGKILL)
    first.wait_stopped()
    starter = ThreadPoolExecutor(1)
    bring_up = starter.submit(_bring_up, tester, second)  # while the burst's calls run out

    answered, timed_out = [], []
    for i, call in enumerate(burst):
        left = sent_at + CALL_TIMEOUT - time.monotonic()
        try:
            answered.append(call.result(max(left, 0.0)))
        except TimeoutError:
            timed_out.append(i)
    returned_after = time.monotonic() - sent_at
    assert returned_after < CALL_TIMEOUT + 1.0, f"the calls returned only after {returned_after:.1f} s"
    print(f"killed mid-burst: {len(answered)} answered before the kill, {len(timed_out)} timed out")
    assert timed_out, "the node answered the whole burst before it was killed: the test proved nothing"

    deadline = time.monotonic() + 5.0
    while any(_alive(pid) for pid in workers) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not any(_alive(pid) for pid in workers), "worker processes outlived their killed node"

    bring_up.result(timeout=120.0)
    starter.shutdown()
    client.wait_until_ready(timeout=120.0)
    from maru_planner_interfaces.msg import PlanningError

    retries = [plan(i) for i in timed_out]  # the callers' retries, answered by the restarted node
    codes = [call.result(30.0).error.code for call in retries]
    assert codes == [PlanningError.SUCCESS] * len(retries), second.log()


def _bring_up(tester, proc) -> None:
    """Configure and activate the node at ``proc`` through its lifecycle services."""
    from lifecycle_msgs.msg import Transition
    from lifecycle_msgs.srv import ChangeState

    from maru_planner.ros.planning_client import call_until_answered

    change_state = tester.node.create_client(ChangeState, "/planning_node/change_state")
    try:
        # a transition no state has is refused and changes nothing: its answer proves both directions, so the
        # configure below is not sent while the new node cannot yet answer this client (the answer would be lost)
        call_until_answered(change_state, ChangeState.Request(transition=Transition(id=99)), 120.0)
        for transition in (Transition.TRANSITION_CONFIGURE, Transition.TRANSITION_ACTIVATE):
            answer = tester.call(change_state, ChangeState.Request(transition=Transition(id=transition)), 120.0)
            assert answer.success, f"transition {transition} failed:\n" + proc.log()
    finally:
        tester.node.destroy_client(change_state)

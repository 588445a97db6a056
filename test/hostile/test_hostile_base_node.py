"""base_planner_node against hostile requests and maps (issue 18), through real rclpy clients.

Property-based (hypothesis, fixed seed, bounded examples): every PlanBasePath and GetPlan request
and every /map message drawn from ``hostile_inputs`` gets an answer within its budget + 0.5 s with
a proper code and a one-line message, never UNKNOWN, a traceback or a dead node; after each batch
a known-good request on the good map still succeeds. RSS grows by at most 50 MB over 10,000 junk
/map messages.
"""

from __future__ import annotations

import pytest
from hostile_inputs import (
    BASE_LIMITS,
    SUITE_EXAMPLES,
    BaseNodeTarget,
    occupancy_grids,
    params_file_arguments,
    rss_mb,
    run_batch,
    serve_module,
    tally,
)

pytestmark = pytest.mark.ros

TARGET = "base_planner_node"
EXAMPLES = {name: SUITE_EXAMPLES[name] for name in ("plan_base_path", "make_plan", "map")}
JUNK_MAPS = 10_000
RSS_GROWTH_MB = 50.0
MEASURED: list[str] = []  # lines printed with the counts


@pytest.fixture(scope="module")
def node(node_process, rclpy_session, request):
    from conftest import SpinningNode

    process = node_process(
        "maru_planner.ros.base_planner_node", params_file_arguments("base_planner.yaml", BASE_LIMITS)
    )
    yield from serve_module(BaseNodeTarget(SpinningNode("hostile_base_client"), process), request, MEASURED)


def _still_serving(node) -> None:
    assert node.process.alive(), node.process.log()[-3000:]
    response = node.good_request()
    assert response is not None and response.error_code == 0, response


def test_hostile_plan_base_path_requests(node):
    run_batch(TARGET, node.requests(), node.send, EXAMPLES["plan_base_path"])
    _still_serving(node)


def test_hostile_make_plan_requests(node):
    run_batch(TARGET, node.get_plan_requests(), node.send_get_plan, EXAMPLES["make_plan"])
    _still_serving(node)


def test_hostile_maps_then_a_good_map_recovers(node):
    try:
        run_batch(TARGET, occupancy_grids(), node.publish_map, EXAMPLES["map"])
    finally:
        assert node.restore_map(), "no known-good plan after the good map was published again"
    _still_serving(node)


def test_rss_over_10000_junk_maps(node):
    before = rss_mb(node.process.proc.pid)
    node.junk_maps(JUNK_MAPS)
    assert node.restore_map(), "no known-good plan after the junk maps"
    after = rss_mb(node.process.proc.pid)
    MEASURED.append(f"base_planner_node RSS {before:.1f} MB -> {after:.1f} MB over {JUNK_MAPS} junk /map messages")
    assert after - before <= RSS_GROWTH_MB


def test_no_broken_invariant_and_enough_inputs(node):
    record = tally(TARGET)
    assert record.broken == 0, record.failures
    assert record.inputs >= sum(EXAMPLES.values()) * 0.9

"""reactive_node against property-based hostile messages on every topic it subscribes (issue 18).

test_reactive_node_hostile sends one targeted bad message at a time and checks each warning; this
suite sends hypothesis-drawn goals, plans, scans and odometry (fixed seed, bounded examples) in
batches: the node stays alive, prints no traceback, counts no callback error, and after each batch
a good goal and scan still move the base. RSS grows by at most 50 MB over 10,000 junk scans.
"""

from __future__ import annotations

import pytest
from hostile_inputs import (
    REACTIVE_BATCHES,
    SUITE_EXAMPLES,
    ReactiveNodeTarget,
    reactive_messages,
    rss_mb,
    run_batch,
    serve_module,
    tally,
)

pytestmark = pytest.mark.ros

TARGET = "reactive_node"
BATCHES, EXAMPLES = REACTIVE_BATCHES, SUITE_EXAMPLES["reactive"]
JUNK_SCANS = 10_000
RSS_GROWTH_MB = 50.0
MEASURED: list[str] = []  # lines printed with the counts


@pytest.fixture(scope="module")
def node(node_process, rclpy_session, tmp_path_factory, request):
    from conftest import SpinningNode

    process = node_process("maru_planner.ros.reactive_node",
                           ReactiveNodeTarget.node_arguments(tmp_path_factory.mktemp("hostile_reactive")))  # fmt: skip
    yield from serve_module(ReactiveNodeTarget(SpinningNode("hostile_reactive_client"), process), request, MEASURED)


@pytest.mark.filterwarnings("ignore::RuntimeWarning")  # building hostile messages from inf values
@pytest.mark.parametrize("batch", range(BATCHES))
def test_hostile_messages_on_every_topic(node, batch):
    before = rss_mb(node.process.proc.pid)
    run_batch(TARGET, reactive_messages(), node.send, EXAMPLES, seed_value=1800 + batch)
    MEASURED.append(f"reactive_node RSS {before:.1f} MB -> {rss_mb(node.process.proc.pid):.1f} MB over batch {batch}")
    node.settle()
    node.send_good_goal()
    assert node.good_step(), node.process.log()[-2000:]
    assert node.spinning.wait_for(lambda: node.callback_errors() == 0, timeout=30), node.process.log()[-2000:]


def test_rss_over_10000_junk_scans(node):
    assert node.good_step()
    before = rss_mb(node.process.proc.pid)
    node.junk_scans(JUNK_SCANS)
    node.settle()
    node.send_good_goal()
    assert node.good_step(), "no good command after the junk scans"
    after = rss_mb(node.process.proc.pid)
    MEASURED.append(f"reactive_node RSS {before:.1f} MB -> {after:.1f} MB over {JUNK_SCANS} junk scans")
    assert after - before <= RSS_GROWTH_MB


def test_no_broken_invariant_and_enough_inputs(node):
    record = tally(TARGET)
    assert record.broken == 0, record.failures
    assert record.inputs >= BATCHES * EXAMPLES * 0.9
    assert "Traceback" not in node.process.log()

"""A node stopped by SIGTERM or Ctrl-C exits quietly (code 0, no traceback) and releases what ``configure`` built,
whether the signal comes while it starts (configure and activate publish their transitions on a context the signal
shut down) or while it spins (the lifecycle shutdown transition cannot be published then either)."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap

import pytest
import rclpy

from maru_planner.ros import lifecycle

# A ManagedNode that signals itself at a chosen moment, then records its cleanup on stdout.
NODE = textwrap.dedent(
    """
    import os, signal, sys, time
    import rclpy
    from maru_planner.ros.lifecycle import ManagedNode, run_node

    WHEN, SIGNAL = sys.argv[1], getattr(signal, sys.argv[2])


    def wait_for_shutdown(node):
        deadline = time.monotonic() + 10.0
        while node.context.ok() and time.monotonic() < deadline:
            time.sleep(0.01)


    class Node(ManagedNode):
        def __init__(self):
            super().__init__("signal_test")
            self.start()

        def configure(self):
            if WHEN == "configure":
                os.kill(os.getpid(), SIGNAL)
                if SIGNAL == signal.SIGTERM:
                    wait_for_shutdown(self)
            elif WHEN == "spin":
                self.create_timer(0.2, lambda: os.kill(os.getpid(), SIGNAL))

        def cleanup(self):
            print("cleaned up", flush=True)


    sys.exit(run_node("signal_test", Node))
    """
)


@pytest.mark.parametrize("when", ["configure", "spin"])
@pytest.mark.parametrize("signal_name", ["SIGTERM", "SIGINT"])
def test_a_signal_stops_the_node_quietly_and_releases_it(when, signal_name):
    done = subprocess.run([sys.executable, "-c", NODE, when, signal_name], capture_output=True, text=True,
                          timeout=30, env=dict(os.environ))  # fmt: skip
    output = done.stdout + done.stderr
    assert done.returncode == 0, output
    assert "Traceback" not in output, output
    # Ctrl-C raises inside configure, which then never finished: nothing was configured, nothing to release
    assert done.stdout.count("cleaned up") == (0 if (when, signal_name) == ("configure", "SIGINT") else 1), output


def test_a_context_a_signal_shut_down_during_try_shutdown_counts_as_shut_down(monkeypatch):
    """rclpy.try_shutdown checks the context, then shuts it down: a signal in between makes rcl raise. That context
    is shut down, which is all the caller asked; an error on a context still up is not swallowed."""

    def raced() -> None:
        raise RuntimeError("failed to shutdown: rcl_shutdown already called on the given context")

    monkeypatch.setattr(rclpy, "try_shutdown", raced)
    monkeypatch.setattr(rclpy, "ok", lambda: False)
    lifecycle.shut_down_context()
    monkeypatch.setattr(rclpy, "ok", lambda: True)
    with pytest.raises(RuntimeError, match="already called"):
        lifecycle.shut_down_context()

"""maru_planner.ros.executor.MultiThreadedExecutor: coroutines that wait cost each executor round O(their number).

rclpy's own MultiThreadedExecutor keeps a task once per resumption until it ends (its list grew past 1,000 in a
storm of 32 action goals); ours keeps each once, and still raises what a callback raised.
"""

from __future__ import annotations

import threading

import pytest

pytestmark = pytest.mark.ros

WAITING = 20
WAKE_UPS = 200


@pytest.fixture
def spun(rclpy_session):
    from maru_planner.ros.executor import MultiThreadedExecutor

    executor = MultiThreadedExecutor(num_threads=2)
    thread = threading.Thread(target=executor.spin, daemon=True)
    thread.start()
    yield executor
    executor.shutdown(timeout_sec=5.0)
    thread.join(timeout=5.0)


def test_waiting_coroutines_are_held_once_however_often_the_executor_wakes(spun):
    from rclpy.task import Future

    release = Future(executor=spun)

    async def wait() -> bool:
        return await release

    tasks = [spun.create_task(wait) for _ in range(WAITING)]
    for _ in range(WAKE_UPS):  # each wake-up resumes every waiting task once
        spun.wake()
        threading.Event().wait(0.001)
    held = len(spun._dispatched)
    release.set_result(True)
    spun.wake()
    finished = threading.Event()
    tasks[-1].add_done_callback(lambda _task: finished.set())
    assert finished.wait(10.0)
    assert all(task.done() and task.result() for task in tasks)
    assert held <= WAITING + 1, f"{held} tasks held for {WAITING} waiting coroutines"


def test_what_a_callback_raises_still_reaches_the_spinning_thread(rclpy_session):
    from maru_planner.ros.executor import MultiThreadedExecutor

    executor = MultiThreadedExecutor(num_threads=2)

    def fail() -> None:
        raise ValueError("raised in a callback")

    executor.create_task(fail)
    with pytest.raises(ValueError, match="raised in a callback"):
        for _ in range(20):
            executor.spin_once(timeout_sec=0.1)
    executor.shutdown(timeout_sec=5.0)

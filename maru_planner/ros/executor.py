"""rclpy's ``MultiThreadedExecutor`` without its quadratic cost for coroutines that wait (our nodes' executor).

rclpy (Jazzy) resumes every pending coroutine task (a service callback or action goal awaiting its plan) at each
wake-up of the executor, and its ``MultiThreadedExecutor`` appends the task to a list at every resumption,
removing it only when the task ends; every dispatch then scans that list. With 32 action goals waiting for ~1 s
the list held over 1,000 entries and one executor round took 40-80 ms: a storm's cancels took 250 ms to reach
their clients. :class:`MultiThreadedExecutor` here keeps each task once, so a round costs O(pending tasks).
"""

from __future__ import annotations

from collections.abc import Callable

from rclpy import executors


class MultiThreadedExecutor(executors.MultiThreadedExecutor):
    """``rclpy.executors.MultiThreadedExecutor`` holding each dispatched task once (module doc)."""

    def __init__(self, num_threads: int | None = None, **kwargs) -> None:
        super().__init__(num_threads, **kwargs)
        self._dispatched: dict[int, executors.Task] = {}  # id -> task, until it is done (then its error is raised)

    def _spin_once_impl(
        self,
        timeout_sec: float | executors.TimeoutObject | None = None,
        wait_condition: Callable[[], bool] = lambda: False,
    ) -> None:
        try:
            handler = self.wait_for_ready_callbacks(timeout_sec, None, wait_condition)[0]
        except (
            executors.ExternalShutdownException,
            executors.ShutdownException,
            executors.TimeoutException,
            executors.ConditionReachedException,
        ):
            return
        except RuntimeError as exc:  # rcl's RCLError
            # an action server destroyed by a lifecycle transition in another thread while the wait set was
            # being built: the next round builds it without that server
            if "invalid" not in str(exc):
                raise
            self._cb_iter = None
            return
        self._executor.submit(handler)
        self._dispatched[id(handler)] = handler
        for key, task in list(self._dispatched.items()):
            if task.done():
                del self._dispatched[key]
                task.result()  # raise what the callback raised, as rclpy does

"""Following joint trajectories on a simulated arm, as joint_trajectory_controller does on a real one.

:class:`ArmController` owns the servo set-points of an :class:`~maru_planner.physics.arm_sim.ArmSim`: every
control cycle (one 1 kHz physics step) it reads the arm's state, samples the active trajectory
(:mod:`maru_planner.execution.interpolation`), checks the tolerances (:mod:`maru_planner.execution.tolerances`)
and writes the desired positions and velocities. Joints the trajectory does not name hold where they were.

A goal is refused with a typed error (nothing moves): joint names the arm lacks (InvalidJointNames), bad
points (see ``interpolation.checked_points``), a first point off the current state (StartToleranceViolated).
A new goal while another executes preempts it (the controller's behaviour): the old one ends cancelled.
Cancelling, and any abort, brings the arm to rest from its current state with every joint decelerating
uniformly within its acceleration limit, all stopping together; then it holds.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from maru_planner.execution.interpolation import SplineTrajectory, TrajectoryPoints
from maru_planner.execution.tolerances import ResultCode, Tolerances, check_start, tolerances, violated, within_goal
from maru_planner.physics.arm_sim import ArmSim, Contact, ContactLog

SAMPLE_EVERY = 4  # control cycles between recorded samples (250 Hz at 1 kHz)


@dataclass
class ExecutionResult:
    """How an execution ended and how well the arm followed; samples are in the trajectory's joint order."""

    code: ResultCode
    message: str
    joint_names: list[str]
    cancelled: bool = False
    duration: float = 0.0  # planned: the last point's time
    finished_at: float | None = None  # s since start when the goal tolerances first held (None: never)
    times: np.ndarray = field(default_factory=lambda: np.zeros(0))
    desired: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    actual: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    contacts: list[Contact] = field(default_factory=list)  # the deepest per (link, obstacle) pair
    saturated_steps: int = 0

    @property
    def success(self) -> bool:
        return self.code == ResultCode.SUCCESSFUL and not self.cancelled

    @property
    def error(self) -> np.ndarray:
        return self.desired - self.actual

    @property
    def max_error(self) -> np.ndarray:
        """Per joint, the largest |desired - actual| over the samples."""
        return np.max(np.abs(self.error), axis=0) if len(self.times) else np.zeros(len(self.joint_names))

    @property
    def rms_error(self) -> np.ndarray:
        return np.sqrt(np.mean(self.error**2, axis=0)) if len(self.times) else np.zeros(len(self.joint_names))

    @property
    def overrun(self) -> float | None:
        """(time the goal was reached - planned duration) / planned duration; None when never reached."""
        if self.finished_at is None:
            return None
        return max(0.0, self.finished_at - self.duration) / max(self.duration, 1e-9)

    @property
    def max_penetration(self) -> float:
        return max((c.depth for c in self.contacts), default=0.0)


class _Execution:
    """One goal in progress: its spline, tolerances, recorded samples and logs."""

    def __init__(self, points: TrajectoryPoints, index: np.ndarray, spline: SplineTrajectory, tol: Tolerances):
        self.points, self.index, self.spline, self.tol = points, index, spline, tol
        self.cycle = 0
        self.times: list[float] = []
        self.desired: list[np.ndarray] = []
        self.actual: list[np.ndarray] = []
        self.contacts = ContactLog()
        self.saturated_at_start = 0

    def result(self, code: ResultCode, message: str, finished_at: float | None, saturated: int, *, cancelled=False):
        k = len(self.index)
        return ExecutionResult(
            code=code,
            message=message,
            joint_names=list(self.points.joint_names),
            cancelled=cancelled,
            duration=self.points.duration,
            finished_at=finished_at,
            times=np.asarray(self.times),
            desired=np.asarray(self.desired).reshape(-1, k),
            actual=np.asarray(self.actual).reshape(-1, k),
            contacts=sorted(self.contacts.deepest.values(), key=lambda c: -c.depth),
            saturated_steps=saturated - self.saturated_at_start,
        )


class ArmController:
    """The servo set-points of ``sim``: a trajectory being followed, or a stop ramp / hold."""

    def __init__(self, sim: ArmSim):
        self.sim = sim
        state = sim.state()
        self._hold_from(state.positions, np.zeros_like(state.positions))
        self._active: _Execution | None = None
        self.preempted: ExecutionResult | None = None  # the goal the last ``start`` replaced

    @property
    def busy(self) -> bool:
        return self._active is not None

    def start(self, points: TrajectoryPoints, tol: Tolerances | None = None) -> None:
        """Begin following ``points`` from the arm's current state (typed errors: see the module docstring)."""
        index = self.sim.arm.joint_indices(points.joint_names)
        tol = tol or tolerances(len(index), points.duration)
        state = self.sim.state()
        check_start(points.positions[0], state.positions[index], points.joint_names, tol)
        spline = SplineTrajectory(points, state.positions[index], state.velocities[index])
        self.preempted = None
        if self._active is not None:
            self.preempted = self._finish(ResultCode.SUCCESSFUL, "preempted by a new goal", None, cancelled=True)
        execution = _Execution(points, index, spline, tol)
        execution.saturated_at_start = self.sim.saturated_steps
        self._active = execution

    def latest_sample(self) -> tuple[float, list[str], np.ndarray, np.ndarray] | None:
        """The active goal's last recorded (time since start, joint names, desired, actual), or None."""
        execution = self._active
        if execution is None or not execution.times:
            return None
        return execution.times[-1], execution.points.joint_names, execution.desired[-1], execution.actual[-1]

    def cancel(self) -> ExecutionResult | None:
        """Stop the active goal (the arm comes to rest within its limits); its result, or None if idle."""
        if self._active is None:
            return None
        return self._finish(ResultCode.SUCCESSFUL, "cancelled", None, cancelled=True)

    def step(self) -> ExecutionResult | None:
        """One control cycle and one physics step; the active goal's result when it ends in this cycle."""
        execution = self._active
        if execution is None:
            self._command_hold()
            self.sim.step()
            return None
        t = execution.cycle * self.sim.timestep
        state = self.sim.state()
        desired = execution.spline.sample([t])
        actual_p, actual_v = state.positions[execution.index], state.velocities[execution.index]
        error_p, error_v = desired.positions[0] - actual_p, desired.velocities[0] - actual_v
        if execution.cycle % SAMPLE_EVERY == 0:
            execution.times.append(t)
            execution.desired.append(desired.positions[0])
            execution.actual.append(actual_p)
        outcome = self._check(execution, t, error_p, error_v)
        if outcome is not None:
            return outcome
        n = self.sim.arm.nq
        command_p, command_v, command_a = self.sim.data.ctrl[:n].copy(), np.zeros(n), np.zeros(n)
        command_p[execution.index], command_v[execution.index] = desired.positions[0], desired.velocities[0]
        if t < execution.spline.duration:  # after it the set-point is the last point at rest: no acceleration to feed
            command_a[execution.index] = desired.accelerations[0]
        self.sim.command(command_p, command_v, command_a)
        execution.contacts.add(self.sim.step())
        execution.cycle += 1
        return None

    def run(self, points: TrajectoryPoints, tol: Tolerances | None = None, *, cancel_at: float | None = None):
        """``start`` then step until the goal ends (``cancel_at``: cancel that many seconds in); its result."""
        self.start(points, tol)
        while True:
            if (
                cancel_at is not None
                and self._active is not None
                and self._active.cycle * self.sim.timestep >= cancel_at
            ):
                result = self.cancel()
                assert result is not None
                return result
            result = self.step()
            if result is not None:
                return result

    def settle(self, seconds: float) -> None:
        """Step ``seconds`` with no goal (the stop ramp or hold keeps running)."""
        for _ in range(int(round(seconds / self.sim.timestep))):
            self.step()

    # ------------------------------------------------------------------------------------------ internals --
    def _check(self, execution: _Execution, t: float, error_p: np.ndarray, error_v: np.ndarray):
        tol, names = execution.tol, execution.points.joint_names
        if t < execution.spline.duration:
            for error, limits, what in (
                (error_p, tol.path_position, "position"),
                (error_v, tol.path_velocity, "velocity"),
            ):
                joint = violated(error, limits)
                if joint >= 0:
                    message = (
                        f"path tolerance violated at {t:.3f} s: joint '{names[joint]}' {what} error {error[joint]:+.4f}"
                    )
                    return self._finish(ResultCode.PATH_TOLERANCE_VIOLATED, message, None)
            return None
        if within_goal(error_p, error_v, tol):
            return self._finish(ResultCode.SUCCESSFUL, "goal reached", t)
        if tol.goal_time > 0 and t > execution.spline.duration + tol.goal_time:
            joint = int(np.argmax(np.abs(error_p)))
            message = (
                f"goal tolerance violated {tol.goal_time:.3f} s after the end:"
                f" joint '{names[joint]}' error {error_p[joint]:+.4f}"
            )
            return self._finish(ResultCode.GOAL_TOLERANCE_VIOLATED, message, None)
        return None

    def _finish(self, code: ResultCode, message: str, finished_at: float | None, *, cancelled: bool = False):
        execution = self._active
        assert execution is not None
        self._active = None
        state = self.sim.state()
        if code == ResultCode.SUCCESSFUL and not cancelled:
            self._hold_from(self.sim.data.ctrl[: self.sim.arm.nq].copy(), np.zeros(self.sim.arm.nq))
        else:
            self._hold_from(state.positions, state.velocities)
        return execution.result(code, message, finished_at, self.sim.saturated_steps, cancelled=cancelled)

    def _hold_from(self, positions: np.ndarray, velocities: np.ndarray) -> None:
        """A stop ramp from (``positions``, ``velocities``): every joint decelerates uniformly, all stopping at
        the time the slowest to stop needs at its acceleration limit; then the stop position is held."""
        limits = self.sim.arm.acceleration_limits
        self._ramp_start = self.sim.time
        self._ramp_p, self._ramp_v = positions.copy(), velocities.copy()
        self._ramp_time = float(np.max(np.abs(velocities) / limits)) if len(limits) else 0.0

    @property
    def stop_duration(self) -> float:
        """How long the current stop ramp decelerates (0 when it started at rest)."""
        return self._ramp_time

    def ramp(self, elapsed: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The stop ramp's desired positions, velocities and accelerations ``elapsed`` seconds in."""
        T = self._ramp_time
        if T <= 0:
            zero = np.zeros_like(self._ramp_p)
            return self._ramp_p.copy(), zero, zero
        s = min(max(elapsed, 0.0), T)
        deceleration = -self._ramp_v / T
        position = self._ramp_p + self._ramp_v * s + 0.5 * deceleration * s**2
        moving = elapsed < T
        return position, self._ramp_v + deceleration * s, deceleration if moving else np.zeros_like(deceleration)

    def _command_hold(self) -> None:
        position, velocity, acceleration = self.ramp(self.sim.time - self._ramp_start)
        arm = self.sim.arm
        self.sim.command(np.clip(position, arm.lower_limits, arm.upper_limits), velocity, acceleration)

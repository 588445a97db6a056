"""``MotionPlanner.plan(MotionRequest) -> MotionResult``: validate, (IK), search, simplify, time-parameterise.

One hard time budget per request covers validation, IK, search and post-processing. Bad input
never raises: the typed error (``maru_planner.errors``) becomes ``result.status`` + message.

Watching and cancelling: ``plan(request, monitor)`` reports its stages ("validation", "ik", "search",
"simplify", "certify", "parameterize") with the tree size and best path length where they are known,
attaches every OMPL search to the :class:`~maru_planner.monitor.PlanMonitor` (``cancel()`` ends it at
OMPL's next check) and checks it between stages and in the Python loops (shortcutting, blend checks);
a cancelled plan ends with PLANNING_FAILED and a :class:`~maru_planner.errors.PlanningCancelled` error,
its statistics as far as it got.

Threads: ``plan`` and ``set_scene`` of one MotionPlanner are serialised by its own lock (the
robot model, checker and roadmap cache are not thread-safe), and every OMPL search in the process
runs under one module lock, because OMPL's seed generator is process-global: reseeding it right
before the planner is built and solved is what makes "same seed, same path" hold. Concurrent
requests therefore queue; a node wanting parallel planning would need separate processes.
"""

from __future__ import annotations

import contextlib
import dataclasses
import itertools
import math
import secrets
import threading
import time
from collections.abc import Iterator
from typing import Any

import numpy as np
from ompl import base as ob
from ompl import util as ou

from maru_planner import errors
from maru_planner.monitor import PlanMonitor
from maru_planner.planning import postprocess, timing
from maru_planner.planning.cartesian import CartesianRequest, CartesianResult, compute_cartesian_path
from maru_planner.planning.checkers import (
    collision_model_of,
    default_exact_checker,
    is_compiled_sphere_checker,
    is_sphere_checker,
    make_checkers,
    padded_checker,
)
from maru_planner.planning.config import PlannerConfig
from maru_planner.planning.constrained_planner import plan_constrained
from maru_planner.planning.constraints import goal_in_region
from maru_planner.planning.pose_goal import solve_pose_goal
from maru_planner.planning.registry import (
    ArmPlannerSpec,
    ProvesFailure,
    ReportsGraphSize,
    get_spec,
    merged_params,
)
from maru_planner.planning.roadmap import Roadmap
from maru_planner.planning.space import EdgeChecker, GroupSetup, GroupSpace, full_configurations
from maru_planner.planning.types import (
    MotionRequest,
    MotionResult,
    PlanStats,
    PlanStatus,
    Trajectory,
    set_failure,
)
from maru_planner.scene_attached import attachment_key, robot_with_attached

OMPL_LOCK = threading.RLock()
# rad: chords of a certified blend. Their count drives the blends' certification; the chord deviation margin
# grows with the step squared. On 30 MotionBenchMaker plans 0.05 -> 0.1 rad took time parameterisation from
# 21.5 to 14.8 ms median with 215 of 217 corners still blended (216 before); 0.2 rad stopped at 8 corners.
CERTIFIED_CHORD_STEP = 0.1
REPAIR_RESOLUTION = 0.02  # rad: the coarsest motion step of a repair's local search
NEAR_END_PADDING = 0.75  # of the nearer end's clearance: the search's padding when an end is nearer than the margin
PADDED_CHECKERS = 4  # padded search checkers kept (the margin's, and a few for ends nearer than it)
REPAIR_SHORTCUT_TRIES = 10  # a repair's local path is short: few failed shortcuts end its simplification
REPAIR_MIN_PADDING = 0.005  # m: the most a repair may pad when twice the margin is less (a margin of 0 included)
ou.setLogLevel(ou.LOG_WARN)  # OMPL's INFO chatter would mix into CLI output


@contextlib.contextmanager
def seeded_ompl(seed: int) -> Iterator[None]:
    """Hold the OMPL lock with OMPL's seed generator restarted from ``seed`` (its warning silenced)."""
    with OMPL_LOCK:
        level = ou.getLogLevel()
        ou.setLogLevel(ou.LOG_NONE)
        try:
            ou.RNG.setSeed(int(seed) % (2**31 - 2) + 1)
        finally:
            ou.setLogLevel(level)
        yield


def _finite_time(value, name: str) -> float:
    try:
        value = float(value)
    except (TypeError, ValueError) as exc:
        raise errors.InvalidRequest(f"{name} must be a number, got {value!r}") from exc
    if not math.isfinite(value) or value <= 0:
        raise errors.InvalidRequest(f"{name} must be a finite number > 0, got {value}")
    return value


class MotionPlanner:
    """Arm motion planning on OMPL for one robot model and collision checker (see module doc).

    Planning on a :class:`~maru_planner.collision.SphereCollisionChecker` returns only paths verified
    on the exact model: the final path is re-checked with ``exact_checker`` (default: a
    :class:`~maru_planner.collision.CollisionChecker` on the same scene) every
    ``config.verify_step`` rad; a path that fails is re-planned at half the motion resolution in the
    time left, up to ``config.max_refinements`` times, and never returned as a success.
    ``stats.verified``, ``verify_time`` and ``replans`` say how that went.

    With a pinocchio robot (``config.certify``, the default) every returned path is certified instead
    (``docs/certification.md``): proven collision-free on the exact model between its waypoints, keeping
    ``safety_margin``; a failing segment is re-planned locally, up to ``max_refinements`` times in the time
    left, before the request fails. ``stats.certified``, ``certify_time``, ``min_clearance`` and ``repairs``
    report it (on a sphere checker ``verified``/``verify_time``/``replans`` too).
    """

    def __init__(self, robot, checker, config: PlannerConfig | None = None, scene=None, exact_checker=None):
        self.config = config or PlannerConfig()
        if exact_checker is None:
            exact_checker = default_exact_checker(robot, checker)
        self._plan_for(robot, checker, exact_checker)
        self._lock = threading.RLock()
        self._scene_epoch = 0
        self._monitor = PlanMonitor()  # the running plan's (plan() sets it under the lock); never cancelled idle
        self.last_revalidation = None
        self.scene = None
        if scene is not None:
            self.set_scene(scene)

    @classmethod
    def from_scene(cls, robot, scene=None, config: PlannerConfig | None = None) -> MotionPlanner:
        """A planner on the checker ``config.collision_model`` names ("exact" | "spheres")."""
        config = config or PlannerConfig()
        robot = robot_with_attached(robot, scene)
        checkers = make_checkers(robot, scene, config.collision_model)
        planner = cls(robot, checkers.checker, config, exact_checker=checkers.exact)
        planner.scene = scene
        return planner

    # --- scene ------------------------------------------------------------------------------
    def set_scene(self, scene) -> None:
        """Give the checker(s) a new scene; cached roadmaps are re-validated at their next query.

        When the scene's attached objects differ from those the robot carries, the robot, checkers and
        certifier are rebuilt around them (:func:`~maru_planner.scene_attached.robot_with_attached`).
        """
        with self._lock:
            if attachment_key(scene) != attachment_key(self.robot):
                self._carry(robot_with_attached(self.robot, scene), scene)
            else:
                self.checker.set_scene(scene)
                if self.exact_checker is not None:
                    self.exact_checker.set_scene(scene)
                for padded in self._padded.values():
                    padded.set_scene(scene)
            if self.certifier is not None:
                self.certifier.prepare()
            self.scene = scene
            self._scene_epoch += 1

    def _carry(self, robot, scene) -> None:
        """Plan for ``robot`` (the robot with other attached objects): new checkers, certifier and caches."""
        checkers = make_checkers(robot, scene, collision_model_of(self.checker))
        self._plan_for(robot, checkers.checker, checkers.exact)

    def _plan_for(self, robot, checker, exact_checker) -> None:
        """Plan for ``robot`` on ``checker``, verified on ``exact_checker``: its certifier, and empty caches."""
        self.robot, self.checker = robot, checker
        self.exact_checker = exact_checker  # None: the plan's own checker is the exact model
        self.certifier = self._make_certifier()
        self._roadmaps: dict[tuple, Roadmap] = {}
        self._setups: dict[tuple, GroupSetup] = {}  # per (group's joint indices, checker), reused across requests
        # (padding, checker padded by it): the search's checker when certifying with a margin
        self._padded: dict[float, Any] = {}  # padding -> the checker padded by it, oldest first
        self._search_checker = checker  # the checker the running search plans on (_search_checker_for)

    def _follow_attachments(self) -> None:
        """Pick up objects attached or detached by editing the scene in place since the last call."""
        scene = getattr(self.checker, "scene", None)
        if scene is not None and attachment_key(scene) != attachment_key(self.robot):
            self.set_scene(scene)

    # --- planning ---------------------------------------------------------------------------
    def cartesian_path(self, request: CartesianRequest) -> CartesianResult:
        """A straight task-space path (:mod:`~maru_planner.planning.cartesian`) on this planner's robot,
        checker and certifier; never raises."""
        with self._lock:
            self._follow_attachments()
            return compute_cartesian_path(self, request)

    def plan(self, request: MotionRequest, monitor: PlanMonitor | None = None) -> MotionResult:
        """Plan ``request``; never raises (errors become the result's status and message).

        ``monitor`` receives the stages and progress and can cancel the plan from another thread (module doc).
        """
        t0 = time.monotonic()
        with self._lock:
            self._follow_attachments()
            constraints = getattr(request, "path_constraints", None)
            if constraints is not None and not constraints.empty:
                return plan_constrained(self, request, constraints)
            self._monitor = monitor or PlanMonitor()
            try:
                result = self._plan_once(request, t0, self.config.resolution)
                if self.certifier is not None:
                    result = self._certify(request, result, t0)
                elif self.exact_checker is not None:
                    result = self._verify(request, result, t0)
            finally:
                self._monitor = PlanMonitor()
        result.stats.total_time = time.monotonic() - t0
        return result

    def _plan_once(self, request: MotionRequest, t0: float, resolution: float) -> MotionResult:
        """One search + post-processing at motion step ``resolution``, errors caught into the result."""
        stats = PlanStats(
            planner_id=getattr(request, "planner_id", "") or self.config.default_planner,
            collision_model=collision_model_of(self.checker),
        )
        result = MotionResult(status=PlanStatus.PLANNING_FAILED, stats=stats)
        try:
            self._plan(request, result, t0, resolution)
        except Exception as exc:  # a typed error, or a bug or checker failure: reported, the planner keeps serving
            set_failure(result, exc)
        return result

    # --- certification (docs/certification.md) -----------------------------------------------
    def _make_certifier(self):
        """A PathCertifier on the exact model, or None (certification off, or no pinocchio geometry to prove on)."""
        exact = self.exact_checker or self.checker
        if not self.config.certify or not hasattr(type(exact), "reachable_obstacles"):
            return None
        # lazy: certification loads numba (batched kinematics); planners on toy checkers never need it
        from maru_planner.collision.certify import PathCertifier

        spheres = self.checker.spheres if is_sphere_checker(self.checker) else None  # bounds meshes too
        return PathCertifier(self.robot, exact, self.config.safety_margin, spheres=spheres)

    def _certify(self, request: MotionRequest, result: MotionResult, t0: float) -> MotionResult:
        """Certify ``result``'s path; repair failing segments locally in the time left, else fail the request."""
        if not result.success:
            return result
        try:
            self._certify_path(request, result, t0)
        except Exception as exc:  # a typed error, or a bug in certification: reported, the planner keeps serving
            set_failure(result, exc)
            result.path, result.trajectory = None, None
        return result

    def _certify_path(self, request: MotionRequest, result: MotionResult, t0: float) -> None:
        from maru_planner.collision.certify import Certificate, certify_and_repair  # lazy: numba, as in _make_certifier

        stats = result.stats
        self._monitor.report("certify")
        proof = result.curve_proof
        if proof is not None:  # every straight part was proven with the blends (_set_path): nothing left
            stats.certified = True
            if is_sphere_checker(self.checker):
                certificate = Certificate(valid=True, margin=self.safety_margin(request), checks=proof.certify_checks,
                                          seconds=proof.certify_time)  # fmt: skip
                _record_verification(result, certificate, 0)
            return
        certify_deadline = time.monotonic() + self.config.certify_timeout
        repaired = certify_and_repair(
            self.certifier,
            self._full_path(request, result),
            self._repair_planner(request, stats.seed or 0),
            t0 + float(request.time_budget),
            margin=self.safety_margin(request),
            max_repairs=self.config.max_refinements,
            certify_deadline=certify_deadline,
            corner_blends=result.corner_blends,
        )
        self._monitor.check()  # a repair search ended by a cancel looks like a failed repair
        certificate = repaired.certificate
        stats.certified, stats.repairs = repaired.path is not None, repaired.repairs
        stats.certify_time = certificate.seconds
        stats.min_clearance = min(stats.min_clearance, certificate.min_clearance)  # and the blends' (_set_path)
        if is_sphere_checker(self.checker):
            _record_verification(result, certificate, repaired.repairs)
        if repaired.path is None:
            raise errors.PlanningFailed(
                f"path failed verification on the exact model: segment {certificate.first_failing_segment} "
                f"not certified ({certificate.reason}) after {repaired.repairs} repair(s)",
                source="planner",
            )
        if repaired.repairs:  # timing the repaired path may take as long as the certification was allowed to
            indices = [self.robot.joint_names.index(n) for n in result.joint_names]
            full_path = repaired.path
            self._set_path(request, result, full_path[:, indices], full_path[0], indices, certify_deadline)

    def _repair_planner(self, request: MotionRequest, seed: int):
        """The local planner of a repair: RRT-Connect between two waypoints of the request's group, searched like
        the request was -- the compiled kernel on the sphere checker, else OMPL's RRTConnect on the exact one.

        It plans padded by more than the margin -- half-way to the nearer end's clearance, at most twice the
        margin or :data:`REPAIR_MIN_PADDING` if more: its checks are of states, certification's of the motion
        between them -- at
        ``config.resolution`` or :data:`REPAIR_RESOLUTION` if finer (a coarse search's gaps are what certification
        caught), with a short simplification.
        """
        names = self.robot.joint_names
        group = [names[i] for i in self.robot.group_joint_indices(request.group)]
        attempt = itertools.count(1)
        monitor = self._monitor

        def plan_between(qa: np.ndarray, qb: np.ndarray, margin: float, deadline: float) -> np.ndarray | None:
            config = dataclasses.replace(  # built per repair: checking a config costs more than most requests need
                self.config,
                resolution=min(self.config.resolution, REPAIR_RESOLUTION),
                simplify_max_tries=min(self.config.simplify_max_tries, REPAIR_SHORTCUT_TRIES),
                certify=False,
                time_parameterization="trapezoid",
            )
            ends = min(self.certifier.clearance(qa), self.certifier.clearance(qb))
            padding = min(max(2.0 * margin, REPAIR_MIN_PADDING), 0.5 * (margin + ends)) if ends > margin else margin
            fast = is_sphere_checker(self.checker)
            checker = padded_checker(self.robot, self.checker if fast else self.certifier.checker, padding)
            local = MotionPlanner(self.robot, checker, config)
            sub = MotionRequest(
                request.group, start=dict(zip(names, qa, strict=True)),
                goal_joints={n: float(qb[names.index(n)]) for n in group},
                planner_id="CompiledRRTConnect" if fast else "RRTConnect",
                time_budget=max(deadline - time.monotonic(), 1e-3), seed=seed + next(attempt),
            )  # fmt: skip
            nested = PlanMonitor()
            with monitor.attach(_CancelsNested(nested)):
                found = local.plan(sub, nested)
            return local._full_path(sub, found) if found.success else None

        return plan_between

    def _set_path(self, req: MotionRequest, result: MotionResult, path: np.ndarray, start_full: np.ndarray,
                  indices, deadline: float) -> Trajectory:  # fmt: skip
        """Make ``path`` (group configurations) the result's path, with its trajectory (returned) and statistics."""
        stats = result.stats
        t_par = time.monotonic()
        result.trajectory, report = self._time_parameterize(req, path, start_full, indices, stats, deadline)
        result.corner_blends = report.corner_blends if self.certifier is not None else None
        result.curve_proof = report if report.curve_certified else None  # only a certifier's check proves pieces
        stats.min_clearance = min(stats.min_clearance, report.min_clearance)  # the blends' (the path's: _certify_path)
        stats.parameterize_time += time.monotonic() - t_par
        result.path = path
        stats.waypoints = len(path)
        stats.path_length = postprocess.path_length(path)
        stats.smoothness = postprocess.smoothness(path)
        return result.trajectory

    def _verify(self, request: MotionRequest, result: MotionResult, t0: float) -> MotionResult:
        """Re-check ``result``'s path on the exact model; re-plan at half the step while it fails (class doc)."""
        # lazy: the sphere module loads numba, which exact-only callers never need
        from maru_planner.collision.spheres import verify_path

        resolution, verify_time, replans = self.config.resolution, 0.0, 0
        while result.success:
            self._monitor.report("certify")
            t_ver = time.monotonic()
            path = self._full_path(request, result)
            result.verification = verify_path(self.exact_checker, path, self.config.verify_step)
            verify_time += time.monotonic() - t_ver
            if result.verification.valid:
                result.stats.verified = True
                break
            segment = result.verification.first_invalid_segment
            out_of_time = time.monotonic() >= t0 + float(request.time_budget)
            if replans >= self.config.max_refinements or out_of_time:
                set_failure(result, errors.PlanningFailed(
                    f"path failed verification on the exact model (segment {segment}) after {replans} re-plan(s)"
                    + (", time budget spent" if out_of_time else ""),
                    source="planner",
                ))  # fmt: skip
                result.path, result.trajectory = None, None
                break
            replans += 1
            resolution *= 0.5
            result = self._plan_once(request, t0, resolution)
        result.stats.verify_time, result.stats.replans = verify_time, replans
        return result

    def _full_path(self, request: MotionRequest, result: MotionResult) -> np.ndarray:
        """The result's waypoints as full configurations (joints outside the group at their start values)."""
        indices = [self.robot.joint_names.index(n) for n in result.joint_names]
        start = self.start_configuration(request.start, indices, request.group)
        return full_configurations(start, indices, np.asarray(result.path, dtype=float))

    def _plan(self, req: MotionRequest, result: MotionResult, t0: float, resolution: float) -> None:
        stats = result.stats
        spec = get_spec(req.planner_id or self.config.default_planner)
        planner_id = stats.planner_id = spec.id
        budget, seed = self.check_request(req)
        deadline = t0 + budget
        stats.seed = seed

        monitor = self._monitor
        monitor.report("validation")
        indices = sorted(self.robot.group_joint_indices(req.group))
        names = [self.robot.joint_names[i] for i in indices]
        result.joint_names = names
        start_full = self.start_configuration(req.start, indices, req.group)
        if req.goal_poses:
            monitor.report("ik")
            t_ik = time.monotonic()
            goal_full = self._solve_pose_goal(req, start_full, indices, deadline)
            stats.ik_time = time.monotonic() - t_ik
            monitor.report("validation")
        else:
            goal_full = self._goal_state(req, start_full, indices)
        t_val = time.monotonic()
        self.check_free(start_full, errors.StartInCollision, "start")
        self.check_free(goal_full, errors.GoalInCollision, "goal")
        stats.validation_time = time.monotonic() - t_val

        self._search_checker = self._search_checker_for(req, start_full, goal_full)
        setup = self._group_setup(names, indices, start_full, resolution)
        gs = setup.gs
        start, goal = start_full[indices], goal_full[indices]
        checks0 = self._search_checker.check_count
        try:
            monitor.report("search")
            raw = self._search(spec, gs, start, goal, seed, int(req.attempts), deadline, stats, resolution)
            stats.raw_waypoints = len(raw)
            stats.raw_path_length = postprocess.path_length(raw)
            monitor.report("simplify", best_cost=stats.raw_path_length)
            path = self._simplify(req, setup.edges, raw, seed, deadline, stats)
        finally:
            stats.collision_checks = int(self._search_checker.check_count - checks0)

        monitor.report("parameterize", best_cost=postprocess.path_length(path))
        trajectory = self._set_path(req, result, path, start_full, indices, deadline)
        if time.monotonic() > deadline:
            raise errors.PlanningTimedOut(
                f"a path was found but the {budget:.3g} s budget ran out during post-processing", source="planner"
            )
        result.status = PlanStatus.SUCCESS
        result.message = (
            f"{planner_id}: {len(path)} waypoints, length {stats.path_length:.3f} rad, "
            f"trajectory {trajectory.duration:.2f} s ({stats.time_parameterization})"
        )

    def _time_parameterize(self, req, path, start_full, indices, stats, deadline=None
                           ) -> tuple[Trajectory, timing.TimingReport]:  # fmt: skip
        """``path`` timed by the request's method (:mod:`~maru_planner.planning.timing`), blends checked by
        :meth:`_curve_check`; with how it was made.

        Blends still unchecked at ``deadline`` (the request's budget; None: no limit) become stops, so a
        tight budget gets a slower trajectory rather than a timeout.
        """
        curve_free, certify_step = self._curve_check(req, start_full, indices, deadline)
        limits = timing.Limits.scaled(
            np.asarray(self.robot.velocity_limits)[indices],
            np.asarray(self.robot.acceleration_limits)[indices],
            float(req.velocity_scaling),
            float(req.acceleration_scaling),
            float(req.jerk_scaling),
        )
        trajectory, report = timing.parameterize(
            path,
            [self.robot.joint_names[i] for i in indices],
            limits,
            req.time_parameterization or self.config.time_parameterization,
            curve_free=curve_free,
            max_deviation=self.config.blend_deviation,
            dt=self.config.trajectory_dt,
            max_points=self.config.max_trajectory_points,
            deadline=deadline,
            certify_step=certify_step,
            sample_deadline=deadline,
        )
        stats.time_parameterization = report.method
        return trajectory, report

    def _curve_check(self, req, start_full, indices, deadline) -> tuple[timing.CurveFree, float]:
        """How blended corners are checked, and the joint step of their samples.

        With a certifier, like the path: proven clear by the request's safety margin, toppra's parabolic blends
        as they are, sampled curves (Ruckig's) continuously along chords :data:`CERTIFIED_CHORD_STEP` apart, the
        margin grown by how far the curve leaves them. Otherwise the exact checker at the states alone,
        :data:`timing.CERTIFY_STEP` apart.
        """
        monitor = self._monitor
        if self.certifier is not None:
            margin = self.safety_margin(req)
            curve_free = timing.certified_curve(self.certifier, start_full, indices, deadline, margin)
            step = CERTIFIED_CHORD_STEP
        else:
            checker = self.exact_checker or self.checker

            def curve_free(states: np.ndarray, _chord_deviation: np.ndarray) -> bool:
                return checker.first_invalid(full_configurations(start_full, indices, states)) < 0

            step = timing.CERTIFY_STEP

        return timing.WatchedCurve(curve_free, monitor.check), step

    # --- request validation -----------------------------------------------------------------
    def safety_margin(self, req: MotionRequest) -> float:
        """The clearance (m) ``req``'s certified path keeps: its own ``safety_margin``, else the configuration's."""
        return _safety_margin(req, self.config)

    def check_request(self, req: MotionRequest) -> tuple[float, int]:
        """``req``'s time budget and seed (its own, or a random one); InvalidRequest naming the first bad field
        among time_budget, attempts, the scalings, time_parameterization, safety_margin and seed."""
        budget = _finite_time(req.time_budget, "time_budget")
        if int(req.attempts) < 1:
            raise errors.InvalidRequest(f"attempts must be >= 1, got {req.attempts}")
        for name in ("velocity_scaling", "acceleration_scaling", "jerk_scaling"):
            timing.check_scaling(getattr(req, name), name)
        timing.check_method(req.time_parameterization or self.config.time_parameterization)
        self.safety_margin(req)
        seed = int(req.seed) if req.seed is not None else secrets.randbelow(2**31 - 1)
        if not 0 <= seed < 2**63:
            raise errors.InvalidRequest(f"seed must be in [0, 2^63), got {seed}")
        return budget, seed

    def _check_values(self, values: dict, what: str) -> dict[int, float]:
        """Joint index → value for a name → value map; unknown names, NaN and limits raise."""
        if not isinstance(values, dict):
            raise errors.InvalidRequest(f"{what} must map joint names to values, got {type(values).__name__}")
        known = {n: i for i, n in enumerate(self.robot.joint_names)}
        unknown = [n for n in values if n not in known]
        if unknown:
            raise errors.InvalidJointNames(f"{what}: unknown joint(s) {', '.join(map(str, unknown))}")
        out = {}
        lower, upper = np.asarray(self.robot.lower_limits), np.asarray(self.robot.upper_limits)
        for name, value in values.items():
            i = known[name]
            try:
                v = float(value)
            except (TypeError, ValueError) as exc:
                raise errors.InvalidState(f"{what}: joint {name} has a non-numeric value {value!r}") from exc
            if not math.isfinite(v):
                raise errors.InvalidState(f"{what}: joint {name} is {v}")
            if v < lower[i] - 1e-9 or v > upper[i] + 1e-9:
                raise errors.InvalidState(
                    f"{what}: joint {name} = {v:.4f} is outside its limits [{lower[i]:.4f}, {upper[i]:.4f}]"
                )
            out[i] = min(max(v, lower[i]), upper[i])
        return out

    def start_configuration(self, start: dict | None, indices, group: str = "") -> np.ndarray:
        """Full configuration of ``start`` ({joint: value}, checked: names, NaN, limits, every joint of
        ``indices`` given); joints it does not name are at neutral."""
        if not start:
            raise errors.NoStartState("no start state given (start is empty)")
        values = self._check_values(start, "start")
        missing = [self.robot.joint_names[i] for i in indices if i not in values]
        if missing:
            raise errors.InvalidJointNames(f"start is missing joint(s) of group {group}: {', '.join(missing)}")
        q = np.asarray(self.robot.neutral(), dtype=float).copy()
        for i, v in values.items():
            q[i] = v
        return q

    def goal_configuration(self, req: MotionRequest, start_full: np.ndarray, indices) -> np.ndarray:
        """The full goal configuration of ``req``: its joint goal (checked), or IK of its goal poses."""
        if req.goal_poses:
            return self._solve_pose_goal(req, start_full, indices, time.monotonic() + float(req.time_budget))
        return self._goal_state(req, start_full, indices)

    def _goal_state(self, req: MotionRequest, start_full: np.ndarray, indices) -> np.ndarray:
        region = getattr(req, "goal_region", None)
        if region is not None and not region.empty:
            if req.goal_joints:
                raise errors.InvalidRequest("give either goal_joints or goal_region, not both")
            rng = np.random.default_rng(req.seed)
            deadline = time.monotonic() + float(req.time_budget) / 2
            return goal_in_region(self.robot, region, start_full, np.asarray(indices), self.checker.is_valid, rng,
                                  deadline)  # fmt: skip
        if req.goal_joints is None:
            raise errors.InvalidRequest("no goal: give goal_joints or goal_poses")
        values = self._check_values(req.goal_joints, "goal")
        in_group = set(indices)
        outside = [self.robot.joint_names[i] for i in values if i not in in_group]
        if outside:
            raise errors.InvalidJointNames(f"goal names joint(s) outside group {req.group}: {', '.join(outside)}")
        if len(values) != len(indices):
            missing = [self.robot.joint_names[i] for i in indices if i not in values]
            raise errors.InvalidJointCount(
                f"goal has {len(values)} value(s) for group {req.group} of {len(indices)} joints; "
                f"missing: {', '.join(missing)}"
            )
        q = start_full.copy()
        for i, v in values.items():
            q[i] = v
        return q

    def _solve_pose_goal(self, req: MotionRequest, start_full, indices, deadline) -> np.ndarray:
        if req.goal_joints:
            raise errors.InvalidRequest("give either goal_joints or goal_poses, not both")
        return solve_pose_goal(self.robot, self.checker, req.group, req.goal_poses or {}, start_full, indices, deadline)

    def check_free(self, q: np.ndarray, error_cls, what: str) -> None:
        """Raise ``error_cls`` naming the colliding pairs if the full configuration ``q`` collides."""
        if self.checker.is_valid(q):
            return
        pairs = list(self.checker.colliding_pairs(q))
        named = ", ".join(f"{a}–{b}" for a, b in pairs[:5]) or "unknown bodies"
        raise error_cls(f"{what} configuration is in collision: {named}", pairs=pairs)

    # --- search -----------------------------------------------------------------------------
    def _search(self, spec: ArmPlannerSpec, gs, start, goal, seed, attempts, deadline, stats, resolution) -> np.ndarray:
        if np.allclose(start, goal, atol=1e-12, rtol=0):
            stats.attempts_used = 0
            return np.vstack([start, goal])
        reserve = self.config.postprocess_reserve * max(0.0, deadline - time.monotonic())
        search_deadline = deadline - reserve
        params = merged_params(spec.id, self.config.planner_params.get(spec.id))
        search = self._search_roadmap if spec.has("roadmap") else self._search_once
        failure = None
        for attempt in range(attempts):
            if search_deadline <= time.monotonic():
                break
            stats.attempts_used = attempt + 1
            t_solve = time.monotonic()
            build_before = stats.roadmap_build_time
            path, failure = search(spec, gs, start, goal, params, seed + attempt, search_deadline, stats, resolution)
            # roadmap planners: query time only; the roadmap build is reported apart (roadmap_build_time)
            stats.solve_time += time.monotonic() - t_solve - (stats.roadmap_build_time - build_before)
            self._monitor.report("search", nodes=stats.nodes)  # raises if the search ended by a cancel
            if path is not None:
                return path
        if failure is None or time.monotonic() >= search_deadline:
            raise errors.PlanningTimedOut(
                f"{spec.id} found no path within the time budget ({stats.attempts_used} attempt(s), "
                f"{stats.nodes} nodes)",
                source="planner",
            )
        raise errors.PlanningFailed(failure, source="planner")

    def _search_checker_for(self, req: MotionRequest, start_full: np.ndarray, goal_full: np.ndarray):
        """The checker ``req``'s search and shortcutting plan on (docs/certification.md, "Why the search is padded").

        When its path will be certified with a safety margin: ``self.checker`` padded by that margin, so the
        search's paths rarely pass closer than certification accepts. A start or goal closer than the margin
        (certification then keeps half the nearer one's clearance, :func:`certify_and_repair`) is searched
        padded by :data:`NEAR_END_PADDING` of that clearance (more than certification keeps: the search checks
        states, certification the motion between them); unpadded if it touches.
        """
        margin = self.safety_margin(req) if self.certifier is not None else 0.0
        if margin <= 0.0:
            return self.checker
        padded = self._padded_checker(margin)
        if padded.is_valid(start_full) and padded.is_valid(goal_full):
            return padded
        ends = min(self.certifier.clearance(start_full), self.certifier.clearance(goal_full))
        return self._padded_checker(NEAR_END_PADDING * ends) if ends > 0.0 else self.checker

    def _padded_checker(self, padding: float):
        """``self.checker`` padded by ``padding`` (kept for the next requests, with their OMPL setups)."""
        padded = self._padded.pop(padding, None) or padded_checker(self.robot, self.checker, padding)
        self._padded[padding] = padded  # most recent last
        while len(self._padded) > PADDED_CHECKERS:
            dropped = self._padded.pop(next(iter(self._padded)))
            self._setups = {key: setup for key, setup in self._setups.items() if key[1] != id(dropped)}
        return padded

    def _group_setup(self, names, indices, base: np.ndarray, resolution: float) -> GroupSetup:
        """The group's space and OMPL setup (built once per group), prepared for ``base`` and ``resolution``."""
        key = (tuple(indices), id(self._search_checker))
        setup = self._setups.get(key)
        if setup is None:
            lower, upper = self.robot.lower_limits[indices], self.robot.upper_limits[indices]
            setup = GroupSetup(GroupSpace(names, indices, lower, upper, base), self._search_checker, resolution)
            self._setups[key] = setup
        setup.prepare(base, resolution)
        return setup

    def _search_once(self, spec, gs, start, goal, params, seed, search_deadline, stats, resolution):
        """One solve of a fresh planner on the group's reused setup; (path | None, proven-failure message | None)."""
        setup = self._group_setup(gs.joint_names, gs.indices, gs.base, resolution)
        edges, ss = setup.edges, setup.ss
        si = ss.getSpaceInformation()
        with seeded_ompl(seed):
            ss.setStartAndGoalStates(gs.to_state(start), gs.to_state(goal))
            planner = spec.factory(si, params, edges)  # params: merged and checked once per request (_search)
            ss.setPlanner(planner)
            ptc = ob.timedPlannerTerminationCondition(max(0.0, search_deadline - time.monotonic()))
            with self._monitor.attach(ptc):
                ss.solve(ptc)
        stats.nodes, stats.edges = _graph_size(planner, si)
        if ss.haveExactSolutionPath():
            return np.array([gs.to_array(s) for s in ss.getSolutionPath().getStates()]), None
        return None, planner.failure_proof() if isinstance(planner, ProvesFailure) else None

    def _scene_key(self) -> tuple:
        """Changes whenever the scene does: a set_scene call or an edit that bumps ``scene.version``."""
        scene = getattr(self.checker, "scene", None) or self.scene
        return (self._scene_epoch, id(scene), getattr(scene, "version", None))

    def _roadmap_for(self, spec: ArmPlannerSpec, gs: GroupSpace, params, resolution: float) -> Roadmap:
        outside = np.setdiff1d(np.arange(len(gs.base)), gs.indices)
        key = (spec.id, tuple(gs.indices), tuple(np.round(gs.base[outside], 9)), resolution, tuple(params.items()),
               id(self._search_checker))  # fmt: skip
        roadmap = self._roadmaps.get(key)
        if roadmap is None:
            roadmap = Roadmap(gs, self._search_checker, resolution, spec.id, params)
            roadmap.scene_epoch = self._scene_key()
            self._roadmaps = {key: roadmap}  # one roadmap at a time: bounded memory
        return roadmap

    def _search_roadmap(self, spec, gs, start, goal, params, seed, search_deadline, stats, resolution):
        """Query the cached roadmap; after a scene change, verify the answer and fall back to re-validation.

        A roadmap built before the last scene change is "stale": its answer is checked against the
        current scene in one batched call (cheap) and returned if free. Only when that check fails is
        the whole roadmap re-validated, and rebuilt if any milestone or edge died. ``seed`` seeds OMPL
        while a roadmap is created and grown, so a fresh planner builds the same roadmap for the same seed.
        """
        with seeded_ompl(seed):
            roadmap = self._roadmap_for(spec, gs, params, resolution)
            stale = roadmap.scene_epoch != self._scene_key()
            path = self._query_roadmap(roadmap, start, goal, search_deadline, stats)
            if path is None or not stale:
                return path, None
            t_check = time.monotonic()
            path_ok = roadmap.edges.path_valid(path)
            stats.validation_time += time.monotonic() - t_check
            if path_ok:
                return path, None
            report = roadmap.revalidate()
            self.last_revalidation = report
            stats.validation_time += report.seconds
            if report.still_valid:  # cannot happen with a deterministic checker; keep the roadmap if it does
                roadmap.scene_epoch = self._scene_key()
                return path, None
            self._roadmaps.clear()
            roadmap = self._roadmap_for(spec, gs, params, resolution)
            return self._query_roadmap(roadmap, start, goal, search_deadline, stats), None

    def _query_roadmap(self, roadmap: Roadmap, start, goal, search_deadline, stats):
        stats.roadmap_reused = roadmap.queries > 0
        if roadmap.milestones < self.config.prm_roadmap_nodes:
            before = roadmap.build_time
            roadmap.build(self.config.prm_roadmap_nodes, search_deadline)
            stats.roadmap_build_time += roadmap.build_time - before
        self._monitor.report("search", nodes=roadmap.milestones)
        seconds = search_deadline - time.monotonic()
        if seconds <= 0:
            return None
        _mode, path = roadmap.query(start, goal, seconds)
        stats.nodes, stats.edges = roadmap.milestones, roadmap.edge_count
        return path

    # --- post-processing --------------------------------------------------------------------
    def _simplify(self, req, edges: EdgeChecker, raw, seed, deadline, stats) -> np.ndarray:
        """``raw`` shortcut on ``edges`` (the search's group, checker and motion resolution)."""
        if not getattr(req, "simplify", True) or len(raw) <= 2:
            return raw
        t_simp = time.monotonic()
        monitor = self._monitor
        max_tries = self.config.simplify_max_tries
        if is_compiled_sphere_checker(edges.checker):
            # lazy: numba is loaded already (a sphere checker exists); exact-only callers never need it
            from maru_planner.planning.compiled_shortcut import shortcut

            path = shortcut(raw, edges, seed, deadline, max_tries, monitor.check)
        else:

            def edge_valid(qa: np.ndarray, qb: np.ndarray) -> bool:
                monitor.check()
                return edges.edge_valid(qa, qb)

            path, _checks = postprocess.shortcut(raw, edge_valid, np.random.default_rng(seed), deadline, max_tries)
        stats.simplify_time = time.monotonic() - t_simp
        return path


class _CancelsNested:
    """Attached to a request's monitor, its cancel reaches a nested plan (a repair) that reports its own stages."""

    def __init__(self, nested: PlanMonitor):
        self.nested = nested

    def terminate(self) -> None:
        self.nested.cancel()


def _record_verification(result: MotionResult, certificate, repairs: int) -> None:
    """A sphere plan's exact re-check is its certification: the verification fields report it."""
    from maru_planner.collision.spheres import PathVerification  # lazy: numba; only sphere plans get here

    stats = result.stats
    stats.verified, stats.verify_time, stats.replans = stats.certified, certificate.seconds, repairs
    failing = certificate.first_failing_segment
    result.verification = PathVerification(stats.certified, failing, certificate.checks)


def _safety_margin(request: MotionRequest, config: PlannerConfig) -> float:
    """The request's safety margin (m), else the configuration's; InvalidRequest unless finite and >= 0."""
    value: Any = config.safety_margin if getattr(request, "safety_margin", None) is None else request.safety_margin
    try:
        margin = float(value)
    except (TypeError, ValueError) as exc:
        raise errors.InvalidRequest(f"safety_margin must be a number (m), got {value!r}") from exc
    if not (math.isfinite(margin) and margin >= 0.0):
        raise errors.InvalidRequest(f"safety_margin must be a finite number >= 0 m, got {margin}")
    return margin


def _graph_size(planner, si) -> tuple[int, int]:
    """(nodes, edges) the planner built: its own count if it reports one, else from a PlannerData copy."""
    if isinstance(planner, ReportsGraphSize):
        return planner.graph_size()
    data = ob.PlannerData(si)
    planner.getPlannerData(data)
    return int(data.numVertices()), int(data.numEdges())

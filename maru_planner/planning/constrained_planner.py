"""Planning with path constraints: CBiRRT (Berenson, Srinivasa, Ferguson, Kuffner 2009).

RRT-Connect in the group's joint space where every extension step is *projected* onto the constraint
region (:meth:`PathConstraints.project`: damped least squares on the violated components), so both
trees only hold states that satisfy the constraints. An edge between consecutive states (at most
``step`` rad long) is kept only if its states every ``config.resolution`` rad are collision-free and
satisfy the constraints too (constrained edge interpolation), so the path -- and the trajectory, which
stays within :data:`~maru_planner.planning.cartesian.BLEND_DEVIATION` rad of it -- holds the constraint
all along. The path is then shortcut (shortcuts checked the same way), certified collision-free on the
exact model (``docs/certification.md``; no repair: a repair would not know the constraints) and timed.

This is the equivalent of OMPL's projection-based constrained planning (``ProjectedStateSpace``), whose
Python bindings OMPL 2.0.1 does not expose in a usable form (no ``Constraint`` subclassing). Requests with
path constraints are planned by this planner (``planner_id`` ``CBiRRT`` or empty); other ids are refused.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from maru_planner import errors
from maru_planner.params import ParamSpec
from maru_planner.planning import postprocess
from maru_planner.planning.cartesian import end_margin, time_dense_path
from maru_planner.planning.checkers import collision_model_of
from maru_planner.planning.constraints import PathConstraints
from maru_planner.planning.space import edge_states, full_configurations
from maru_planner.planning.types import MotionRequest, MotionResult, PlanStats, PlanStatus, set_failure

if TYPE_CHECKING:  # the facade imports this module to hand constrained requests over
    from maru_planner.planning.motion_planner import MotionPlanner

PLANNER_ID = "CBiRRT"
STEP = ParamSpec("step", 0.1, "largest joint move (rad) of one projected extension step", lower=1e-3, upper=1.0)
INSET = ParamSpec("inset", 0.2, "share of each tolerance projection keeps free inside the bound", lower=0.0, upper=0.9)
PARAMS = {STEP.name: STEP, INSET.name: INSET}
DESCRIPTION = "constrained bidirectional RRT: RRT-Connect with every step projected onto the path constraints"
CONNECT_DISTANCE = 1e-3  # rad: the trees meet when a state comes this close to the other tree's


@dataclass
class _Problem:
    """One constrained search: the robot, constraints and checks on group configurations."""

    planner: MotionPlanner
    constraints: PathConstraints
    base: np.ndarray  # full configuration supplying the joints outside the group
    indices: np.ndarray
    step: float
    inset: float

    def full(self, q: np.ndarray) -> np.ndarray:
        out = self.base.copy()
        out[self.indices] = q
        return out

    def project(self, q: np.ndarray) -> np.ndarray | None:
        projected = self.constraints.project(self.planner.robot, self.full(q), self.indices, self.inset)
        return None if projected is None else projected[self.indices]

    def edge_valid(self, qa: np.ndarray, qb: np.ndarray) -> bool:
        """Every state of qa -> qb at the motion resolution is free and satisfies the constraints."""
        states = edge_states(qa, qb, self.planner.config.resolution)
        full = full_configurations(self.base, self.indices, states)
        robot = self.planner.robot
        if not all(self.constraints.satisfied(robot, q) for q in full):
            return False
        return int(self.planner.checker.first_invalid(full)) < 0


def plan_constrained(planner, request: MotionRequest, constraints: PathConstraints) -> MotionResult:
    """Plan ``request`` keeping ``constraints`` (module doc); never raises."""
    t0 = time.monotonic()
    stats = PlanStats(planner_id=PLANNER_ID, collision_model=collision_model_of(planner.checker))
    result = MotionResult(status=PlanStatus.PLANNING_FAILED, stats=stats)
    try:
        _plan(planner, request, constraints, result, t0)
    except Exception as exc:  # a typed error, or a bug: reported as the facade does, the planner keeps serving
        set_failure(result, exc)
        result.path = result.trajectory = None
    stats.total_time = time.monotonic() - t0
    return result


def _plan(planner, request: MotionRequest, constraints: PathConstraints, result: MotionResult, t0: float) -> None:
    if request.planner_id not in ("", PLANNER_ID):
        raise errors.InvalidPlanner(
            f"planner {request.planner_id!r} does not support path constraints; use {PLANNER_ID} (or leave it empty)"
        )
    budget, seed = planner.check_request(request)
    deadline = t0 + budget
    robot, stats = planner.robot, result.stats
    constraints.check_links(robot)
    indices = np.array(sorted(robot.group_joint_indices(request.group)), dtype=int)
    result.joint_names = [robot.joint_names[i] for i in indices]
    start = planner.start_configuration(request.start, indices, request.group)
    goal = planner.goal_configuration(request, start, indices)
    _check_end(robot, constraints, start, "start", errors.StartViolatesConstraints)
    _check_end(robot, constraints, goal, "goal", errors.InvalidRequest)
    planner.check_free(start, errors.StartInCollision, "start")
    planner.check_free(goal, errors.GoalInCollision, "goal")
    params = {**{n: p.default for n, p in PARAMS.items()}, **planner.config.planner_params.get(PLANNER_ID, {})}
    problem = _Problem(planner, constraints, start, indices, STEP.check(params["step"]), INSET.check(params["inset"]))
    stats.seed = seed
    rng = np.random.default_rng(seed)
    t_solve = time.monotonic()
    raw = _cbirrt(problem, start[indices], goal[indices], rng, t0 + 0.8 * budget, stats)
    stats.solve_time = time.monotonic() - t_solve
    stats.raw_waypoints, stats.raw_path_length = len(raw), postprocess.path_length(raw)
    path = raw
    if request.simplify:
        t_simp = time.monotonic()
        path, _checks = postprocess.shortcut(raw, problem.edge_valid, rng, t0 + 0.9 * budget, 50)
        stats.simplify_time = time.monotonic() - t_simp
    full = full_configurations(start, indices, path)
    margin = _certify(planner, full, planner.safety_margin(request), deadline, stats)
    t_par = time.monotonic()
    method = request.time_parameterization or planner.config.time_parameterization
    scalings = (float(request.velocity_scaling), float(request.acceleration_scaling))
    result.trajectory = time_dense_path(robot, planner.config, planner.certifier, full, indices, method, scalings,
                                        deadline, margin)  # fmt: skip
    stats.parameterize_time = time.monotonic() - t_par
    result.path = path
    stats.waypoints, stats.path_length = len(path), postprocess.path_length(path)
    stats.smoothness = postprocess.smoothness(path)
    result.status = PlanStatus.SUCCESS
    result.message = f"{PLANNER_ID}: {len(path)} waypoints on the path constraints, length {stats.path_length:.3f} rad"


def _check_end(robot, constraints: PathConstraints, q: np.ndarray, what: str, error_cls) -> None:
    orientation, position = constraints.violation(robot, q)
    if orientation > 0 or position > 0:
        raise error_cls(
            f"the {what} state violates the path constraints (orientation by {orientation:.3f} rad, "
            f"position by {position:.3f} m), so they cannot hold along the motion"
        )


def _certify(planner, full: np.ndarray, margin: float, deadline: float, stats: PlanStats) -> float:
    """Certify the path (no repairs) by the request's ``margin``, lowered to half the ends' clearance when they are
    closer; the margin used."""
    certifier = planner.certifier
    if certifier is None:
        return 0.0
    margin = end_margin(planner, margin, full[0], full[-1])
    certificate = certifier.certify_path(full, max(deadline, time.monotonic() + planner.config.certify_timeout),
                                         margin=margin)  # fmt: skip
    stats.certify_time, stats.min_clearance = certificate.seconds, certificate.min_clearance
    if not certificate.valid:
        raise errors.PlanningFailed(
            f"{PLANNER_ID} path not certified collision-free: segment {certificate.first_failing_segment} "
            f"({certificate.reason})", source="planner",
        )  # fmt: skip
    stats.certified = True
    return margin


class _Tree:
    def __init__(self, root: np.ndarray, capacity: int = 1024):
        self.nodes = np.empty((capacity, len(root)))
        self.nodes[0] = root
        self.parent = [-1]

    def __len__(self) -> int:
        return len(self.parent)

    def add(self, q: np.ndarray, parent: int) -> int:
        if len(self) == len(self.nodes):
            self.nodes = np.vstack([self.nodes, np.empty_like(self.nodes)])
        self.nodes[len(self)] = q
        self.parent.append(parent)
        return len(self) - 1

    def nearest(self, q: np.ndarray) -> int:
        return int(np.argmin(np.abs(self.nodes[: len(self)] - q).max(axis=1)))

    def branch(self, index: int) -> list[np.ndarray]:
        """The states from the root to ``index``."""
        out = []
        while index >= 0:
            out.append(self.nodes[index])
            index = self.parent[index]
        return out[::-1]


def _extend(problem: _Problem, tree: _Tree, target: np.ndarray) -> tuple[int, bool]:
    """Constrained extension from the nearest node towards ``target``: (last node added or reached, reached)."""
    index = tree.nearest(target)
    q = tree.nodes[index]
    while True:
        gap = target - q
        distance = float(np.abs(gap).max())
        if distance < CONNECT_DISTANCE:
            return index, True
        step = target if distance <= problem.step else q + gap * (problem.step / distance)
        projected = problem.project(step)
        if projected is None:
            return index, False
        moved = float(np.abs(projected - q).max())
        if moved < 1e-6 or moved > 2 * problem.step or np.abs(target - projected).max() >= distance:
            return index, False
        if not problem.edge_valid(q, projected):
            return index, False
        index, q = tree.add(projected, index), projected


def _cbirrt(problem: _Problem, start: np.ndarray, goal: np.ndarray, rng, deadline: float, stats) -> np.ndarray:
    lower = problem.planner.robot.lower_limits[problem.indices]
    upper = problem.planner.robot.upper_limits[problem.indices]
    trees = (_Tree(start), _Tree(goal))
    grow, other = trees
    while time.monotonic() < deadline:
        reached, _ = _extend(problem, grow, rng.uniform(lower, upper))
        meet, connected = _extend(problem, other, grow.nodes[reached])
        if connected:
            stats.nodes = len(trees[0]) + len(trees[1])
            a, b = (reached, meet) if grow is trees[0] else (meet, reached)
            return np.array(trees[0].branch(a) + trees[1].branch(b)[::-1][1:])
        grow, other = other, grow
    stats.nodes = len(trees[0]) + len(trees[1])
    raise errors.PlanningTimedOut(
        f"{PLANNER_ID} found no path on the path constraints within the time budget ({stats.nodes} nodes)",
        source="planner",
    )

"""Virtual wall planner (paper 004, §2.3): step forward, turning only within the free rotation range.

At step n the gait rectangle may rotate about the pivot O (a point on its
axis, by default the front edge's centre) clockwise by at most θ1(n) and
counter-clockwise by at most θ2(n) before it touches an obstacle (the
"virtual walls"). The planner tracks them as in eq. 6–7,

    θ1(n) = θ1(n−1) − ξ(n−1) + γ,   θ2(n) = θ2(n−1) + ξ(n−1) + γ

(ξ: the rotation actually made, counter-clockwise positive; γ: the change
caused by walking straight, eq. 8, γ = asin(d2/L) − asin(d1/L) from the
lateral room d before and after the step and the pivot-to-corner length L).
A side whose measured limit exceeds this prediction is *widening* (eq. 9–10).

Which way to turn: the robot heads for a look-ahead point on the
steepest-descent line of a cost-to-go field (a wavefront from the goal over
cells where half the gait's smaller side fits) — the paper leaves the goal
direction implicit. The turn is clipped to the free range (ξ < θ, eq. 6–7)
and to ``max_turn``. When the robot cannot move forward, it turns toward
the widening side (eq. 9–10; both widening: toward the larger limit,
eq. 11). In straight passages the limits oscillate; when
θ1(n−1) + θ2(n−1) = θ1(n) + θ2(n) and θ(n−2) = θ(n) the turn is divided by
the number c of consecutive such steps (eq. 12).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numba
import numpy as np

from maru_planner.base.biped.geometry import RectangleChecker
from maru_planner.base.biped.mapping import BipedMap2D
from maru_planner.base.biped.space import BipedPlanner, BipedSpace, BipedStats
from maru_planner.base.biped.world import BipedRobot
from maru_planner.base.budget import Deadline, unlimited
from maru_planner.base.common import wrap_angle
from maru_planner.base.kernels import heap_grow, heap_pop, heap_push, now
from maru_planner.base.planner import Endpoint, PlanRun
from maru_planner.errors import InvalidRequest, NoPath
from maru_planner.params import param


@dataclass
class WallParams:
    step: float = param(0.04, "metres walked per step", lower=1e-4, upper=10.0)
    pivot: float = param(
        0.5, "pivot O along the axis, in gait lengths from the centre (0.5 = front edge)", lower=-0.5, upper=0.5
    )
    max_turn: float = param(math.radians(12), "largest rotation per step (rad)", lower=1e-4, upper=math.pi)
    safety: float = param(0.8, "xi <= safety * theta (eq. 6-7 need xi < theta)", lower=1e-3, upper=0.999)
    angle_step: float = param(math.radians(2), "resolution of theta1, theta2 (rad)", lower=1e-4, upper=math.pi)
    max_angle: float = param(math.radians(90), "largest rotation limit measured (rad)", lower=1e-4, upper=math.pi)
    lookahead: float = param(0.35, "metres along the cost-to-go descent", lower=1e-3, upper=100.0)
    goal_tolerance: float = param(0.05, "distance to the goal that counts as arrived (m)", lower=1e-4, upper=10.0)
    max_steps: int = param(2000, "steps before giving up", lower=1, upper=10_000_000)
    patience: int = param(150, "steps without getting closer to the goal before giving up", lower=1, upper=10_000_000)
    oscillation_tolerance: float = param(
        math.radians(1), "limit change that counts as oscillating (rad)", lower=0.0, upper=math.pi
    )
    centering: float = param(2.0, "extra cost-to-go per cell of clearance missing to K", lower=0.0, upper=1000.0)

    def validate(self) -> None:
        checks = [
            (self.step > 0, "step must be > 0"),
            (-0.5 <= self.pivot <= 0.5, "pivot must be in [-0.5, 0.5] gait lengths"),
            (0 < self.max_turn <= math.pi, "max_turn must be in (0, pi]"),
            (0 < self.safety < 1, "safety must be in (0, 1) (the paper requires xi < theta)"),
            (0 < self.angle_step <= self.max_angle <= math.pi, "need 0 < angle_step <= max_angle <= pi"),
            (self.lookahead > 0 and self.goal_tolerance > 0, "lookahead and goal_tolerance must be > 0"),
            (self.max_steps > 0 and self.patience > 0, "max_steps and patience must be > 0"),
            (self.centering >= 0, "centering must be >= 0"),
        ]
        for ok, message in checks:
            if not ok:
                raise InvalidRequest(message)


@dataclass
class WallStats(BipedStats):
    damped_steps: int = 0
    jammed_steps: int = 0


def cost_to_go(
    passable: np.ndarray, goal_cell, cell_cost: np.ndarray | None = None, deadline: Deadline | None = None
) -> np.ndarray:
    """Octile wavefront cost from ``goal_cell`` over ``passable`` cells (inf elsewhere), 8-connected, no corner cutting.

    A move costs its length times the mean ``cell_cost`` of its two cells (1 by default).
    Raises PlanningTimedOut when ``deadline`` passes.
    """
    passable = np.ascontiguousarray(passable, dtype=np.bool_)
    costs = np.ones(passable.shape) if cell_cost is None else np.ascontiguousarray(cell_cost, dtype=float)
    deadline = deadline or unlimited()
    dist, finished = _wavefront_kernel(passable, costs, int(goal_cell[0]), int(goal_cell[1]), deadline.kernel_at)
    if not finished:
        deadline.raise_timeout(f"the cost-to-go wavefront over {passable.shape[1]} x {passable.shape[0]} cells")
    return dist


@numba.njit(cache=True, nogil=True)
def _wavefront_kernel(passable, costs, gr, gc, deadline_at):
    """Dijkstra from (gr, gc); returns (distances, False when the deadline passed first)."""
    h, w = passable.shape
    dist = np.full((h, w), np.inf)
    closed = np.zeros((h, w), dtype=np.bool_)
    keys, gs, ids = np.empty(1024), np.empty(1024), np.empty(1024, dtype=np.int64)
    dist[gr, gc] = 0.0
    size = heap_push(keys, gs, ids, 0, 0.0, 0.0, gr * w + gc)
    pops = 0
    while size > 0:
        node, d, size = heap_pop(keys, gs, ids, size)
        r, c = node // w, node % w
        if closed[r, c]:
            continue
        closed[r, c] = True
        pops += 1
        if (pops & 4095) == 0 and now() > deadline_at[0]:
            return dist, False
        for dr in range(-1, 2):
            for dc in range(-1, 2):
                nr, nc = r + dr, c + dc
                if (dr == 0 and dc == 0) or nr < 0 or nc < 0 or nr >= h or nc >= w:
                    continue
                if not passable[nr, nc] or closed[nr, nc]:
                    continue
                step = 1.0
                if dr != 0 and dc != 0:
                    if not (passable[r + dr, c] and passable[r, c + dc]):
                        continue
                    step = math.sqrt(2.0)
                nd = d + step * (0.5 * (costs[r, c] + costs[nr, nc]))
                if nd < dist[nr, nc]:
                    dist[nr, nc] = nd
                    if size == keys.shape[0]:
                        keys, gs, ids = heap_grow(keys, gs, ids)
                    size = heap_push(keys, gs, ids, size, nd, nd, nr * w + nc)
    return dist, True


class VirtualWallPlanner(BipedPlanner):
    """Virtual wall planner on a :class:`BipedMap2D` for a :class:`BipedRobot`."""

    def __init__(self, robot: BipedRobot, params: WallParams | None = None, **overrides):
        self.robot = robot
        unknown = set(overrides) - {f.name for f in dataclasses.fields(WallParams)}
        if unknown:
            raise InvalidRequest(f"unknown biped_wall parameter(s) {sorted(unknown)}")
        self.params = dataclasses.replace(params or WallParams(), **overrides)
        self.params.validate()

    # ----------------------------------------------------------- geometry
    def _pivot(self, pose, pivot: float | None = None) -> tuple[float, float]:
        offset = (self.params.pivot if pivot is None else pivot) * self.robot.gait_length
        return pose[0] + offset * math.cos(pose[2]), pose[1] + offset * math.sin(pose[2])

    def _rotate(self, pose, angle: float, pivot: float | None = None):
        ox, oy = self._pivot(pose, pivot)
        c, s = math.cos(angle), math.sin(angle)
        dx, dy = pose[0] - ox, pose[1] - oy
        return ox + c * dx - s * dy, oy + s * dx + c * dy, wrap_angle(pose[2] + angle)

    def rotation_limits(self, pose, checker: RectangleChecker, pivot: float | None = None) -> tuple[float, float]:
        """(θ1 clockwise, θ2 counter-clockwise) free rotation about O, to ``angle_step``."""
        return self._limit(pose, checker, -1.0, pivot), self._limit(pose, checker, 1.0, pivot)

    def _limit(self, pose, checker, sign: float, pivot: float | None = None) -> float:
        p = self.params
        free = 0.0
        angle = p.angle_step
        while angle <= p.max_angle + 1e-12:
            if checker.collides(*self._rotate(pose, sign * angle, pivot)):
                break
            free = angle
            angle += p.angle_step
        return free

    def _lateral_room(self, pose, checker: RectangleChecker, side: float) -> float:
        """d of eq. 8: free distance from O sideways (side +1 left, −1 right), up to the corner arm L."""
        ox, oy = self._pivot(pose)
        nx, ny = -math.sin(pose[2]) * side, math.cos(pose[2]) * side
        arm = self._arm()
        m = checker
        for d in np.arange(0.0, arm + 1e-9, m.resolution / 2):
            col = int(math.floor((ox + d * nx - m.origin[0]) / m.resolution))
            row = int(math.floor((oy + d * ny - m.origin[1]) / m.resolution))
            h, w = m.occupied.shape
            if not (0 <= row < h and 0 <= col < w) or m.occupied[row, col]:
                return d
        return arm

    def _arm(self) -> float:
        """L of eq. 8: pivot-to-far-corner distance."""
        along = self.robot.gait_length * (0.5 + abs(self.params.pivot))
        return math.hypot(along, self.robot.gait_width / 2)

    def _gamma(self, before: float, after: float) -> float:
        arm = self._arm()
        return math.asin(min(1.0, after / arm)) - math.asin(min(1.0, before / arm))

    # ------------------------------------------------------------ guidance
    def _reference_heading(self, field: np.ndarray, m: BipedMap2D, pose) -> float | None:
        row, col = m.world_to_cell(pose[0], pose[1])
        h, w = field.shape
        if not (0 <= row < h and 0 <= col < w):
            return None
        if not np.isfinite(field[row, col]):
            window = field[max(0, row - 3) : row + 4, max(0, col - 3) : col + 4]
            if not np.isfinite(window).any():
                return None
            lowest = np.unravel_index(np.argmin(window), window.shape)
            row, col = max(0, row - 3) + int(lowest[0]), max(0, col - 3) + int(lowest[1])
        steps = int(math.ceil(self.params.lookahead / m.resolution))
        for _ in range(steps):
            best = (field[row, col], row, col)
            for dr in (-1, 0, 1):
                for dc in (-1, 0, 1):
                    r, c = row + dr, col + dc
                    if 0 <= r < h and 0 <= c < w and field[r, c] < best[0]:
                        best = (field[r, c], r, c)
            if best[1:] == (row, col):
                break
            row, col = best[1], best[2]
        x, y = m.cell_to_world(row, col)
        if math.hypot(x - pose[0], y - pose[1]) < 1e-9:
            return None
        return math.atan2(y - pose[1], x - pose[0])

    # ---------------------------------------------------------------- plan
    def new_stats(self) -> BipedStats:
        return WallStats(deciding_stage="virtual_wall")

    def search(self, space: BipedSpace, start_end: Endpoint, goal_end: Endpoint, run: PlanRun) -> np.ndarray:
        try:
            poses = self._search(space.map, space.checker, start_end.pose, goal_end.pose, run)
        finally:
            run.stats.collision_checks = space.checker.checks
        run.message = f"virtual-wall walk reached the goal in {len(poses) - 1} steps"
        return np.asarray(poses, dtype=float)

    def _search(self, m: BipedMap2D, checker: RectangleChecker, start, goal, run: PlanRun) -> list:
        robot = self.robot
        trace: dict[str, list[float]] = {"theta_cw": [], "theta_ccw": [], "xi": [], "widening": [], "damping": []}
        run.layers["trace"] = trace
        # passability and the centring cost look at clearances up to K only
        clearance = m.clearance(robot.corner_distance + m.resolution, run.deadline)
        passable = clearance >= min(robot.gait_length, robot.gait_width) / 2 - 1e-9
        goal_cell = m.world_to_cell(goal[0], goal[1])
        passable[goal_cell] = True
        # Narrow cells cost more, so the descent keeps to the middle of passages narrower than K.
        shortfall = np.clip(robot.corner_distance - clearance, 0.0, None) / m.resolution
        run.deadline.check_now("virtual-wall set-up")
        field = cost_to_go(passable, goal_cell, 1.0 + self.params.centering * shortfall, run.deadline)
        run.layers["cost_to_go"] = field
        start_cell = m.world_to_cell(start[0], start[1])
        if not np.isfinite(field[start_cell]) and self._reference_heading(field, m, start) is None:
            raise NoPath("no passage wide enough for the gait joins start and goal")
        return self._walk(m, checker, field, start, goal, run, trace)

    def _walk(self, m, checker, field, start, goal, run: PlanRun, trace) -> list:
        p, stats = self.params, run.stats_as(WallStats)
        pose = tuple(float(v) for v in start)
        poses = [pose]
        prev_limits = None
        prev_xi = 0.0
        prev_room = (self._lateral_room(pose, checker, 1.0), self._lateral_room(pose, checker, -1.0))
        damping = 1
        best_distance, since_best = math.inf, 0
        for _ in range(p.max_steps):
            run.deadline.check_now("virtual-wall walk")
            stats.expansions += 1
            distance = math.hypot(goal[0] - pose[0], goal[1] - pose[1])
            if distance <= p.goal_tolerance:
                arrived, why = self._arrive(checker, pose, goal, poses)
                if arrived is None:
                    raise NoPath(why)
                return arrived
            if distance <= p.lookahead / 2:
                arrived, _ = self._arrive(checker, pose, goal, poses)  # close: side-step straight onto the goal
                if arrived is not None:
                    return arrived
            if distance < best_distance - 1e-6:
                best_distance, since_best = distance, 0
            else:
                since_best += 1
                if since_best > p.patience:
                    raise NoPath(f"stuck {distance:.2f} m from the goal (no progress in {p.patience} steps)")
            cw, ccw = self.rotation_limits(pose, checker)
            room = (self._lateral_room(pose, checker, 1.0), self._lateral_room(pose, checker, -1.0))
            widening = self._widening(prev_limits, (cw, ccw), prev_xi, prev_room, room)
            trace["theta_cw"].append(cw)
            trace["theta_ccw"].append(ccw)
            trace["widening"].append(widening)
            desired = self._desired(field, m, pose, goal, distance)
            xi = float(np.clip(desired, -min(p.safety * cw, p.max_turn), min(p.safety * ccw, p.max_turn)))
            damping = self._damping(trace, xi, prev_xi, damping)
            xi /= damping
            trace["damping"].append(damping)
            stats.damped_steps += damping > 1
            moved = self._move(checker, pose, xi, min(p.step, distance))
            if moved is None:
                stats.jammed_steps += 1
                moved, xi = self._unjam(checker, pose, desired, cw, ccw, widening, min(p.step, distance))
                if moved is None:
                    raise NoPath(f"jammed at ({pose[0]:.2f}, {pose[1]:.2f}): no free rotation or step")
            trace["xi"].append(xi)
            prev_limits, prev_xi, prev_room = (cw, ccw), xi, room
            pose = moved
            poses.append(pose)
        raise NoPath(f"gave up after {p.max_steps} steps")

    def _widening(self, prev_limits, limits, prev_xi, prev_room, room) -> tuple[bool, bool]:
        """Eq. 9–10: did the clockwise / counter-clockwise limit grow beyond eq. 6–7's prediction?"""
        if prev_limits is None:
            return False, False
        gamma_right = self._gamma(prev_room[1], room[1])
        gamma_left = self._gamma(prev_room[0], room[0])
        predicted_cw = prev_limits[0] + prev_xi + gamma_right
        predicted_ccw = prev_limits[1] - prev_xi + gamma_left
        tol = self.params.angle_step
        return limits[0] > predicted_cw + tol, limits[1] > predicted_ccw + tol

    def _desired(self, field, m, pose, goal, distance) -> float:
        """Heading change toward the look-ahead point of the cost-to-go descent (the goal when close)."""
        heading = self._reference_heading(field, m, pose)
        if heading is None or distance < self.params.lookahead / 2:
            heading = math.atan2(goal[1] - pose[1], goal[0] - pose[0])
        return wrap_angle(heading - pose[2])

    def _damping(self, trace, xi, prev_xi, damping) -> int:
        """Eq. 12: count consecutive oscillating steps (c) while the turn keeps changing sign."""
        cw, ccw = trace["theta_cw"], trace["theta_ccw"]
        if len(cw) < 3 or xi * prev_xi >= 0:
            return 1
        tol = self.params.oscillation_tolerance
        same_sum = abs((cw[-2] + ccw[-2]) - (cw[-1] + ccw[-1])) <= tol
        repeats = abs(cw[-3] - cw[-1]) <= tol or abs(ccw[-3] - ccw[-1]) <= tol
        return damping + 1 if same_sum and repeats else 1

    def _move(self, checker, pose, xi, step, pivot: float | None = None):
        """Rotate by ξ about O, then walk straight; None when no part of that is free."""
        turned = self._rotate(pose, xi, pivot) if xi else pose
        if xi and checker.collides(*turned):
            return None
        for fraction in (1.0, 0.5, 0.25):
            d = step * fraction
            moved = (turned[0] + d * math.cos(turned[2]), turned[1] + d * math.sin(turned[2]), turned[2])
            if not checker.sweep_collides(np.array([turned, moved]), checker.resolution / 2):
                return moved
        return None

    def _unjam(self, checker, pose, desired, cw, ccw, widening, step):
        """A way on when the step about O is blocked; returns (pose, ξ) or (None, 0).

        In order: the guided turn about another point of the axis (front, centre,
        rear) followed by the step; a turn in place toward the widening side
        (eq. 9–10; both widening: toward the larger limit, eq. 11); half a step back.
        """
        p = self.params
        sign = 1.0 if desired > 0 else -1.0
        for pivot in (0.5, 0.0, -0.5):
            if pivot == p.pivot:
                continue
            limit = self._limit(pose, checker, sign, pivot)
            xi = sign * min(abs(desired), p.safety * limit, p.max_turn)
            if xi:
                moved = self._move(checker, pose, xi, step, pivot)
                if moved is not None:
                    return moved, xi
        wide_cw, wide_ccw = widening
        if wide_cw != wide_ccw:
            turn = -1.0 if wide_cw else 1.0
        else:
            turn = 1.0 if ccw > cw else -1.0 if cw > ccw else 0.0
        limit = ccw if turn > 0 else cw
        if turn and limit > 0:
            xi = turn * min(p.safety * limit, p.max_turn)
            return self._rotate(pose, xi), xi
        back = (pose[0] - 0.5 * step * math.cos(pose[2]), pose[1] - 0.5 * step * math.sin(pose[2]), pose[2])
        if not checker.sweep_collides(np.array([pose, back]), checker.resolution / 2):
            return back, 0.0
        return None, 0.0

    def _arrive(self, checker, pose, goal, poses) -> tuple[list | None, str]:
        """Step (sideways if need be, a biped can) onto the goal and turn to its heading about the centre.

        Returns (the poses with the arrival, "") or (None, why not).
        """
        final = (goal[0], goal[1], pose[2])
        if checker.sweep_collides(np.array([pose, final]), checker.resolution / 2):
            return None, "could not make the last step onto the goal"
        aligned = (goal[0], goal[1], goal[2])
        if checker.sweep_collides(np.array([final, aligned]), checker.resolution / 2):
            return None, "reached the goal position but cannot turn to the goal heading"
        return poses + [final, aligned], ""

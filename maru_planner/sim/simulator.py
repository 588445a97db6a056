"""Kinematic 2-D simulator: diff-drive robot, LMS200-like ray-cast laser, moving obstacles, collisions."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from maru_planner.reactive.kinematics import clamp_twist, integrate_unicycle
from maru_planner.reactive.scan import LaserScanData
from maru_planner.sim.geometry import (
    fan_vs_circles,
    point_in_polygon,
    points_to_segments,
    polygon_segments,
    rays_vs_segments,
    segments_intersect,
    transform,
)
from maru_planner.sim.world import OccupancyMap, World


@dataclass
class RunResult:
    """Outcome of one closed-loop run (the CLI's JSON, plus the trajectory and strip snapshots)."""

    success: bool
    outcome: str  # "goal" | "collision" | "timeout"
    collisions: int
    time_to_goal: float | None
    path_length: float
    min_clearance: float
    update_ms: dict
    trajectory: np.ndarray
    updates: int = 0
    strips: list = field(default_factory=list)  # (time, pose, strip (k, 2), obstacle points (m, 2))

    def to_json(self) -> dict:
        return {
            "success": self.success,
            "outcome": self.outcome,
            "collisions": self.collisions,
            "time_to_goal": self.time_to_goal,
            "path_length": round(self.path_length, 4),
            "min_clearance": round(self.min_clearance, 4),
            "update_ms": self.update_ms,
            "updates": self.updates,
        }


class Simulator:
    """A world, a robot pose and a clock. ``seed`` drives start jitter, laser noise and mover timing."""

    def __init__(
        self,
        world: World,
        seed: int = 0,
        start_jitter: float = 0.0,
        heading_jitter: float = 0.0,
        mover_jitter: float = 0.0,
        noise: float | None = None,
    ):
        self.world = world
        self.rng = np.random.default_rng(seed)
        start = world.robot.start.astype(float).copy()
        if start_jitter > 0:
            start[:2] += self.rng.uniform(-start_jitter, start_jitter, 2)
        if heading_jitter > 0:
            start[2] += self.rng.uniform(-heading_jitter, heading_jitter)
        self.robot_pose = (float(start[0]), float(start[1]), float(start[2]))
        self.mover_offset = float(self.rng.uniform(-mover_jitter, mover_jitter)) if mover_jitter > 0 else 0.0
        self.time = 0.0
        laser = world.robot.laser
        self.noise = laser.noise if noise is None else noise
        self._beam_angles = math.radians(-laser.fov_deg / 2) + math.radians(laser.resolution_deg) * np.arange(
            laser.beams
        )
        self.collided = False
        self._distance_field = world.occupancy.distance_field() if world.occupancy is not None else None

    # -- sensing ------------------------------------------------------------------------------------
    def laser_pose(self) -> tuple[float, float, float]:
        laser = self.world.robot.laser
        x, y, th = self.robot_pose
        c, s = math.cos(th), math.sin(th)
        return x + c * laser.x - s * laser.y, y + s * laser.x + c * laser.y, th + laser.yaw

    def true_ranges(self) -> np.ndarray:
        """Noise-free ranges of every beam (inf where nothing is within range_max)."""
        laser = self.world.robot.laser
        lx, ly, lth = self.laser_pose()
        origin = np.array([lx, ly])
        a = lth + self._beam_angles
        dirs = np.stack([np.cos(a), np.sin(a)], axis=1)
        r = fan_vs_circles(
            origin,
            lth + self._beam_angles[0],
            math.radians(laser.resolution_deg),
            laser.beams,
            self.world.circles_at(self.time, self.mover_offset),
            laser.range_max,
        )
        r = np.minimum(r, rays_vs_segments(origin, dirs, self.world.segments))
        if self.world.occupancy is not None:
            r = np.minimum(r, _rays_vs_map(self.world.occupancy, origin, dirs, laser.range_max))
        r[r > laser.range_max] = np.inf
        return r

    def scan(self) -> LaserScanData:
        """One LMS200-like scan at the current time (Gaussian range noise, REP 117 inf for no return)."""
        laser = self.world.robot.laser
        r = self.true_ranges()
        if self.noise > 0:
            finite = np.isfinite(r)
            r[finite] = r[finite] + self.rng.normal(0.0, self.noise, int(finite.sum()))
            r[finite] = np.clip(r[finite], laser.range_min, laser.range_max)
        return LaserScanData(
            angle_min=math.radians(-laser.fov_deg / 2),
            angle_increment=math.radians(laser.resolution_deg),
            ranges=r,
            range_min=laser.range_min,
            range_max=laser.range_max,
            stamp=self.time,
        )

    # -- geometry --------------------------------------------------------------------------------------
    def _footprint_world(self, pose) -> np.ndarray | None:
        fp = self.world.robot.footprint
        return None if fp is None else transform(fp, pose)

    def clearance(self, pose=None) -> float:
        """Signed distance from the robot body to the nearest obstacle (< 0 when overlapping)."""
        pose = self.robot_pose if pose is None else pose
        circles = self.world.circles_at(self.time, self.mover_offset)
        centre = np.array(pose[:2])
        fp = self._footprint_world(pose)
        best = np.inf
        if fp is None:
            radius = self.world.robot.radius
            if len(circles):
                best = min(best, float(np.min(np.hypot(*(circles[:, :2] - centre).T) - circles[:, 2])) - radius)
            for poly in self.world.polygons:
                d = float(points_to_segments(centre[None], polygon_segments(poly)).min())
                inside = point_in_polygon(centre[None], poly)[0]
                best = min(best, (-d if inside else d) - radius)
            if self._distance_field is not None:
                best = min(best, self._map_distance(centre[None]) - radius)
            return best
        edges = polygon_segments(fp)
        if len(circles):
            d = points_to_segments(circles[:, :2], edges).min(axis=1) - circles[:, 2]
            inside = point_in_polygon(circles[:, :2], fp)
            best = min(best, float(np.min(np.where(inside, -circles[:, 2], d))))
        for poly in self.world.polygons:
            poly_edges = polygon_segments(poly)
            if (
                segments_intersect(edges, poly_edges)
                or point_in_polygon(fp[:1], poly)[0]
                or point_in_polygon(poly[:1], fp)[0]
            ):
                return -1e-3 if best > 0 else best
            best = min(
                best, float(points_to_segments(fp, poly_edges).min()), float(points_to_segments(poly, edges).min())
            )
        if self._distance_field is not None:
            samples = np.vstack([fp, 0.5 * (fp + np.roll(fp, -1, axis=0)), centre[None]])
            best = min(best, self._map_distance(samples))
        return best

    def _map_distance(self, points: np.ndarray) -> float:
        occupancy, distances = self.world.occupancy, self._distance_field
        if occupancy is None or distances is None:
            return math.inf
        row, col, inside = occupancy.cells(points)
        if not np.any(inside):
            return math.inf
        return float(distances[row[inside], col[inside]].min())

    # -- motion ----------------------------------------------------------------------------------------
    def step(self, v: float, w: float, dt: float) -> bool:
        """Drive (v, w) clipped to the robot's limits for ``dt`` s in sub-steps; True if it collided.

        A sub-step that would overlap an obstacle is not taken (bumper stop).
        """
        return self._step(v, w, dt)[0]

    def _step(self, v: float, w: float, dt: float) -> tuple[bool, float | None]:
        """:meth:`step`, plus the clearance at the end when the last sub-step was taken (else None)."""
        robot = self.world.robot
        v, w = clamp_twist(float(v), float(w), robot.max_linear, robot.max_angular)
        n = max(1, int(math.ceil(max(abs(v) * dt / 0.02, abs(w) * dt / 0.05))))
        h = dt / n
        hit, clearance = False, None
        for _ in range(n):
            pose = integrate_unicycle(self.robot_pose, v, w, h)
            self.time += h
            clearance = self.clearance(pose)
            if clearance < 0.0:
                hit, clearance = True, None  # the robot stays; the clock (and the movers) moved on
                continue
            self.robot_pose = pose
        if hit:
            self.collided = True
        return hit, clearance

    def goal_distance(self) -> float:
        g = self.world.robot.goal
        return math.hypot(self.robot_pose[0] - g[0], self.robot_pose[1] - g[1])

    # -- closed loop -----------------------------------------------------------------------------------
    def run(
        self,
        controller,
        max_time: float | None = None,
        stop_on_collision: bool = True,
        strip_every: int = 0,
        progress=None,
    ) -> RunResult:
        """Run ``controller`` (ElasticStripController-like: update(pose, scan) -> (v, w)) at the laser rate."""
        max_time = self.world.max_time if max_time is None else max_time
        dt = 1.0 / self.world.robot.laser.rate
        if self.world.path is not None:
            controller.set_path(np.vstack([np.array(self.robot_pose[:2])[None], self.world.path[:, :2]]))
        else:
            controller.set_goal(self.world.robot.goal)
        traj = [self.robot_pose]
        update_times, strips = [], []
        collisions, in_contact, min_clear, length = 0, False, self.clearance(), 0.0
        outcome, tick = "timeout", 0
        while self.time < max_time:
            scan = self.scan()
            t0 = time.perf_counter()
            out = controller.update(self.robot_pose, scan)
            update_times.append(time.perf_counter() - t0)
            if strip_every and tick % strip_every == 0:
                strips.append(
                    (self.time, self.robot_pose, np.asarray(out.strip).copy(), np.asarray(out.obstacle_points).copy())
                )
            before = self.robot_pose
            hit, clearance = self._step(out.v, out.w, dt)
            length += math.hypot(self.robot_pose[0] - before[0], self.robot_pose[1] - before[1])
            traj.append(self.robot_pose)
            min_clear = min(min_clear, self.clearance() if clearance is None else clearance)
            if hit and not in_contact:
                collisions += 1
            in_contact = hit
            tick += 1
            if progress is not None:
                progress(self)
            if collisions and stop_on_collision:
                outcome = "collision"
                break
            if self.goal_distance() <= self.world.goal_tolerance:
                outcome = "goal"
                break
        ms = np.array(update_times) * 1e3 if update_times else np.zeros(1)
        success = outcome == "goal" and collisions == 0
        return RunResult(
            success=success,
            outcome=outcome,
            collisions=collisions,
            time_to_goal=round(self.time, 3) if outcome == "goal" else None,
            path_length=length,
            min_clearance=float(min_clear),
            update_ms={"median": round(float(np.median(ms)), 4), "p99": round(float(np.percentile(ms, 99)), 4)},
            trajectory=np.array(traj),
            updates=len(update_times),
            strips=strips,
        )


def _rays_vs_map(occ: OccupancyMap, origin: np.ndarray, dirs: np.ndarray, max_range: float) -> np.ndarray:
    """Range of each ray to the first occupied cell, marched at half a cell (inf for none within max_range)."""
    step = 0.5 * occ.resolution
    t = np.arange(step, max_range + step, step)
    pts = origin[None, None, :] + dirs[:, None, :] * t[None, :, None]
    hit = occ.is_occupied(pts)
    first = np.argmax(hit, axis=1)
    return np.where(hit.any(axis=1), t[first], np.inf)

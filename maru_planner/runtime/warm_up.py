"""Load (or, on a fresh install, compile) the kernels an arm plan runs before its first request.

numba compiles a kernel at its first call and keeps the machine code in an on-disk cache (``cache=True``). On a
fresh install the first plan spent ~40 s compiling (a 30 s budget timed out); a new process with the cache full
still spends ~0.2 s loading it in its first plan. :func:`warm_up` pays either once, outside any request's budget,
by planning two short motions of the robot's largest group: one in a scene of one box, one in a scene of more
boxes than the checkers' large-scene paths start at (the grid of the sphere checker, certification's near-path
pair tables), on the checker, certification and time parameterisation of the config, with OMPL's RRT-Connect and
(on a sphere checker) the compiled kernels of RRT-Connect and RC-RRT and the compiled shortcut.

``planning_node`` warms up at configure (its in-process planners and each worker process before it reports
ready); ``make setup`` runs ``python -m maru_planner.planning.warm_up`` after a source change, so the disk cache is
full before the first node or test starts.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import threading
import time
from dataclasses import dataclass

import numpy as np

from maru_planner import errors
from maru_planner.collision.broadphase import robot_reach
from maru_planner.planning.checkers import is_compiled_sphere_checker, is_sphere_checker
from maru_planner.planning.config import COLLISION_MODELS, PlannerConfig
from maru_planner.planning.motion_planner import MotionPlanner
from maru_planner.planning.space import EdgeChecker, GroupSpace
from maru_planner.planning.types import MotionRequest
from maru_planner.robot import RobotModel
from maru_planner.scene import Obstacle, Scene
from maru_planner.trajectory import Limits, parameterize

SAMPLE_TRIES = 200  # random starts tried for a free start and goal
STEP = 0.3  # rad: the goal is at most this far from the start in each joint of the group
EDGE_STEP = 0.01  # rad: the straight motion from start to goal is checked free at states this far apart
# s per warm-up plan: a first compile (~35 s here) cannot be interrupted and this is no request's budget; the search
# itself ends at once (a free straight motion), so the whole warm-up stays well inside a worker's start-up timeout
BUDGET = 120.0
SEED = 1
BOX = 0.02  # m: edge of the warm-up boxes
MANY_BOXES = 80  # boxes of the large scene: above certify.NEAR_PATH_MIN_OBSTACLES and the sphere grid's threshold


warmed_configs: set[tuple] = set()  # the config keys this process has warmed up for (the kernels stay loaded)
_warmed_lock = threading.Lock()


@dataclass(frozen=True)
class WarmUp:
    """What :func:`warm_up` did: seconds taken, the (planner id, scene, status) of each plan (none: this process
    had already warmed up for such a config), and why it stopped early ("" if it did not)."""

    seconds: float
    plans: tuple[tuple[str, str, str], ...]
    error: str = ""

    def summary(self) -> str:
        """One line for a log."""
        if self.error:
            return f"kernel warm-up stopped after {self.seconds:.1f} s: {self.error}"
        statuses = ", ".join(f"{pid} in {scene}: {status}" for pid, scene, status in self.plans)
        return f"kernels warmed up in {self.seconds:.1f} s ({statuses or 'already loaded'})"


def warm_up(robot: RobotModel, config: PlannerConfig | None = None) -> WarmUp:
    """Plan short motions of ``robot`` as a planner of ``config`` would (module doc), once per process and kind of
    config. Never raises: a plan that fails still ran its kernels up to the failure; anything else (no free start
    and goal sampled, a robot the planner cannot take) ends the warm-up and is reported in ``error``."""
    t0 = time.monotonic()
    config = config or PlannerConfig()
    key = (config.collision_model, config.certify, config.time_parameterization)
    with _warmed_lock:
        if key in warmed_configs:
            return WarmUp(0.0, ())
        try:
            done = _plan_short_motions(robot, config)
        except Exception as exc:  # noqa: BLE001 - a warm-up never stops its caller; the first request will tell
            return WarmUp(time.monotonic() - t0, (), errors.one_line(f"{type(exc).__name__}: {exc}"))
        warmed_configs.add(key)
    return WarmUp(time.monotonic() - t0, done)


def _plan_short_motions(robot: RobotModel, config: PlannerConfig) -> tuple[tuple[str, str, str], ...]:
    group = max(robot.groups, key=lambda name: len(robot.groups[name]))
    planner = MotionPlanner.from_scene(robot, None, config)
    plans = []
    for scene_name, scene in (("one box", boxes(robot, 1)), ("many boxes", boxes(robot, MANY_BOXES))):
        planner.set_scene(scene)
        start, goal = free_pair(planner, group)
        for planner_id in _planner_ids(planner):
            request = MotionRequest(group, start=start, goal_joints=goal, planner_id=planner_id, time_budget=BUDGET,
                                    seed=SEED)  # fmt: skip
            plans.append((planner_id, scene_name, planner.plan(request).status.value))
        shortcut_bent_path(planner, group, start, goal)
    _time_bent_path(planner, group, start, goal)
    return tuple(plans)


def _bent_path(planner: MotionPlanner, group: str, start: dict[str, float], goal: dict[str, float]
               ) -> tuple[GroupSpace, np.ndarray]:  # fmt: skip
    """``group``'s space and the path start → a point off the line → goal (the warm-up plans' motions are straight,
    which leaves the shortcut nothing to do and toppra nothing to solve)."""
    robot = planner.robot
    indices = sorted(robot.group_joint_indices(group))
    names = [robot.joint_names[i] for i in indices]
    lower, upper = robot.lower_limits[indices], robot.upper_limits[indices]
    base = np.array([start[name] for name in robot.joint_names])
    a, b = base[indices], np.array([goal[name] for name in names])
    path = np.array([a, np.clip(0.5 * (a + b) + 0.5 * EDGE_STEP, lower, upper), b])
    return GroupSpace(names, indices, lower, upper, base), path


def shortcut_bent_path(planner: MotionPlanner, group: str, start: dict[str, float], goal: dict[str, float]) -> None:
    """On a compiled sphere checker, the compiled shortcut of :func:`_bent_path`."""
    if not is_compiled_sphere_checker(planner.checker):
        return
    from maru_planner.planning.planners.compiled_shortcut import shortcut  # lazy: numba, loaded with the sphere checker

    space, path = _bent_path(planner, group, start, goal)
    shortcut(path, EdgeChecker(space, planner.checker, planner.config.resolution), SEED, time.monotonic() + BUDGET, 1)


def _time_bent_path(planner: MotionPlanner, group: str, start: dict[str, float], goal: dict[str, float]) -> None:
    """toppra along :func:`_bent_path` (its numba kernel), its corner taken as free: only the kernel is warmed."""
    space, path = _bent_path(planner, group, start, goal)
    robot = planner.robot
    limits = Limits.scaled(robot.velocity_limits[space.indices], robot.acceleration_limits[space.indices])
    parameterize(path, space.joint_names, limits, "toppra", curve_free=lambda states, deviation: True,
                 max_deviation=planner.config.blend_deviation)  # fmt: skip


def _planner_ids(planner: MotionPlanner) -> list[str]:
    """OMPL's RRT-Connect (the checker's kernels; other planners' own code is Python or OMPL's), and the compiled
    loops where they run (a sphere checker with numba): CompiledRRTConnect's and RCRRT's."""
    if not is_sphere_checker(planner.checker):
        return ["RRTConnect"]
    return ["RRTConnect", "CompiledRRTConnect"] + (["RCRRT"] if is_compiled_sphere_checker(planner.checker) else [])


def boxes(robot: RobotModel, count: int) -> Scene:
    """``count`` small boxes on a circle around the root, half-way to the robot's reach (kept by its broad phase)."""
    radius = 0.5 * robot_reach(robot)
    angles = np.linspace(0.0, 2.0 * np.pi, count, endpoint=False) + 0.25 * np.pi
    return Scene([Obstacle(f"warm_up_{k}", "box", size=[BOX] * 3, pose=[radius * np.cos(a), radius * np.sin(a), 0.0])
                  for k, a in enumerate(angles)])  # fmt: skip


def free_pair(planner: MotionPlanner, group: str) -> tuple[dict[str, float], dict[str, float]]:
    """A start (all joints) and a goal of ``group``'s joints a short step away with the straight motion between
    them free (sampled every :data:`EDGE_STEP`), so every warm-up search ends at once; drawn with a fixed seed."""
    robot, rng = planner.robot, np.random.default_rng(SEED)
    names = robot.joint_names
    indices = robot.group_joint_indices(group)
    for _ in range(SAMPLE_TRIES):
        start = robot.random_configuration(rng)
        goal = start.copy()
        goal[indices] += rng.uniform(-STEP, STEP, len(indices))
        goal = np.clip(goal, robot.lower_limits, robot.upper_limits)
        states = np.linspace(start, goal, int(np.ceil(np.abs(goal - start).max() / EDGE_STEP)) + 1)
        if planner.checker.first_invalid(states) < 0:
            return dict(zip(names, map(float, start), strict=True)), {names[i]: float(goal[i]) for i in indices}
    raise errors.InvalidRequest(f"warm-up: no free start and goal of {robot.name} in {SAMPLE_TRIES} samples")


def main(argv: list[str] | None = None) -> int:
    """``python -m maru_planner.planning.warm_up``: fill numba's disk cache, with Maru-1 on both checkers (the
    kernels' argument types are the same for every robot, so any robot's first plan then only loads them) and
    every mobile-base planner."""
    argparse.ArgumentParser(description=__doc__.splitlines()[0]).parse_args(argv)
    robot = RobotModel.maru1()
    for model in COLLISION_MODELS:
        done = warm_up(robot, dataclasses.replace(PlannerConfig(), collision_model=model))
        print(f"[warm-up] {model} checker: {done.summary()}", flush=True)
        if done.error:
            return 1
    from maru_planner.base import registry as base_registry  # lazy: the arm planning nodes never load the base's

    t0 = time.monotonic()
    base_registry.warm_up()  # the mobile-base planners' kernels (base_planner_node warms up the same way)
    print(f"[warm-up] base planners: kernels warmed up in {time.monotonic() - t0:.1f} s", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())

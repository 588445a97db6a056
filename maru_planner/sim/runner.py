"""Glue between a World and the reactive controller: parameters from the robot entry, one seeded run."""

from __future__ import annotations

from typing import Any

from maru_planner.reactive import ElasticStripController, StripParams
from maru_planner.sim.simulator import RunResult, Simulator
from maru_planner.sim.world import World

# Seeded variation of the benchmark runs: start jitter (m, rad) and mover timing (s).
START_JITTER = 0.10
HEADING_JITTER = 0.10
MOVER_JITTER = 0.5


def strip_params_for(world: World, strip: str = "modified", **overrides) -> StripParams:
    """StripParams matching the world's robot: radius (circumradius of a footprint), limits, laser mount."""
    robot = world.robot
    laser = robot.laser
    values: dict[str, Any] = dict(
        strip=strip,
        robot_radius=robot.bounding_radius,
        max_linear=robot.max_linear,
        max_angular=robot.max_angular,
        laser_pose=(laser.x, laser.y, laser.yaw),
    )
    if laser.beams != 361:  # the paper's window (31, 331) is for a 361-beam LMS200 scan
        values["beam_window"] = None
    values.update(overrides)
    return StripParams(**values)


def run_world(
    world: World,
    strip: str = "modified",
    seed: int = 0,
    jitter: bool = True,
    strip_every: int = 0,
    stop_on_collision: bool = True,
    max_time: float | None = None,
    **overrides,
) -> RunResult:
    """One closed-loop run of the elastic strip in ``world``."""
    sim = Simulator(
        world,
        seed=seed,
        start_jitter=START_JITTER if jitter else 0.0,
        heading_jitter=HEADING_JITTER if jitter else 0.0,
        mover_jitter=MOVER_JITTER if jitter else 0.0,
    )
    ctrl = ElasticStripController(strip_params_for(world, strip, **overrides))
    return sim.run(ctrl, max_time=max_time, stop_on_collision=stop_on_collision, strip_every=strip_every)

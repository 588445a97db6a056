"""2-D simulator for the reactive layer: worlds (YAML), diff-drive robot, LMS200 ray caster, movers."""

from maru_planner.sim.simulator import RunResult, Simulator
from maru_planner.sim.world import LaserSpec, Mover, OccupancyMap, RobotSpec, World, WorldError

__all__ = ["LaserSpec", "Mover", "OccupancyMap", "RobotSpec", "RunResult", "Simulator", "World", "WorldError"]

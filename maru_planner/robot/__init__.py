"""Robot model layer: URDF/SRDF loading, FK/Jacobians, IK, example robots."""

from maru_planner.robot.example_robots import load_example_robot
from maru_planner.robot.model import RobotModel

__all__ = ["RobotModel", "load_example_robot"]

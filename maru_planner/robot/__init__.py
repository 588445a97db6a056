"""Robot model layer: URDF/SRDF loading, robot profiles, FK/Jacobians, IK."""

from maru_planner.robot.model import RobotModel, load_example_robot

__all__ = ["RobotModel", "load_example_robot"]

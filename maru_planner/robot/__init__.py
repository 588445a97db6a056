"""Robot model layer: URDF/SRDF loading, robot profiles, FK/Jacobians, IK.

Importing this package registers the robots known by name (:mod:`maru_planner.robot.profiles`), so
``RobotModel.from_profile(name)`` finds them whichever module of the package is imported first.
"""

from maru_planner.robot import profiles  # noqa: F401  (registers the robots known by name)
from maru_planner.robot.model import RobotModel, load_example_robot

__all__ = ["RobotModel", "load_example_robot"]

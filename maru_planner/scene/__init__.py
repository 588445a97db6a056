"""The planning scene: obstacles of the shape table in the robot's root frame, and objects attached to links.

- :mod:`~maru_planner.scene.shapes`: the obstacle types, one table (fields, coal geometry, kernel
  primitive, picture, ROS forms);
- :mod:`~maru_planner.scene.poses`: 4x4 poses from what scenes and requests write;
- :mod:`~maru_planner.scene.obstacle`: :class:`Obstacle` and :class:`AttachedObject`;
- :mod:`~maru_planner.scene.planning_scene`: :class:`Scene`, its YAML schema and validation;
- :mod:`~maru_planner.scene.moveit` and :mod:`~maru_planner.scene.motion_bench_maker`: MoveIt planning
  scenes and requests, and MotionBenchMaker's problem tarball, as these types.

The scene knows nothing of robots: the robot carrying attached objects is
:mod:`maru_planner.robot.attached`.
"""

from maru_planner.scene.obstacle import MAX_NAME_LENGTH, AttachedObject, Obstacle
from maru_planner.scene.planning_scene import MAX_OBSTACLES, BuildClock, Scene
from maru_planner.scene.poses import matrix_rpy, pose_matrix, rpy_matrix

__all__ = [
    "MAX_NAME_LENGTH",
    "MAX_OBSTACLES",
    "AttachedObject",
    "BuildClock",
    "Obstacle",
    "Scene",
    "matrix_rpy",
    "pose_matrix",
    "rpy_matrix",
]

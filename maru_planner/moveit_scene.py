"""Old home of the MoveIt / MotionBenchMaker loaders (re-exported here).

Now :mod:`maru_planner.scene.moveit` (scenes and requests), :mod:`maru_planner.scene.motion_bench_maker`
(the problem tarball) and :mod:`maru_planner.robot.robots.panda` (the Panda those problems use).
"""

from maru_planner.robot.robots.panda import PANDA_FINGERS_OPEN, mbm_panda
from maru_planner.scene.motion_bench_maker import MbmProblem, iter_mbm_problems
from maru_planner.scene.moveit import (
    MoveItRequest,
    pose_from_msg,
    primitive_obstacle,
    quaternion_matrix,
    request_from_moveit,
    robot_root_pose,
    scene_from_moveit,
)

__all__ = [
    "PANDA_FINGERS_OPEN",
    "MbmProblem",
    "MoveItRequest",
    "iter_mbm_problems",
    "mbm_panda",
    "pose_from_msg",
    "primitive_obstacle",
    "quaternion_matrix",
    "request_from_moveit",
    "robot_root_pose",
    "scene_from_moveit",
]

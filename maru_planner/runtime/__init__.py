"""The planning service without ROS (MoveIt's ``move_group`` context is the model): robot loading, a versioned
scene, the robot's latest joint values, admission, worker threads and processes, the kernels' warm-up and
:class:`PlanningRuntime`, whose methods ``planning_node`` calls. No rclpy and no ROS messages here.

- :mod:`~maru_planner.runtime.robot_loading`: :class:`RobotSource` (a profile, or URDF + SRDF) and the files
  made of XML text;
- :mod:`~maru_planner.runtime.scene_store`: :class:`SceneStore` and its edits;
- :mod:`~maru_planner.runtime.robot_state`: :class:`JointStateStore`, joint values by name -> configuration;
- :mod:`~maru_planner.runtime.admission`: :class:`WorkerPool` (threads; BUSY when the expected wait exceeds the
  budget, or beyond ``workers + queue_size``);
- :mod:`~maru_planner.runtime.process_pool`: :class:`ProcessPool` (plans in worker processes);
- :mod:`~maru_planner.runtime.worker_process`: what runs in one of those worker processes;
- :mod:`~maru_planner.runtime.warm_up`: the kernels run once before the first request (``warm_up``, not
  re-exported here: the name is the module's);
- :mod:`~maru_planner.runtime.requests`: what a worker runs (plan, IK, FK, validity, Cartesian path);
- :mod:`~maru_planner.runtime.planning_runtime`: :class:`PlanningRuntime`.
"""

from maru_planner.runtime.admission import WorkerContext, WorkerPool
from maru_planner.runtime.planning_runtime import PlanningRuntime, RuntimeSettings
from maru_planner.runtime.process_pool import ProcessPool
from maru_planner.runtime.requests import IkRequest, ik_timeout
from maru_planner.runtime.robot_loading import DescriptionFiles, RobotDescription, RobotSource, description_source
from maru_planner.runtime.robot_state import JointStateStore, configuration
from maru_planner.runtime.scene_store import (
    AddObstacle,
    AttachObject,
    DetachObject,
    MoveObstacle,
    RemoveObstacle,
    SceneEdit,
    SceneStore,
)

__all__ = [
    "AddObstacle",
    "AttachObject",
    "DescriptionFiles",
    "DetachObject",
    "IkRequest",
    "JointStateStore",
    "MoveObstacle",
    "PlanningRuntime",
    "ProcessPool",
    "RemoveObstacle",
    "RobotDescription",
    "RobotSource",
    "RuntimeSettings",
    "SceneEdit",
    "SceneStore",
    "WorkerContext",
    "WorkerPool",
    "configuration",
    "description_source",
    "ik_timeout",
]

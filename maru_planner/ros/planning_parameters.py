"""``planning_node``'s parameters: its own settings (:class:`NodeSettings`), ``PlannerConfig``'s fields and,
per registered planner, its parameters as ``planners.<ID>.<name>`` (:mod:`maru_planner.planning.registry`).

Each is declared with a descriptor (type, range, description) by :mod:`maru_planner.ros.parameters`.
"""

from __future__ import annotations

import copy
import dataclasses
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from maru_planner import errors
from maru_planner.params import ParamSpec, dataclass_params, param
from maru_planner.planning import PlannerConfig
from maru_planner.planning.config import PLANNER_CONFIG_PARAMS
from maru_planner.planning.registry import PLANNERS
from maru_planner.ros import parameters
from maru_planner.runtime import RuntimeSettings

PLANNER_PREFIX = "planners"
EXECUTE_TRAJECTORY = "maru_planner_interfaces/action/ExecuteTrajectory"
FOLLOW_JOINT_TRAJECTORY = "control_msgs/action/FollowJointTrajectory"


@dataclass
class NodeSettings:
    """The node's own settings (the planner's are ``PlannerConfig``'s); each is a ROS parameter."""

    robot_urdf: str = param("", "URDF file; empty = the package's urdf/maru1_upper_body.urdf", read_only=True)
    robot_srdf: str = param("", "SRDF file; empty = the package's urdf/maru1_upper_body.srdf", read_only=True)
    robot_file: str = param(
        "",
        "robot profile YAML (docs/your_robot.md: URDF, SRDF, groups, limits, IK); set: used instead of robot_urdf, "
        "robot_srdf, robot_description* and package_dirs",
        read_only=True,
    )
    package_dirs: list[str] = param(
        default_factory=list, description="extra directories that resolve package:// mesh URIs", read_only=True
    )
    robot_description: str = param(
        "", "URDF XML as robot_state_publisher takes it; set: used instead of robot_urdf", read_only=True
    )
    robot_description_semantic: str = param(
        "", "SRDF XML (MoveIt's parameter); set: used instead of robot_srdf", read_only=True
    )
    robot_description_source: str = param(
        "parameter",
        "where the URDF comes from: parameter (robot_description if set, else robot_urdf) or topic (the "
        "latched robot_description topic of robot_state_publisher, waited for when configuring)",
        choices=("parameter", "topic"),
        read_only=True,
    )
    robot_description_timeout: float = param(
        10.0, "s configuring waits for the robot_description topic (source topic)", lower=0.1, upper=3600.0
    )
    publish_robot_description: bool = param(
        False,
        "publish the URDF on the latched robot_description topic, for setups without robot_state_publisher",
        read_only=True,
    )
    planning_frame: str = param(
        "base_link", "frame of goal poses, obstacles, trajectories and markers (the URDF root)", read_only=True
    )
    default_group: str = param("upper_body", "planning group used when a request leaves group empty")
    max_planning_time: float = param(
        60.0,
        "largest allowed_planning_time a request may ask for (s); more is INVALID_REQUEST",
        lower=0.01,
        upper=3600.0,
    )
    default_attempts: int = param(1, "num_attempts used when a request gives 0", lower=1, upper=1000)
    ik_timeout: float = param(1.0, "compute_ik budget when the request gives none (s)", lower=0.001, upper=60.0)
    scene_file: str = param(
        "",
        "start-up scene; empty = config/scenes/maru13_desk_box.yaml, none = empty scene; "
        "a relative path is looked up in the working directory, then in the package's config/",
        read_only=True,
    )
    workers: int = param(2, "planning threads, each with its own robot model, checker and planner", lower=1, upper=32)
    worker_processes: bool = param(
        True,
        "each planning thread hands its plans to a worker process (own OMPL, robot model and scene), so "
        "concurrent plans use every core; false: plans run in the threads, whose OMPL searches take turns",
        read_only=True,
    )
    queue_size: int = param(
        200,
        "most requests admitted to wait for a busy worker (a memory bound: beyond workers + queue_size, BUSY); "
        "below it a request is BUSY only when its expected wait exceeds its budget",
        lower=0,
        upper=1024,
    )
    request_queue_depth: int = param(
        256,
        "QoS depth of the service request queues (requests the middleware holds until the node takes them)",
        lower=1,
        upper=100000,
        read_only=True,
    )
    executor_threads: int = param(
        4, "executor threads for callbacks (services never hold one while planning)", lower=2, upper=64, read_only=True
    )
    marker_period: float = param(
        1.0, "how often a new ~/markers subscriber is looked for, to send it the scene (s)", lower=0.01, upper=60.0
    )
    feedback_period: float = param(
        0.1, "seconds between plan_motion action feedback messages (at most 0.2: at least 5 Hz)", lower=0.01, upper=0.2
    )
    execution_action: str = param(
        "execute_trajectory",
        "FollowJointTrajectory-compatible action a plan_motion goal with execute sends its trajectory to "
        "(arm_sim_node's, or e.g. /joint_trajectory_controller/follow_joint_trajectory on a robot)",
    )
    execution_action_type: str = param(
        EXECUTE_TRAJECTORY,
        "the type of execution_action: ours (arm_sim_node) or control_msgs' (ros2_control; needs control_msgs)",
        choices=(EXECUTE_TRAJECTORY, FOLLOW_JOINT_TRAJECTORY),
        read_only=True,
    )
    execution_server_timeout: float = param(
        2.0, "s an execute goal waits for the execution action server before failing", lower=0.0, upper=60.0
    )
    execution_duration_scaling: float = param(
        1.2,
        "an execution without a result after duration x this + execution_duration_margin is cancelled "
        "(MoveIt's allowed_execution_duration_scaling)",
        lower=1.0,
        upper=100.0,
    )
    execution_duration_margin: float = param(
        0.5, "s added to the scaled duration (MoveIt's allowed_goal_duration_margin)", lower=0.0, upper=600.0
    )
    view: bool = param(
        False, "serve the live scene, start state and plans to a browser (maru_planner/ros/plan_view_bridge.py)",
        read_only=True,
    )  # fmt: skip
    view_host: str = param("127.0.0.1", "address the view is served on (another than this machine's only by choice)",
                           read_only=True)  # fmt: skip
    view_port: int = param(8080, "the view's port (the next free one if taken; 0: any)", lower=0, upper=65535,
                           read_only=True)  # fmt: skip


NODE_PARAMS: dict[str, ParamSpec] = dataclass_params(NodeSettings)


def parameter_specs() -> dict[str, ParamSpec]:
    """Every parameter of the node: its settings, ``PlannerConfig``'s, ``planners.<ID>.<name>`` per planner."""
    specs = {**NODE_PARAMS, **PLANNER_CONFIG_PARAMS}
    specs["default_planner"] = dataclasses.replace(specs["default_planner"], choices=tuple(PLANNERS))
    for planner_id, planner in PLANNERS.items():
        specs.update(parameters.prefixed(planner.params, f"{PLANNER_PREFIX}.{planner_id}"))
    return specs


def planner_config(values: dict[str, Any], base: PlannerConfig | None = None) -> PlannerConfig:
    """``base`` (else the defaults) with the config fields and ``planners.<ID>.<name>`` found in ``values``."""
    base = base or PlannerConfig()
    fields = {name: value for name, value in values.items() if name in PLANNER_CONFIG_PARAMS}
    planner_params = copy.deepcopy(base.planner_params)
    for name, value in values.items():
        if name.startswith(PLANNER_PREFIX + "."):
            _, planner_id, key = name.split(".", 2)
            planner_params.setdefault(planner_id, {})[key] = value
    return dataclasses.replace(base, **fields, planner_params=planner_params)


def node_settings(values: dict[str, Any]) -> NodeSettings:
    """The node's settings among the parameter ``values``."""
    return NodeSettings(**{name: values[name] for name in NODE_PARAMS})


def runtime_settings(settings: NodeSettings) -> RuntimeSettings:
    """What the planning runtime takes of the node's settings."""
    return RuntimeSettings(settings.default_group, settings.workers, settings.worker_processes, settings.queue_size)


def checked_config(build: Callable[[], PlannerConfig]) -> PlannerConfig:
    """``build()``; a value PlannerConfig refuses becomes InvalidParameter (naming it)."""
    try:
        return build()
    except ValueError as exc:
        raise errors.InvalidParameter(str(exc)) from None

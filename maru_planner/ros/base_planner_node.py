"""base_planner_node: mobile-base grid planning (paper 002's MSPP and friends) on /map.

- subscribes ``map`` (nav_msgs/OccupancyGrid, transient local, reliable: a
  map_server latches it);
- serves ``plan_base_path`` (maru_planner_interfaces/PlanBasePath: planner
  id, footprint, start, goal -> Path, Nav2-style error code + message, stats)
  and ``make_plan`` (nav_msgs/GetPlan, the standard service: empty path on
  failure, the reason in the log);
- offers ``plan_base_path`` also as an action (maru_planner_interfaces/action/PlanBasePath: the
  service's request as goal, its response as result; feedback every 0.1 s: stage, elapsed,
  expansions; a cancel stops the search at its next deadline check, the goal ends CANCELED);
- publishes the last path on ``plan`` (nav_msgs/Path) and, only while someone
  subscribes, the grown maps on ``~/eca_map``, ``~/baa_map`` and
  ``~/grown_map`` (nav_msgs/OccupancyGrid);
- publishes the cost map on ``~/costmap`` (nav_msgs/OccupancyGrid, latched, Nav2's 0-100 scaling): Nav2's
  inflation layer of the map for the ``footprint`` parameter, ``inflation_radius`` and
  ``cost_scaling_factor``, again whenever the map or one of those changes.

Parameters: the fields of :class:`BaseNodeConfig` (descriptors with ranges; ``config/base_planner.yaml``),
and per grid planner ``<planner_id>.cost_travel_multiplier``, ``.smooth`` and ``.min_turning_radius``
(Nav2 style: the planner's own parameters under its name). ``inflation_radius`` and
``cost_scaling_factor`` go to every planner that has them.
Run-time changes apply to the next request (``unknown_is_occupied`` and ``occupied_threshold``
re-read the last map); a bad value is rejected with the reason. Any planner of
``maru_planner.base.registry`` is served; it gets the ``headings`` and ``biped_world`` parameters
only when its capabilities ask for them. Poses are in the map frame (an empty frame_id is taken
as the map's).

Plans run one at a time, in arrival order, on a planning thread (a search may take the whole 2 GB
search budget, and the built planners with their footprint caches are shared); the service and
action callbacks await them, so the executor keeps taking maps, feedback timers and cancel requests
while a plan runs.
"""

from __future__ import annotations

import dataclasses
import math
import sys
from concurrent.futures import ThreadPoolExecutor
from typing import Any

import numpy as np
from nav_msgs.msg import OccupancyGrid as OccupancyGridMsg
from nav_msgs.msg import Path
from nav_msgs.srv import GetPlan
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rclpy.task import Future

from maru_planner.base import registry
from maru_planner.base.biped.planners import resolve_world_path
from maru_planner.base.biped.world import load_world
from maru_planner.base.budget import Deadline
from maru_planner.base.costmap import NAV2_COST_SCALING_FACTOR, NAV2_INFLATION_RADIUS, check_inflation, cost_layer
from maru_planner.base.footprint import as_polygon, footprint_radii
from maru_planner.base.grid import OccupancyGrid
from maru_planner.base.planner import BasePlanner
from maru_planner.base.result import BasePlanResult
from maru_planner.errors import InvalidRequest, MaruError
from maru_planner.monitor import PlanMonitor, Progress
from maru_planner.params import ParamSpec, dataclass_params, param
from maru_planner.ros import base_conversions as conv
from maru_planner.ros import parameters
from maru_planner.ros.lifecycle import ManagedNode, run_node
from maru_planner.ros.plan_actions import PlanActionServer
from maru_planner_interfaces.action import PlanBasePath as PlanBasePathAction
from maru_planner_interfaces.srv import PlanBasePath

E = PlanBasePath.Response
_PLANNER_CACHE_SIZE = 16  # built planners kept (their rasterised footprints survive between requests)
FEEDBACK_PERIOD = 0.1  # s between plan_base_path action feedback messages (10 Hz)


@dataclasses.dataclass
class BaseNodeConfig:
    """base_planner_node's parameters."""

    planner_id: str = param("mspp", "planner used when a request names none (a base registry id)")
    footprint: list = param(
        default_factory=lambda: [0.45, 0.15, -0.45, 0.15, -0.45, -0.15, 0.45, -0.15],
        description="robot footprint in base_link, flat x, y list (m), used when a request gives none",
    )
    headings: int = param(32, "SE(2) heading discretisation for planners that need headings", lower=1, upper=3600)
    allowed_planning_time: float = param(10.0, "planning budget (s) when a request gives 0", lower=1e-3, upper=3600.0)
    unknown_is_occupied: bool = param(True, "unknown (-1) map cells block the robot")
    occupied_threshold: int = param(65, "map values >= this are obstacles", lower=1, upper=100)
    map_topic: str = param("map", "nav_msgs/OccupancyGrid topic (transient local)", read_only=True)
    biped_world: str = param("", "3-D world YAML for world_3d planners (biped_*); empty = plan on the map")
    inflation_radius: float = param(
        NAV2_INFLATION_RADIUS, "m: Nav2 inflation layer's radius (cost map and planners)", lower=0.0, upper=100.0
    )
    cost_scaling_factor: float = param(
        NAV2_COST_SCALING_FACTOR, "1/m: decay rate of the inflation cost (Nav2)", lower=0.0, upper=1e6
    )


NODE_SPECS = dataclass_params(BaseNodeConfig)
COSTMAP_PARAMS = ("inflation_radius", "cost_scaling_factor")
PLANNER_COST_PARAMS = ("cost_travel_multiplier", "smooth", "min_turning_radius")


def planner_cost_specs() -> dict[str, ParamSpec]:
    """``<planner_id>.<name>`` for each registered planner's own cost parameters (defaults: the planner's)."""
    specs: dict[str, ParamSpec] = {}
    for planner_id in registry.planner_ids():
        own = registry.spec(planner_id).params
        specs.update(parameters.prefixed({n: own[n] for n in PLANNER_COST_PARAMS if n in own}, planner_id))
    return specs


def check_config(config: BaseNodeConfig) -> None:
    """InvalidRequest naming the parameter when the values cannot serve requests."""
    registry.spec(config.planner_id)
    try:
        polygon = as_polygon(conv.footprint_from_param(config.footprint))
    except (MaruError, ValueError) as exc:
        raise InvalidRequest(f"parameter 'footprint': {exc}") from None
    check_inflation(config.inflation_radius, config.cost_scaling_factor, footprint_radii(polygon)[0])
    if config.biped_world:
        load_world(resolve_world_path(config.biped_world))


class BasePlannerNode(ManagedNode):
    """A managed node (:mod:`maru_planner.ros.lifecycle`): the map is followed from configure on, plans
    are served while active."""

    def __init__(self, **kwargs: Any):
        """InvalidParameter (one line) for a bad parameter; with ``autostart`` what configuring raises."""
        super().__init__("base_planner_node", **kwargs)
        self.specs = {**NODE_SPECS, **planner_cost_specs()}
        values = parameters.declare_parameters(self, self.specs)
        self.config = BaseNodeConfig(**{k: v for k, v in values.items() if k in NODE_SPECS})
        self.planner_costs = {k: v for k, v in values.items() if k not in NODE_SPECS}
        self.grid: OccupancyGrid | None = None
        self.map_msg: OccupancyGridMsg | None = None
        self.map_error = "not configured"
        self.planners: dict[tuple, BasePlanner] = {}
        self.requests = 0
        self._plan_action: PlanActionServer | None = None
        parameters.add_on_set_parameters_callback(self, self.specs, self.when_configured(self.apply_parameters))
        self.start()

    def configure(self) -> None:
        """Check the parameters, warm the planners up, follow the map, offer the services."""
        values = parameters.read_parameters(self, self.specs)
        self.config = BaseNodeConfig(**{k: v for k, v in values.items() if k in NODE_SPECS})
        self.planner_costs = {k: v for k, v in values.items() if k not in NODE_SPECS}
        check_config(self.config)
        registry.warm_up()
        self.map_error = "no map received yet on " + self.config.map_topic
        latched = QoSProfile(
            depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL, reliability=ReliabilityPolicy.RELIABLE
        )
        self.create_subscription(OccupancyGridMsg, self.config.map_topic, self._on_map, latched)
        self.path_pub = self.create_lifecycle_publisher(Path, "plan", latched)
        self.layer_pubs = {
            name: self.create_lifecycle_publisher(OccupancyGridMsg, f"~/{name}_map", latched)
            for name in ("eca", "baa", "grown")
        }
        self.costmap_pub = self.create_lifecycle_publisher(OccupancyGridMsg, "~/costmap", latched)
        self._planning = ThreadPoolExecutor(max_workers=1, thread_name_prefix="base_planner")
        callbacks = ReentrantCallbackGroup()  # a callback awaiting its plan must not block the others
        self.create_managed_service(PlanBasePath, "plan_base_path", self._on_plan_base_path, callback_group=callbacks)
        self.create_managed_service(GetPlan, "make_plan", self._on_get_plan, callback_group=callbacks)
        self._plan_action = PlanActionServer(
            self,
            PlanBasePathAction,
            "plan_base_path",
            plan=lambda goal, monitor: self._answer_plan(goal, PlanBasePathAction.Result(), monitor),
            succeeded=lambda result: result.error_code == E.NONE,
            feedback=_feedback_msg,
            period=lambda: FEEDBACK_PERIOD,
            callback_group=callbacks,
        )
        self.get_logger().info(
            f"base planner ready (default planner {self.config.planner_id!r}, planners {registry.planner_ids()})"
        )

    def activate(self) -> None:
        self._schedule_costmap()  # what was computed while inactive was not sent

    def cleanup(self) -> None:
        self._planning.shutdown(wait=False, cancel_futures=True)  # a running plan ends at its deadline
        self.grid, self.map_msg = None, None
        self.map_error = "not configured"
        self.planners.clear()

    def requests_in_progress(self) -> int:
        goals = self._plan_action.running_goals if self._plan_action is not None else 0
        return super().requests_in_progress() + goals

    # ------------------------------------------------------------- parameters
    def apply_parameters(self, changes: dict[str, Any]) -> None:
        """Check the changed configuration as a whole, then use it (raises to reject with the reason)."""
        config = dataclasses.replace(self.config, **{k: v for k, v in changes.items() if k in NODE_SPECS})
        check_config(config)
        self.config = config
        self.planner_costs.update({k: v for k, v in changes.items() if k not in NODE_SPECS})
        self.planners.clear()
        if self.map_msg is not None and {"unknown_is_occupied", "occupied_threshold"} & set(changes):
            self._on_map(self.map_msg)
        elif {"footprint", *COSTMAP_PARAMS} & set(changes):
            self._schedule_costmap()

    # ---------------------------------------------------------------- cost map
    def _schedule_costmap(self) -> None:
        """Compute and publish the cost map of the current map on the planning thread (after queued plans)."""
        if self.grid is not None:
            self._planning.submit(self._publish_costmap, self.grid, self.config)

    def _publish_costmap(self, grid: OccupancyGrid, config: BaseNodeConfig) -> None:
        try:
            inscribed, circumscribed = footprint_radii(conv.footprint_from_param(config.footprint))
            layer = cost_layer(
                grid,
                inscribed,
                circumscribed,
                config.inflation_radius,
                config.cost_scaling_factor,
                Deadline(max(config.allowed_planning_time, 1.0)),
            )
        except MaruError as exc:
            self.get_logger().warning(f"cost map not published: {exc}")
            return
        self.costmap_pub.publish(conv.costmap_to_msg(grid, layer, self.get_clock().now().to_msg(), grid.frame_id))

    # -------------------------------------------------------------------- map
    def _on_map(self, msg: OccupancyGridMsg) -> None:
        try:
            self.grid = conv.grid_from_msg(
                msg,
                occupied_threshold=self.config.occupied_threshold,
                unknown_is_occupied=self.config.unknown_is_occupied,
            )
            self.map_msg = msg
            self.map_error = ""
            self.get_logger().info(f"map {self.grid.width} x {self.grid.height} cells of {self.grid.resolution} m")
            self._schedule_costmap()
        except (MaruError, ValueError) as exc:
            self.grid, self.map_msg = None, None
            self.map_error = f"the last map was rejected: {exc}"
            self.get_logger().warning(self.map_error)

    # --------------------------------------------------------------- planning
    def plan(
        self,
        planner_id: str,
        footprint: np.ndarray,
        start_msg,
        goal_msg,
        time_limit: float,
        monitor: PlanMonitor | None = None,
    ):
        """Returns (error_code, message, result or None, nav_msgs/Path of the result, empty on failure).

        ``monitor`` watches and cancels the plan (the action's goals).
        """
        self.requests += 1
        grid = self.grid  # the map of this request, whatever arrives meanwhile
        if grid is None:
            return E.NO_MAP, f"no map: {self.map_error}", None, _empty_path("map")
        try:
            self._check_request(grid, start_msg, goal_msg, time_limit)
            planner = self._planner(planner_id or self.config.planner_id, footprint)
            result = planner.plan(
                grid,
                conv.pose_from_msg(start_msg),
                conv.pose_from_msg(goal_msg),
                time_limit=time_limit or self.config.allowed_planning_time,
                monitor=monitor,
            )
        except MaruError as exc:
            return conv.error_code(exc), str(exc), None, _empty_path(grid.frame_id)
        return conv.STATUS_TO_ERROR[result.status], result.message, result, self._publish(result, grid)

    def _check_request(self, grid: OccupancyGrid, start_msg, goal_msg, time_limit: float) -> None:
        for name, pose in (("start", start_msg), ("goal", goal_msg)):
            frame = pose.header.frame_id
            if frame and frame != grid.frame_id:
                raise InvalidRequest(
                    f"{name} is in frame {frame[:40]!r}; poses must be in the map frame {grid.frame_id!r}"
                )
        if not (math.isfinite(time_limit) and 0 <= time_limit <= 3600):
            raise InvalidRequest(f"allowed_planning_time must be in [0, 3600] s, got {time_limit}")

    def _planner(self, planner_id: str, footprint: np.ndarray) -> BasePlanner:
        """The planner for this request, built from the registry (kept for later requests)."""
        spec = registry.spec(planner_id)
        if len(footprint) == 0:
            footprint = conv.footprint_from_param(self.config.footprint)
        params: dict[str, Any] = {}
        if spec.has(registry.NEEDS_HEADINGS):
            params["headings"] = self.config.headings
        if spec.has(registry.WORLD_3D) and self.config.biped_world:
            params["world"] = self.config.biped_world
        for name in COSTMAP_PARAMS:
            if name in spec.params:
                params[name] = getattr(self.config, name)
        prefix = f"{spec.id}."
        params.update({k[len(prefix) :]: v for k, v in self.planner_costs.items() if k.startswith(prefix)})
        key = (spec.id, np.asarray(footprint, dtype=float).tobytes(), tuple(sorted(params.items())))
        if key not in self.planners:
            if len(self.planners) >= _PLANNER_CACHE_SIZE:
                self.planners.clear()
            self.planners[key] = registry.make_planner(spec.id, footprint, **params)
        return self.planners[key]

    def _publish(self, result: BasePlanResult, grid: OccupancyGrid) -> Path:
        """Publish the path (when solved) and the watched layers; returns the path message for the response."""
        stamp = self.get_clock().now().to_msg()
        frame = grid.frame_id
        path_msg = conv.path_to_msg(result.path, stamp, frame)
        if result.success:
            self.path_pub.publish(path_msg)
        for name, pub in self.layer_pubs.items():
            layer = result.layers.get(name)
            if layer is not None and pub.get_subscription_count() > 0:
                pub.publish(conv.grid_to_msg(grid, layer, stamp, frame))
        return path_msg

    def _in_planning_thread(self, fn, *args) -> Future:
        """Run ``fn(*args)`` on the planning thread (one plan at a time); an rclpy Future a callback can await."""
        future = Future(executor=self.executor)

        def job() -> None:
            try:
                future.set_result(fn(*args))
            except BaseException as exc:  # noqa: BLE001 - handed to the awaiting callback
                future.set_exception(exc)
            finally:
                if self.executor is not None:
                    self.executor.wake()

        self._planning.submit(job)
        return future

    async def _on_plan_base_path(self, request, response):
        return await self._answer_plan(request, response)

    async def _answer_plan(self, request, response, monitor: PlanMonitor | None = None):
        """Plan ``request`` (a service request or action goal) and fill ``response`` (its response or result)."""
        code, message, result, path_msg = await self._in_planning_thread(
            self.plan,
            request.planner_id,
            conv.footprint_from_points(request.footprint),
            request.start,
            request.goal,
            request.allowed_planning_time,
            monitor,
        )
        response.error_code, response.error_msg, response.path = code, message, path_msg
        if result is not None:
            stats = result.stats
            response.deciding_stage = stats.deciding_stage
            response.planning_time = float(stats.planning_time)
            response.expansions = int(stats.expansions)
            response.collision_checks = int(stats.collision_checks)
            response.stats_json = conv.stats_json(stats)
        self._log_outcome("plan_base_path", code, message)
        return response

    async def _on_get_plan(self, request, response):
        code, message, _, path_msg = await self._in_planning_thread(
            self.plan, "", np.zeros((0, 2)), request.start, request.goal, 0.0
        )
        response.plan = path_msg  # empty on failure
        self._log_outcome("make_plan", code, message)
        return response

    def _log_outcome(self, service: str, code: int, message: str) -> None:
        if code == E.NONE:
            self.get_logger().info(f"{service}: {message}")
        else:
            self.get_logger().warning(f"{service}: error {code}: {message}")


def _empty_path(frame_id: str) -> Path:
    msg = Path()
    msg.header.frame_id = frame_id
    return msg


def _feedback_msg(progress: Progress) -> PlanBasePathAction.Feedback:
    return PlanBasePathAction.Feedback(
        stage=progress.stage, elapsed=float(progress.elapsed), expansions=int(progress.info.get("expansions", 0))
    )


def main(args: list[str] | None = None) -> int:
    """Entry point of ``ros2 run maru_planner base_planner_node``; exit code 2 on bad start-up input."""
    return run_node("base_planner_node", BasePlannerNode, args,
                    farewell=lambda node: f"served {node.requests} requests")  # fmt: skip


if __name__ == "__main__":
    sys.exit(main())

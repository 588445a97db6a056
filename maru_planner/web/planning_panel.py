"""The side panel that sets up a plan: group, planner, its parameters (one control per registry
:class:`~maru_planner.params.ParamSpec`, ranged and described), time budget, and a draggable goal per end effector.

Nothing here plans: :meth:`PlanningPanel.request_parts` reads the controls, the server turns them into a request.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import viser

from maru_planner import errors
from maru_planner.params import ParamSpec
from maru_planner.planning.planners.registry import PLANNERS, get_spec
from maru_planner.robot import RobotModel
from maru_planner.web.robot_view import pose_of, wxyz_position

GOAL_ROOT = "/goals"
#: the group planned by default per robot profile; other robots: their first group
DEFAULT_GROUPS = {"maru1": "upper_body", "panda": "arm", "ur5": "manipulator", "tiago": "arm_torso", "talos": "r_arm"}
Control = Any  # a viser GUI input handle (number, checkbox, dropdown, text)


def param_control(gui: viser.GuiApi, spec: ParamSpec) -> Control:
    """An input for ``spec``: a checkbox, a dropdown of its choices, a ranged number, or a text (unset: empty)."""
    hint = spec.describe() or None
    kind = spec.value_type
    if kind is bool:
        return gui.add_checkbox(spec.name, bool(spec.default), hint=hint)
    if spec.choices:
        return gui.add_dropdown(spec.name, spec.choices, initial_value=str(spec.default), hint=hint)
    if kind in (int, float) and spec.default is not None:
        step = 1 if kind is int else 0.001
        return gui.add_number(spec.name, spec.default, min=spec.lower, max=spec.upper, step=step, hint=hint)
    return gui.add_text(spec.name, "" if spec.default is None else str(spec.default), hint=hint)


def control_value(spec: ParamSpec, control: Control) -> Any:
    """The control's value in ``spec``'s type (an empty text: None); InvalidRequest naming the parameter."""
    value = control.value
    if isinstance(value, str) and spec.value_type is not str:
        if not value.strip():
            return None
        try:
            value = spec.value_type(value)
        except ValueError:
            raise errors.InvalidRequest(f"parameter {spec.name!r} must be a {spec.value_type.__name__}") from None
    return spec.check(value)


def default_group(robot: RobotModel) -> str:
    group = DEFAULT_GROUPS.get(robot.name, "")
    return group if group in robot.groups else next(iter(robot.groups))


def moved_by(robot: RobotModel, frame: str) -> set[str]:
    """The joints whose motion moves ``frame``."""
    model = robot.model
    joint, names = model.frames[robot.frame_id(frame)].parentJoint, set()
    while joint > 0:
        names.add(model.names[joint])
        joint = model.parents[joint]
    return names


class PlanningPanel:
    """Controls of the next plan and the goal gizmos (module doc); ``on_plan`` runs when "Plan" is pressed."""

    def __init__(self, server: viser.ViserServer, robot: RobotModel, on_plan: Callable[[], None]):
        self.robot = robot
        gui = server.gui
        self._shown = True
        with gui.add_folder("Planning") as self.folder:
            self.group = gui.add_dropdown("group", tuple(robot.groups), initial_value=default_group(robot))
            self.planner = gui.add_dropdown("planner", tuple(PLANNERS), initial_value="CompiledRRTConnect")
            self.budget = gui.add_number("time budget (s)", 2.0, min=0.1, max=60.0, step=0.1)
            self.plan_button = gui.add_button("Plan", disabled=True, hint="IK to the goals, plan, play the trajectory")
            self.message = gui.add_markdown("loading the planner ...")
        # one planner's parameter folder at a time, made when it is first chosen: fewer controls for a new page
        self._gui = gui
        self.params: dict[str, dict[str, Control]] = {}
        self._folders: dict[str, viser.GuiFolderHandle] = {}
        self._show_params()
        self.planner.on_update(lambda _: self._show_params())
        self.plan_button.on_click(lambda _: on_plan())
        self.goals = {
            ee: server.scene.add_transform_controls(f"{GOAL_ROOT}/{ee}", scale=0.2, line_width=2.0)
            for ee in robot.end_effectors
        }

    def _show_params(self) -> None:
        chosen = self.planner.value
        if chosen not in self._folders:
            order = next(iter(self._folders.values())).order if self._folders else None  # where the first one is
            with self._gui.add_folder(f"{chosen} parameters", order=order, expand_by_default=False) as folder:
                self._folders[chosen] = folder
                self.params[chosen] = {name: param_control(self._gui, p) for name, p in get_spec(chosen).params.items()}
        for planner_id, folder in self._folders.items():
            folder.visible = self._shown and planner_id == chosen

    def set_shown(self, shown: bool) -> None:
        """Show or hide the panel and the goal gizmos."""
        self._shown = shown
        self.folder.visible = shown
        self._show_params()
        for handle in self.goals.values():
            handle.visible = shown

    def planner_params(self) -> dict[str, Any]:
        """The chosen planner's parameters that differ from the registry defaults."""
        planner_id = self.planner.value
        specs = get_spec(planner_id).params
        self._show_params()  # its controls exist (a chosen planner's are made by the dropdown's callback)
        values = {name: control_value(specs[name], c) for name, c in self.params[planner_id].items()}
        return {name: v for name, v in values.items() if v != specs[name].default}

    def place_goals(self, q: np.ndarray) -> None:
        """Put every goal gizmo on its end effector at configuration ``q``."""
        for ee, handle in self.goals.items():
            wxyz, position = wxyz_position(self.robot.frame_pose(q, self.robot.end_effectors[ee]))
            handle.wxyz, handle.position = wxyz, position

    def set_goal(self, ee: str, pose: np.ndarray) -> None:
        """Move goal ``ee`` to the 4x4 ``pose`` (what a drag does)."""
        if ee not in self.goals:
            raise errors.InvalidRequest(f"unknown end effector {ee!r}; known: {', '.join(self.goals)}")
        wxyz, position = wxyz_position(pose)
        self.goals[ee].wxyz, self.goals[ee].position = wxyz, position

    def goal_poses(self) -> dict[str, np.ndarray]:
        """{end-effector frame: 4x4 goal} for the end effectors the chosen group moves."""
        joints = set(self.robot.groups[self.group.value])
        poses = {}
        for ee, handle in self.goals.items():
            frame = self.robot.end_effectors[ee]
            if moved_by(self.robot, frame) & joints:
                poses[frame] = pose_of(handle.wxyz, handle.position)
        if not poses:
            raise errors.InvalidGroup(f"group {self.group.value!r} moves none of the end effectors {list(self.goals)}")
        return poses

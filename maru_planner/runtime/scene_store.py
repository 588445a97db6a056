"""The planning runtime's scene: one current :class:`Scene` and its version, changed all-or-nothing.

Edits are plain values (:data:`SceneEdit`): add, move and remove obstacles, attach an object to a link of the
robot (a scene obstacle where it is, or a new shape) and detach it. :meth:`SceneStore.apply` applies a sequence
of them to a copy of the scene and keeps the copy only when every edit and the final check of the attached
objects succeeded; each kept change increments :attr:`SceneStore.version`, which the planning workers compare
against to bring their own scene up to date.
"""

from __future__ import annotations

import copy
import threading
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from maru_planner import errors
from maru_planner.paths import config_path
from maru_planner.planning.queries import compute_fk
from maru_planner.robot import RobotModel
from maru_planner.robot.attached import check_attachments
from maru_planner.runtime.robot_state import configuration
from maru_planner.scene import Obstacle, Scene

DEFAULT_SCENE = "scenes/maru13_desk_box.yaml"


@dataclass(frozen=True)
class AddObstacle:
    """Add ``obstacle`` (or replace the one of its name)."""

    obstacle: Obstacle


@dataclass(frozen=True)
class MoveObstacle:
    """Give obstacle ``name`` the 4x4 ``pose`` (planning frame)."""

    name: str
    pose: np.ndarray


@dataclass(frozen=True)
class RemoveObstacle:
    name: str


@dataclass(frozen=True)
class AttachObject:
    """Fix object ``name`` to ``link``, the link placed at the joint values ``robot_state`` (empty: the latest).

    ``shape`` None attaches the scene obstacle ``name`` where it is; else ``shape()`` gives a new object (a
    :meth:`Obstacle.from_dict` dict, its pose in the planning frame). It is called once the link is placed, so a
    request that is wrong in both ways is refused for its link or state first.
    """

    name: str
    link: str
    robot_state: dict[str, float] = field(default_factory=dict)
    touch_links: tuple[str, ...] = ()
    shape: Callable[[], dict[str, Any]] | None = None


@dataclass(frozen=True)
class DetachObject:
    """Put attached object ``name`` back into the scene, its link placed at ``robot_state`` (empty: the latest)."""

    name: str
    robot_state: dict[str, float] = field(default_factory=dict)


SceneEdit = AddObstacle | MoveObstacle | RemoveObstacle | AttachObject | DetachObject
LinkPose = Callable[[str, dict[str, float]], np.ndarray]  # (link, joint values) -> 4x4 pose in the planning frame


class Attachments:
    """What attach/detach edits need from the robot: link poses, and a check of the attached objects' links.

    ``latest`` returns the latest reported joint values (used when an edit's ``robot_state`` is empty).
    Thread-safe: every pose comes from its own Pinocchio data.
    """

    def __init__(self, robot: RobotModel, latest: Callable[[], dict[str, float]]):
        self.robot, self.latest = robot, latest

    def link_pose(self, link: str, values: dict[str, float]) -> np.ndarray:
        if not values:
            values = self.latest()
            if not values:
                raise errors.NoStartState("robot_state is empty and no /joint_states message has been received")
        return compute_fk(self.robot, configuration(self.robot, values), [link])[link]

    def check(self, scene: Scene) -> None:
        """InvalidLink / ObjectAlreadyAttached for attached objects the robot cannot carry."""
        check_attachments(self.robot, scene)


def apply_edit(scene: Scene, edit: SceneEdit, link_pose: LinkPose) -> None:
    """Apply one edit to ``scene`` (raises the scene's typed errors, naming the object); ``link_pose`` places
    the links of attach/detach edits (:meth:`Attachments.link_pose`)."""
    if isinstance(edit, AddObstacle):
        scene.add(edit.obstacle)
    elif isinstance(edit, MoveObstacle):
        scene.move(edit.name, edit.pose)
    elif isinstance(edit, RemoveObstacle):
        scene.remove(edit.name)
    elif isinstance(edit, DetachObject):
        if edit.name not in scene.attached:
            raise errors.InvalidObject(f"object '{edit.name}': not attached (attached: {list(scene.attached)})")
        scene.detach(edit.name, link_pose(scene.attached[edit.name].link, edit.robot_state))
    elif isinstance(edit, AttachObject):
        _attach(scene, edit, link_pose)
    else:
        raise errors.InvalidScene(f"not a scene edit: {type(edit).__name__}")


def _attach(scene: Scene, edit: AttachObject, link_pose: LinkPose) -> None:
    here = link_pose(edit.link, edit.robot_state)
    touch_links = list(edit.touch_links)
    if edit.shape is None:
        scene.attach(edit.name, edit.link, here, touch_links=touch_links)
        return
    shape = edit.shape()
    local = np.linalg.inv(here) @ np.asarray(shape.pop("pose"))
    obstacle = Obstacle.from_dict({**shape, "pose": local})
    scene.attach(edit.name, edit.link, touch_links=touch_links, obstacle=obstacle)


class SceneStore:
    """The current scene and its version, changed atomically; readers get copies."""

    def __init__(self, scene_dict: dict):
        self._lock = threading.Lock()
        self._scene = Scene.from_dict(scene_dict)
        self.version = 0

    def snapshot(self) -> tuple[dict, int]:
        """(a copy of the scene as :meth:`Scene.to_dict`, its version)."""
        with self._lock:
            return copy.deepcopy(self._scene.to_dict()), self.version

    def obstacle_names(self) -> list[str]:
        return [o["name"] for o in self.snapshot()[0].get("obstacles", [])]

    def apply(self, edits: Iterable[SceneEdit], clear: bool, attachments: Attachments) -> list[str]:
        """Apply ``edits`` in order (after an optional clear) all-or-nothing; the obstacle names after them.

        ``edits`` is consumed under the store's lock, one at a time: a lazy sequence (a generator converting
        messages) raises its own errors in the order of the edits.
        """
        with self._lock:
            scene = Scene.from_dict(copy.deepcopy(self._scene.to_dict()))
            if clear:
                scene.clear()
            for edit in edits:
                apply_edit(scene, edit, attachments.link_pose)
            attachments.check(scene)
            self._scene = scene
            self.version += 1
            return [o["name"] for o in scene.to_dict().get("obstacles", [])]

    def replace(self, scene_dict: dict, attachments: Attachments) -> int:
        """Make ``scene_dict`` the scene (InvalidScene etc. if it is malformed, nothing changed); its version."""
        scene = Scene.from_dict(copy.deepcopy(scene_dict))
        attachments.check(scene)
        with self._lock:
            self._scene = scene
            self.version += 1
            return self.version


def load_scene_dict(scene_file: str) -> dict:
    """The scene of ``scene_file``: empty = the package's desk + box scene, ``none`` = an empty scene; a relative
    path is looked up in the working directory, then in the package's config/."""
    if scene_file.lower() == "none":
        return Scene().to_dict()
    path = Path(scene_file) if scene_file else config_path(DEFAULT_SCENE)
    if not path.is_absolute() and not path.is_file():
        path = config_path(scene_file)  # e.g. "scenes/maru6_desk.yaml" from the package's config/
    return Scene.from_yaml(path).to_dict()

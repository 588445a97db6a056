"""Scene editing in the browser: add a box, sphere or cylinder, move one (a gizmo), remove it, attach it to a link
or detach it, and save the scene as YAML.

The controls build runtime scene edits (:data:`~maru_planner.runtime.SceneEdit`) and hand them to ``apply``
(the server applies them all-or-nothing to the planning runtime's scene and redraws); the same methods
(:meth:`SceneEditor.add`, :meth:`move`, :meth:`remove`, :meth:`attach`, :meth:`detach`, :meth:`save`) are the
editor's programmatic API.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin
import viser

from maru_planner import errors
from maru_planner.robot import RobotModel
from maru_planner.runtime import AddObstacle, AttachObject, DetachObject, MoveObstacle, RemoveObstacle, SceneEdit
from maru_planner.scene import Obstacle, Scene
from maru_planner.web.robot_view import pose_of, wxyz_position

EDITABLE_SHAPES = ("box", "sphere", "cylinder")
NEW_POSITION = (0.5, 0.0, 0.5)  # m: where a new obstacle appears (in front of most robots, at table height)
NONE = "(none)"
Apply = Callable[[Sequence[SceneEdit]], None]  # applies edits all-or-nothing; raises a MaruError to refuse


def new_obstacle(name: str, shape: str, size: Sequence[float], radius: float, length: float) -> Obstacle:
    """A ``shape`` obstacle called ``name`` at :data:`NEW_POSITION` (InvalidScene naming a bad field)."""
    if shape not in EDITABLE_SHAPES:
        raise errors.InvalidScene(
            f"obstacle {name!r}: shape must be one of {', '.join(EDITABLE_SHAPES)}, got {shape!r}"
        )
    dimensions: dict[str, Any] = {"size": tuple(size)} if shape == "box" else {"radius": radius}
    if shape == "cylinder":
        dimensions["length"] = length
    return Obstacle(name, shape, list(NEW_POSITION), **dimensions)


def body_links(robot: RobotModel) -> list[str]:
    """The robot's link names (body frames), root first."""
    return [f.name for f in robot.model.frames if f.type == pin.FrameType.BODY]


class SceneEditor:
    """The "Scene" folder (module doc); ``current`` returns the scene dict, ``state`` the shown joint values."""

    def __init__(
        self,
        server: viser.ViserServer,
        robot: RobotModel,
        apply: Apply,
        current: Callable[[], dict],
        state: Callable[[], dict[str, float]],
    ):
        self._server, self._apply, self._current, self._state = server, apply, current, state
        gui = server.gui
        with gui.add_folder("Scene", expand_by_default=False) as self.folder:
            self.shape = gui.add_dropdown("shape", EDITABLE_SHAPES, initial_value="box")
            self.name = gui.add_text("name", "box1")
            self.size = gui.add_vector3("size (m)", (0.1, 0.1, 0.1), min=(1e-3,) * 3, max=(5.0,) * 3, step=0.01)
            self.radius = gui.add_number("radius (m)", 0.05, min=1e-3, max=5.0, step=0.01)
            self.length = gui.add_number("length (m)", 0.2, min=1e-3, max=5.0, step=0.01)
            self.add_button = gui.add_button("Add obstacle")
            self.selected = gui.add_dropdown("obstacle", (NONE,))
            self.remove_button = gui.add_button("Remove obstacle")
            self.link = gui.add_dropdown("link", tuple(body_links(robot)), initial_value=body_links(robot)[-1])
            self.attach_button = gui.add_button("Attach to link")
            self.attached = gui.add_dropdown("attached", (NONE,))
            self.detach_button = gui.add_button("Detach")
            self.file = gui.add_text("file", "scene.yaml")
            self.save_button = gui.add_button("Save YAML")
            self.message = gui.add_markdown("")
        self.gizmo: viser.TransformControlsHandle | None = None
        self._wire()

    def _wire(self) -> None:
        self.add_button.on_click(lambda _: self.report(self._add_from_controls))
        self.remove_button.on_click(lambda _: self.report(lambda: self.remove(self.selected.value)))
        self.attach_button.on_click(lambda _: self.report(lambda: self.attach(self.selected.value, self.link.value)))
        self.detach_button.on_click(lambda _: self.report(lambda: self.detach(self.attached.value)))
        self.save_button.on_click(lambda _: self.report(lambda: self.save(self.file.value)))
        self.selected.on_update(lambda _: self._place_gizmo())

    # ------------------------------------------------------------ the API (the buttons call these)
    def add(self, obstacle: Obstacle) -> None:
        self._apply([AddObstacle(obstacle)])
        self.selected.value = obstacle.name  # type: ignore[misc]  # (viser types a settable value read-only)

    def move(self, name: str, pose: np.ndarray) -> None:
        self._apply([MoveObstacle(name, np.asarray(pose, dtype=float))])

    def remove(self, name: str) -> None:
        self._apply([RemoveObstacle(name)])

    def attach(self, name: str, link: str) -> None:
        self._apply([AttachObject(name, link, robot_state=self._state())])

    def detach(self, name: str) -> None:
        self._apply([DetachObject(name, robot_state=self._state())])

    def save(self, path: str | Path) -> Path:
        """Write the scene as YAML to ``path``; InvalidScene with the reason if it cannot be written."""
        target = Path(path).expanduser()
        try:
            target.write_text(Scene.from_dict(self._current()).to_yaml())
        except OSError as exc:
            raise errors.InvalidScene(f"cannot write the scene to {target}: {exc.strerror}") from None
        self.message.content = f"saved {target}"
        return target

    def refresh(self, scene: dict) -> None:
        """Bring the dropdowns and the move gizmo to ``scene`` (after every applied edit)."""
        names = [o["name"] for o in scene.get("obstacles", [])]
        attached = [a["name"] for a in scene.get("attached", [])]
        keep = self.selected.value if self.selected.value in names else (names[-1] if names else NONE)
        self.selected.options = tuple(names) or (NONE,)
        self.selected.value = keep  # type: ignore[misc]
        self.attached.options = tuple(attached) or (NONE,)
        self.attached.value = attached[-1] if attached else NONE  # type: ignore[misc]
        self._place_gizmo(scene)

    # ------------------------------------------------------------ inside
    def _add_from_controls(self) -> None:
        size = tuple(float(v) for v in self.size.value)
        self.add(new_obstacle(self.name.value, self.shape.value, size, self.radius.value, self.length.value))

    def _place_gizmo(self, scene: dict | None = None) -> None:
        """A gizmo on the selected obstacle; dropping it moves the obstacle there."""
        scene = scene if scene is not None else self._current()
        found = [o for o in scene.get("obstacles", []) if o["name"] == self.selected.value]
        if self.gizmo is not None:
            self.gizmo.remove()
            self.gizmo = None
        if not found:
            return
        wxyz, position = wxyz_position(Obstacle.from_dict(found[0]).pose)
        name = self.selected.value
        gizmo = self._server.scene.add_transform_controls("/edit/gizmo", scale=0.15, wxyz=wxyz, position=position)

        @gizmo.on_update
        def _(event: viser.TransformControlsEvent) -> None:
            if event.phase == "end":
                self.report(lambda: self.move(name, pose_of(gizmo.wxyz, gizmo.position)))

        self.gizmo = gizmo

    def report(self, action: Callable[[], object]) -> None:
        """Run a button's action; a refused edit is shown as its one-line message."""
        try:
            action()
        except errors.MaruError as exc:
            self.message.content = f"**refused**: {exc.message}"

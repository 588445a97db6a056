"""Scene: named obstacles (any shape of :data:`maru_planner.scene.shapes.SHAPES`) in the robot's root frame.

YAML schema (what benchmarks and external checks write)::

    frame: base_link
    obstacles:
      - {name: desk, type: box, size: [x, y, z], pose: {xyz: [x, y, z], rpy: [r, p, y]}}
      - {name: ball, type: sphere, radius: r, pose: {xyz: [x, y, z]}}
      - {name: post, type: cylinder, radius: r, length: l, pose: {xyz: [...], rpy: [...]}}
      - {name: part, type: mesh, path: part.stl, scale: [1, 1, 1], pose: {...}}

Box sizes are full side lengths; cylinders are along their local z, centred. Each obstacle's
fields are its shape's dimensions (``maru_planner/scene/shapes.py``); a relative file path (a mesh) is
resolved against the YAML file's directory.
Objects attached to the robot (``attached``) move with their link: each is a shape with its pose in
the link's frame, the link, and the links it may touch (the link itself always may)::

    attached:
      - {name: cup, type: cylinder, radius: 0.04, length: 0.1, pose: {xyz: [0, 0, 0.08]}, link: r_hand,
         touch_links: [r_arm_link5]}

:meth:`Scene.attach` takes a scene obstacle (or a new shape) onto a link, :meth:`Scene.detach` puts it
back into the scene where it is; the collision model that carries them is
:func:`maru_planner.robot.attached.robot_with_attached`.
Every change bumps ``scene.version`` so planners can cache on it.
"""

from __future__ import annotations

import itertools
import time
from collections import Counter, OrderedDict
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from maru_planner.errors import InvalidObject, InvalidScene, ObjectAlreadyAttached, one_line
from maru_planner.scene.obstacle import AttachedObject, Obstacle
from maru_planner.scene.poses import pose_matrix


def _is_file(text: str) -> bool:
    try:
        return Path(text).is_file()
    except (OSError, ValueError):  # e.g. a long one-line YAML string is not a valid file name
        return False


MAX_OBSTACLES = 500_000  # default size limit of a scene
DEFAULT_FRAME = "base_link"  # the frame of a scene that names none (maru1's root link)


class BuildClock:
    """Deadline of a scene build (``budget`` seconds, None = none), checked every ``every`` obstacles.

    Running out raises InvalidScene naming the stage and how far it got.
    """

    def __init__(self, budget: float | None, total: int, every: int = 1024):
        self.deadline = None if budget is None else time.monotonic() + float(budget)
        self.budget, self.total, self.every = budget, total, every

    def tick(self, done: int, stage: str) -> None:
        if self.deadline is not None and done % self.every == 0 and time.monotonic() > self.deadline:
            raise InvalidScene(
                f"scene: the build ran out of its {self.budget:g} s budget while {stage} "
                f"({done} of {self.total} obstacles); use a smaller scene or a larger build budget"
            )


class Scene:
    """An ordered set of named obstacles in ``frame`` (the robot's root frame), at most ``max_obstacles``."""

    def __init__(
        self, obstacles: list[Obstacle] | None = None, frame: str = DEFAULT_FRAME, *, max_obstacles: int = MAX_OBSTACLES
    ):
        self.frame = frame
        self.max_obstacles = int(max_obstacles)
        self.obstacles: OrderedDict[str, Obstacle] = OrderedDict()
        self.attached: OrderedDict[str, AttachedObject] = OrderedDict()
        self.version = 0
        self._origin_distances = (-1, np.zeros(0))  # (version, per obstacle): see obstacles_within
        for obstacle in obstacles or []:
            self.add(obstacle)

    # ------------------------------------------------------------ editing --
    def add(self, obstacle: Obstacle) -> None:
        """Add (or replace, keeping its position in the order) an obstacle."""
        if not isinstance(obstacle, Obstacle):
            raise InvalidScene(f"expected an Obstacle, got {type(obstacle).__name__}")
        if obstacle.name in self.attached:
            raise ObjectAlreadyAttached(f"obstacle '{obstacle.name}': an attached object has that name")
        if obstacle.name not in self.obstacles and len(self.obstacles) >= self.max_obstacles:
            raise InvalidScene(f"obstacle '{obstacle.name}': the scene is full ({self.max_obstacles} obstacles)")
        self.obstacles[obstacle.name] = obstacle
        self.version += 1

    def move(self, name: str, pose: Any) -> None:
        """Set an obstacle's pose (4x4, xyz, xyz+rpy or {xyz, rpy})."""
        obstacle = self._get(name)
        obstacle.pose = pose_matrix(pose, f"obstacle '{name}'")
        self.version += 1

    def remove(self, name: str) -> None:
        self._get(name)
        del self.obstacles[name]
        self.version += 1

    def clear(self) -> None:
        """Remove every obstacle (attached objects stay on the robot)."""
        self.obstacles.clear()
        self.version += 1

    def attach(
        self, name: str, link: str, link_pose: Any = None, touch_links: Any = (), obstacle: Obstacle | None = None
    ) -> AttachedObject:
        """Fix obstacle ``name`` to ``link`` where it is (``link_pose``: the link's pose in the scene now), or,
        given ``obstacle`` (its pose in the link's frame), a new shape. InvalidObject / ObjectAlreadyAttached."""
        if name in self.attached:
            raise ObjectAlreadyAttached(f"object '{name}' is already attached to '{self.attached[name].link}'")
        if obstacle is None:
            if name not in self.obstacles:
                have = list(itertools.islice(self.obstacles, 10))
                raise InvalidObject(f"object '{name}': not in the scene (have {have})")
            link_from_scene = np.linalg.inv(pose_matrix(link_pose, f"attach '{name}': link pose"))
            source = self.obstacles[name]
            obstacle = Obstacle(name, source.type, link_from_scene @ source.pose, **source.dimensions)
        elif obstacle.name != name or name in self.obstacles:
            raise InvalidObject(f"object '{name}': a new shape needs a name no obstacle has (got {obstacle.name!r})")
        attached = AttachedObject(obstacle, link, touch_links)
        self.obstacles.pop(name, None)
        self.attached[name] = attached
        self.version += 1
        return attached

    def detach(self, name: str, link_pose: Any) -> Obstacle:
        """Put attached object ``name`` back into the scene at its current pose (``link_pose``: its link's pose)."""
        if name not in self.attached:
            raise InvalidObject(f"object '{name}': not attached (attached: {list(self.attached)})")
        obstacle = self.attached[name].obstacle
        pose = pose_matrix(link_pose, f"detach '{name}': link pose") @ obstacle.pose
        placed = Obstacle(name, obstacle.type, pose, **obstacle.dimensions)
        del self.attached[name]
        self.add(placed)
        return placed

    def _get(self, name: str) -> Obstacle:
        if name not in self.obstacles:
            have = list(itertools.islice(self.obstacles, 10)) + (["..."] if len(self.obstacles) > 10 else [])
            raise InvalidScene(f"obstacle '{name}': not in the scene (have {have})")
        return self.obstacles[name]

    def obstacles_within(self, radius: float, clock: BuildClock | None = None) -> list[Obstacle]:
        """The obstacles whose kernel primitive's bounding sphere comes within ``radius`` of the frame origin.

        How near each one comes is worked out once per scene version (``clock`` ticking) and shared by every
        checker of the scene (a padded twin, the exact verifier), so far obstacles cost one pass per edit.
        """
        obstacles = list(self.obstacles.values())
        if self._origin_distances[0] != self.version:
            clock = clock or BuildClock(None, len(obstacles))
            distances = np.empty(len(obstacles))
            for k, obstacle in enumerate(obstacles):
                clock.tick(k, "culling far obstacles")
                distances[k] = obstacle.kernel_primitive().origin_distance
            self._origin_distances = (self.version, distances)
        return [obstacles[k] for k in np.flatnonzero(self._origin_distances[1] <= radius)]

    def __len__(self) -> int:
        return len(self.obstacles)

    def __contains__(self, name: str) -> bool:
        return name in self.obstacles

    # ---------------------------------------------------------------- I/O --
    @classmethod
    def from_dict(
        cls,
        d: dict | None,
        base_dir: Path | None = None,
        *,
        max_obstacles: int = MAX_OBSTACLES,
        budget: float | None = None,
    ) -> Scene:
        """A scene from its dict form (at most ``max_obstacles``, read within ``budget`` seconds if given)."""
        if d is None:
            return cls(max_obstacles=max_obstacles)
        if not isinstance(d, dict):
            raise InvalidScene(f"scene must be a mapping with 'obstacles', got {type(d).__name__}")
        unknown = set(d) - {"frame", "obstacles", "attached"}
        if unknown:
            raise InvalidScene(f"scene: unknown field(s) {sorted(unknown)}")
        entries = d.get("obstacles") or []
        if not isinstance(entries, list):
            raise InvalidScene("scene: field 'obstacles' must be a list")
        if len(entries) > max_obstacles:
            raise InvalidScene(f"scene: {len(entries)} obstacles, more than the limit of {max_obstacles}")
        clock = BuildClock(budget, len(entries))
        obstacles = []
        for k, entry in enumerate(entries):
            clock.tick(k, "reading obstacles")
            obstacles.append(Obstacle.from_dict(entry, base_dir))
        dupes = sorted(name for name, count in Counter(o.name for o in obstacles).items() if count > 1)
        if dupes:
            raise InvalidScene(f"scene: duplicate obstacle name(s) {dupes}")
        scene = cls(obstacles, frame=str(d.get("frame", DEFAULT_FRAME)), max_obstacles=max_obstacles)
        attached = d.get("attached") or []
        if not isinstance(attached, list):
            raise InvalidScene("scene: field 'attached' must be a list")
        for entry in attached:
            item = AttachedObject.from_dict(entry, base_dir)
            scene.attach(item.name, item.link, touch_links=item.touch_links, obstacle=item.obstacle)
        return scene

    @classmethod
    def from_yaml(cls, source: str | Path, *, max_obstacles: int = MAX_OBSTACLES, budget: float | None = None) -> Scene:
        """Load from a YAML file path or a YAML string."""
        base_dir = None
        text = str(source)
        single_line = "\n" not in text
        is_path = isinstance(source, Path) or (single_line and (text.endswith((".yaml", ".yml")) or _is_file(text)))
        if is_path:
            path = Path(source)
            if not path.is_file():
                raise InvalidScene(f"scene file not found: {path}")
            text, base_dir = path.read_text(), path.parent
        try:
            data = yaml.safe_load(text)
        except yaml.YAMLError as exc:
            raise InvalidScene(f"scene YAML does not parse: {one_line(exc, 160)}") from None
        return cls.from_dict(data, base_dir, max_obstacles=max_obstacles, budget=budget)

    def to_dict(self) -> dict:
        d = {"frame": self.frame, "obstacles": [o.to_dict() for o in self.obstacles.values()]}
        if self.attached:
            d["attached"] = [a.to_dict() for a in self.attached.values()]
        return d

    def to_yaml(self) -> str:
        return yaml.safe_dump(self.to_dict(), sort_keys=False)

    def __repr__(self) -> str:
        return f"Scene({list(self.obstacles)}, version={self.version})"

"""MotionBenchMaker's problems (a tarball of MoveIt scene and request YAML pairs) as scenes and requests.

Each ``<set>[_panda]/sceneNNNN.yaml`` + ``requestNNNN.yaml`` pair is one :class:`MbmProblem`, read straight
from the tarball. The Panda those problems are posed for is
:func:`~maru_planner.robot.robots.panda.mbm_panda` (fingers open: ``PANDA_FINGERS_OPEN``).
"""

from __future__ import annotations

import re
import tarfile
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path

import yaml

from maru_planner.scene.moveit import MoveItRequest, request_from_moveit, scene_from_moveit
from maru_planner.scene.planning_scene import Scene


@dataclass
class MbmProblem:
    """One MotionBenchMaker problem: ``<set>`` and number, scene and request."""

    set_name: str
    index: int
    scene: Scene
    request: MoveItRequest

    @property
    def name(self) -> str:
        return f"{self.set_name}/{self.index:04d}"


_YAML_LOADER = getattr(yaml, "CSafeLoader", yaml.SafeLoader)  # libyaml when available: 10x faster
_MEMBER = re.compile(r"(?:^|/)(?P<set>[^/]+?)(?:_panda)?/(?P<kind>scene|request)(?P<num>\d+)\.yaml$")


def iter_mbm_problems(
    tarball: str | Path,
    sets: list[str] | None = None,
    limit_per_set: int | None = None,
    fixed_joints: Mapping[str, float] | None = None,
) -> Iterator[MbmProblem]:
    """Problems straight from the MotionBenchMaker tarball (no extraction), sorted by set and number.

    ``sets`` filters by set name (e.g. ``["box", "cage"]``); ``limit_per_set`` keeps the first N of each.
    """
    texts: dict[tuple[str, int], dict[str, str]] = {}
    with tarfile.open(tarball, "r:*") as tar:
        for member in tar:
            m = _MEMBER.search(member.name)
            if not member.isfile() or m is None:
                continue
            if sets is not None and m["set"] not in sets:
                continue
            num = int(m["num"])
            if limit_per_set is not None and num > limit_per_set:
                continue
            fh = tar.extractfile(member)
            if fh is None:  # only for members that are not files, skipped above
                continue
            with fh:
                texts.setdefault((m["set"], num), {})[m["kind"]] = fh.read().decode("utf-8")
    chosen: dict[str, int] = {}
    for set_name, num in sorted(texts):
        pair = texts[(set_name, num)]
        if "scene" not in pair or "request" not in pair:
            continue
        if limit_per_set is not None and chosen.get(set_name, 0) >= limit_per_set:
            continue
        chosen[set_name] = chosen.get(set_name, 0) + 1
        yield MbmProblem(
            set_name,
            num,
            scene_from_moveit(yaml.load(pair["scene"], Loader=_YAML_LOADER)),
            request_from_moveit(yaml.load(pair["request"], Loader=_YAML_LOADER), fixed_joints),
        )

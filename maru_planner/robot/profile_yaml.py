"""Robot profiles as YAML files: one robot's files, limits, groups, end effectors and IK, read and checked.

The built-in robots are such files (``maru_planner/robot/robots/<name>.yaml``); a user's robot is one too,
given by path wherever a robot name is taken (``maru-plan --robot my_arm.yaml``, the planning node's
``robot_file``, ``RobotModel.from_profile("my_arm.yaml")``). docs/your_robot.md walks through one. Keys::

    name: my_arm                        # required: the robot's name in logs and results
    source: example-robot-data          # where urdf/srdf are: example-robot-data, maru_planner (its urdf/) or a
                                        #   directory (relative to this file); default: this file's directory
    urdf: my_arm_description/urdf/my_arm.urdf      # required
    srdf: my_arm_description/srdf/my_arm.srdf      # optional (no SRDF: one group "all", no disabled pairs)
    package_dirs: [meshes_root]         # more directories package:// URIs resolve under (relative to this file)
    urdf_name: MY_ARM                   # the URDF's <robot name>: a robot_description with it gets this IK
    acceleration_limits: 5.0            # rad/s^2 (m/s^2): one value, or a list in joint order
    end_effectors: {tool: tool0}        # name -> frame; default: the SRDF's, else the last link
    groups: {arm: [joint1, joint2]}     # planning groups added to the SRDF's
    locked_joints: {gripper_joint: 0.0} # joints frozen at a value (not planned)
    ignore_links_touching_at_rest: false  # true: links touching at the neutral posture are never checked
    ik_strategies: [my_package.my_ik:strategy]  # "module:function" IK tried before the numeric one
    sphere_model: {max_protrusion: 0.01}  # the sphere model's fit (SphereFitOptions); omitted keys keep defaults:
                                        #   max_protrusion 0.015, max_edge 0.025, grid_step 0.012 (m),
                                        #   cylinder_sides 16, cluster_size 6

Any other key, a missing required key or a value of the wrong kind raises :class:`InvalidRobotProfile`
with one line naming the file and the key.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Mapping
from importlib import import_module
from pathlib import Path
from typing import Any

import yaml

from maru_planner.robot import robot_profile
from maru_planner.robot.ik_strategy import IKStrategy
from maru_planner.robot.robot_profile import DEFAULT_ACCELERATION_LIMIT, SOURCES, InvalidRobotProfile, RobotProfile
from maru_planner.robot.sphere_options import SPHERE_OPTION_RANGES, SphereFitOptions

PROFILE_SUFFIXES = (".yaml", ".yml")
NAME = re.compile(r"^[A-Za-z][A-Za-z0-9_.-]*$")
STRATEGY = re.compile(r"^[A-Za-z_][\w.]*:[A-Za-z_]\w*$")
MAX_FILE_BYTES = 1_000_000


def is_profile_file(robot: str | Path) -> bool:
    """Whether ``robot`` names a profile file (a .yaml/.yml path) rather than a built-in robot."""
    return str(robot).lower().endswith(PROFILE_SUFFIXES)


def resolve(robot: str | Path | RobotProfile) -> RobotProfile:
    """A profile: itself, read from a YAML file (a .yaml/.yml path), or the built-in robot of that name."""
    if isinstance(robot, RobotProfile):
        return robot
    if isinstance(robot, Path) or is_profile_file(robot):
        return load_profile(Path(robot))
    return robot_profile.profile(robot)


def load_profile(path: Path, *, check_files: bool = True) -> RobotProfile:
    """The profile in YAML file ``path``; ``check_files``: its URDF/SRDF must exist (checked when found)."""
    where = f"robot file {path}"
    if not path.is_file():
        raise InvalidRobotProfile(f"{where}: no such file")
    if path.stat().st_size > MAX_FILE_BYTES:
        raise InvalidRobotProfile(f"{where}: larger than {MAX_FILE_BYTES} bytes")
    try:
        data = yaml.safe_load(path.read_text())
    except (OSError, UnicodeDecodeError) as exc:
        raise InvalidRobotProfile(f"{where}: cannot be read ({exc})") from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        at = f" at line {mark.line + 1}" if mark is not None else ""
        raise InvalidRobotProfile(f"{where}: not valid YAML{at}") from None
    profile = profile_from_mapping(data, path.resolve().parent, where)
    if check_files:
        check_profile_files(profile, where)
    return profile


def profile_from_mapping(data: Any, directory: Path, where: str = "robot profile") -> RobotProfile:
    """A profile from the parsed YAML ``data``; relative directories are taken from ``directory``."""
    fields = _Fields(data, where)
    name = fields.take("name", _name, required=True)
    source = fields.take("source", lambda v, k: _source(v, k, directory)) or str(directory)
    profile = RobotProfile(
        name=name,
        source=source,
        urdf=fields.take("urdf", _relative_path, required=True),
        srdf=fields.take("srdf", _relative_path),
        urdf_name=fields.take("urdf_name", _text) or "",
        acceleration_limits=fields.take("acceleration_limits", _limits) or DEFAULT_ACCELERATION_LIMIT,
        end_effectors=fields.take("end_effectors", _frames) or {},
        groups=fields.take("groups", _groups) or {},
        ignore_links_touching_at_rest=fields.take("ignore_links_touching_at_rest", _flag) or False,
        ik_strategies=fields.take("ik_strategies", _strategies) or (),
        package_dirs=tuple(str(directory / d) for d in fields.take("package_dirs", _directories) or ()),
        locked_joints=fields.take("locked_joints", _locked) or {},
        sphere_model=fields.take("sphere_model", _sphere_options) or SphereFitOptions(),
    )
    fields.no_others()
    return profile


def check_profile_files(profile: RobotProfile, where: str) -> None:
    """InvalidRobotProfile naming ``urdf``/``srdf``/``source`` when a file the profile names is missing."""
    try:
        files = profile.files()
    except FileNotFoundError as exc:
        raise InvalidRobotProfile(f"{where}: source: {exc}") from None
    if not files.urdf.is_file():
        raise InvalidRobotProfile(f"{where}: urdf: no such file {files.urdf}")
    if files.srdf is not None and not files.srdf.is_file():
        raise InvalidRobotProfile(f"{where}: srdf: no such file {files.srdf}")
    for directory in files.package_dirs:
        if not directory.is_dir():
            raise InvalidRobotProfile(f"{where}: package_dirs: no such directory {directory}")


class _Fields:
    """The keys of one profile mapping, taken one by one so that what is left over can be named."""

    def __init__(self, data: Any, where: str):
        if not isinstance(data, Mapping):
            raise InvalidRobotProfile(f"{where}: expected a mapping of profile keys, got {_kind(data)}")
        self.data = dict(data)
        self.where = where

    def take(self, key: str, parse: Callable[[Any, str], Any], *, required: bool = False) -> Any:
        if key not in self.data or self.data[key] is None:
            self.data.pop(key, None)
            if required:
                raise InvalidRobotProfile(f"{self.where}: {key}: required")
            return None
        value = self.data.pop(key)
        try:
            return parse(value, key)
        except _Bad as exc:
            raise InvalidRobotProfile(f"{self.where}: {key}: {exc}") from None

    def no_others(self) -> None:
        if self.data:
            unknown = ", ".join(sorted(str(k) for k in self.data))
            raise InvalidRobotProfile(f"{self.where}: unknown key(s) {unknown}; known: {', '.join(KEYS)}")


KEYS = (
    "name", "source", "urdf", "srdf", "package_dirs", "urdf_name", "acceleration_limits", "end_effectors", "groups",
    "locked_joints", "ignore_links_touching_at_rest", "ik_strategies", "sphere_model",
)  # fmt: skip


class _Bad(ValueError):
    """A value of the wrong kind (the caller adds the file and key)."""


def _kind(value: Any) -> str:
    return f"{type(value).__name__} {str(value)[:40]!r}"


def _text(value: Any, key: str) -> str:
    if not isinstance(value, str) or not value.strip():
        raise _Bad(f"expected a non-empty string, got {_kind(value)}")
    return value.strip()


def _name(value: Any, key: str) -> str:
    text = _text(value, key)
    if not NAME.match(text) or is_profile_file(text):
        raise _Bad(f"expected a name of letters, digits, '_', '-' or '.' (not ending in .yaml), got {text!r}")
    return text


def _relative_path(value: Any, key: str) -> str:
    return _text(value, key)


def _source(value: Any, key: str, directory: Path) -> str:
    text = _text(value, key)
    return text if text in SOURCES else str(directory / text)


def _directories(value: Any, key: str) -> list[str]:
    if not isinstance(value, list):
        raise _Bad(f"expected a list of directories, got {_kind(value)}")
    return [_text(v, key) for v in value]


def _number(value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise _Bad(f"expected a finite number, got {_kind(value)}")
    return float(value)


def _positive(value: Any) -> float:
    number = _number(value)
    if number <= 0.0:
        raise _Bad(f"expected a positive number, got {number:g}")
    return number


def _limits(value: Any, key: str) -> float | tuple[float, ...]:
    if isinstance(value, list):
        if not value:
            raise _Bad("expected a positive number or a non-empty list of them, got []")
        return tuple(_positive(v) for v in value)
    return _positive(value)


def _frames(value: Any, key: str) -> dict[str, str]:
    if not isinstance(value, Mapping) or not value:
        raise _Bad(f"expected a mapping name -> frame, got {_kind(value)}")
    return {_text(k, key): _text(v, key) for k, v in value.items()}


def _groups(value: Any, key: str) -> dict[str, list[str]]:
    if not isinstance(value, Mapping) or not value:
        raise _Bad(f"expected a mapping group -> list of joints, got {_kind(value)}")
    groups = {}
    for group, joints in value.items():
        if not isinstance(joints, list) or not joints:
            raise _Bad(f"group {group!r}: expected a non-empty list of joints, got {_kind(joints)}")
        groups[_text(group, key)] = [_text(j, key) for j in joints]
    return groups


def _locked(value: Any, key: str) -> dict[str, float]:
    if not isinstance(value, Mapping) or not value:
        raise _Bad(f"expected a mapping joint -> value, got {_kind(value)}")
    return {_text(k, key): _number(v) for k, v in value.items()}


def _flag(value: Any, key: str) -> bool:
    if not isinstance(value, bool):
        raise _Bad(f"expected true or false, got {_kind(value)}")
    return value


def _strategies(value: Any, key: str) -> tuple[IKStrategy, ...]:
    if not isinstance(value, list):
        raise _Bad(f"expected a list of 'module:function' names, got {_kind(value)}")
    return tuple(_strategy(_text(v, key)) for v in value)


def _strategy(reference: str) -> IKStrategy:
    """The callable ``module:function`` names (a module of the robot being defined may still be loading)."""
    if not STRATEGY.match(reference):
        raise _Bad(f"expected 'module:function', got {reference!r}")
    module_name, function = reference.split(":")
    try:
        module = import_module(module_name)
    except Exception as exc:  # the user's module may fail in any way while it is imported
        raise _Bad(f"{reference}: cannot import {module_name} ({type(exc).__name__}: {exc})") from None
    found = getattr(module, function, None)
    if not callable(found):
        raise _Bad(f"{reference}: {module_name} has no function {function}")
    return found


def _sphere_options(value: Any, key: str) -> SphereFitOptions:
    """The fit's options: a mapping of some of SphereFitOptions' fields, each within SPHERE_OPTION_RANGES."""
    if not isinstance(value, Mapping):
        raise _Bad(f"expected a mapping of {', '.join(SPHERE_OPTION_RANGES)}, got {_kind(value)}")
    unknown = sorted(str(k) for k in value if k not in SPHERE_OPTION_RANGES)
    if unknown:
        raise _Bad(f"unknown key(s) {', '.join(unknown)}; known: {', '.join(SPHERE_OPTION_RANGES)}")
    options: dict[str, Any] = {str(k): _sphere_option(str(k), v) for k, v in value.items()}  # int or float per key
    return SphereFitOptions(**options)


def _sphere_option(name: str, value: Any) -> float | int:
    low, high = SPHERE_OPTION_RANGES[name]
    is_count = isinstance(SphereFitOptions.__dataclass_fields__[name].default, int)
    if is_count and (isinstance(value, bool) or not isinstance(value, int)):
        raise _Bad(f"{name}: expected a whole number, got {_kind(value)}")
    try:
        number = _number(value)
    except _Bad as exc:
        raise _Bad(f"{name}: {exc}") from None
    if not low <= number <= high:
        raise _Bad(f"{name}: expected a value in [{low:g}, {high:g}], got {number:g}")
    return int(value) if is_count else number

"""Where the planning runtime's robot comes from: a profile (a built-in name or a YAML file), or URDF + SRDF files
(or their XML text).

:class:`RobotSource` is picklable, so every worker process loads its own model from it.
:func:`description_source` picks the files the way ``planning_node`` documents its parameters: a robot profile
file (``robot_file``, docs/your_robot.md: files, groups, limits, IK), else XML text (``robot_description`` and
``robot_description_semantic``, or a URDF read from a topic) written to a private directory
(:class:`DescriptionFiles`), else the given files, else the package's Maru-1 upper body.
"""

from __future__ import annotations

import tempfile
from dataclasses import dataclass
from pathlib import Path

from maru_planner import errors
from maru_planner.paths import urdf_path
from maru_planner.robot import RobotModel
from maru_planner.robot.profile_yaml import is_profile_file, load_profile

DEFAULT_URDF = "maru1_upper_body.urdf"
DEFAULT_SRDF = "maru1_upper_body.srdf"


@dataclass(frozen=True)
class RobotSource:
    """Where a worker loads its robot model from: a profile (name or YAML file), else URDF + SRDF files (picklable).

    With a profile, ``urdf``/``srdf`` are the profile's files, for whoever reads them (the node publishes the URDF).
    """

    urdf: str = ""
    srdf: str = ""
    package_dirs: tuple[str, ...] = ()
    profile: str = ""

    def load(self) -> RobotModel:
        if self.profile:
            return RobotModel.from_profile(self.profile)
        return RobotModel.from_urdf(self.urdf, self.srdf or None, package_dirs=list(self.package_dirs) or None)


class DescriptionFiles:
    """URDF/SRDF XML text written to files in one private directory, made on first use; :meth:`cleanup` removes it."""

    def __init__(self, prefix: str):
        self._prefix = prefix
        self._directory: tempfile.TemporaryDirectory | None = None

    def written(self, name: str, text: str) -> str:
        """The path of file ``name`` holding ``text``."""
        if self._directory is None:
            self._directory = tempfile.TemporaryDirectory(prefix=self._prefix)
        path = Path(self._directory.name) / name
        path.write_text(text)
        return str(path)

    def cleanup(self) -> None:
        if self._directory is not None:
            self._directory.cleanup()
            self._directory = None


@dataclass(frozen=True)
class RobotDescription:
    """The robot's description as given: XML text (wins when set) or file paths, and package directories.

    ``urdf_from`` names where ``urdf_xml`` came from, for the log (a parameter or a topic).
    """

    urdf_xml: str = ""
    srdf_xml: str = ""
    urdf_file: str = ""
    srdf_file: str = ""
    package_dirs: tuple[str, ...] = ()
    urdf_from: str = "the robot_description parameter"
    robot_file: str = ""  # a robot profile YAML file: used instead of all the above


def description_source(description: RobotDescription, files: DescriptionFiles) -> tuple[RobotSource, str]:
    """The :class:`RobotSource` of ``description`` (XML written to ``files``) and one line saying where it came from."""
    d = description
    if d.robot_file:
        return profile_source(d)
    urdf = files.written("robot_description.urdf", d.urdf_xml) if d.urdf_xml else d.urdf_file
    srdf = files.written("robot_description_semantic.srdf", d.srdf_xml) if d.srdf_xml else d.srdf_file
    urdf, srdf = urdf or str(urdf_path(DEFAULT_URDF)), srdf or str(urdf_path(DEFAULT_SRDF))
    origin = (
        f"URDF from {d.urdf_from if d.urdf_xml else urdf}, "
        f"SRDF from {'the robot_description_semantic parameter' if d.srdf_xml else srdf}"
    )
    return RobotSource(urdf, srdf, tuple(p for p in d.package_dirs if p)), origin


def profile_source(description: RobotDescription) -> tuple[RobotSource, str]:
    """The source of ``description.robot_file`` (read and checked now); InvalidParameter naming ``robot_file``
    when the file is not a usable profile or another robot description is set too."""
    d = description
    others = [name for name, value in (("robot_description", d.urdf_xml), ("robot_urdf", d.urdf_file)) if value]
    if others or d.srdf_xml or d.srdf_file or d.package_dirs:
        given = others + [n for n, v in (("robot_srdf", d.srdf_file), ("package_dirs", d.package_dirs)) if v]
        given += ["robot_description_semantic"] if d.srdf_xml else []
        raise errors.InvalidParameter(
            f"parameter 'robot_file' is set, and so are {', '.join(given)}: the profile names its own files; set one"
        )
    if not is_profile_file(d.robot_file):
        raise errors.InvalidParameter(f"parameter 'robot_file' = {d.robot_file!r}: expected a .yaml or .yml file")
    try:
        profile = load_profile(Path(d.robot_file))
    except errors.InvalidRequest as exc:
        raise errors.InvalidParameter(f"parameter 'robot_file': {exc}") from None
    found = profile.files()
    source = RobotSource(
        str(found.urdf),
        str(found.srdf or ""),
        tuple(str(p) for p in found.package_dirs),
        profile=str(Path(d.robot_file).resolve()),
    )
    return source, f"robot {profile.name} from the profile {d.robot_file} (URDF {found.urdf})"


def check_group(robot: RobotModel, group: str) -> None:
    """InvalidParameter (naming ``default_group``) unless ``group`` is a planning group of ``robot``."""
    if group not in robot.groups:
        raise errors.InvalidParameter(
            f"parameter 'default_group' = {group!r} is not a group of the robot; known: {', '.join(robot.groups)}"
        )

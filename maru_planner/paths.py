"""Where the package's data files live, in a source checkout or an install."""

from __future__ import annotations

import os
import sys
from pathlib import Path

PACKAGE_NAME = "maru_planner"
# Where the colcon/ament manifest (package.xml, setup.py) sits, relative to the repository root: the root itself.
PACKAGE_MANIFEST_DIR = Path(".")


def share_dir() -> Path:
    """Directory holding ``config/``, ``urdf/`` and ``launch/``.

    A source checkout (or editable install) uses the repository root; an
    ament install uses ``<prefix>/share/maru_planner``.
    """
    repo_root = Path(__file__).resolve().parent.parent
    if (repo_root / "config").is_dir() and (repo_root / PACKAGE_MANIFEST_DIR / "package.xml").is_file():
        return repo_root
    for prefix in os.environ.get("AMENT_PREFIX_PATH", "").split(os.pathsep) + [sys.prefix]:
        candidate = Path(prefix) / "share" / PACKAGE_NAME
        if (candidate / "config").is_dir():
            return candidate
    raise FileNotFoundError("cannot locate the maru_planner share directory (config/, urdf/)")


def config_path(*parts: str) -> Path:
    """A file under the share directory's ``config/``."""
    return share_dir().joinpath("config", *parts)


def urdf_path(*parts: str) -> Path:
    """A file under the share directory's ``urdf/``."""
    return share_dir().joinpath("urdf", *parts)


def benchmarks_dir() -> Path:
    """Public benchmark data (MovingAI, BARN, MotionBenchMaker); not shipped with the package.

    ``MARU_BENCHMARKS_DIR`` wins; else ``../shared/benchmarks`` next to a source checkout.
    The directory may not exist: callers skip or fail with a message naming it.
    """
    override = os.environ.get("MARU_BENCHMARKS_DIR")
    if override:
        return Path(override)
    return Path(__file__).resolve().parent.parent.parent / "shared" / "benchmarks"

"""The contract of a robot-specific IK method, which a robot profile names and a RobotModel tries before the
numeric solver (``robot/ik.py``)."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any, Protocol

import numpy as np

Validity = Callable[[np.ndarray], bool]


class IKStrategy(Protocol):
    """A robot-specific IK method (see the module docstring)."""

    def __call__(
        self,
        robot: Any,  # a RobotModel (robot/model.py imports this module)
        targets: Mapping[str, np.ndarray],
        q_seed: np.ndarray,
        group: str | None,
        *,
        deadline: float | None,
        is_valid: Validity | None,
    ) -> np.ndarray | None: ...

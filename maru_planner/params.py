"""Declared parameters of the core: one :class:`ParamSpec` per setting, read by the CLIs and nodes.

A configuration dataclass documents each field once, in its ``metadata``::

    resolution: float = param(0.02, "collision-check step along an edge (rad)", lower=1e-4, upper=1.0)

:func:`dataclass_params` turns those fields into ``ParamSpec`` s; the ROS adapters turn each spec
into a parameter with a descriptor (type, range, description, read-only), the CLIs into options,
and planner registries use the same class for planner parameters. Nothing here imports rclpy.
"""

from __future__ import annotations

import builtins
import dataclasses
import math
from collections.abc import Callable, Sequence
from typing import Any

from maru_planner.errors import InvalidRequest, excerpt


@dataclasses.dataclass(frozen=True)
class ParamSpec:
    """One declared parameter: default, type, documentation, limits.

    ``lower``/``upper`` bound numbers (inclusive), ``choices`` enumerate the allowed strings,
    ``read_only`` marks what cannot change after start-up (the node rejects a run-time change
    with that reason), ``optional`` allows ``None``.
    """

    name: str
    default: Any
    description: str = ""
    lower: float | None = None
    upper: float | None = None
    choices: tuple[str, ...] | None = None
    read_only: bool = False
    optional: bool = False
    type: builtins.type | None = None  # the field shadows the builtin inside the class body

    @property
    def value_type(self) -> builtins.type:
        """bool, int, float, str, list or dict (from ``type``, else from the default)."""
        if self.type is not None:
            return self.type
        if self.default is None:
            return float
        return type(self.default)

    def check(self, value: Any) -> Any:
        """``value`` converted to this parameter's type; InvalidRequest naming the parameter if it does not fit."""
        if value is None:
            if self.optional:
                return None
            raise InvalidRequest(f"parameter {self.name!r} must be set")
        kind = self.value_type
        if kind is bool:
            if not isinstance(value, bool):
                raise InvalidRequest(f"parameter {self.name!r} must be true or false, got {excerpt(value, 40)}")
            return value
        if kind in (int, float):
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise InvalidRequest(f"parameter {self.name!r} must be a number, got {excerpt(value, 40)}")
            if kind is int and isinstance(value, float):
                if not value.is_integer():
                    raise InvalidRequest(f"parameter {self.name!r} must be an integer, got {excerpt(value, 40)}")
                value = int(value)
            value = kind(value)
            if not math.isfinite(value):
                raise InvalidRequest(f"parameter {self.name!r} must be finite, got {value}")
            if (self.lower is not None and value < self.lower) or (self.upper is not None and value > self.upper):
                raise InvalidRequest(
                    f"parameter {self.name!r} = {value} is outside [{_bound(self.lower, '-inf')}, {_bound(self.upper)}]"
                )
            return value
        if kind is str:
            if not isinstance(value, str):
                raise InvalidRequest(f"parameter {self.name!r} must be a string, got {excerpt(value, 40)}")
            if self.choices is not None and value not in self.choices:
                raise InvalidRequest(
                    f"parameter {self.name!r} = {excerpt(value, 40)} is not one of {', '.join(self.choices)}"
                )
            return value
        if not isinstance(value, kind):
            raise InvalidRequest(f"parameter {self.name!r} must be a {kind.__name__}, got {excerpt(value, 40)}")
        return value

    def describe(self) -> str:
        """One line: description, range or choices, read-only."""
        parts = [self.description] if self.description else []
        if self.choices:
            parts.append("one of " + ", ".join(self.choices))
        elif self.lower is not None or self.upper is not None:
            parts.append(f"range [{_bound(self.lower, '-inf')}, {_bound(self.upper)}]")
        if self.read_only:
            parts.append("read-only after start-up")
        return "; ".join(parts)


def param(
    default: Any = dataclasses.MISSING,
    description: str = "",
    *,
    lower: float | None = None,
    upper: float | None = None,
    choices: Sequence[str] | None = None,
    read_only: bool = False,
    default_factory: Callable[[], Any] | Any = dataclasses.MISSING,
) -> Any:
    """A dataclass field that carries its parameter documentation (see module doc)."""
    metadata = {
        "description": description,
        "lower": lower,
        "upper": upper,
        "choices": tuple(choices) if choices is not None else None,
        "read_only": read_only,
    }
    if default_factory is not dataclasses.MISSING:
        return dataclasses.field(default_factory=default_factory, metadata=metadata)
    return dataclasses.field(default=default, metadata=metadata)


def dataclass_params(cls: type, *, skip: Sequence[str] = ()) -> dict[str, ParamSpec]:
    """The :class:`ParamSpec` of every field of dataclass ``cls`` (name → spec), in field order."""
    specs: dict[str, ParamSpec] = {}
    for f in dataclasses.fields(cls):
        if f.name in skip or f.name.startswith("_"):
            continue
        if f.default is not dataclasses.MISSING:
            default = f.default
        elif f.default_factory is not dataclasses.MISSING:
            default = f.default_factory()
        else:
            default = None
        meta = f.metadata
        specs[f.name] = ParamSpec(
            name=f.name,
            default=default,
            description=meta.get("description", ""),
            lower=meta.get("lower"),
            upper=meta.get("upper"),
            choices=meta.get("choices"),
            read_only=meta.get("read_only", False),
            optional=default is None,
        )
    return specs


def check_params(specs: dict[str, ParamSpec], values: dict[str, Any], owner: str) -> dict[str, Any]:
    """Defaults of ``specs`` updated with ``values``, each checked; unknown names raise InvalidRequest."""
    out = {name: spec.default for name, spec in specs.items()}
    for name, value in (values or {}).items():
        spec = specs.get(name)
        if spec is None:
            known = ", ".join(specs) or "none"
            raise InvalidRequest(f"{owner} has no parameter {name!r}; known: {known}")
        out[name] = spec.check(value)
    return out


def _bound(value: float | None, infinite: str = "inf") -> str:
    return infinite if value is None else f"{value:g}"

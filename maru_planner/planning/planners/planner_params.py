"""OMPL's planner parameter mechanism (``ompl::base::ParamSet``) for planners driven from Python.

In C++ every OMPL planner declares its parameters in its constructor
(``declareParam<double>("range", this, &RRT::setRange, &RRT::getRange, "0.:1.:10000.")``) and
callers set them by name through ``planner->params()``. OMPL 2.0.1's nanobind bindings do not
expose ``ParamSet`` (``Planner.params()`` raises "Unable to convert function return value"), so
this module provides the same mechanism on the Python side:

* a Python planner (:class:`~maru_planner.planning.planners.rc_rrt.RCRRT`) owns a :class:`PlannerParams`
  (:func:`stored_params`: values in a dict) and returns it from ``params()``;
* an OMPL C++ planner gets a :class:`PlannerParams` bound to the setters and getters its C++
  constructor declares, under the same names (:func:`ompl_params`).

Each parameter is described by a :class:`~maru_planner.params.ParamSpec` (default, range,
description), so a value is checked once, with a message naming the parameter, before the setter runs.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from functools import partial
from typing import Any

from maru_planner.errors import InvalidRequest
from maru_planner.params import ParamSpec


@dataclass(frozen=True)
class _Declared:
    spec: ParamSpec
    setter: Callable[[Any], object]
    getter: Callable[[], Any]


#: Upper bound of a joint-space distance parameter (rad): far beyond any arm's extent, so only absurd values fail.
MAX_JOINT_DISTANCE = 100.0
#: Upper bound of a neighbour or candidate count (a k-nearest query of that many nodes per sample).
MAX_NEIGHBOURS = 1000
SEED_MAX = 2**63 - 1  # a ROS integer parameter holds an int64

#: Our sampling planners' seed parameter (RCRRT, CompiledRRTConnect).
SAMPLER_SEED = ParamSpec(
    "seed",
    None,
    "seed of the sampler; unset: drawn from OMPL's seeded generator",
    lower=0,
    upper=SEED_MAX,
    optional=True,
    type=int,
)


class PlannerParams:
    """The named parameters of one planner instance: declare once, then set/get by name."""

    def __init__(self, owner: str):
        self.owner = owner
        self._declared: dict[str, _Declared] = {}

    def declare_param(self, spec: ParamSpec, setter: Callable[[Any], object], getter: Callable[[], Any]) -> None:
        """Make ``spec.name`` settable: values are checked against ``spec``, then passed to ``setter``."""
        self._declared[spec.name] = _Declared(spec, setter, getter)

    def param_names(self) -> list[str]:
        return list(self._declared)

    def set_param(self, name: str, value: Any) -> None:
        """Check ``value`` against the parameter's spec and apply it; InvalidRequest names the culprit."""
        self._lookup(name).setter(self._lookup(name).spec.check(value))

    def get_param(self, name: str) -> Any:
        return self._lookup(name).getter()

    def set_params(self, values: Mapping[str, Any]) -> None:
        for name, value in values.items():
            self.set_param(name, value)

    def _lookup(self, name: str) -> _Declared:
        declared = self._declared.get(name)
        if declared is None:
            known = ", ".join(self._declared) or "none"
            raise InvalidRequest(f"planner {self.owner} has no parameter {name!r}; known: {known}", source="planner")
        return declared


def stored_params(owner: str, specs: Mapping[str, ParamSpec]) -> tuple[PlannerParams, dict[str, Any]]:
    """A Python planner's :class:`PlannerParams` whose values live in the returned dict (the specs' defaults)."""
    values = {name: spec.default for name, spec in specs.items()}
    params = PlannerParams(owner)
    for name, spec in specs.items():
        params.declare_param(spec, partial(values.__setitem__, name), partial(values.__getitem__, name))
    return params, values


def ompl_params(
    planner: object, specs: Mapping[str, ParamSpec], accessors: Mapping[str, tuple[str, str]]
) -> PlannerParams:
    """A :class:`PlannerParams` on an OMPL C++ planner: name → (setter, getter) method names it declares."""
    params = PlannerParams(str(planner.getName()))  # type: ignore[attr-defined]
    for name, (setter, getter) in accessors.items():
        params.declare_param(specs[name], getattr(planner, setter), getattr(planner, getter))
    return params

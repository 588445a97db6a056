"""ROS parameters from :class:`~maru_planner.params.ParamSpec` s, as Nav2's servers declare theirs.

Three pieces, used together by every node:

- :func:`declare_parameters` declares each spec with a descriptor (type, description with the
  range or choices, ``FloatingPointRange``/``IntegerRange`` where bounded, ``read_only``; dynamic
  typing only for an optional spec, whose value may be unset) and returns the start-up values,
  each checked by :meth:`ParamSpec.check`. A wrong type or an out-of-range value raises
  :class:`~maru_planner.errors.InvalidParameter` with one line naming the parameter.
- :func:`add_on_set_parameters_callback` validates every run-time change with ``ParamSpec.check``
  and hands the accepted ones to a function of the node; what that function raises (a
  ``MaruError``/``ValueError``) rejects the change with its message as the reason. Read-only
  parameters are rejected by rclpy itself, from their descriptor ("Trying to set a read-only
  parameter: <name>.").
- :func:`prefixed` renames specs into a parameter namespace (``planners.PRM.``).

Usage in a node::

    from maru_planner.params import ParamSpec
    from maru_planner.ros import parameters

    SPECS = {
        "resolution": ParamSpec("resolution", 0.02, "edge check step (rad)", lower=1e-4, upper=1.0),
        "robot_urdf": ParamSpec("robot_urdf", "", "URDF path", read_only=True),
    }

    class MyNode(Node):
        def __init__(self):
            super().__init__("my_node")
            self.settings = parameters.declare_parameters(self, SPECS)  # may raise InvalidParameter
            parameters.add_on_set_parameters_callback(self, SPECS, self._apply)

        def _apply(self, changes: dict[str, Any]) -> None:
            self.settings.update(changes)  # raise MaruError/ValueError to reject with a reason

    def main():
        rclpy.init()
        try:
            node = MyNode()
        except InvalidParameter as exc:
            rclpy.logging.get_logger("my_node").fatal(str(exc))  # one line, no traceback
            return 2
        ...

An array spec takes its element type from its default's items; an empty default is a string
array (ROS cannot infer the type of ``[]``) and reads as the default while unset.
"""

from __future__ import annotations

import array
import dataclasses
import math
from collections.abc import Callable, Mapping
from typing import Any

from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor, SetParametersResult
from rclpy.exceptions import InvalidParameterTypeException, InvalidParameterValueException
from rclpy.node import Node
from rclpy.parameter import Parameter

from maru_planner.errors import InvalidParameter, MaruError
from maru_planner.params import ParamSpec

INT64_MIN, INT64_MAX = -(2**63), 2**63 - 1

_SCALAR_TYPES = {
    bool: Parameter.Type.BOOL,
    int: Parameter.Type.INTEGER,
    float: Parameter.Type.DOUBLE,
    str: Parameter.Type.STRING,
}
_ARRAY_TYPES = {
    bool: Parameter.Type.BOOL_ARRAY,
    int: Parameter.Type.INTEGER_ARRAY,
    float: Parameter.Type.DOUBLE_ARRAY,
    str: Parameter.Type.STRING_ARRAY,
}

ApplyChanges = Callable[[dict[str, Any]], None]


def ros_type(spec: ParamSpec) -> Parameter.Type:
    """The ROS parameter type of ``spec`` (TypeError for a type ROS parameters cannot hold, e.g. dict)."""
    kind = spec.value_type
    if kind in _SCALAR_TYPES:
        return _SCALAR_TYPES[kind]
    if kind in (list, tuple):
        items = list(spec.default or [])
        if items and all(isinstance(v, bool) for v in items):
            return Parameter.Type.BOOL_ARRAY
        if items and all(isinstance(v, int) and not isinstance(v, bool) for v in items):
            return Parameter.Type.INTEGER_ARRAY
        if items and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in items):
            return Parameter.Type.DOUBLE_ARRAY
        return Parameter.Type.STRING_ARRAY
    raise TypeError(f"parameter {spec.name!r}: a {kind} value cannot be a ROS parameter")


def descriptor(spec: ParamSpec) -> ParameterDescriptor:
    """The descriptor of ``spec``: type, description (with range/choices), range, read-only."""
    desc = ParameterDescriptor(
        name=spec.name, description=spec.describe(), read_only=spec.read_only, dynamic_typing=spec.optional
    )
    if not spec.optional:
        desc.type = ros_type(spec).value
    if spec.choices:
        desc.additional_constraints = "one of: " + ", ".join(spec.choices)
    bounded = spec.lower is not None or spec.upper is not None
    if bounded and spec.value_type is float:
        desc.floating_point_range = [
            FloatingPointRange(
                from_value=-math.inf if spec.lower is None else float(spec.lower),
                to_value=math.inf if spec.upper is None else float(spec.upper),
            )
        ]
    elif bounded and spec.value_type is int:
        desc.integer_range = [
            IntegerRange(
                from_value=INT64_MIN if spec.lower is None else math.ceil(spec.lower),
                to_value=INT64_MAX if spec.upper is None else math.floor(spec.upper),
            )
        ]
    return desc


def prefixed(specs: Mapping[str, ParamSpec], prefix: str) -> dict[str, ParamSpec]:
    """``specs`` renamed ``<prefix>.<name>`` (keys and ``ParamSpec.name``), e.g. ``planners.PRM``."""
    return {f"{prefix}.{name}": dataclasses.replace(spec, name=f"{prefix}.{name}") for name, spec in specs.items()}


def declare_parameters(node: Node, specs: Mapping[str, ParamSpec]) -> dict[str, Any]:
    """Declare every spec (key = parameter name) on ``node``; return the checked start-up values.

    Raises InvalidParameter (one line naming the parameter) for a value of the wrong type or
    outside its range/choices, from a params file or ``-p``.
    """
    for name, spec in specs.items():
        _declare(node, name, spec)
    return read_parameters(node, specs)


def read_parameters(node: Node, specs: Mapping[str, ParamSpec]) -> dict[str, Any]:
    """The current values of the declared ``specs``, each checked (InvalidParameter if bad)."""
    return {name: read_parameter(node, name, spec) for name, spec in specs.items()}


def read_parameter(node: Node, name: str, spec: ParamSpec) -> Any:
    """The current value of declared parameter ``name``, checked by ``spec`` (InvalidParameter if bad)."""
    unset = Parameter(name, value=_ros_value(spec.default))
    return _checked(spec, node.get_parameter_or(name, unset).value)


def add_on_set_parameters_callback(
    node: Node, specs: Mapping[str, ParamSpec], apply: ApplyChanges
) -> Callable[[list[Parameter]], SetParametersResult]:
    """Validate run-time changes of ``specs`` and pass the accepted ones to ``apply``; return the callback.

    ``apply`` gets ``{name: checked value}`` for the parameters of ``specs`` in one
    ``set_parameters`` call (others are left to other callbacks) before rclpy stores them, so
    it must use the values it is given. A ``MaruError``/``ValueError`` it raises rejects the
    whole change with that message as the reason; nothing is stored then.
    """

    def on_set(changed: list[Parameter]) -> SetParametersResult:
        unset = [p.name for p in changed if p.name in specs and p.type_ == Parameter.Type.NOT_SET]
        if unset:  # rclpy would undeclare them
            return SetParametersResult(successful=False, reason=f"parameter {unset[0]!r} cannot be unset at run time")
        try:
            accepted = {p.name: _checked(specs[p.name], p.value) for p in changed if p.name in specs}
            if accepted:
                apply(accepted)
        except (MaruError, ValueError) as exc:
            return SetParametersResult(successful=False, reason=str(exc))
        return SetParametersResult(successful=True)

    node.add_on_set_parameters_callback(on_set)
    return on_set


def _declare(node: Node, name: str, spec: ParamSpec) -> None:
    desc = descriptor(spec)
    default = _ros_value(spec.default)
    # an empty array carries no element type: declare the type, the value stays unset until given
    value = ros_type(spec) if default == [] and not spec.optional else default
    try:
        node.declare_parameter(name, value, desc)
    except InvalidParameterTypeException as exc:
        expected = "any type" if spec.optional else ros_type(spec).name.lower().replace("_", " ")
        raise InvalidParameter(f"parameter {name!r} must be a {expected}: {_first_part(exc)}") from None
    except InvalidParameterValueException as exc:
        reason = _first_part(exc).split("Reason: ", 1)[-1]
        raise InvalidParameter(f"parameter {name!r} rejected: {reason} ({spec.describe()})") from None


def _checked(spec: ParamSpec, value: Any) -> Any:
    try:
        return spec.check(_python_value(value, spec))
    except MaruError as exc:
        raise InvalidParameter(str(exc)) from None


def _ros_value(value: Any) -> Any:
    """A Python default as rclpy declares it (tuples become lists)."""
    return list(value) if isinstance(value, tuple) else value


def _python_value(value: Any, spec: ParamSpec) -> Any:
    """A parameter value as ``spec`` checks it: arrays (rclpy gives ``array.array``) as the spec's list/tuple."""
    if not isinstance(value, (array.array, list, tuple)):
        return value
    if spec.value_type is tuple:
        return tuple(value)
    return list(value) if spec.value_type is list else value


def _first_part(exc: Exception) -> str:
    """rclpy's message without the ``: <parameter name>`` suffix its ParameterException adds."""
    return str(exc).rsplit(": ", 1)[0]

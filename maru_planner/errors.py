"""Typed errors of the core. Nodes map each class to an error code in one place.

Every error carries ``source`` (the stage that raised it) and a message that
names what is wrong (the joint, obstacle, link or field).
"""

from __future__ import annotations

MESSAGE_LIMIT = 300  # characters of an error message a node or CLI passes on (a bad value is quoted as an excerpt)


def one_line(message: object, limit: int = MESSAGE_LIMIT) -> str:
    """``message`` as one line of at most ``limit`` characters (whitespace runs collapsed, the rest cut)."""
    text = " ".join(str(message).split())
    return text if len(text) <= limit else text[: limit - 3] + "..."


EXCERPT_LIMIT = 60  # characters of a bad value quoted in a message


def excerpt(value: object, limit: int = EXCERPT_LIMIT, *, tail: bool = False) -> str:
    """``repr`` of a bad value cut to ``limit`` characters; ``tail`` keeps the end (a path's file name)."""
    text = repr(value)
    if len(text) <= limit:
        return text
    return "..." + text[-(limit - 3) :] if tail else text[: limit - 3] + "..."


class MaruError(Exception):
    """Base of all maru_planner errors."""

    source = "core"

    def __init__(self, message: str, *, source: str | None = None):
        super().__init__(message)
        if source is not None:
            self.source = source

    @property
    def message(self) -> str:
        return str(self)


class InvalidRequest(MaruError, ValueError):
    """A request field is invalid (e.g. a time budget <= 0)."""

    source = "validation"


class InvalidParameter(InvalidRequest):
    """A node parameter has the wrong type, is out of range or cannot change at run time."""

    source = "parameters"


class Busy(MaruError):
    """A node's bounded request queue is full; the request was not started (retry later)."""

    source = "node"


class InvalidGroup(InvalidRequest):
    """The planning group does not exist."""


class InvalidPlanner(InvalidRequest):
    """The planner id is not registered."""


class InvalidJointNames(InvalidRequest):
    """Unknown, duplicated or missing joint names."""


class InvalidJointCount(InvalidRequest):
    """The number of values does not match the names or the group."""


class InvalidState(InvalidRequest):
    """A joint value is NaN/inf or outside its limits."""


class NoStartState(InvalidRequest):
    """No start state was given and none is known."""


class InCollision(MaruError):
    """A configuration collides; ``pairs`` names the colliding bodies."""

    source = "collision"

    def __init__(self, message: str, pairs: list[tuple[str, str]] | None = None, **kwargs):
        super().__init__(message, **kwargs)
        self.pairs = list(pairs or [])


class StartInCollision(InCollision):
    """The start configuration collides."""


class GoalInCollision(InCollision):
    """The goal configuration collides."""


class NoIKSolution(MaruError):
    """Inverse kinematics found no configuration reaching the target(s)."""

    source = "ik"


class InvalidScene(MaruError, ValueError):
    """A scene or obstacle is malformed; the message names the obstacle and field."""

    source = "scene"


class PlanningFailed(MaruError):
    """The planner found no path within its attempts."""

    source = "planner"


class PlanningTimedOut(PlanningFailed):
    """The time budget ran out."""


class PlanningCancelled(PlanningFailed):
    """The caller cancelled the request (e.g. an action goal's cancel) before it finished."""


class StartOutsideMap(InvalidRequest):
    """The start pose lies outside the map."""


class GoalOutsideMap(InvalidRequest):
    """The goal pose lies outside the map."""


class StartOccupied(StartInCollision):
    """The robot at the start pose covers an obstacle of the map."""


class GoalOccupied(GoalInCollision):
    """The robot at the goal pose covers an obstacle of the map."""


class InvalidMap(InvalidRequest):
    """A map file or map message is malformed; the message names the file or field."""


class TooLarge(InvalidRequest):
    """A map, world or search exceeds a size or memory limit (refused before allocating)."""


class NoPath(PlanningFailed):
    """The search finished without finding a path."""


class NoPathProven(NoPath):
    """No path exists, decided without a search (e.g. the start is enclosed)."""


class InvalidLink(InvalidRequest):
    """A link (frame) name the robot does not have."""


class InvalidObject(InvalidScene):
    """An attach/detach names an object the scene does not have (or an attached object that is not)."""


class ObjectAlreadyAttached(InvalidObject):
    """An object is attached again, or a new obstacle takes the name of an attached object."""


class StartViolatesConstraints(InvalidRequest):
    """The start state already breaks the request's path constraints (they cannot hold along the motion)."""

    source = "constraints"

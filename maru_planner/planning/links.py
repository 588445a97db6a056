"""Link names of a robot, checked with one-line errors (used by FK, Cartesian paths and the CLI)."""

from __future__ import annotations

import pinocchio as pin

from maru_planner import errors


def link_names(robot) -> list[str]:
    """The robot's links: its body frames, in model order."""
    return [f.name for f in robot.model.frames if f.type == pin.FrameType.BODY]


def check_link(robot, link: str, what: str = "link") -> int:
    """The frame id of ``link``; InvalidLink naming it (and a few known links) otherwise."""
    if not isinstance(link, str) or not link or not robot.model.existFrame(link):
        known = link_names(robot)
        shown = ", ".join(known[:8]) + (", ..." if len(known) > 8 else "")
        raise errors.InvalidLink(f"{what} {link!r} is not a link of {robot.name} (links: {shown})")
    return robot.model.getFrameId(link)

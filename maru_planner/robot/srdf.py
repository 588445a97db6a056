"""A small SRDF reader: groups, group states, end effectors, disabled collision pairs.

Groups may list ``<joint>``, ``<chain base_link tip_link>`` and nested
``<group>`` elements (``<link>`` elements are ignored: planning groups here
are joint sets). Chains are expanded by the caller, who knows the kinematic
tree, through the ``chain_joints`` callback.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path


@dataclass
class SrdfInfo:
    groups: dict[str, list[str]] = field(default_factory=dict)
    group_states: dict[str, dict[str, float]] = field(default_factory=dict)
    end_effectors: dict[str, str] = field(default_factory=dict)  # name -> parent link
    disabled_pairs: set[frozenset[str]] = field(default_factory=set)


def _resolve_group(
    name: str,
    elements: dict[str, ET.Element],
    chain_joints: Callable[[str, str], list[str]],
    resolving: tuple[str, ...] = (),
) -> list[str]:
    if name in resolving:
        raise ValueError(f"SRDF group {name!r} includes itself")
    joints: list[str] = []
    for child in elements[name]:
        if child.tag == "joint":
            joints.append(child.attrib["name"])
        elif child.tag == "chain":
            joints += chain_joints(child.attrib["base_link"], child.attrib["tip_link"])
        elif child.tag == "group":
            sub = child.attrib["name"]
            if sub not in elements:
                raise ValueError(f"SRDF group {name!r} refers to unknown group {sub!r}")
            joints += _resolve_group(sub, elements, chain_joints, (*resolving, name))
    return list(dict.fromkeys(joints))


def parse_srdf(source: str | Path, chain_joints: Callable[[str, str], list[str]]) -> SrdfInfo:
    """Parse an SRDF file (path) or text (string starting with '<'); ValueError (one line) when it is not one."""
    is_text = isinstance(source, str) and source.lstrip().startswith("<")
    text = str(source) if is_text else Path(source).read_text()
    where = "text" if is_text else str(source)
    try:
        return _read(ET.fromstring(text), chain_joints)
    except ET.ParseError as exc:
        raise ValueError(f"SRDF {where}: not valid XML ({exc})") from None
    except KeyError as exc:
        raise ValueError(f"SRDF {where}: an element lacks its attribute {exc}") from None


def _read(root: ET.Element, chain_joints: Callable[[str, str], list[str]]) -> SrdfInfo:
    info = SrdfInfo()
    elements = {g.attrib["name"]: g for g in root.findall("group")}
    for name in elements:
        info.groups[name] = _resolve_group(name, elements, chain_joints)
    for state in root.findall("group_state"):
        # multi-value joints (a free-flyer's 7 numbers) are not planning joints: skipped
        scalar = [j for j in state.findall("joint") if " " not in j.attrib["value"].strip()]
        values = {j.attrib["name"]: float(j.attrib["value"]) for j in scalar}
        info.group_states[state.attrib["name"]] = values
    for ee in root.findall("end_effector"):
        info.end_effectors[ee.attrib["name"]] = ee.attrib["parent_link"]
    for pair in root.findall("disable_collisions"):
        info.disabled_pairs.add(frozenset((pair.attrib["link1"], pair.attrib["link2"])))
    return info

"""Sampling-based SRDF disabled pairs on a tiny robot whose answer is known."""

from __future__ import annotations

from maru_planner.robot.disabled_collisions import compute_disabled_collisions

URDF = """<robot name="toy">
  <link name="base"><collision><geometry><box size="0.2 0.2 0.2"/></geometry></collision></link>
  <link name="far"><collision><origin xyz="0 0 0"/><geometry><sphere radius="0.05"/></geometry></collision></link>
  <link name="arm"><collision><origin xyz="0.3 0 0"/><geometry><box size="0.4 0.05 0.05"/></geometry></collision></link>
  <link name="tip"><collision><origin xyz="0.25 0 0"/><geometry><box size="0.5 0.04 0.04"/></geometry>
  </collision></link>
  <joint name="fixed_far" type="fixed"><parent link="base"/><child link="far"/><origin xyz="3 0 0"/></joint>
  <joint name="j1" type="revolute"><parent link="base"/><child link="arm"/><axis xyz="0 0 1"/>
    <limit lower="-3.1" upper="3.1" effort="1" velocity="1"/></joint>
  <joint name="j2" type="revolute"><parent link="arm"/><child link="tip"/><origin xyz="0.5 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-3.1" upper="3.1" effort="1" velocity="1"/></joint>
</robot>"""


def test_adjacent_never_and_kept_pairs():
    reasons = {frozenset((a, b)): r for a, b, r in compute_disabled_collisions(URDF, n_samples=2000, seed=1)}
    assert reasons[frozenset(("base", "arm"))] == "Adjacent"
    assert reasons[frozenset(("arm", "tip"))] == "Adjacent"
    assert reasons[frozenset(("base", "far"))] == "Adjacent"  # welded to the base by a fixed joint
    assert reasons[frozenset(("far", "arm"))] == "Never"  # 3 m away, the arm reaches 0.5 m
    assert frozenset(("base", "tip")) not in reasons  # the tip can fold back onto the base

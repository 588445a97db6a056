"""Elastic-strip forces (eq. 36, 38-41), the strip window and IsSort."""

from __future__ import annotations

import numpy as np
import pytest

from maru_planner.reactive.forces import (
    internal_forces,
    modified_external_forces,
    plain_external_forces,
    remove_tangential,
    repulsion,
    side_nearest,
    unit_tangents,
)
from maru_planner.reactive.strip import ElasticStrip, resample_path
from maru_planner.reactive.vias import ViaTarget, is_sort

K_R, K_C, D0 = 0.5, 0.3, 0.75
EAST = np.array([[1.0, 0.0]])


def test_internal_force_is_zero_on_evenly_spaced_straight_strip():
    vias = np.stack([np.linspace(0, 3, 7), np.zeros(7)], axis=1)
    assert np.allclose(internal_forces(vias, K_C), 0.0)


def test_internal_force_pulls_bent_via_back_to_the_chord():
    vias = np.array([[0.0, 0.0], [1.0, 0.6], [2.0, 0.0]])
    f = internal_forces(vias, K_C)
    assert f[0] == pytest.approx([0, 0]) and f[2] == pytest.approx([0, 0])
    # ratio 1/2: target (1, 0); f = k_c * ((1, 0) - (1, 0.6))
    assert f[1] == pytest.approx([0.0, -K_C * 0.6])


def test_internal_force_keeps_spacing_ratio():
    vias = np.array([[0.0, 0.0], [0.5, 0.0], [3.0, 0.0]])  # straight but uneven: keeps the ratio, no force
    assert np.allclose(internal_forces(vias, K_C), 0.0)


def test_plain_repulsion_direction_and_magnitude():
    via = np.array([[0.0, 0.0]])
    pts = np.array([[0.3, 0.4], [3.0, 0.0]])  # nearest at distance 0.5
    f = plain_external_forces(via, pts, D0, K_R)[0]
    assert np.linalg.norm(f) == pytest.approx(K_R * (D0 - 0.5))
    assert f / np.linalg.norm(f) == pytest.approx([-0.6, -0.8])


def test_no_force_beyond_d0():
    assert np.allclose(plain_external_forces(np.zeros((1, 2)), np.array([[0.8, 0.0]]), D0, K_R), 0.0)
    assert np.allclose(repulsion(np.array([[1.0, 0.0]]), np.array([np.inf]), D0, K_R), 0.0)


def test_side_nearest_splits_left_and_right_of_the_direction():
    pts = np.array([[0.2, 0.5], [0.0, 0.4], [0.1, -0.3], [0.0, -2.0]])
    _, d_l, _, d_r = side_nearest(np.zeros((1, 2)), EAST, pts)
    assert d_l[0] == pytest.approx(0.4) and d_r[0] == pytest.approx(np.hypot(0.1, 0.3))
    _, d_l, _, d_r = side_nearest(np.zeros((1, 2)), EAST, pts[:2])
    assert np.isinf(d_r[0])


def test_modified_is_sum_of_left_and_right_repulsions():
    via = np.zeros((1, 2))
    pts = np.array([[0.0, 0.5], [0.0, -0.3]])  # a corridor: left 0.5 m, right 0.3 m
    f_mod = modified_external_forces(via, EAST, pts, D0, K_R)[0]
    expected = K_R * (D0 - 0.5) * np.array([0, -1]) + K_R * (D0 - 0.3) * np.array([0, 1])
    assert f_mod == pytest.approx(expected)
    # plain sees only the nearest (right) point and pushes harder to the left
    f_plain = plain_external_forces(via, pts, D0, K_R)[0]
    assert f_plain == pytest.approx(K_R * (D0 - 0.3) * np.array([0, 1]))
    assert f_plain[1] > f_mod[1] > 0


def test_balanced_corridor_centres_modified_strip():
    via = np.zeros((1, 2))
    pts = np.array([[0.0, 0.4], [0.0, -0.4]])
    assert np.allclose(modified_external_forces(via, EAST, pts, D0, K_R), 0.0)


def test_head_on_plain_pushes_straight_back_modified_turns_aside():
    """Paper's Fig. 18(a): the nearest point lies on the line to the goal."""
    via = np.zeros((1, 2))
    angles = np.linspace(-0.6, 0.6, 25)  # front face of a round obstacle centred on the strip
    centre = np.array([0.9, 0.0])
    pts = centre + 0.5 * np.stack([-np.cos(angles), np.sin(angles)], axis=1)
    f_plain = plain_external_forces(via, pts, D0, K_R)[0]
    assert f_plain[0] < 0 and abs(f_plain[1]) < 1e-9
    assert np.allclose(remove_tangential(f_plain[None], EAST), 0.0)  # nothing left to bend the strip
    f_mod = modified_external_forces(via, EAST, pts, D0, K_R)[0]
    assert abs(f_mod[1]) >= np.linalg.norm(f_plain) - 1e-9  # a sideways push of the stronger side's size
    assert f_mod[1] > 0  # exact tie -> left (prefer=+1)
    assert modified_external_forces(via, EAST, pts, D0, K_R, prefer=-1.0)[0][1] < 0


def test_head_on_turns_to_the_side_with_less_obstacle():
    via = np.zeros((1, 2))
    face = np.stack([np.full(9, 0.5), np.linspace(-0.1, 0.5, 9)], axis=1)  # wall across, mostly on the left
    f_mod = modified_external_forces(via, EAST, face, D0, K_R)[0]
    assert f_mod[1] < 0


def test_unit_tangents_follow_the_strip():
    vias = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]])
    t = unit_tangents(vias)
    assert t[0] == pytest.approx([1, 0]) and t[2] == pytest.approx([0, 1])
    assert t[1] == pytest.approx(np.array([1, 1]) / np.sqrt(2))


def test_resample_path_spacing():
    pts = resample_path(np.array([[0, 0], [3, 0], [3, 1]]), 0.5)
    steps = np.hypot(*np.diff(pts, axis=0).T)
    assert pts[0] == pytest.approx([0, 0]) and pts[-1] == pytest.approx([3, 1])
    assert np.all(steps <= 0.5 + 1e-9)


def test_strip_window_has_fixed_size_and_advances():
    strip = ElasticStrip(num_vias=6, spacing=0.5, k_c=K_C, k_r=K_R, d0=D0)
    strip.set_path(np.array([[0.0, 0.0], [10.0, 0.0]]))
    assert len(strip.vias) == 6
    strip.anchor((1.1, 0.0))
    vias = strip.vias
    assert len(vias) == 6 and vias[0] == pytest.approx([1.1, 0.0]) and vias[1][0] > 1.1
    for _ in range(4):  # at most num_vias shifts per update: a long jump takes a few updates
        strip.anchor((9.9, 0.0))
    assert len(strip.vias) <= 6 and strip.vias[-1] == pytest.approx([10.0, 0.0])


def test_strip_bends_around_obstacle_on_its_path():
    strip = ElasticStrip(num_vias=12, spacing=0.3, k_c=K_C, k_r=K_R, d0=D0, strip="modified")
    strip.set_path(np.array([[0.0, 0.0], [4.0, 0.0]]))
    angles = np.linspace(-1.2, 1.2, 40)
    pts = np.array([2.0, 0.0]) + 0.4 * np.stack([-np.cos(angles), np.sin(angles)], axis=1)
    for _ in range(30):
        strip.anchor((0.0, 0.0))
        strip.deform(pts)
    vias = strip.vias
    nearest = np.min(np.hypot(vias[:, None, 0] - pts[None, :, 0], vias[:, None, 1] - pts[None, :, 1]), axis=1)
    assert np.max(np.abs(vias[:, 1])) > 0.3  # bent sideways
    plain = ElasticStrip(num_vias=12, spacing=0.3, k_c=K_C, k_r=K_R, d0=D0, strip="plain")
    plain.set_path(np.array([[0.0, 0.0], [4.0, 0.0]]))
    for _ in range(30):
        plain.anchor((0.0, 0.0))
        plain.deform(pts)
    assert np.max(np.abs(plain.vias[:, 1])) < np.max(np.abs(vias[:, 1]))
    assert nearest.min() >= 0.0


@pytest.mark.parametrize(
    "candidate, rule, accepted",
    [
        ((1.0, 1.0), "either_axis", True),  # 1 m away on both axes
        ((1.0, 0.2), "either_axis", False),  # within 0.5 m on y -> dropped (paper's code)
        ((0.3, 0.3), "either_axis", False),
        ((1.0, 0.2), "both_axes", True),
        ((0.3, 0.3), "both_axes", False),
    ],
)
def test_is_sort(candidate, rule, accepted):
    assert is_sort(candidate, (0.0, 0.0), 0.5, rule) is accepted


def test_via_target_insert_filter_and_drop():
    via = ViaTarget(reach=0.3, blocked_radius=0.3)
    assert via.offer((2.0, 1.0), (5.0, 0.0), 0.5, "either_axis") and via.active
    assert not via.offer((2.2, 1.1), via.point, 0.5, "either_axis")  # too close to the current via
    assert via.filtered == 1 and via.point == pytest.approx([2.0, 1.0])
    via.refresh((0.0, 0.0), np.array([1.0, 0.0]), np.array([[2.1, 1.0]]))  # blocked by a new point
    assert not via.active
    via.offer((2.0, 1.0), (5.0, 0.0), 0.5, "either_axis")
    via.refresh((1.9, 1.0), np.array([1.0, 0.0]), np.zeros((0, 2)))  # reached
    assert not via.active

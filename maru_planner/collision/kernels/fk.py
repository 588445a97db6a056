"""Forward kinematics of a flattened kinematic tree, and points fixed in joint frames placed in the world (numba).

The tree's arrays (parent, joint kind, axis, fixed placement, index in q) come from
:class:`maru_planner.collision.kinematic_tree.KinematicTree`, whose vectorised numpy version is the reference the
tests compare these kernels against.
"""

from __future__ import annotations

import numpy as np
from numba import njit

FIXED, REVOLUTE, PRISMATIC, REVOLUTE_UNBOUNDED = 0, 1, 2, 3  # joint kinds


@njit(cache=True, inline="always")
def joint_pose_nb(j, q, parent, kind, axis, prot, ppos, idx_q, rot, pos):
    """Joint ``j``'s world pose, written into ``rot[j]`` and ``pos[j]`` from its parent's (already there).

    Plain loops on purpose (numba): 3x3 products unrolled beat BLAS calls; the parent's rotation times the
    placement is kept in scalars, not a scratch array allocated per call.
    """
    par = parent[j]
    for a in range(3):
        pos[j, a] = (pos[par, a] + rot[par, a, 0] * ppos[j, 0] + rot[par, a, 1] * ppos[j, 1]
                     + rot[par, a, 2] * ppos[j, 2])  # fmt: skip
    k = kind[j]
    revolute = k == REVOLUTE or k == REVOLUTE_UNBOUNDED
    if revolute:
        i = idx_q[j]
        ang = q[i] if k == REVOLUTE else np.arctan2(q[i + 1], q[i])
        x, y, z = axis[j, 0], axis[j, 1], axis[j, 2]
        c, s = np.cos(ang), np.sin(ang)
        t = 1.0 - c
        r00, r01, r02 = t * x * x + c, t * x * y - s * z, t * x * z + s * y
        r10, r11, r12 = t * x * y + s * z, t * y * y + c, t * y * z - s * x
        r20, r21, r22 = t * x * z - s * y, t * y * z + s * x, t * z * z + c
    for a in range(3):
        m0 = rot[par, a, 0] * prot[j, 0, 0] + rot[par, a, 1] * prot[j, 1, 0] + rot[par, a, 2] * prot[j, 2, 0]
        m1 = rot[par, a, 0] * prot[j, 0, 1] + rot[par, a, 1] * prot[j, 1, 1] + rot[par, a, 2] * prot[j, 2, 1]
        m2 = rot[par, a, 0] * prot[j, 0, 2] + rot[par, a, 1] * prot[j, 1, 2] + rot[par, a, 2] * prot[j, 2, 2]
        if revolute:
            rot[j, a, 0] = m0 * r00 + m1 * r10 + m2 * r20
            rot[j, a, 1] = m0 * r01 + m1 * r11 + m2 * r21
            rot[j, a, 2] = m0 * r02 + m1 * r12 + m2 * r22
        else:
            rot[j, a, 0], rot[j, a, 1], rot[j, a, 2] = m0, m1, m2
            if k == PRISMATIC:
                pos[j, a] += q[idx_q[j]] * (m0 * axis[j, 0] + m1 * axis[j, 1] + m2 * axis[j, 2])


@njit(cache=True, inline="always")
def root_pose_nb(rot, pos):
    """The root (world) joint's pose: identity."""
    for a in range(3):
        pos[0, a] = 0.0
        for b in range(3):
            rot[0, a, b] = 1.0 if a == b else 0.0


@njit(cache=True)
def joint_poses_nb(q, parent, kind, axis, prot, ppos, idx_q, rot, pos):
    """One configuration's joint world poses, written into ``rot`` (nj,3,3) and ``pos`` (nj,3)."""
    root_pose_nb(rot, pos)
    for j in range(1, parent.shape[0]):
        joint_pose_nb(j, q, parent, kind, axis, prot, ppos, idx_q, rot, pos)


def _sphere_centers_py(rot, pos, sphere_joint, sphere_local, out):
    """World centres of spheres fixed in joint frames: out[s] = R[joint] @ local + p[joint]."""
    for s in range(sphere_joint.shape[0]):
        j = sphere_joint[s]
        for a in range(3):
            out[s, a] = (
                pos[j, a]
                + rot[j, a, 0] * sphere_local[s, 0]
                + rot[j, a, 1] * sphere_local[s, 1]
                + rot[j, a, 2] * sphere_local[s, 2]
            )


sphere_centers_nb = njit(cache=True)(_sphere_centers_py)


@njit(cache=True)
def frame_placements_nb(rot, pos, frame_joint, local_rot, local_pos, out_rot, out_pos):
    """World placements of frames fixed in joint frames: R[joint] @ local_rot and R[joint] @ local_pos + p[joint]."""
    sphere_centers_nb(rot, pos, frame_joint, local_pos, out_pos)
    for f in range(frame_joint.shape[0]):
        j = frame_joint[f]
        for a in range(3):
            for b in range(3):
                out_rot[f, a, b] = (rot[j, a, 0] * local_rot[f, 0, b] + rot[j, a, 1] * local_rot[f, 1, b]
                                    + rot[j, a, 2] * local_rot[f, 2, b])  # fmt: skip


@njit(cache=True, inline="always")
def point_in_world(rot, pos, joint, local, i):
    """World position of ``local[i]``, fixed in the frame of joint ``joint[i]`` (sphere_centers_nb's arithmetic)."""
    j = joint[i]
    x = pos[j, 0] + rot[j, 0, 0] * local[i, 0] + rot[j, 0, 1] * local[i, 1] + rot[j, 0, 2] * local[i, 2]
    y = pos[j, 1] + rot[j, 1, 0] * local[i, 0] + rot[j, 1, 1] * local[i, 1] + rot[j, 1, 2] * local[i, 2]
    z = pos[j, 2] + rot[j, 2, 0] * local[i, 0] + rot[j, 2, 1] * local[i, 1] + rot[j, 2, 2] * local[i, 2]
    return x, y, z


@njit(cache=True, inline="always")
def place_points(rot, pos, joint, local, first, end, world):
    """World positions of ``local[first:end]`` into ``world[first:end]``."""
    for i in range(first, end):
        world[i, 0], world[i, 1], world[i, 2] = point_in_world(rot, pos, joint, local, i)


@njit(cache=True, inline="always")
def place_members(owner, start, placed, rot, pos, joint, local, world):
    """Place the members ``start[owner]:start[owner + 1]`` of a group (its clusters) or of a cluster (its spheres),
    unless ``placed[owner]`` says they already are for this state."""
    if not placed[owner]:
        placed[owner] = True
        place_points(rot, pos, joint, local, start[owner], start[owner + 1], world)


@njit(cache=True, inline="always")
def row_distance(world_a, a, world_b, b):
    """Distance between the points ``world_a[a]`` and ``world_b[b]``, indexed: row views in a kernel's inner loop
    cost more than the distance (numba counts their references)."""
    dx, dy, dz = world_a[a, 0] - world_b[b, 0], world_a[a, 1] - world_b[b, 1], world_a[a, 2] - world_b[b, 2]
    return np.sqrt(dx * dx + dy * dy + dz * dz)

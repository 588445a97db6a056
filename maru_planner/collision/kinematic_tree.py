"""A pinocchio kinematic tree as flat arrays, and its forward kinematics for many configurations at once (numpy).

The tree is flattened into plain arrays (parent, joint kind, axis, fixed placement, index in q) so
that the same data drives the numba kernels (:mod:`maru_planner.collision.kernels.fk`, used inside the batched
collision kernels) and a vectorised numpy version (:func:`batch_joint_poses`), which is the fallback
and the reference the tests compare against pinocchio.

Supported joints: revolute about any axis (``RX``/``RY``/``RZ``/``RevoluteUnaligned``), unbounded
revolute (``RUBX``… stored as ``(cos, sin)`` in q), prismatic about any axis (``PX``/``PY``/``PZ``/
``PrismaticUnaligned``). Fixed joints are already folded into the placements by pinocchio.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from maru_planner.collision.kernels.fk import PRISMATIC, REVOLUTE, REVOLUTE_UNBOUNDED


@dataclass(frozen=True)
class KinematicTree:
    """A pinocchio model's joints as flat arrays (index 0 = the universe, the world frame)."""

    parent: np.ndarray  # (nj,) int64, parent joint index (parent[j] < j)
    kind: np.ndarray  # (nj,) int64, FIXED / REVOLUTE / PRISMATIC / REVOLUTE_UNBOUNDED
    axis: np.ndarray  # (nj, 3) unit axis in the joint frame
    placement_rot: np.ndarray  # (nj, 3, 3) joint placement in the parent joint frame
    placement_pos: np.ndarray  # (nj, 3)
    idx_q: np.ndarray  # (nj,) int64, first index in q (-1 for the universe)
    nq: int
    joint_names: tuple[str, ...]

    @property
    def njoints(self) -> int:
        return len(self.parent)

    @classmethod
    def from_pinocchio(cls, model) -> KinematicTree:
        """Flatten a pinocchio ``Model``; unsupported joint types raise ``ValueError`` naming the joint."""
        nj = model.njoints
        data = model.createData()
        pin.forwardKinematics(model, data, pin.neutral(model))
        parent = np.zeros(nj, dtype=np.int64)
        kind = np.zeros(nj, dtype=np.int64)
        axis = np.zeros((nj, 3))
        rot = np.tile(np.eye(3), (nj, 1, 1))
        pos = np.zeros((nj, 3))
        idx_q = np.full(nj, -1, dtype=np.int64)
        for j in range(1, nj):
            joint = model.joints[j]
            parent[j] = model.parents[j]
            rot[j] = model.jointPlacements[j].rotation
            pos[j] = model.jointPlacements[j].translation
            idx_q[j] = joint.idx_q
            kind[j], axis[j] = _joint_kind(model.names[j], joint, np.asarray(data.joints[j].S).ravel())
        return cls(parent, kind, axis, rot, pos, idx_q, int(model.nq), tuple(model.names))


def _joint_kind(name: str, joint, motion_subspace: np.ndarray) -> tuple[int, np.ndarray]:
    short = joint.shortname()
    linear, angular = motion_subspace[:3], motion_subspace[3:]
    if joint.nv != 1:
        raise ValueError(f"joint '{name}' ({short}) has {joint.nv} DOF: only 1-DOF joints are supported")
    if short.startswith("JointModelRUB"):
        return REVOLUTE_UNBOUNDED, angular / np.linalg.norm(angular)
    if joint.nq == 1 and np.linalg.norm(linear) < 1e-12 and np.linalg.norm(angular) > 0.5:
        return REVOLUTE, angular / np.linalg.norm(angular)
    if joint.nq == 1 and np.linalg.norm(angular) < 1e-12 and np.linalg.norm(linear) > 0.5:
        return PRISMATIC, linear / np.linalg.norm(linear)
    raise ValueError(f"joint '{name}' ({short}) is not a revolute or prismatic joint")


def _axis_angle_rot(axis: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """Rotation matrices (n, 3, 3) about one unit ``axis`` by each of ``angle`` (n,)."""
    x, y, z = axis
    c, s = np.cos(angle), np.sin(angle)
    t = 1.0 - c
    out = np.empty((len(angle), 3, 3))
    out[:, 0, 0] = t * x * x + c
    out[:, 0, 1] = t * x * y - s * z
    out[:, 0, 2] = t * x * z + s * y
    out[:, 1, 0] = t * x * y + s * z
    out[:, 1, 1] = t * y * y + c
    out[:, 1, 2] = t * y * z - s * x
    out[:, 2, 0] = t * x * z - s * y
    out[:, 2, 1] = t * y * z + s * x
    out[:, 2, 2] = t * z * z + c
    return out


def batch_joint_poses(tree: KinematicTree, qs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """World poses of every joint for a batch ``qs`` (n, nq): rotations (n, nj, 3, 3), positions (n, nj, 3)."""
    qs = np.atleast_2d(np.asarray(qs, dtype=float))
    n = qs.shape[0]
    rot = np.empty((n, tree.njoints, 3, 3))
    pos = np.empty((n, tree.njoints, 3))
    rot[:, 0] = np.eye(3)
    pos[:, 0] = 0.0
    for j in range(1, tree.njoints):
        par = tree.parent[j]
        r = rot[:, par] @ tree.placement_rot[j]
        p = pos[:, par] + rot[:, par] @ tree.placement_pos[j]
        k, i = tree.kind[j], tree.idx_q[j]
        if k == REVOLUTE:
            r = r @ _axis_angle_rot(tree.axis[j], qs[:, i])
        elif k == REVOLUTE_UNBOUNDED:
            r = r @ _axis_angle_rot(tree.axis[j], np.arctan2(qs[:, i + 1], qs[:, i]))
        elif k == PRISMATIC:
            p = p + (r @ tree.axis[j]) * qs[:, i : i + 1]
        rot[:, j], pos[:, j] = r, p
    return rot, pos


def tree_arrays(tree: KinematicTree) -> tuple:
    """The argument tuple the numba kernels take after ``q``."""
    return (tree.parent, tree.kind, tree.axis, tree.placement_rot, tree.placement_pos, tree.idx_q)

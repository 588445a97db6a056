"""Arm update of paper 001 (eq. 46-49): forces on arm control points -> joint torques -> joint steps.

Control points P_1..P_7 are the origins of each arm's link frames. Each
gets an internal force pulling it back to where the planned (nominal) arm
configuration puts it (eq. 36's role for the arm) and the external force
of the nearest left/right obstacle points (eq. 41, or eq. 39 for the plain
strip). The 2-D world's obstacles are vertical prisms, so a laser point
stands for an obstacle at every height: distances are taken in the plane,
at the control point's own height (the paper's "same z" rule).

Torques Γ = Σ J_iᵀ F_i use the linear rows of each control point's
world-aligned Jacobian from Pinocchio; steps Δθ = α τ are clipped to
``max_joint_step`` and to the joint limits.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from maru_planner.paths import urdf_path
from maru_planner.reactive.description import arm_joint_names, arm_link_names
from maru_planner.reactive.forces import external_forces

NOMINAL = {
    "left": (0.0, -1.2, 0.0, -1.5, 0.0, 0.0, 0.0),
    "right": (0.0, 1.2, 0.0, 1.5, 0.0, 0.0, 0.0),
}


class ArmReactive:
    """Both 7-DOF arms in the base frame (a fixed-base Pinocchio model with the wheels locked)."""

    def __init__(
        self,
        urdf: str | None = None,
        k_c: float = 0.3,
        k_r: float = 0.5,
        d0: float = 0.2,
        alpha: float = 1.0,
        max_joint_step: float = 0.05,
        strip: str = "modified",
    ):
        full = pin.buildModelFromUrdf(str(urdf or urdf_path("mobile_manipulator.urdf")))
        wheels = [full.getJointId(n) for n in ("left_wheel_joint", "right_wheel_joint") if full.existJointName(n)]
        self.model = pin.buildReducedModel(full, wheels, pin.neutral(full)) if wheels else full
        self.data = self.model.createData()
        self.joint_names = arm_joint_names("left") + arm_joint_names("right")
        self._q_index = np.array([self.model.idx_qs[self.model.getJointId(n)] for n in self.joint_names])
        self._v_index = np.array([self.model.idx_vs[self.model.getJointId(n)] for n in self.joint_names])
        self._frames = [self.model.getFrameId(n) for n in arm_link_names("left") + arm_link_names("right")]
        self.lower = self.model.lowerPositionLimit[self._q_index]
        self.upper = self.model.upperPositionLimit[self._q_index]
        self.configure(k_c=k_c, k_r=k_r, d0=d0, alpha=alpha, max_joint_step=max_joint_step, strip=strip)
        self.q_nominal = np.array(NOMINAL["left"] + NOMINAL["right"])
        self.q = self.q_nominal.copy()
        self._p_nominal = self.control_points(self.q_nominal)
        reach = np.max(np.linalg.norm(self._p_nominal[:, :2], axis=1))
        self.reach = float(reach + 0.7)  # generous bound on how far an arm point can get from the base centre

    def configure(self, *, k_c: float, k_r: float, d0: float, alpha: float, max_joint_step: float, strip: str) -> None:
        """Gains, margin, step size and strip kind of the arm update (the joint state is kept)."""
        self.k_c, self.k_r, self.d0 = k_c, k_r, d0
        self.alpha, self.max_joint_step, self.strip = alpha, max_joint_step, strip

    def _full_q(self, q_arm: np.ndarray) -> np.ndarray:
        q = pin.neutral(self.model)
        q[self._q_index] = q_arm
        return q

    def control_points(self, q_arm: np.ndarray) -> np.ndarray:
        """Control points P_1..P_7 of both arms (14, 3) in the base frame."""
        pin.framesForwardKinematics(self.model, self.data, self._full_q(q_arm))
        return np.array([self.data.oMf[f].translation for f in self._frames])

    def step(self, points_base: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """One update from obstacle points in the base frame (m, 2); returns (joint steps (14,), forces (14, 3))."""
        q_full = self._full_q(self.q)
        pin.computeJointJacobians(self.model, self.data, q_full)
        pin.updateFramePlacements(self.model, self.data)
        p = np.array([self.data.oMf[f].translation for f in self._frames])
        forces = np.zeros((len(self._frames), 3))
        forces += self.k_c * (self._p_nominal - p)
        if len(points_base):
            near = points_base[np.hypot(points_base[:, 0], points_base[:, 1]) < self.reach]
            if len(near):
                radial = p[:, :2] / np.maximum(np.linalg.norm(p[:, :2], axis=1, keepdims=True), 1e-9)
                tangents = np.stack([-radial[:, 1], radial[:, 0]], axis=1)
                forces[:, :2] += external_forces(p[:, :2], tangents, near, self.d0, self.k_r, self.strip)
        tau = np.zeros(self.model.nv)
        for frame, force in zip(self._frames, forces, strict=True):
            if not np.any(force):
                continue
            jac = pin.getFrameJacobian(self.model, self.data, frame, pin.LOCAL_WORLD_ALIGNED)
            tau += jac[:3].T @ force
        steps = np.clip(self.alpha * tau[self._v_index], -self.max_joint_step, self.max_joint_step)
        new_q = np.clip(self.q + steps, self.lower, self.upper)
        steps = new_q - self.q
        self.q = new_q
        return steps, forces

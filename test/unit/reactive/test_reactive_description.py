"""The mobile manipulator's URDF/SRDF: generated file in sync, DH chain, loads in Pinocchio."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import numpy as np
import pinocchio as pin
import pytest

from maru_planner.paths import urdf_path
from maru_planner.reactive import description as desc


def dh(theta, d, alpha, a):
    ct, st, ca, sa = math.cos(theta), math.sin(theta), math.cos(alpha), math.sin(alpha)
    return np.array([[ct, -st * ca, st * sa, a * ct], [st, ct * ca, -ct * sa, a * st], [0, sa, ca, d], [0, 0, 0, 1]])


def test_committed_files_match_the_generator():
    assert urdf_path("mobile_manipulator.urdf").read_text() == desc.urdf_text()
    assert urdf_path("mobile_manipulator.srdf").read_text() == desc.srdf_text()


def test_model_has_two_seven_dof_arms_wheels_and_laser():
    model = pin.buildModelFromUrdf(str(urdf_path("mobile_manipulator.urdf")))
    names = list(model.names)
    for side in ("left", "right"):
        for j in desc.arm_joint_names(side):
            assert j in names
        assert f"{side}_wheel_joint" in names
    assert model.existFrame("laser_link")
    root = ET.parse(urdf_path("mobile_manipulator.urdf")).getroot()
    laser = root.find("joint[@name='laser_joint']/origin").get("xyz").split()
    assert float(laser[0]) == pytest.approx(desc.LASER_XYZ[0])


def test_arm_chain_follows_table2_dh():
    model = pin.buildModelFromUrdf(str(urdf_path("mobile_manipulator.urdf")))
    data = model.createData()
    q = pin.neutral(model)
    rng = np.random.default_rng(0)
    thetas = rng.uniform(-1.0, 1.0, 7)
    for i, name in enumerate(desc.arm_joint_names("left")):
        q[model.idx_qs[model.getJointId(name)]] = thetas[i]
    pin.framesForwardKinematics(model, data, q)
    mount = data.oMf[model.getFrameId("left_arm_mount")].homogeneous
    tool = data.oMf[model.getFrameId("left_tool")].homogeneous
    chain = np.eye(4)
    for theta, (d, alpha, a) in zip(thetas, desc.DH_TABLE, strict=True):
        chain = chain @ dh(theta, d, alpha, a)
    assert np.linalg.inv(mount) @ tool == pytest.approx(chain, abs=1e-5)  # URDF rpy has 6 decimals


def test_srdf_groups():
    root = ET.parse(urdf_path("mobile_manipulator.srdf")).getroot()
    groups = {g.get("name") for g in root.findall("group")}
    assert {"left_arm", "right_arm", "both_arms", "base"} <= groups

"""execution/carry_demo.py: Maru-1 carries a 1 kg box with both hands across the desk, planned with the box attached
and executed in MuJoCo (the box a payload of the right hand) without contacts, on time; the picture is drawn; a
payload is real mass the servos feel, and a bad payload is a typed error."""

from __future__ import annotations

import numpy as np
import pytest

from maru_planner.errors import InvalidScene
from maru_planner.execution.carry_demo import BOX, BOX_MASS, carry_problem, carry_scene, main, run_carry, summary
from maru_planner.execution.tolerances import ResultCode
from maru_planner.physics.arm_model import build_arm_model


@pytest.fixture(scope="module")
def run():
    return run_carry(seed=1)


def test_the_box_goes_from_the_right_of_the_desk_to_the_left_without_contacts(run):
    assert run.plan.success and run.execution is not None
    result = run.execution
    assert result.code == ResultCode.SUCCESSFUL and not result.contacts and result.saturated_steps == 0
    assert result.overrun is not None and result.overrun <= 0.05
    assert np.max(result.max_error) <= 0.02
    carrying_y = [run.robot.frame_pose(run.q_full(row), "r_hand")[1, 3] for row in result.actual[[0, -1]]]
    assert carrying_y[0] < 0.0 < carrying_y[1]  # right of the robot's axis, then left
    translation, rotation = run.grip_error(result.actual)
    assert translation < 0.01 and rotation < 0.02  # the executed hands keep their grip (sag under the load)
    assert "SUCCESSFUL" in summary(run)


def test_the_box_is_planned_as_an_attached_body_and_weighs_on_the_right_hand(maru1):
    problem = carry_problem()
    scene = carry_scene(maru1, problem)
    assert BOX in scene.attached and scene.attached[BOX].link == "r_hand" and "box" not in scene.obstacles
    light, loaded = build_arm_model(maru1, scene), build_arm_model(maru1, scene, payloads={BOX: BOX_MASS})
    assert loaded.model.body_subtreemass[0] == pytest.approx(light.model.body_subtreemass[0] + BOX_MASS)
    with pytest.raises(InvalidScene, match="payload 'nothing'"):
        build_arm_model(maru1, scene, payloads={"nothing": 1.0})
    with pytest.raises(InvalidScene, match="mass must be"):
        build_arm_model(maru1, scene, payloads={BOX: -1.0})


def test_the_command_line_draws_the_executed_motion(run, tmp_path, monkeypatch, capsys):
    monkeypatch.setattr("maru_planner.execution.carry_demo.run_carry", lambda seed: run)
    out = tmp_path / "carry.png"
    assert main(["--out", str(out)]) == 0
    assert out.stat().st_size > 10_000
    assert "picture" in capsys.readouterr().out

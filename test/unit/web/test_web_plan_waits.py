"""maru-view's controls and planner come after the page is up (so the robot's first frame is not slowed by the panel
or the warm-up), and "Plan" pressed before then says so, shows them, loads the planner at once and plans when it is
ready (no browser: no page ever connects). The
view starts a robot in a collision-free named state; TIAGo plans with the exact checker unless told otherwise."""

from __future__ import annotations

import numpy as np

from maru_planner.collision.checker import CollisionChecker
from maru_planner.planning.config import PlannerConfig
from maru_planner.planning.problems import PROBLEMS
from maru_planner.runtime import RobotSource
from maru_planner.scene import Scene
from maru_planner.web import cli, server
from maru_planner.web.server import ViewApp, ViewSettings, rest_state


def test_plan_before_the_planner_loaded_waits_for_it_and_plans():
    app = ViewApp(ViewSettings(robot="maru1", scene="none", port=0))
    try:
        assert app.runtime is None and not app.ready.is_set()  # no page yet: nothing warms up
        assert not app.panel.plan_button.disabled and app.panel.plan_button.label == server.LOADING_LABEL
        controls = [app.view.folder, app.panel.folder, app.editor.folder, *app.panel.goals.values()]
        assert not any(c.visible for c in controls)  # no page yet: the robot draws first
        problem = PROBLEMS["maru13"]
        goal_q = app.start.copy()
        goal_q[app.robot.joint_indices(app.robot.groups[problem.group])] = problem.goal
        for ee, frame in app.robot.end_effectors.items():
            app.panel.set_goal(ee, app.robot.frame_pose(goal_q, frame))
        result = app.plan()  # what a press does (in its thread)
        assert result is not None and result.success, result.message if result else "busy"
        assert app.ready.is_set() and app.runtime is not None
        assert app.panel.plan_button.label == server.PLAN_LABEL
        assert all(c.visible for c in controls)
        assert app.panel._folders["CompiledRRTConnect"].visible  # the chosen planner's parameters
        assert app.view.wait_played(timeout=30.0)
    finally:
        app.close()


def test_a_view_closed_before_its_planner_loaded_never_builds_one():
    app = ViewApp(ViewSettings(robot="panda", scene="none", port=0))
    app.close()
    assert app.ready.is_set() and app.runtime is None


def test_the_view_starts_talos_in_its_collision_free_named_state_not_its_neutral_one():
    talos = RobotSource(profile="talos").load()
    checker = CollisionChecker(talos, Scene())
    assert not checker.is_valid(talos.neutral())  # arms in the legs: why the view does not start there
    start = rest_state(talos, Scene())
    assert checker.is_valid(start)
    np.testing.assert_array_equal(start, talos.named_state("half_sitting"))


def test_the_view_starts_in_the_first_named_state_when_it_is_free():
    maru1 = RobotSource(profile="maru1").load()
    np.testing.assert_array_equal(rest_state(maru1, Scene()), maru1.named_state("home"))
    panda = RobotSource(profile="panda").load()  # no "home" or "ready": its SRDF's first
    np.testing.assert_array_equal(rest_state(panda, Scene()), panda.named_state(next(iter(panda.named_states))))


def test_tiago_plans_with_the_exact_checker_unless_told_and_says_why(capsys):
    def settings(robot: str, *argv: str) -> ViewSettings:
        return cli.settings_of(cli.parser().parse_args(["--robot", robot, *argv]))

    assert settings("tiago").collision_model == "exact"
    err = capsys.readouterr().err.strip()
    assert "tiago plans with --collision-model exact" in err and "\n" not in err
    assert settings("tiago", "--collision-model", "spheres").collision_model == "spheres"
    assert settings("panda").collision_model == PlannerConfig.collision_model
    assert capsys.readouterr().err == ""

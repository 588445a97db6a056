"""maru-view in a real headless browser (Chromium + Playwright): the page loads and draws, a moved goal and a press
of "Plan" play a trajectory that ends in the plan's final state, a failure shows its one-line message, and a scene
edit made in the page round-trips through the saved YAML. One view and one browser for the module."""

from __future__ import annotations

import time
from collections.abc import Iterator

import numpy as np
import pytest

from maru_planner.planning.problems import PROBLEMS
from maru_planner.scene import Scene
from maru_planner.web import browser
from maru_planner.web.scene_edit import new_obstacle
from maru_planner.web.server import ViewApp, ViewSettings, wait_ready

pytestmark = pytest.mark.skipif(browser.missing_reason() is not None, reason=browser.missing_reason() or "")


@pytest.fixture(scope="module")
def app() -> Iterator[ViewApp]:
    view = ViewApp(ViewSettings(robot="maru1", scene="none", port=0))  # the planner loads while the page does
    try:
        yield view
    finally:
        view.close()


@pytest.fixture(scope="module")
def page(app: ViewApp):
    # lazy: playwright only for the browser tests (skipped without a browser)
    from playwright.sync_api import sync_playwright

    with sync_playwright() as playwright:
        chromium = browser.launch(playwright)
        page = chromium.new_page(viewport=browser.VIEWPORT)
        page.goto(app.url)
        yield page
        chromium.close()


def _input(page, label: str):
    """The text input of the control labelled ``label`` (viser's labels are not tied to their inputs)."""
    return page.locator(f"xpath=//label[normalize-space()='{label}']/following::input[1]")


def _wait_result(app: ViewApp, before: object, timeout: float = 20.0) -> None:
    deadline = time.monotonic() + timeout
    while app.last_result is before and time.monotonic() < deadline:
        time.sleep(0.02)
    assert app.last_result is not before, "pressing Plan produced no result"


def test_the_page_loads_and_draws_the_robot(app: ViewApp, page):
    page.wait_for_selector("canvas", timeout=40_000)
    wait_ready(app, 60.0)
    page.wait_for_function("document.body.innerText.includes('planner ready')", timeout=10_000)
    assert page.get_by_role("button", name="Plan").is_enabled()
    screen = browser.Screen(page)
    robot = browser.robot_pixels(screen, app.view.robot_view.set_visible)
    assert robot.share > 0.002, "hiding the robot changed (almost) nothing on the page"
    assert browser.robot_shown(screen.grab(robot.box), robot) >= browser.SHOWN_SHARE  # shown again
    assert browser.robot_shown(robot.hidden, robot) == 0.0


def test_a_moved_goal_and_plan_play_the_trajectory_to_its_final_state(app: ViewApp, page):
    browser.wait_drawn(page, timeout=40.0)
    before_image = browser.canvas_image(page)
    problem = PROBLEMS["maru13"]
    goal_q = app.start.copy()
    goal_q[app.robot.joint_indices(app.robot.groups[problem.group])] = problem.goal
    goals = {ee: app.robot.frame_pose(goal_q, frame) for ee, frame in app.robot.end_effectors.items()}
    for ee, goal in goals.items():
        app.panel.set_goal(ee, goal)
    before = app.last_result
    page.get_by_role("button", name="Plan").click()
    _wait_result(app, before)
    result = app.last_result
    assert result is not None and result.success, result.message if result else ""
    assert app.view.wait_played(timeout=20.0)
    trajectory = result.trajectory
    shown = app.view.robot_view.q[app.robot.joint_indices(trajectory.joint_names)]
    np.testing.assert_allclose(shown, trajectory.positions[-1], atol=1e-9)
    assert app.view.frames_shown > 2  # played, not jumped to the end
    for ee, goal in goals.items():
        reached = app.robot.frame_pose(app.view.robot_view.q, app.robot.end_effectors[ee])
        np.testing.assert_allclose(reached[:3, 3], goal[:3, 3], atol=1e-3)
    page.wait_for_function("document.body.innerText.includes('SUCCESS')", timeout=10_000)
    assert "clearance" in page.inner_text("body")
    time.sleep(0.3)  # the last frame reaches the page
    moved = np.mean(np.any(browser.canvas_image(page) != before_image, axis=-1))
    assert moved > 0.001, "the robot did not move on the page"


def test_a_failed_plan_shows_its_one_line_message(app: ViewApp, page):
    ee = next(iter(app.robot.end_effectors))
    goal = np.eye(4)
    goal[:3, 3] = [3.0, 0.0, 0.5]  # out of reach
    app.panel.set_goal(ee, goal)
    before = app.last_result
    page.get_by_role("button", name="Plan").click()
    _wait_result(app, before)
    assert app.last_result is not None and app.last_result.status.value == "NO_IK_SOLUTION"
    page.wait_for_function("document.body.innerText.includes('NO_IK_SOLUTION')", timeout=10_000)
    app.panel.place_goals(app.start)


def test_a_scene_edit_in_the_page_round_trips_to_yaml(app: ViewApp, page, tmp_path):
    page.get_by_text("Scene", exact=True).click()  # the folder starts collapsed
    _input(page, "name").fill("crate")
    page.get_by_role("button", name="Add obstacle").click()
    deadline = time.monotonic() + 10.0
    while "crate" not in [o["name"] for o in app.scene_dict()["obstacles"]] and time.monotonic() < deadline:
        time.sleep(0.02)
    target = tmp_path / "edited.yaml"
    _input(page, "file").fill(str(target))
    page.get_by_role("button", name="Save YAML").click()
    deadline = time.monotonic() + 10.0
    while not target.is_file() and time.monotonic() < deadline:
        time.sleep(0.02)
    saved = Scene.from_yaml(target).to_dict()
    assert [o["name"] for o in saved["obstacles"]] == ["crate"]
    assert saved == app.scene_dict()
    assert saved["obstacles"][0]["size"] == [0.1, 0.1, 0.1]


def test_obstacles_move_attach_detach_and_go(app: ViewApp):
    app.editor.add(new_obstacle("ball", "sphere", (0.1, 0.1, 0.1), 0.05, 0.1))
    pose = np.eye(4)
    pose[:3, 3] = [0.4, -0.3, 1.0]
    app.editor.move("ball", pose)
    (ball,) = [o for o in app.scene_dict()["obstacles"] if o["name"] == "ball"]
    assert ball["pose"]["xyz"] == pytest.approx([0.4, -0.3, 1.0])
    app.editor.attach("ball", "r_hand")
    assert [a["name"] for a in app.scene_dict()["attached"]] == ["ball"]
    assert app.editor.attached.value == "ball" and "ball" not in app.view.scene_view.obstacle_names
    app.editor.detach("ball")
    (back,) = [o for o in app.scene_dict()["obstacles"] if o["name"] == "ball"]
    assert back["pose"]["xyz"] == pytest.approx([0.4, -0.3, 1.0])
    app.editor.remove("ball")
    assert "ball" not in app.view.scene_view.obstacle_names
    app.editor.report(lambda: app.editor.remove("ball"))  # what "Remove obstacle" does with a refused edit
    assert "refused" in app.editor.message.content and "ball" in app.editor.message.content

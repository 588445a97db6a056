"""The planning runtime without ROS (maru_planner.runtime): admission, scene versions, plans through the workers,
IK, robot state and bad input. Maru-1's upper body from its URDF (planning_node's default robot), the paper problem.
"""

from __future__ import annotations

import threading
import time

import numpy as np
import pytest
from conftest import PAPER_GOAL, PAPER_START

from maru_planner import errors
from maru_planner.monitor import PlanMonitor
from maru_planner.paths import config_path, urdf_path
from maru_planner.planning import MotionPlanner, MotionRequest, PlannerConfig, PlanStatus
from maru_planner.planning.constraints import PathConstraints
from maru_planner.runtime import (
    AddObstacle,
    AttachObject,
    DescriptionFiles,
    DetachObject,
    IkRequest,
    JointStateStore,
    MoveObstacle,
    PlanningRuntime,
    RemoveObstacle,
    RobotDescription,
    RobotSource,
    RuntimeSettings,
    WorkerContext,
    WorkerPool,
    description_source,
    ik_timeout,
)
from maru_planner.runtime.admission import time_left
from maru_planner.scene import Obstacle, Scene

GROUP = "upper_body"
SOURCE = RobotSource(str(urdf_path("maru1_upper_body.urdf")), str(urdf_path("maru1_upper_body.srdf")))
CONFIG = PlannerConfig(certify_timeout=30.0)  # a loaded machine's answers stay a quiet one's (test_process_pool)
THREADS = RuntimeSettings(GROUP, workers=1, worker_processes=False, queue_size=1)
LIVENESS_TIMEOUT = 60.0  # s: a bound on waiting, never a performance claim
BOX = Obstacle("runtime_box", "box", size=[0.1, 0.1, 0.1], pose=[0.6, -0.6, 0.2])


def _request(**overrides) -> MotionRequest:
    fields = dict(group=GROUP, start=PAPER_START, goal_joints=PAPER_GOAL, planner_id="RRTConnect", time_budget=30.0,
                  seed=2)  # fmt: skip
    return MotionRequest(**{**fields, **overrides})


def _desk() -> Scene:
    return Scene.from_yaml(config_path("scenes", "maru13_desk_box.yaml"))


class _Searching:
    """A PlanMonitor sink that signals when the search has begun."""

    def __init__(self):
        self.started = threading.Event()

    def __call__(self, progress) -> None:
        if progress.stage == "search":
            self.started.set()


def _occupy(runtime: PlanningRuntime) -> tuple[PlanMonitor, object]:
    """An endless plan (plain RRT on the paper problem) holding one worker until its monitor is cancelled."""
    searching = _Searching()
    monitor = PlanMonitor(searching)
    future = runtime.plan(_request(planner_id="RRT", time_budget=120.0), monitor)
    assert searching.started.wait(LIVENESS_TIMEOUT)
    return monitor, future


@pytest.fixture(scope="module")
def runtime():
    with PlanningRuntime(SOURCE, "", CONFIG, THREADS) as started:
        yield started


@pytest.fixture(scope="module")
def local():
    return MotionPlanner.from_scene(SOURCE.load(), _desk(), CONFIG)


# ---------------------------------------------------------------- admission


def test_the_pool_admits_workers_plus_queue_size_then_answers_busy():
    release = threading.Event()
    pool = WorkerPool([WorkerContext(planner=None, scene_version=0)], queue_size=1)  # type: ignore[arg-type]
    try:
        pool.submit(lambda context: release.wait())
        pool.submit(lambda context: None)
        with pytest.raises(errors.Busy) as refused:
            pool.submit(lambda context: None)
        assert str(refused.value) == ("2 requests are planning or waiting (workers 1 + queue_size 1); try again later")
    finally:
        release.set()
        pool.close()


def test_a_budget_spent_waiting_is_a_time_out():
    with pytest.raises(errors.PlanningTimedOut, match="the IK timeout ran out while the request waited"):
        time_left(time.monotonic() - 0.1, "IK timeout")
    assert 0.0 < time_left(time.monotonic() + 10.0, "IK timeout") <= 10.0


def test_a_full_runtime_answers_busy_at_once_and_a_waiting_request_times_out(runtime):
    monitor, running = _occupy(runtime)
    waiting = runtime.plan(_request(time_budget=0.2))  # queue_size 1: admitted, waits longer than its budget
    with pytest.raises(errors.Busy, match="workers 1 \\+ queue_size 1"):
        runtime.plan(_request())
    assert runtime.admitted == 2
    time.sleep(0.3)
    monitor.cancel()
    assert isinstance(running.result().error, errors.PlanningCancelled)
    with pytest.raises(errors.PlanningTimedOut, match="allowed_planning_time ran out while the request waited"):
        waiting.result()
    assert runtime.plan(_request()).result().success  # serving again


# ---------------------------------------------------------------- plans and the scene


def test_a_plan_gives_the_in_process_path_for_the_same_seed(runtime, local):
    result = runtime.plan(_request()).result()
    expected = local.plan(_request())
    assert result.success and expected.success, (result.message, expected.message)
    np.testing.assert_array_equal(result.path, expected.path)


def test_scene_edits_apply_all_or_nothing_and_each_change_is_a_version(runtime):
    scene, version = runtime.get_scene()
    names = [o["name"] for o in scene["obstacles"]]
    with pytest.raises(errors.InvalidScene):
        runtime.apply_scene([AddObstacle(BOX), RemoveObstacle("no_such_obstacle")])
    assert runtime.get_scene() == (scene, version)  # the add is gone with the failed remove
    assert runtime.apply_scene([AddObstacle(BOX)]) == [*names, BOX.name]
    moved = np.eye(4)
    moved[:3, 3] = [0.6, -0.6, 0.3]
    runtime.apply_scene([MoveObstacle(BOX.name, moved)])
    assert runtime.scene_version == version + 2
    assert runtime.apply_scene([RemoveObstacle(BOX.name)]) == names
    assert runtime.get_scene() == (scene, version + 3)


def test_a_lazy_sequence_of_edits_fails_at_its_own_error(runtime):
    def edits():
        yield AddObstacle(BOX)
        raise errors.InvalidScene("the second message is malformed")

    before = runtime.get_scene()
    with pytest.raises(errors.InvalidScene, match="second message"):
        runtime.apply_scene(edits())
    assert runtime.get_scene() == before


def test_the_workers_plan_on_the_latest_scene(runtime, local):
    scene, _ = runtime.get_scene()
    blocked = Scene.from_dict(scene)
    blocked.add(Obstacle("torso", "box", size=[0.3, 0.3, 0.3], pose=[0.0, 0.0, 0.0]))
    try:
        runtime.set_scene(blocked)
        assert runtime.plan(_request()).result().status is PlanStatus.START_IN_COLLISION
    finally:
        runtime.set_scene(Scene.from_dict(scene))
    np.testing.assert_array_equal(runtime.plan(_request()).result().path, local.plan(_request()).path)


def test_attach_and_detach_place_the_link_at_the_latest_joint_state(runtime):
    cup = Obstacle("cup", "cylinder", radius=0.03, length=0.1, pose=[0.5, -0.3, 0.2])
    link = runtime.robot.end_effectors["right"]
    runtime.joint_states.clear()
    with pytest.raises(errors.NoStartState):
        runtime.apply_scene([AddObstacle(cup), AttachObject("cup", link)])
    assert "cup" not in runtime.obstacle_names()
    try:
        runtime.apply_scene([AddObstacle(cup), AttachObject("cup", link, dict(PAPER_START))])
        assert [a["name"] for a in runtime.get_scene()[0]["attached"]] == ["cup"]
        runtime.update_joint_state(list(PAPER_START), list(PAPER_START.values()))
        runtime.apply_scene([DetachObject("cup")])
        placed = Scene.from_dict(runtime.get_scene()[0]).obstacles["cup"]
        np.testing.assert_allclose(placed.pose[:3, 3], [0.5, -0.3, 0.2], atol=1e-9)
    finally:
        runtime.apply_scene([RemoveObstacle("cup")])
        runtime.joint_states.clear()
    with pytest.raises(errors.InvalidLink):
        runtime.apply_scene([AddObstacle(cup), AttachObject("cup", "no_such_link", dict(PAPER_START))])


# ---------------------------------------------------------------- IK, FK, validity


def test_ik_reaches_the_hands_poses_of_a_known_state(runtime):
    links = sorted(runtime.robot.end_effectors.values())
    targets = runtime.compute_fk(dict(PAPER_START), links).result()
    request = IkRequest(GROUP, targets, seed={}, timeout=5.0, strict_seed=True, avoid_collisions=False)
    q = runtime.compute_ik(request).result()
    reached = runtime.compute_fk(dict(zip(runtime.robot.joint_names, q, strict=True)), links).result()
    for link in links:
        np.testing.assert_allclose(reached[link], targets[link], atol=1e-3)


def test_ik_fk_and_validity_refuse_bad_input(runtime):
    with pytest.raises(errors.InvalidRequest, match="max_planning_time"):
        ik_timeout(float("nan"), 1.0, 60.0)
    assert ik_timeout(0.0, 1.0, 60.0) == 1.0 and ik_timeout(2.0, 1.0, 60.0) == 2.0
    pose = np.eye(4)
    with pytest.raises(errors.InvalidJointNames):
        runtime.compute_ik(IkRequest(GROUP, {"base_link": pose}, {"no_such_joint": 0.0}, 1.0)).result()
    with pytest.raises(errors.InvalidJointNames):
        runtime.compute_fk({"no_such_joint": 0.0}, []).result()
    with pytest.raises(errors.InvalidJointNames):
        runtime.check_state_validity({"no_such_joint": 0.0}, PathConstraints()).result()
    assert runtime.check_state_validity(dict(PAPER_START), PathConstraints()).result().valid


# ---------------------------------------------------------------- robot state, settings, robot loading


def test_joint_states_keep_known_finite_values_and_count_the_rest():
    store = JointStateStore()
    assert store.merge(["a", "b", "x", "a"], [1.0, float("nan"), 2.0, 3.0], known={"a", "b"}) == 3
    assert store.latest() == {"a": 3.0} and store.ignored == 3
    store.clear()
    assert store.latest() == {} and store.ignored == 3


def test_reconfigure_rebuilds_the_workers_only_for_planner_settings_or_their_count(runtime):
    try:
        assert not runtime.reconfigure(CONFIG, RuntimeSettings(GROUP, 1, False, queue_size=4))
        with pytest.raises(errors.InvalidParameter, match="'default_group' = 'no_such_group' is not a group"):
            runtime.reconfigure(PlannerConfig(resolution=0.05), RuntimeSettings("no_such_group", 1, False, 1))
        assert runtime.settings.queue_size == 4 and runtime.config == CONFIG  # nothing applied
        coarse = PlannerConfig(resolution=0.05, certify_timeout=30.0)
        assert runtime.reconfigure(coarse, RuntimeSettings(GROUP, 1, False, queue_size=4))
        assert runtime.config == coarse and runtime.plan(_request()).result().success
    finally:
        runtime.reconfigure(CONFIG, THREADS)
    assert runtime.workers == 1 and runtime.settings == THREADS


def test_bad_start_up_input_is_a_clear_error():
    with pytest.raises(errors.InvalidParameter, match="default_group"):
        PlanningRuntime(SOURCE, "none", CONFIG, RuntimeSettings("no_such_group", 1, False, 0))
    with pytest.raises(errors.InvalidScene, match="not found"):
        PlanningRuntime(SOURCE, "/no/such/scene.yaml", CONFIG, THREADS)


def test_description_text_is_written_to_files_and_said_where_it_came_from(tmp_path):
    files = DescriptionFiles(prefix="runtime_test_")
    urdf_text = urdf_path("maru1_upper_body.urdf").read_text()
    source, origin = description_source(RobotDescription(urdf_xml=urdf_text, package_dirs=("", "/x")), files)
    try:
        assert open(source.urdf).read() == urdf_text and source.package_dirs == ("/x",)
        assert source.srdf == str(urdf_path("maru1_upper_body.srdf"))
        assert origin == f"URDF from the robot_description parameter, SRDF from {source.srdf}"
    finally:
        files.cleanup()
    defaults, origin = description_source(RobotDescription(), files)
    assert defaults == SOURCE and origin == f"URDF from {SOURCE.urdf}, SRDF from {SOURCE.srdf}"


def test_worker_processes_plan_on_the_latest_scene_with_the_in_process_path(local):
    logged: list[str] = []
    settings = RuntimeSettings(GROUP, workers=1, worker_processes=True, queue_size=0)
    with PlanningRuntime(SOURCE, _desk(), CONFIG, settings, log=logged.append) as processes:
        assert [line.split(":")[0] for line in logged if line.startswith("worker process")] == ["worker process 0"]
        np.testing.assert_array_equal(processes.plan(_request()).result().path, local.plan(_request()).path)
        processes.apply_scene([AddObstacle(Obstacle("torso", "box", size=[0.3, 0.3, 0.3], pose=[0.0, 0.0, 0.0]))])
        assert processes.plan(_request()).result().status is PlanStatus.START_IN_COLLISION

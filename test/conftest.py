"""Shared test set-up: loopback-only DDS on a random domain, rclpy helpers.

Every process that starts rclpy in the suite (this one and the node
subprocesses it spawns, which inherit ``os.environ``) talks DDS on 127.0.0.1
only, on a domain id picked at random for this run among those no other DDS
participant on this machine is using (test runs may share a machine).
"""

from __future__ import annotations

import os
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from maru_planner.paths import benchmarks_dir, config_path
from maru_planner.planning.problems import PROBLEMS
from maru_planner.robot import RobotModel, load_example_robot
from maru_planner.robot.robots.panda import PANDA_FINGERS_OPEN
from maru_planner.ros.env import configure_loopback_dds, unused_domain_id
from maru_planner.scene import Obstacle, Scene
from maru_planner.scene.motion_bench_maker import iter_mbm_problems

REPO_ROOT = Path(__file__).resolve().parent.parent
# planning_node's default group (upper_body) and paper 000's 13-DOF problem over it
GROUP_JOINTS = ["waist_yaw"] + [f"r_arm_j{i}" for i in range(1, 7)] + [f"l_arm_j{i}" for i in range(1, 7)]
PAPER_START = PROBLEMS["maru13"].start_dict(GROUP_JOINTS)
PAPER_GOAL = PROBLEMS["maru13"].goal_dict(GROUP_JOINTS)
MBM_TARBALL = benchmarks_dir() / "motionbenchmaker" / "vamp_panda_problems.tar.bz2"
needs_mbm = pytest.mark.skipif(not MBM_TARBALL.is_file(), reason="MotionBenchMaker tarball not present")


def mbm_problem(name: str):
    """One MotionBenchMaker Panda problem by name ("cage/0073"), fingers open as the benchmark has them."""
    set_name, number = name.split("/")
    problems = iter_mbm_problems(MBM_TARBALL, sets=[set_name], limit_per_set=int(number),
                                 fixed_joints=PANDA_FINGERS_OPEN)  # fmt: skip
    (problem,) = [p for p in problems if p.name == name]
    return problem


def panda_clutter(seed: int, count: int = 9) -> Scene:
    """``count`` boxes, spheres and cylinders at random poses in the Panda's workspace."""
    rng = np.random.default_rng(seed)
    obstacles = []
    for i in range(count):
        pose = np.eye(4)
        pose[:3, :3] = pin.rpy.rpyToMatrix(*rng.uniform(-np.pi, np.pi, 3))
        pose[:3, 3] = rng.uniform([-0.6, -0.6, 0.0], [0.6, 0.6, 0.9])
        kind = ("box", "sphere", "cylinder")[i % 3]
        dims = {"box": {"size": tuple(rng.uniform(0.05, 0.3, 3))}, "sphere": {"radius": rng.uniform(0.03, 0.12)},
                "cylinder": {"radius": rng.uniform(0.03, 0.1), "length": rng.uniform(0.1, 0.4)}}[kind]  # fmt: skip
        obstacles.append(Obstacle(f"o{i}", kind, pose=pose, **dims))
    return Scene(obstacles)


def pytest_configure(config):
    # The user's exported ROS_DOMAIN_ID is kept (make test then runs one worker per lane), else each pytest process
    # takes a free one: xdist workers inherit the controller's environment, so what the user exported is passed on
    # apart from the domain the controller chose for itself.
    user_domain = os.environ.setdefault("MARU_USER_ROS_DOMAIN_ID", os.environ.get("ROS_DOMAIN_ID", ""))
    configure_loopback_dds(domain_id=int(user_domain) if user_domain.isdigit() else unused_domain_id())
    os.environ.setdefault("MPLBACKEND", "Agg")


@pytest.fixture(scope="module")
def panda() -> RobotModel:
    return load_example_robot("panda")


@pytest.fixture(scope="module")
def maru1() -> RobotModel:
    return RobotModel.maru1()


@pytest.fixture(scope="session")
def rclpy_session():
    """rclpy initialised once for the test process; shut down at the end."""
    import rclpy

    if not rclpy.ok():
        rclpy.init()
    yield rclpy
    if rclpy.ok():
        rclpy.shutdown()


class SpinningNode:
    """A test node spun by a background executor thread (clients, subscribers)."""

    def __init__(self, name: str):
        import rclpy
        from rclpy.executors import SingleThreadedExecutor

        self.node = rclpy.create_node(name)
        # Single-threaded: test callbacks only store messages and resolve futures, and rclpy's
        # MultiThreadedExecutor spins hot (holding the GIL) while a ready callback waits for a worker.
        self.executor = SingleThreadedExecutor()
        self.executor.add_node(self.node)
        self._thread = threading.Thread(target=self.executor.spin, daemon=True)
        self._thread.start()

    def call(self, client, request, timeout: float = 60.0):
        """Call a service synchronously from the test thread."""
        if not client.wait_for_service(timeout_sec=timeout):
            raise TimeoutError(f"service {client.srv_name} not available after {timeout} s")
        future = client.call_async(request)
        deadline = time.monotonic() + timeout
        while not future.done():
            if time.monotonic() > deadline:
                client.remove_pending_request(future)
                raise TimeoutError(f"no response from {client.srv_name} within {timeout} s")
            time.sleep(0.005)
        return future.result()

    def wait_for(self, predicate, timeout: float = 20.0, period: float = 0.01) -> bool:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if predicate():
                return True
            time.sleep(period)
        return predicate()

    def destroy(self):
        # The spin thread must be out of its wait set before the node's handles go, or it dies on them.
        self.executor.shutdown(timeout_sec=30.0)
        self._thread.join(timeout=30.0)
        self.node.destroy_node()


@pytest.fixture
def spinning_node(rclpy_session, request):
    """A fresh spinning client node per test, named after the test."""
    name = "test_" + "".join(c if c.isalnum() else "_" for c in request.node.name)[:50]
    spinning = SpinningNode(name)
    yield spinning
    spinning.destroy()


class NodeProcess:
    """A maru_planner node running as its own process, as ``ros2 run`` would start it."""

    def __init__(self, module: str, args: list[str], log_path: Path):
        self.log_path = log_path
        self._log = open(log_path, "w")
        self.proc = subprocess.Popen(
            [sys.executable, "-m", module, *args],
            stdout=self._log,
            stderr=subprocess.STDOUT,
            stdin=subprocess.DEVNULL,
            cwd=REPO_ROOT,
            env=dict(os.environ),
        )

    def log(self) -> str:
        if not self._log.closed:
            self._log.flush()
        return self.log_path.read_text(errors="replace")

    def alive(self) -> bool:
        return self.proc.poll() is None

    def terminate(self) -> None:
        """Ask the node to shut down (SIGTERM) without waiting for it."""
        if self.alive():
            self.proc.terminate()

    def wait_stopped(self) -> None:
        """Wait for the node to end after :meth:`terminate` (killed after 10 s) and close its log."""
        try:
            self.proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait(timeout=5)
        self._log.close()

    def stop(self) -> None:
        self.terminate()
        self.wait_stopped()


@pytest.fixture(scope="module")
def node_process(tmp_path_factory):
    """Factory: ``node_process("maru_planner.ros.planning_node", ["--ros-args", ...])``.

    Processes are stopped when the test module ends; their logs are printed
    if they died early, to make failures readable.
    """
    started: list[NodeProcess] = []
    log_dir = tmp_path_factory.mktemp("node_logs")

    def start(module: str, args: list[str] | None = None) -> NodeProcess:
        log_path = log_dir / f"{module.rsplit('.', 1)[-1]}_{len(started)}.log"
        proc = NodeProcess(module, args or [], log_path)
        started.append(proc)
        return proc

    yield start
    died = [proc for proc in started if not proc.alive()]
    for proc in started:
        proc.terminate()  # all first: the nodes' shutdowns overlap
    for proc in started:
        proc.wait_stopped()
    for proc in died:
        print(f"--- log of {proc.proc.args}:\n{proc.log()}")


@pytest.fixture(scope="module")
def planner_node(node_process, rclpy_session):
    """planning_node with the default config (Maru-1 upper body, desk + box scene), one per test module."""
    proc = node_process(
        "maru_planner.ros.planning_node", ["--ros-args", "--params-file", str(config_path("planner.yaml"))]
    )
    yield proc
    assert proc.alive(), "planning_node died:\n" + proc.log()


@pytest.fixture(scope="module")
def tester(rclpy_session, request):
    """One spinning client node per test module (discovery happens once, not per test)."""
    spinning = SpinningNode(f"{request.module.__name__}_client")
    yield spinning
    spinning.destroy()


def connected_planning_client(tester: SpinningNode, proc: NodeProcess, namespace: str = ""):
    """A PlanningClient on ``tester`` once the node at ``proc`` serves plan_motion and has matched it."""
    from maru_planner.ros.planning_client import PlanningClient

    planning = PlanningClient(node=tester.node, namespace=namespace)
    assert planning.plan_client.wait_for_service(timeout_sec=120.0), "plan_motion never appeared:\n" + proc.log()
    planning.wait_until_ready(timeout=120.0)  # the node has matched us too: no first answer gets lost
    return planning


def rss_mb(pid: int) -> float:
    """Resident set size of process ``pid`` (MB), from /proc/<pid>/status."""
    with open(f"/proc/{pid}/status") as status:
        for line in status:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024.0
    raise RuntimeError(f"no VmRSS for process {pid}")


def wait_until_node_has_joint_states(planning, timeout: float = 60.0) -> None:
    """Until the planning node behind the PlanningClient ``planning`` has matched the /joint_states publisher, it drops
    what is sent (a node ready and a test that has seen /joint_states say nothing of it): wait for the first one.

    The probe has no goal: INVALID_REQUEST once the node has a joint state, NO_START_STATE before.
    """
    from maru_planner.ros.planning_client import plan_request
    from maru_planner_interfaces.msg import PlanningError

    deadline = time.monotonic() + timeout
    while True:
        answer = planning.call(planning.plan_client, plan_request(None, start=None, time_budget=1.0), 30.0)
        if answer.error.code != PlanningError.NO_START_STATE:
            assert answer.error.code == PlanningError.INVALID_REQUEST, answer.error.message
            return
        assert time.monotonic() < deadline, "the node never received /joint_states"
        time.sleep(0.05)


class BaseNodeClient:
    """base_planner_node's plan_base_path service client and a latched map publisher on a spinning test node."""

    def __init__(self, spinning: SpinningNode, proc: NodeProcess, namespace: str = ""):
        from nav_msgs.msg import OccupancyGrid
        from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

        from maru_planner.ros.planning_client import call_until_answered
        from maru_planner_interfaces.srv import PlanBasePath

        self.spinning, self.proc = spinning, proc
        self.latched = QoSProfile(
            depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL, reliability=ReliabilityPolicy.RELIABLE
        )
        self.map_pub = spinning.node.create_publisher(OccupancyGrid, f"{namespace}/map", self.latched)
        self.plan_client = spinning.node.create_client(PlanBasePath, f"{namespace}/plan_base_path")
        # both directions matched before a test's first call (an empty request changes nothing)
        call_until_answered(self.plan_client, PlanBasePath.Request(), 120.0)

    def publish_map(self, msg, expect_log: str, timeout: float = 20.0) -> None:
        """Publish ``msg`` and wait until the node's log says ``expect_log`` once more."""
        before = self.proc.log().count(expect_log)
        self.map_pub.publish(msg)
        logged = self.spinning.wait_for(lambda: self.proc.log().count(expect_log) > before, timeout=timeout)
        assert logged, self.proc.log()

    def publish_grid(self, grid, expect_log: str, timeout: float = 20.0) -> None:
        """Publish a core OccupancyGrid as the map (see ``publish_map``)."""
        from builtin_interfaces.msg import Time

        from maru_planner.ros.base_conversions import grid_to_msg

        self.publish_map(grid_to_msg(grid, grid.occupied, Time(), "map"), expect_log, timeout)

"""Hostile inputs for every message, file and command line the package accepts, and the tally of answers.

Shared by the ``test_hostile_*`` suites (fixed seed, bounded examples) and ``bench/robustness.py``
(the same generators at a larger scale). A generator is a hypothesis strategy; :func:`run_batch`
feeds its examples to a ``send`` function returning an :class:`Outcome`, tallies it under its
target and, in strict mode, fails at the first outcome that breaks an invariant:

- no crash (the node process is alive, a CLI never raises out of ``main``), no traceback;
- no internal-error code (``PlanningError.INTERNAL_ERROR``, ``PlanBasePath`` ``UNKNOWN``, CLI exit 3);
- an answer within its budget + :data:`LATE_MARGIN`, none lost;
- every error a code plus a one-line message of at most :data:`MAX_MESSAGE` characters (a bad
  value is quoted as a short excerpt, never whole).
"""

from __future__ import annotations

import array
import contextlib
import io
import itertools
import math
import re
import time
from collections.abc import Callable, Iterator
from dataclasses import asdict, dataclass, field
from pathlib import Path as FilePath

import yaml
from builtin_interfaces.msg import Time
from conftest import rss_mb as rss_mb  # re-exported: the hostile tests and bench/robustness.py read RSS here
from geometry_msgs.msg import Point32, PoseStamped
from hypothesis import HealthCheck, Phase, given, seed, settings
from hypothesis import strategies as st
from nav_msgs.msg import OccupancyGrid, Odometry, Path
from reactive_helpers import (
    OBSTACLE,
    ReactiveClient,
    laser_scans,
    odom,
    reactive_params_file,
    shipped_params,
    synthetic_scan,
)
from sensor_msgs.msg import JointState
from shape_msgs.msg import SolidPrimitive

from maru_planner.paths import config_path
from maru_planner.planning.problems import PROBLEMS
from maru_planner.ros.planning_client import PlanningClient
from maru_planner.ros.planning_conversions import joint_state_msg, trajectory_positions
from maru_planner_interfaces.msg import PlanningError, SceneObstacle
from maru_planner_interfaces.srv import ApplyScene, ComputeIK, PlanBasePath, PlanMotion

# Examples per batch in the test suite (about 1,700 in all, ~3 min on 2 cores); bench/robustness.py scales them.
SUITE_EXAMPLES = {
    "plan_motion": 200, "compute_ik": 90, "apply_scene": 90, "scene_topic": 60, "joint_states": 60,
    "plan_base_path": 220, "make_plan": 40, "map": 100, "reactive": 100,
    "scene_files": 100, "map_files": 100, "biped_files": 70, "sim_files": 100,
    "maru-plan": 60, "maru-base-plan": 60, "maru-reactive-sim": 40,
}  # fmt: skip
REACTIVE_BATCHES = 3
LATE_MARGIN = 0.5  # s an answer may take beyond its budget
LOST_AFTER = 30.0  # s beyond the budget after which a request counts as lost
LOG_STAMP = re.compile(r"\[\d+\.\d+\] ")  # a ROS log line's time stamp
MAX_MESSAGE = 400  # characters of an error message (a short excerpt of a bad value, not the value)
SEED = 18  # the suite's fixed hypothesis seed (issue 18)

# ---------------------------------------------------------------- tally


@dataclass
class Outcome:
    """What one hostile input got: an answer (accepted or a proper error) or a broken invariant."""

    accepted: bool = False
    proper_error: bool = False
    crash: bool = False
    traceback: bool = False
    internal: bool = False
    late: bool = False
    lost: bool = False
    detail: str = ""

    @property
    def ok(self) -> bool:
        return (self.accepted or self.proper_error) and not (
            self.crash or self.traceback or self.internal or self.late or self.lost
        )


@dataclass
class Tally:
    """Counts of one target's inputs and outcomes, plus the first few failures."""

    inputs: int = 0
    accepted: int = 0
    proper_errors: int = 0
    crashes: int = 0
    tracebacks: int = 0
    internal_errors: int = 0
    late_answers: int = 0
    lost: int = 0
    failures: list[str] = field(default_factory=list)

    def add(self, outcome: Outcome) -> None:
        self.inputs += 1
        self.accepted += outcome.accepted and outcome.ok
        self.proper_errors += outcome.proper_error and outcome.ok
        self.crashes += outcome.crash
        self.tracebacks += outcome.traceback
        self.internal_errors += outcome.internal
        self.late_answers += outcome.late
        self.lost += outcome.lost
        if not outcome.ok and len(self.failures) < 20:
            self.failures.append(outcome.detail[:300])

    @property
    def broken(self) -> int:
        return self.crashes + self.tracebacks + self.internal_errors + self.late_answers + self.lost

    def row(self) -> dict:
        return {k: v for k, v in asdict(self).items() if k != "failures"}


TALLIES: dict[str, Tally] = {}


def tally(target: str) -> Tally:
    return TALLIES.setdefault(target, Tally())


def summary_lines(targets: list[str] | None = None) -> list[str]:
    """One line per target: the counts the suite prints."""
    lines = []
    for target in targets or sorted(TALLIES):
        t = TALLIES.get(target, Tally())
        lines.append(
            f"hostile inputs: {target}: {t.inputs} inputs, {t.accepted} accepted, {t.proper_errors} proper errors, "
            f"{t.crashes} crashes, {t.tracebacks} tracebacks, {t.internal_errors} internal errors, "
            f"{t.late_answers} late, {t.lost} lost"
        )
    return lines


def message_problem(message: str) -> str:
    """Why ``message`` is not a proper one-line error message ('' when it is)."""
    if not message.strip():
        return "empty message"
    if "\n" in message.strip():
        return f"multi-line message: {message[:200]!r}"
    if len(message) > MAX_MESSAGE:
        return f"message of {len(message)} characters (quotes too much): {message[:120]!r}..."
    if "Traceback" in message:
        return f"traceback in message: {message[:200]!r}"
    return ""


def answer_outcome(code_ok: bool, internal: bool, message: str, elapsed: float, budget: float, what: str) -> Outcome:
    """Outcome of a service answer: accepted (``code_ok``), else a proper error unless a rule is broken."""
    late = elapsed > budget + LATE_MARGIN
    problem = "" if code_ok else message_problem(message)
    detail = f"{what}: answered in {elapsed:.2f} s (budget {budget:g} s); {message[:200]!r} {problem}"
    return Outcome(
        accepted=code_ok, proper_error=not code_ok and not problem, internal=internal, late=late, detail=detail
    )


# ---------------------------------------------------------------- running batches


class BrokenInvariant(AssertionError):
    pass


def run_batch(
    target: str,
    strategy: st.SearchStrategy,
    send: Callable[[object], Outcome],
    examples: int,
    *,
    strict: bool = True,
    seed_value: int = SEED,
    progress: Callable[[int], None] | None = None,
) -> Tally:
    """Send ``examples`` inputs drawn from ``strategy``; tally each under ``target``.

    A crash or a lost request ends the batch (what follows would only wait for a dead node).
    ``strict`` (the tests): then raise :class:`BrokenInvariant` listing the batch's broken
    invariants; else (the bench) they stay in the tally.
    """
    record = tally(target)
    failures_before = len(record.failures)
    stopped: list[Outcome] = []

    @seed(seed_value)
    @settings(max_examples=examples, deadline=None, database=None, derandomize=False,
              phases=(Phase.explicit, Phase.generate), suppress_health_check=list(HealthCheck))  # fmt: skip
    @given(strategy)
    def feed(value):
        if stopped:
            return
        outcome = send(value)
        record.add(outcome)
        if progress is not None:
            progress(record.inputs)
        if outcome.crash or outcome.lost:
            stopped.append(outcome)

    feed()
    failures = record.failures[failures_before:]
    if strict and (failures or stopped):
        raise BrokenInvariant(f"{target}: " + "\n".join(failures or [stopped[0].detail]))
    return record


# ---------------------------------------------------------------- scalars, names, arrays

HUGE_TEXT = "x" * 100_000
HOSTILE_TEXT = st.one_of(
    st.text(max_size=16),
    st.sampled_from(["", " ", "\x00", "\n\nline", "é" * 300, HUGE_TEXT, "../../../etc/passwd", "%s%n{0}", "🤖"]),
)
HOSTILE_FLOAT = st.one_of(
    st.floats(),
    st.sampled_from([math.nan, math.inf, -math.inf, 0.0, -0.0, 1e300, -1e300, 5e-324, 1e-12, 1.0, -1.0]),
)
FLOAT32 = st.one_of(st.floats(width=32), st.sampled_from([math.nan, math.inf, -math.inf, 3.0e38, -3.0e38, 0.0]))
INT32 = st.integers(-(2**31), 2**31 - 1)
INT64 = st.integers(-(2**63), 2**63 - 1)


def hostile_floats(valid: st.SearchStrategy) -> st.SearchStrategy:
    """Half plausible values (to reach the deeper checks), half anything a float can hold."""
    return st.one_of(valid, HOSTILE_FLOAT)


def hostile_lists(element: st.SearchStrategy, huge: list, max_size: int = 20) -> st.SearchStrategy:
    return st.one_of(st.lists(element, max_size=max_size), st.just(huge))


def names_from(known: list[str]) -> st.SearchStrategy:
    return st.one_of(st.sampled_from(known), HOSTILE_TEXT)


# ---------------------------------------------------------------- ROS message pieces


@st.composite
def hostile_poses(draw, frames: list[str], near: tuple[float, float, float] = (0.4, -0.2, 0.9)):
    msg = PoseStamped()
    msg.header.frame_id = draw(names_from(frames))
    p, o = msg.pose.position, msg.pose.orientation
    p.x, p.y, p.z = (draw(hostile_floats(st.floats(c - 0.3, c + 0.3))) for c in near)
    if draw(st.booleans()):
        o.x, o.y, o.z, o.w = 0.0, 0.0, 0.0, 1.0
    else:
        o.x, o.y, o.z, o.w = (draw(HOSTILE_FLOAT) for _ in range(4))
    return msg


@st.composite
def hostile_joint_states(draw, joints: list[str], plausible: dict[str, float]):
    """A JointState: the robot's joints near ``plausible`` values, or any names and values of any length."""
    msg = JointState()
    kind = draw(st.sampled_from(["empty", "plausible", "junk", "huge"]))
    if kind == "plausible":
        names = draw(st.lists(st.sampled_from(list(plausible)), min_size=1, unique=True))
        msg.name = names
        msg.position = [draw(hostile_floats(st.floats(plausible[n] - 0.2, plausible[n] + 0.2))) for n in names]
    elif kind == "junk":
        msg.name = draw(st.lists(names_from(joints), max_size=20))
        msg.position = draw(st.lists(HOSTILE_FLOAT, max_size=20))
    elif kind == "huge":
        msg.name = [f"junk_{i}" for i in range(50_000)]
        msg.position = [0.0] * draw(st.sampled_from([0, 50_000]))
    return msg


# ---------------------------------------------------------------- planning_node requests

PLANNER_IDS = ["", "RRT", "RRTConnect", "PRM", "GoalBiasedRRT", "RCRRT"]
TIME_PARAMETERIZATIONS = ["", "toppra", "ruckig", "trapezoid"]


def mutate(draw, mutations: dict[str, Callable[[], None]], max_mutations: int = 3) -> None:
    """Apply up to ``max_mutations`` of the named field mutations to a plausible message (none: it stays valid)."""
    for name in draw(st.lists(st.sampled_from(sorted(mutations)), max_size=max_mutations, unique=True)):
        mutations[name]()


def _state_fields(state: dict[str, float]) -> tuple[list[str], list[float]]:
    return list(state), list(state.values())


@st.composite
def plan_motion_requests(draw, joints: list[str], start: dict[str, float], groups: list[str], links: list[str]):
    """PlanMotion requests: a plausible plan with up to three hostile fields (names, counts, NaN/inf,
    huge values and arrays, quaternions, frames, budgets, scalings)."""
    req = PlanMotion.Request(
        group="upper_body",
        planner_id=draw(st.sampled_from(PLANNER_IDS)),
        allowed_planning_time=draw(st.floats(0.05, 0.5)),
        seed=draw(st.integers(0, 100)),
    )
    req.start_state.name, req.start_state.position = _state_fields(start)
    goal = {name: value + draw(st.sampled_from([0.0, 0.1, -0.2, 0.3])) for name, value in start.items()}
    req.goal_joint_names, req.goal_positions = _state_fields(goal)
    scaling = hostile_floats(st.sampled_from([0.0, 1e-300, 1e-6, 1e-3, 0.5, 1.0]))

    def pose_goal():
        req.goal_joint_names, req.goal_positions = [], []
        req.goal_poses = draw(st.lists(hostile_poses(["", "base_link", "world"]), max_size=3))
        req.goal_links = draw(st.lists(names_from(links), max_size=3))

    def goal_joints():
        state = draw(hostile_joint_states(joints, goal))
        req.goal_joint_names, req.goal_positions = list(state.name), list(state.position)

    mutate(draw, {
        "group": lambda: setattr(req, "group", draw(names_from(["", *groups]))),
        "start": lambda: setattr(req, "start_state", draw(hostile_joint_states(joints, start))),
        "goal joints": goal_joints,
        "goal poses": pose_goal,
        "both goals": lambda: setattr(req, "goal_poses", draw(st.lists(hostile_poses(["base_link"]), max_size=2))),
        "planner": lambda: setattr(req, "planner_id", draw(names_from(PLANNER_IDS))),
        "budget": lambda: setattr(req, "allowed_planning_time", draw(HOSTILE_FLOAT)),
        "attempts": lambda: setattr(req, "num_attempts", draw(INT32)),
        "seed": lambda: setattr(req, "seed", draw(INT64)),
        "velocity": lambda: setattr(req, "max_velocity_scaling_factor", draw(scaling)),
        "acceleration": lambda: setattr(req, "max_acceleration_scaling_factor", draw(scaling)),
        "jerk": lambda: setattr(req, "max_jerk_scaling_factor", draw(scaling)),
        "timing": lambda: setattr(req, "time_parameterization", draw(names_from(TIME_PARAMETERIZATIONS))),
    })  # fmt: skip
    return req


def plan_motion_budget(request, max_planning_time: float) -> float:
    """The budget an answer must keep: the request's, or 0 when the node must refuse it at once."""
    budget = request.allowed_planning_time
    return budget if math.isfinite(budget) and 0.0 < budget <= max_planning_time else 0.0


@st.composite
def compute_ik_requests(draw, joints: list[str], start: dict[str, float], groups: list[str], links: list[str]):
    """ComputeIK requests: a plausible hand pose with up to three hostile fields."""
    req = ComputeIK.Request(group="right_arm", timeout=draw(st.floats(0.05, 0.3)), avoid_collisions=draw(st.booleans()))
    req.seed_state.name, req.seed_state.position = _state_fields(start)
    req.poses = [draw(hostile_poses(["base_link"]))]
    req.links = ["r_hand"]
    mutate(draw, {
        "group": lambda: setattr(req, "group", draw(names_from(["", *groups]))),
        "seed": lambda: setattr(req, "seed_state", draw(hostile_joint_states(joints, start))),
        "poses": lambda: setattr(req, "poses", draw(hostile_lists(hostile_poses(["", "base_link", "world"]),
                                                                  [PoseStamped()] * 2_000, 3))),
        "links": lambda: setattr(req, "links", draw(st.lists(names_from(links), max_size=3))),
        "timeout": lambda: setattr(req, "timeout", draw(HOSTILE_FLOAT)),
    })  # fmt: skip
    return req


def compute_ik_budget(request, ik_timeout: float, max_time: float) -> float:
    """The request's timeout; <= 0 is the node's ``ik_timeout``; NaN, inf or over ``max_time``: refused (0)."""
    timeout = request.timeout
    if timeout <= 0.0:
        return ik_timeout
    return timeout if math.isfinite(timeout) and timeout <= max_time else 0.0


@st.composite
def scene_obstacles(draw, names: list[str]):

    msg = SceneObstacle()
    msg.header.frame_id = draw(names_from(["", "", "base_link", "world"]))
    msg.name = draw(names_from(names))
    msg.operation = draw(st.one_of(st.sampled_from([0, 1, 2]), st.integers(0, 255)))
    msg.shape.type = draw(st.one_of(st.sampled_from([SolidPrimitive.BOX, SolidPrimitive.SPHERE,
                                                     SolidPrimitive.CYLINDER]), st.integers(0, 255)))  # fmt: skip
    msg.shape.dimensions = draw(st.lists(hostile_floats(st.floats(0.01, 0.2)), max_size=3))  # float64[<=3]
    pose = draw(hostile_poses([""], near=(2.0, 2.0, 2.0)))  # far from the robot: an accepted one blocks nothing
    msg.pose = pose.pose
    return msg


@st.composite
def apply_scene_requests(draw):
    req = ApplyScene.Request()
    req.clear = draw(st.booleans()) and draw(st.booleans())  # a quarter clear the scene
    req.obstacles = draw(st.lists(scene_obstacles(["fuzz_a", "fuzz_b", "desk", "box"]), max_size=4))
    return req


@dataclass
class BurstResult:
    """Answers to ``clients`` simultaneous plan_motion calls: seconds to each answer, codes, lost ones."""

    clients: int
    latencies: list[float]
    codes: list[int]
    lost: int

    def count(self, code: int) -> int:
        return self.codes.count(code)

    def summary(self) -> dict:
        latencies = sorted(self.latencies) or [math.nan]
        return {
            "clients": self.clients,
            "answered": len(self.codes),
            "success": self.count(PlanningError.SUCCESS),
            "busy": self.count(PlanningError.BUSY),
            "lost": self.lost,
            "other": len(self.codes) - self.count(PlanningError.SUCCESS) - self.count(PlanningError.BUSY),
            "p50_s": _percentile(latencies, 50),
            "p95_s": _percentile(latencies, 95),
            "max_s": latencies[-1],
        }


def _percentile(values: list[float], q: float) -> float:
    index = min(len(values) - 1, max(0, math.ceil(q / 100.0 * len(values)) - 1))
    return values[index]


def plan_burst(spinning, clients: int = 64, budget: float = 5.0) -> BurstResult:
    """``clients`` plan_motion clients, each matched first, call at once (small right-arm moves).

    Every client's response reader sees all the burst's answers (one reply topic per service), so
    each keeps a queue twice as deep as the burst.
    """
    from rclpy.qos import QoSProfile

    from maru_planner.ros.planning_client import call_until_answered, plan_request

    node = spinning.node
    deep = QoSProfile(depth=2 * clients)
    callers = [node.create_client(PlanMotion, "plan_motion", qos_profile=deep) for _ in range(clients)]
    try:
        for caller in callers:
            assert caller.wait_for_service(timeout_sec=60.0), "plan_motion never appeared"
            call_until_answered(caller, PlanMotion.Request(), timeout=60.0)
        goals = [{**PAPER_START, "r_arm_j4": PAPER_START["r_arm_j4"] + 0.2 + 0.002 * i} for i in range(clients)]
        started = time.monotonic()
        futures = [caller.call_async(plan_request(goal, start=PAPER_START, planner_id="RRTConnect",
                                                  time_budget=budget, seed=i))
                   for i, (caller, goal) in enumerate(zip(callers, goals, strict=True))]  # fmt: skip
        answered_at: dict[int, float] = {}
        deadline = started + budget + LOST_AFTER
        while len(answered_at) < clients and time.monotonic() < deadline:
            for i, future in enumerate(futures):
                if i not in answered_at and future.done():
                    answered_at[i] = time.monotonic() - started
            time.sleep(0.001)
        codes = [futures[i].result().error.code for i in sorted(answered_at)]
        return BurstResult(clients, [answered_at[i] for i in sorted(answered_at)], codes, clients - len(answered_at))
    finally:
        for caller in callers:
            node.destroy_client(caller)


# ---------------------------------------------------------------- base_planner_node requests

BASE_PLANNER_IDS = ["", "astar", "se2", "mspp", "mspp_local", "tunnel", "biped_track", "biped_wall"]


@st.composite
def plan_base_path_requests(draw, free: tuple[tuple[float, float], tuple[float, float]]):
    """PlanBasePath requests: planner ids, footprints (sizes, extents, NaN), poses, frames, budgets.

    Valid budgets stay within 1 s (a valid large budget is a legitimate request to wait that long).
    """

    req = PlanBasePath.Request()
    req.planner_id = draw(names_from(BASE_PLANNER_IDS))
    kind = draw(st.sampled_from(["default", "small", "junk", "huge_extent", "huge_count"]))
    if kind == "small":
        points = draw(st.lists(st.tuples(st.floats(-0.5, 0.5), st.floats(-0.5, 0.5)), min_size=3, max_size=8))
    elif kind == "junk":
        points = draw(st.lists(st.tuples(FLOAT32, FLOAT32), max_size=10))
    elif kind == "huge_extent":
        half = draw(st.sampled_from([50.0, 1e4, 1e30]))
        points = [(half, half), (-half, half), (-half, -half), (half, -half)]
    elif kind == "huge_count":
        count = draw(st.sampled_from([500, 5_000]))  # 20,000 Point32s take ~0.5 s of rclpy (de)serialisation alone
        points = [(0.3 * math.cos(6.283 * k / count), 0.3 * math.sin(6.283 * k / count)) for k in range(count)]
    else:
        points = []
    req.footprint = [Point32(x=float(x), y=float(y), z=0.0) for x, y in points]
    for pose, centre in ((req.start, free[0]), (req.goal, free[1])):
        msg = draw(hostile_poses(["", "map", "odom"], near=(centre[0], centre[1], 0.0)))
        pose.header, pose.pose = msg.header, msg.pose
    req.allowed_planning_time = draw(st.one_of(
        st.floats(0.0, 1.0), st.sampled_from([math.nan, math.inf, -math.inf, -1.0, 3600.5, 1e300])))  # fmt: skip
    return req


def plan_base_budget(request, default_budget: float) -> float:
    t = request.allowed_planning_time
    if not (math.isfinite(t) and 0.0 <= t <= 3600.0):
        return 0.0
    return t or default_budget


@st.composite
def occupancy_grids(draw, max_cells: int = 10_000):
    """Well-formed nav_msgs/OccupancyGrid messages of bounded size with hostile contents."""
    msg = OccupancyGrid()
    msg.header.frame_id = draw(names_from(["map", ""]))
    width = draw(st.one_of(st.integers(0, 100), st.integers(0, 2**32 - 1)))
    height = draw(st.one_of(st.integers(0, 100), st.integers(0, 2**32 - 1)))
    msg.info.width, msg.info.height = width, height
    msg.info.resolution = draw(st.one_of(st.sampled_from([0.05, 0.1, 0.5]), FLOAT32))
    o = msg.info.origin
    o.position.x, o.position.y = draw(HOSTILE_FLOAT), draw(HOSTILE_FLOAT)
    o.orientation.x, o.orientation.y, o.orientation.z, o.orientation.w = (draw(HOSTILE_FLOAT) for _ in range(4))
    cells = width * height if width * height <= max_cells else draw(st.integers(0, max_cells))
    if draw(st.booleans()):
        cells = draw(st.integers(0, max_cells))  # a size that need not match
    fill = draw(st.integers(-128, 127))
    msg.data = [fill] * cells
    return msg


# ---------------------------------------------------------------- files: scenes, maps, worlds

YAML_JUNK = st.sampled_from([
    "", "~", "5", "[", "{a: [", "- 1\n- 2\n", "obstacles: 5\n", "obstacles: {a: 1}\n", "\t\tbad: indent",
    "obstacles:\n" + "  - {}\n" * 3, "a: &x [*x]\n", "!!python/object:os.system ['true']\n", "obstacles: [" * 200,
])  # fmt: skip
ANY_YAML_VALUE = st.recursive(
    st.one_of(st.none(), st.booleans(), st.integers(-(2**70), 2**70), HOSTILE_FLOAT, st.text(max_size=8)),
    lambda inner: st.one_of(st.lists(inner, max_size=4), st.dictionaries(st.text(max_size=6), inner, max_size=4)),
    max_leaves=12,
)


def _num(draw, valid: st.SearchStrategy):
    return draw(st.one_of(valid, HOSTILE_FLOAT, ANY_YAML_VALUE))


SHAPE_TYPES = ["box", "sphere", "cylinder", "mesh", "cone"]


@st.composite
def scene_documents(draw):
    """A scene YAML document: obstacles with hostile types, sizes, poses and counts, or raw junk."""
    kind = draw(st.sampled_from(["structured", "structured", "junk", "any"]))
    if kind == "junk":
        return draw(YAML_JUNK)
    if kind == "any":
        return {"obstacles": draw(ANY_YAML_VALUE)}
    obstacles = []
    for i in range(draw(st.integers(0, 4))):
        entry = {
            "name": draw(st.one_of(st.just(f"o{i}"), HOSTILE_TEXT, ANY_YAML_VALUE)),
            "type": draw(st.one_of(st.sampled_from(SHAPE_TYPES), ANY_YAML_VALUE)),
        }
        for key in draw(st.lists(st.sampled_from(["size", "radius", "length", "file", "scale"]), max_size=3)):
            entry[key] = draw(st.one_of(st.lists(st.floats(0.01, 1.0), min_size=1, max_size=3),
                                        st.floats(0.01, 1.0), ANY_YAML_VALUE))  # fmt: skip
        if draw(st.booleans()):
            entry["pose"] = draw(st.one_of(
                st.fixed_dictionaries({"xyz": st.lists(HOSTILE_FLOAT, max_size=4),
                                       "rpy": st.lists(HOSTILE_FLOAT, max_size=4)}),
                st.fixed_dictionaries({"xyz": st.lists(HOSTILE_FLOAT, max_size=4),
                                       "quat": st.lists(HOSTILE_FLOAT, max_size=5)}),
                ANY_YAML_VALUE))  # fmt: skip
        obstacles.append(entry)
    if draw(st.integers(0, 19)) == 0:  # many small spheres (pure-Python YAML reads ~1 ms per obstacle)
        obstacles = [{"name": f"s{i}", "type": "sphere", "radius": 0.01} for i in range(draw(st.sampled_from(
            [300, 1_000])))]  # fmt: skip
    doc = {"obstacles": obstacles}
    if draw(st.booleans()):
        doc[draw(st.sampled_from(["frame", "extra"]))] = draw(ANY_YAML_VALUE)
    return doc


@st.composite
def map_files(draw):
    """(map YAML document or text, PGM bytes or None): hostile keys, thresholds, origins, images."""
    kind = draw(st.sampled_from(["structured", "structured", "structured", "junk"]))
    if kind == "junk":
        return draw(YAML_JUNK), None
    doc = {
        "image": draw(st.one_of(st.just("m.pgm"), st.just("missing.pgm"), ANY_YAML_VALUE)),
        "resolution": _num(draw, st.floats(0.01, 1.0)),
        "origin": draw(st.one_of(st.lists(st.floats(-10, 10), min_size=3, max_size=3), ANY_YAML_VALUE)),
    }
    for key, valid in (
        ("occupied_thresh", st.floats(0, 1)),
        ("free_thresh", st.floats(0, 1)),
        ("negate", st.integers(0, 1)),
        ("mode", st.sampled_from(["trinary", "scale", "raw"])),
    ):
        if draw(st.booleans()):
            doc[key] = _num(draw, valid)
    if draw(st.booleans()):
        del doc[draw(st.sampled_from(["image", "resolution", "origin"]))]
    image = draw(st.sampled_from(["small", "small", "empty_header", "huge_header", "not_an_image", "zero"]))
    return doc, pgm_bytes(image, draw(st.integers(0, 255)))


def pgm_bytes(kind: str, fill: int) -> bytes:
    if kind == "small":
        return b"P5\n30 20\n255\n" + bytes([fill]) * 600
    if kind == "huge_header":  # claims 8000 x 8000, holds a few bytes
        return b"P5\n8000 8000\n255\n" + bytes(100)
    if kind == "zero":
        return b"P5\n0 0\n255\n"
    if kind == "empty_header":
        return b"P5\n"
    return b"not a picture at all"


def _xy(draw, lo=-5.0, hi=5.0):
    return draw(st.one_of(st.lists(st.floats(lo, hi), min_size=2, max_size=2), ANY_YAML_VALUE))


@st.composite
def sim_worlds(draw):
    """maru-reactive-sim world documents: obstacles, movers, robot, laser, path, limits; or junk."""
    if draw(st.integers(0, 5)) == 0:
        return draw(YAML_JUNK)
    obstacles = []
    for _ in range(draw(st.integers(0, 3))):
        kind = draw(st.one_of(st.sampled_from(["circle", "box", "polygon"]), ANY_YAML_VALUE))
        entry = {
            "type": kind,
            "center": _xy(draw),
            "radius": _num(draw, st.floats(0.05, 1)),
            "size": _xy(draw, 0.1, 1),
            "points": draw(
                st.one_of(st.lists(st.lists(st.floats(-3, 3), min_size=2, max_size=2), max_size=5), ANY_YAML_VALUE)
            ),
        }
        obstacles.append({k: v for k, v in entry.items() if draw(st.booleans()) or k == "type"})
    laser = {k: _num(draw, v) for k, v in (("fov_deg", st.floats(1, 360)), ("resolution_deg", st.floats(1e-6, 10)),
                                           ("range_min", st.floats(0, 1)), ("range_max", st.floats(0, 30)),
                                           ("noise", st.floats(0, 0.1)), ("rate", st.floats(0.1, 300)))
             if draw(st.booleans())}  # fmt: skip
    robot = {
        "start": draw(st.one_of(st.just([0, 0, 0]), ANY_YAML_VALUE)),
        "goal": draw(st.one_of(st.just([2, 0, 0]), ANY_YAML_VALUE)),
        "radius": _num(draw, st.floats(0.05, 0.5)),
        "laser": laser,
    }
    if draw(st.booleans()):
        robot["footprint"] = draw(st.one_of(st.lists(st.lists(HOSTILE_FLOAT, max_size=3), max_size=5),
                                            ANY_YAML_VALUE))  # fmt: skip
    doc = {"obstacles": obstacles, "robot": robot, "max_time": _num(draw, st.floats(0.1, 2.0))}
    if draw(st.booleans()):
        doc["movers"] = draw(
            st.one_of(
                st.lists(
                    st.fixed_dictionaries(
                        {
                            "radius": st.floats(0.05, 0.5),
                            "speed": HOSTILE_FLOAT,
                            "waypoints": st.lists(st.lists(HOSTILE_FLOAT, min_size=2, max_size=2), max_size=3),
                            "mode": st.sampled_from(["stop", "loop", "pingpong", "bounce"]),
                        }
                    ),
                    max_size=2,
                ),
                ANY_YAML_VALUE,
            )
        )
    for key in draw(st.lists(st.sampled_from(["path", "bounds", "goal_tolerance", "map", "junk_key"]), max_size=2)):
        doc[key] = draw(ANY_YAML_VALUE)
    return doc


@st.composite
def biped_worlds(draw):
    """maru-base-plan --world documents (biped planners): bounds, resolution, boxes, robot; or junk."""
    if draw(st.integers(0, 5)) == 0:
        return draw(YAML_JUNK)
    span = draw(st.sampled_from([4.0, 10.0, 1e6]))
    doc = {"bounds": draw(st.one_of(st.just([0, 0, span, 3]), st.lists(HOSTILE_FLOAT, max_size=5), ANY_YAML_VALUE)),
           "resolution": _num(draw, st.floats(0.02, 0.2)),
           "start": draw(st.one_of(st.just([0.5, 1.5, 0]), ANY_YAML_VALUE)),
           "goal": draw(st.one_of(st.just([3.5, 1.5, 0]), ANY_YAML_VALUE)),
           "obstacles": draw(st.one_of(st.lists(st.fixed_dictionaries({
               "center": st.lists(HOSTILE_FLOAT, max_size=3), "size": st.lists(HOSTILE_FLOAT, max_size=3),
               "yaw": HOSTILE_FLOAT}), max_size=3), ANY_YAML_VALUE))}  # fmt: skip
    for key in draw(st.lists(st.sampled_from(["robot", "reference_line", "name"]), max_size=2)):
        doc[key] = draw(ANY_YAML_VALUE)
    return doc


def write_document(path: FilePath, document) -> FilePath:
    """A generated document as a file: YAML of a structure, or raw text as it is."""
    path.write_text(document if isinstance(document, str) else yaml.safe_dump(document, allow_unicode=True))
    return path


# ---------------------------------------------------------------- files and CLIs in-process


def loader_outcome(load: Callable[[], object], what: str, error_types: tuple[type, ...]) -> Outcome:
    """Accepted when ``load()`` returns, a proper error when it raises one of ``error_types``
    with a proper message; anything else is a crash (a CLI would print its traceback)."""
    try:
        load()
    except error_types as exc:
        problem = message_problem(str(exc))
        return Outcome(proper_error=not problem, detail=f"{what}: {type(exc).__name__}: {problem}")
    except Exception as exc:  # noqa: BLE001 - exactly what the suite looks for
        return Outcome(crash=True, traceback=True, detail=f"{what}: {type(exc).__name__}: {str(exc)[:200]}")
    return Outcome(accepted=True)


CLI_LATE_MARGIN = 10.0  # s beyond a CLI's planning budget (loading the robot, scene or map is outside it)


def cli_outcome(
    main: Callable[[list[str]], int],
    argv: list[str],
    prog: str,
    codes: set[int],
    bad_input: int,
    internal: int | None = None,
    budget: float = 0.0,
) -> Outcome:
    """Run a CLI's ``main(argv)`` in this process: a documented exit code, on bad input exactly one
    stderr line naming the program, on other failures a proper last line; never an exception."""
    out, err = io.StringIO(), io.StringIO()
    started = time.monotonic()
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            try:
                code = main(argv)
            except SystemExit as exc:  # argparse's own exits (--help, bad options)
                code = exc.code if isinstance(exc.code, int) else bad_input
    except Exception as exc:  # noqa: BLE001 - a user would see this traceback
        return Outcome(crash=True, traceback=True, detail=f"{prog} {argv!r:.300}: {type(exc).__name__}: {exc!s:.200}")
    elapsed = time.monotonic() - started
    lines = err.getvalue().strip().splitlines()
    detail = f"{prog} -> exit {code} in {elapsed:.1f} s, stderr {lines[-3:]!r:.300}; argv {argv!r:.300}"
    late = elapsed > budget + CLI_LATE_MARGIN
    traceback = any("Traceback" in line for line in lines)
    if code not in codes:
        return Outcome(late=late, traceback=traceback, detail=detail + " (undocumented exit code)")
    if code == internal:
        return Outcome(internal=True, late=late, detail=detail)
    if code == 0:
        return Outcome(accepted=True, late=late, traceback=traceback, detail=detail)
    if code == bad_input and (len(lines) != 1 or not lines[0].startswith(prog)):
        problem = f"{len(lines)} stderr lines on bad input (one, starting with {prog!r}, expected)"
    else:
        problem = message_problem(lines[-1]) if lines else "nothing on stderr"
    return Outcome(proper_error=not problem, late=late, traceback=traceback, detail=f"{detail} {problem}")


# ---------------------------------------------------------------- CLI argument vectors

NUMBER_TEXT = st.one_of(
    st.sampled_from(["nan", "inf", "-inf", "-1", "0", "1e309", "1e-320", "abc", "", "0x10", "1_0", " 1", "-0", "1e-5"]),
    st.floats(allow_nan=False).map(repr),
    st.integers(-(2**70), 2**70).map(str),
)
SHORT_NUMBER_TEXT = st.sampled_from(["nan", "inf", "-1", "0", "3601", "1e9", "abc", "", "0.2", "1"])


def output_paths(tmp: FilePath, valid_ok: bool = True) -> st.SearchStrategy:
    """Hostile output paths (a directory, under a file, a missing directory, /dev/full, read-only), or a valid one."""
    (tmp / "a_file").write_text("not a directory")
    bad = [str(tmp), str(tmp / "a_file" / "out"), str(tmp / "no" / "such" / "out"), "/dev/full", "/proc/version",
           "", "/"]  # fmt: skip
    return st.sampled_from(bad + ([str(tmp / "out.json")] if valid_ok else []))


class Files:
    """Writes generated documents as numbered files under ``root`` (for --scene, --map, --world)."""

    def __init__(self, root: FilePath):
        self.root = root
        self._count = itertools.count()

    def document(self, document) -> str:
        return str(write_document(self.root / f"doc_{next(self._count)}.yaml", document))

    def map_file(self, files: tuple) -> str:
        directory = self.root / f"map_{next(self._count)}"
        directory.mkdir()
        document, pgm = files
        if pgm is not None:
            (directory / "m.pgm").write_bytes(pgm)
        return str(write_document(directory / "m.yaml", document))


@st.composite
def argv_from(draw, base: dict[str, list[str] | None], mutations: dict[str, st.SearchStrategy]):
    """``base`` options with up to three of them replaced (or added) by hostile values, as an argv list
    (a name ending in ``=`` gives one ``--name=value`` argument)."""
    options = dict(base)
    for name in draw(st.lists(st.sampled_from(sorted(mutations)), max_size=3, unique=True)):
        value = draw(mutations[name])
        options[name] = value if isinstance(value, list) or value is None else [value]
    argv = []
    for name, values in options.items():
        if name.endswith("="):  # --option=VALUE, one argument
            argv.append(name + values[0])
        else:
            argv.append(name)
            argv.extend(values or [])
    return argv


def maru_plan_argv(tmp: FilePath) -> st.SearchStrategy:
    from maru_planner.planning.problems import PROBLEMS

    files = Files(tmp)
    base = {"--quiet": None, "--problem": ["maru6"], "--time": ["0.3"], "--seed": ["1"]}
    numbers = {
        f"--{name}": NUMBER_TEXT
        for name in (
            "time",
            "max-time",
            "seed",
            "attempts",
            "resolution",
            "velocity-scaling",
            "acceleration-scaling",
            "jerk-scaling",
        )
    }
    return argv_from(base, {
        **numbers,
        "--problem": names_from(sorted(PROBLEMS)),
        "--robot": names_from(["maru1", "r2d2"]),
        "--planner": names_from(PLANNER_IDS),
        "--param": st.one_of(HOSTILE_TEXT, st.tuples(st.sampled_from(["step", "range", "goal_bias", "x"]),
                                                     NUMBER_TEXT).map("=".join)),
        "--group": names_from(["upper_body", "right_arm", "legs"]),
        "--start": st.lists(NUMBER_TEXT, max_size=8),
        "--goal": st.lists(NUMBER_TEXT, max_size=8),
        "--scene": st.one_of(scene_documents().map(files.document), st.sampled_from(["none", str(tmp), "/nope.yaml"])),
        "--collision-model": names_from(["exact", "spheres"]),
        "--time-parameterization": names_from(TIME_PARAMETERIZATIONS),
        "--json": output_paths(tmp),
        "--png": output_paths(tmp, valid_ok=False),
        "--bogus": st.none(),
    })  # fmt: skip


def maru_base_plan_argv(tmp: FilePath) -> st.SearchStrategy:
    files = Files(tmp)
    base = {"--map": [str(config_path("maps", "paper002_medium.yaml"))], "--start": ["1", "2", "0"],
            "--goal": ["5", "2", "0"], "--time-limit": ["0.5"]}  # fmt: skip
    footprints = st.one_of(HOSTILE_TEXT, st.sampled_from([
        "rect:-1:0.5", "disc:0", "disc:1e30", "rect:100:100", "1,2 3", "0,0 1,0", "rect:nan:1", "disc:", "0,0;1,0;1,1",
        "rect:0.9:0.3", "-0.4,-0.2 0.4,-0.2 0.4,0.2 -0.4,0.2"]))  # fmt: skip
    return argv_from(base, {
        "--map": st.one_of(map_files().map(files.map_file), st.sampled_from([str(tmp), "/nope.yaml", ""])),
        "--world": biped_worlds().map(files.document),
        "--planner": names_from(BASE_PLANNER_IDS[1:]),
        "--start": st.lists(NUMBER_TEXT, max_size=4),
        "--goal": st.lists(NUMBER_TEXT, max_size=4),
        "--footprint=": footprints,  # one argument: a first vertex may start with '-'
        "--param": st.one_of(HOSTILE_TEXT, st.tuples(st.sampled_from(["headings", "x"]), NUMBER_TEXT).map("=".join)),
        "--time-limit": SHORT_NUMBER_TEXT,
        "--unknown-free": st.none(),
        "--json": output_paths(tmp),
        "--png": output_paths(tmp, valid_ok=False),
    })  # fmt: skip


SIM_WORLD = {"obstacles": [{"type": "circle", "center": [1.5, 0.4], "radius": 0.2}],
             "robot": {"start": [0, 0, 0], "goal": [2, 0, 0]}, "max_time": 2}  # fmt: skip


def maru_reactive_sim_argv(tmp: FilePath) -> st.SearchStrategy:
    files = Files(tmp)
    good = files.document(SIM_WORLD)
    base = {"--world": [good], "--max-time": ["1"], "--quiet": None, "--no-arm": None, "--no-jitter": None}
    return argv_from(base, {
        "--world": st.one_of(sim_worlds().map(files.document), st.sampled_from([str(tmp), "/nope.yaml", ""])),
        "--strip": names_from(["modified", "plain"]),
        "--seed": NUMBER_TEXT,
        "--max-time": SHORT_NUMBER_TEXT,
        "--json": output_paths(tmp),
        "--png": output_paths(tmp, valid_ok=False),
        "--gif": output_paths(tmp, valid_ok=False),
        "--continue-after-collision": st.none(),
    })  # fmt: skip


def number_or_zero(text: str) -> float:
    """A CLI's budget argument as a number (0 when it is not one: the CLI must refuse it at once)."""
    try:
        value = float(text)
    except ValueError:
        return 0.0
    return value if math.isfinite(value) and value > 0 else 0.0


def option_value(argv: list[str], option: str, default: str) -> str:
    """The last value given to ``option`` in ``argv``."""
    indices = [i for i, arg in enumerate(argv[:-1]) if arg == option]
    return argv[indices[-1] + 1] if indices else default


# ---------------------------------------------------------------- node processes


class LogWatch:
    """New output of a node's log since the last look (for tracebacks)."""

    def __init__(self, log_path: FilePath):
        self.log_path = FilePath(log_path)
        self.offset = 0

    def new_text(self) -> str:
        with open(self.log_path, errors="replace") as f:
            f.seek(self.offset)
            text = f.read()
            self.offset = f.tell()
        return text


def timed_call(spinning, client, request, budget: float) -> tuple[object | None, float]:
    """(response or None when lost, seconds to the answer) for one service call."""
    future = client.call_async(request)
    started = time.monotonic()
    deadline = started + budget + LOST_AFTER
    while not future.done():
        if time.monotonic() > deadline:
            client.remove_pending_request(future)
            return None, time.monotonic() - started
        time.sleep(0.001)
    return future.result(), time.monotonic() - started


def service_outcome(
    process,
    watch: LogWatch,
    response,
    elapsed: float,
    budget: float,
    what: str,
    success_code: int,
    internal_code: int,
    code_of: Callable,
    message_of: Callable,
) -> Outcome:
    """Outcome of one call to a node: lost, crashed, traceback in its log, or the answer's own outcome."""
    alive = process.alive()
    traceback = "Traceback" in watch.new_text()
    if response is None:
        return Outcome(lost=True, crash=not alive, traceback=traceback, detail=f"{what}: no answer ({elapsed:.1f} s)")
    code = code_of(response)
    outcome = answer_outcome(
        code == success_code, code == internal_code, message_of(response), elapsed, budget, f"{what} -> code {code}"
    )
    outcome.crash, outcome.traceback = not alive, traceback
    return outcome


def params_file_arguments(config_file: str, limits: dict[str, float]) -> list[str]:
    """``--ros-args`` of a node on a shipped params file with ``limits`` set on top."""
    overrides = [arg for name, value in limits.items() for arg in ("-p", f"{name}:={value}")]
    return ["--ros-args", "--params-file", str(config_path(config_file)), *overrides]


# ---------------------------------------------------------------- planning_node

GROUP_JOINTS = ["waist_yaw"] + [f"r_arm_j{i}" for i in range(1, 7)] + [f"l_arm_j{i}" for i in range(1, 7)]
PAPER_START = PROBLEMS["maru13"].start_dict(GROUP_JOINTS)
EASY_GOAL = {**PAPER_START, "r_arm_j4": PAPER_START["r_arm_j4"] + 0.3}  # a right-arm move clear of the desk
PLANNING_LIMITS = {"max_planning_time": 2.0, "ik_timeout": 0.5}  # node parameters the budgets are checked against


class PlanningNodeTarget:
    """planning_node's services and topics, driven through one spinning rclpy client node."""

    name = "planning_node"

    def __init__(self, spinning, process, robot):
        self.spinning, self.process, self.robot = spinning, process, robot
        self.watch = LogWatch(process.log_path)
        self.client = PlanningClient(node=spinning.node)
        node = spinning.node
        self.joint_states = node.create_publisher(JointState, "/joint_states", 10)
        self.scene_topic = node.create_publisher(SceneObstacle, "/planning_scene_obstacles", 50)
        self.joints = list(robot.joint_names)
        self.groups = list(robot.groups)
        self.links = ["r_hand", "l_hand", "torso", "base_link", *robot.joint_names[:2]]
        self.initial_scene: list = []

    def connect(self, timeout: float = 120.0) -> None:
        assert self.client.plan_client.wait_for_service(timeout_sec=timeout), "plan_motion never appeared"
        self.client.wait_until_ready(timeout=timeout)
        ok = self.spinning.wait_for(lambda: self.joint_states.get_subscription_count() > 0, timeout=timeout)
        assert ok, "planning_node never subscribed to /joint_states"
        self.initial_scene = list(self.client.get_scene().obstacles)

    # ------------------------------------------------------------ strategies
    def plan_requests(self) -> st.SearchStrategy:
        return plan_motion_requests(self.joints, PAPER_START, self.groups, self.links)

    def ik_requests(self) -> st.SearchStrategy:
        return compute_ik_requests(self.joints, PAPER_START, self.groups, self.links)

    def joint_state_messages(self) -> st.SearchStrategy:
        return hostile_joint_states(self.joints, PAPER_START)

    # ------------------------------------------------------------ senders
    def _outcome(self, response, elapsed: float, budget: float, what: str) -> Outcome:
        return service_outcome(
            self.process,
            self.watch,
            response,
            elapsed,
            budget,
            what,
            PlanningError.SUCCESS,
            PlanningError.INTERNAL_ERROR,
            lambda r: r.error.code,
            lambda r: r.error.message,
        )

    def send_plan(self, request) -> Outcome:
        budget = plan_motion_budget(request, PLANNING_LIMITS["max_planning_time"])
        response, elapsed = timed_call(self.spinning, self.client.plan_client, request, budget)
        return self._outcome(response, elapsed, budget, "plan_motion")

    def send_ik(self, request) -> Outcome:
        budget = compute_ik_budget(request, PLANNING_LIMITS["ik_timeout"], PLANNING_LIMITS["max_planning_time"])
        response, elapsed = timed_call(self.spinning, self.client.ik_client, request, budget)
        return self._outcome(response, elapsed, budget, "compute_ik")

    def send_scene(self, request) -> Outcome:
        response, elapsed = timed_call(self.spinning, self.client.apply_client, request, 0.0)
        return self._outcome(response, elapsed, 0.0, "apply_scene")

    def publish(self, publisher, message) -> Outcome:
        publisher.publish(message)
        alive, traceback = self.process.alive(), "Traceback" in self.watch.new_text()
        return Outcome(proper_error=True, crash=not alive, traceback=traceback, detail="published")

    # ------------------------------------------------------------ known-good checks
    def good_plan(self, start: dict[str, float] | None = PAPER_START):
        """A known-good plan (from ``start``, or the latest /joint_states when None); returns the response."""
        return self.client.plan(EASY_GOAL, start=start, planner_id="RRTConnect", time_budget=2.0, seed=7,
                                timeout=60.0)  # fmt: skip

    def restore_scene(self) -> None:
        self.client.apply_scene(self.initial_scene, clear=True)

    def junk_joint_states(self, count: int) -> None:
        """``count`` well-formed /joint_states of 100 junk names (and a NaN for a real joint) each."""
        for i in range(count):
            names = [f"junk_{i}_{k}" for k in range(100)] + ["waist_yaw"]
            self.joint_states.publish(joint_state_msg(names, [0.1 * k for k in range(100)] + [math.nan]))

    def good_state_is_used(self, state: dict[str, float] = PAPER_START, timeout: float = 60.0) -> bool:
        """Publish ``state`` until a plan with an empty start starts there (topics and services are unordered)."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            for _ in range(3):
                self.joint_states.publish(joint_state_msg(list(state), list(state.values())))
                time.sleep(0.02)
            response = self.good_plan(start=None)
            if response.error.code == PlanningError.SUCCESS:
                names, _, positions = trajectory_positions(response.trajectory)
                if all(abs(p - state[n]) < 1e-6 for n, p in zip(names, positions[0], strict=True)):
                    return True
            time.sleep(0.1)
        return False


# ---------------------------------------------------------------- base_planner_node

BASE_LIMITS = {"allowed_planning_time": 1.0}  # the node's default budget (a request's 0)
BASE_START, BASE_GOAL = (1.0, 2.0), (5.0, 2.0)  # free cells of table1("medium")


class BaseNodeTarget:
    """base_planner_node's services and /map, driven through one spinning rclpy client node."""

    name = "base_planner_node"

    def __init__(self, spinning, process):
        from nav_msgs.srv import GetPlan
        from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

        from maru_planner.base.scenes import table1
        from maru_planner.ros.base_conversions import grid_to_msg

        self.spinning, self.process = spinning, process
        self.watch = LogWatch(process.log_path)
        node = spinning.node
        latched = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL,
                             reliability=ReliabilityPolicy.RELIABLE)  # fmt: skip
        self.map_pub = node.create_publisher(OccupancyGrid, "/map", latched)
        self.plan_client = node.create_client(PlanBasePath, "/plan_base_path")
        self.get_plan_client = node.create_client(GetPlan, "/make_plan")
        grid = table1("medium")
        self.good_map = grid_to_msg(grid, grid.occupied, Time(), "map")

    def connect(self, timeout: float = 120.0) -> None:
        for client in (self.plan_client, self.get_plan_client):
            assert client.wait_for_service(timeout_sec=timeout), f"{client.srv_name} never appeared"
        assert self.spinning.wait_for(lambda: self.map_pub.get_subscription_count() > 0, timeout=timeout)
        assert self.restore_map(), "the node never planned on the published map"

    def requests(self) -> st.SearchStrategy:
        return plan_base_path_requests((BASE_START, BASE_GOAL))

    def get_plan_requests(self) -> st.SearchStrategy:
        from nav_msgs.srv import GetPlan

        def request(poses):
            req = GetPlan.Request()
            req.start, req.goal = poses
            return req

        return st.tuples(hostile_poses(["", "map", "odom"], near=(*BASE_START, 0.0)),
                         hostile_poses(["", "map", "odom"], near=(*BASE_GOAL, 0.0))).map(request)  # fmt: skip

    def send(self, request) -> Outcome:
        budget = plan_base_budget(request, BASE_LIMITS["allowed_planning_time"])
        response, elapsed = timed_call(self.spinning, self.plan_client, request, budget)
        return service_outcome(self.process, self.watch, response, elapsed, budget, "plan_base_path",
                               PlanBasePath.Response.NONE, PlanBasePath.Response.UNKNOWN,
                               lambda r: r.error_code, lambda r: r.error_msg)  # fmt: skip

    def send_get_plan(self, request) -> Outcome:
        """nav_msgs/GetPlan has no error field: an answer in time is all it can give."""
        budget = BASE_LIMITS["allowed_planning_time"]
        response, elapsed = timed_call(self.spinning, self.get_plan_client, request, budget)
        return service_outcome(self.process, self.watch, response, elapsed, budget, "make_plan", 0, None,
                               lambda r: 0, lambda r: "")  # fmt: skip

    def publish_map(self, message) -> Outcome:
        self.map_pub.publish(message)
        alive, traceback = self.process.alive(), "Traceback" in self.watch.new_text()
        return Outcome(proper_error=True, crash=not alive, traceback=traceback, detail="published /map")

    def junk_maps(self, count: int) -> None:
        """``count`` 100 x 100 maps of junk values, half of them malformed (one value short)."""
        junk = OccupancyGrid()
        junk.info.width, junk.info.height, junk.info.resolution = 100, 100, 0.05
        for i in range(count):
            junk.data = array.array("b", bytes([i % 100]) * (10_000 if i % 2 else 9_999))  # no per-value check
            self.map_pub.publish(junk)

    def good_request(self):
        req = PlanBasePath.Request(planner_id="mspp", allowed_planning_time=5.0)
        for pose, (x, y) in ((req.start, BASE_START), (req.goal, BASE_GOAL)):
            pose.header.frame_id = "map"
            pose.pose.position.x, pose.pose.position.y, pose.pose.orientation.w = x, y, 1.0
        response, _ = timed_call(self.spinning, self.plan_client, req, 5.0)
        return response

    def restore_map(self, timeout: float = 60.0) -> bool:
        """Publish the good map until a known-good request succeeds on it."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            self.map_pub.publish(self.good_map)
            time.sleep(0.2)
            response = self.good_request()
            if response is not None and response.error_code == PlanBasePath.Response.NONE:
                return True
        return False


# ---------------------------------------------------------------- reactive_node

REACTIVE_GOAL = (4.0, 0.0, 0.0)
REACTIVE_NS = "/hostile_reactive"


@st.composite
def hostile_paths(draw):
    """nav_msgs/Path: a few plausible points with hostile values, or very many, in any frame."""
    msg = Path()
    msg.header.frame_id = draw(names_from(["odom", "", "map"]))
    count = draw(st.one_of(st.integers(0, 8), st.sampled_from([2_000, 5_000])))
    step = draw(hostile_floats(st.floats(0.1, 1.0)))
    for k in range(count):
        pose = PoseStamped()
        pose.header.frame_id = msg.header.frame_id
        pose.pose.position.x = k * step
        pose.pose.position.y = draw(HOSTILE_FLOAT) if k < 8 and draw(st.booleans()) else 0.0
        pose.pose.orientation.w = 1.0
        msg.poses.append(pose)
    return msg


@st.composite
def hostile_odometry(draw):
    msg = Odometry()
    msg.header.frame_id = draw(names_from(["odom", ""]))
    msg.child_frame_id = draw(names_from(["base_link", ""]))
    msg.header.stamp.sec = draw(st.integers(0, 2**31 - 1))
    p, o, t = msg.pose.pose.position, msg.pose.pose.orientation, msg.twist.twist
    p.x, p.y = draw(hostile_floats(st.floats(-1, 1))), draw(hostile_floats(st.floats(-1, 1)))
    o.z, o.w = draw(hostile_floats(st.just(0.0))), draw(hostile_floats(st.just(1.0)))
    t.linear.x, t.angular.z = draw(HOSTILE_FLOAT), draw(HOSTILE_FLOAT)
    return msg


def reactive_messages() -> st.SearchStrategy:
    """(topic, message) for every topic reactive_node subscribes: goal_pose, plan, scan, odom."""
    return st.one_of(
        hostile_poses(["odom", "", "map"], near=REACTIVE_GOAL).map(lambda m: ("goal", m)),
        hostile_paths().map(lambda m: ("plan", m)),
        laser_scans().map(lambda m: ("scan", m)),
        hostile_odometry().map(lambda m: ("odom", m)),
    )


class ReactiveNodeTarget:
    """reactive_node's topics, through the reactive tests' client (sim time, one namespace)."""

    name = "reactive_node"

    def __init__(self, spinning, process):
        self.spinning, self.process = spinning, process
        self.watch = LogWatch(process.log_path)
        self.client = ReactiveClient(spinning, namespace=REACTIVE_NS, process=process)
        c = self.client
        self.publishers = {"goal": c.goal_pub, "plan": c.plan_pub, "scan": c.scan_pub, "odom": c.odom_pub}
        self._stamps = (1000.0 + 0.1 * k for k in itertools.count())

    @staticmethod
    def node_arguments(params_dir: FilePath) -> list[str]:
        params = reactive_params_file(params_dir, scan_reliability="reliable", status_period=0.3, use_sim_time=True,
                                      scan_timeout=600.0, warn_throttle_period=1.0)  # fmt: skip
        return ["--ros-args", "-r", f"__ns:={REACTIVE_NS}", "-r", f"/clock:={REACTIVE_NS}/clock",
                "--params-file", str(params)]  # fmt: skip

    def connect(self) -> None:
        self.client.wait_connected()
        self.send_good_goal()

    def send_good_goal(self) -> None:
        from maru_planner.ros import reactive_conversions as conv

        goal = conv.pose_stamped_msg(REACTIVE_GOAL, "odom", 0.0)
        self.client.send_and_confirm(self.client.goal_pub, goal, self.process, "goal (")

    def send(self, topic_message) -> Outcome:
        topic, message = topic_message
        self.publishers[topic].publish(message)
        alive, traceback = self.process.alive(), "Traceback" in self.watch.new_text()
        return Outcome(proper_error=True, crash=not alive, traceback=traceback, detail=f"published {topic}")

    def callback_errors(self) -> int:
        found = re.findall(r"\bcallback errors (\d+)", self.process.log())
        return int(found[-1]) if found else -1

    def junk_scans(self, count: int) -> None:
        """``count`` scans stamped in the past, with NaN or negative ranges."""
        junk = synthetic_scan(1.0)
        for i in range(count):
            junk.header.stamp.sec = i % 900
            junk.ranges[i % len(junk.ranges)] = math.nan if i % 3 else -1.0
            self.client.scan_pub.publish(junk)

    def settle(self, quiet: float = 0.5, timeout: float = 15.0) -> None:
        """Wait until the node's log has been still for ``quiet`` s: the batch's messages are all handled.

        Messages on different topics are not ordered, so a good goal sent at once could be overtaken by a
        hostile /plan still in flight (which legitimately replaces the goal's path).
        """
        deadline = time.monotonic() + timeout
        size, still_since = self._logged(), time.monotonic()
        while time.monotonic() < deadline:
            time.sleep(0.05)
            now = self._logged()
            if now != size:
                size, still_since = now, time.monotonic()
            elif time.monotonic() - still_since >= quiet:
                return

    def _logged(self) -> int:
        """Lines the node has logged, a line repeating the one before counting once.

        The status line repeats every status_period while nothing arrives; any handled message changes its
        counters (or logs a line of its own).
        """
        lines = LOG_STAMP.sub("", self.process.log()).splitlines()
        return sum(line != before for before, line in zip(["", *lines], lines))

    def good_step(self):
        """Good odometry + scan after the good goal: the command must move the base, within the limits."""
        stamp = next(self._stamps)
        twist = self.client.step(odom((0.0, 0.0, 0.0), stamp), synthetic_scan(stamp, [OBSTACLE]))
        limits = shipped_params()
        return 0.0 < twist.linear.x <= limits["max_linear"] + 1e-9 and abs(twist.angular.z) <= limits["max_angular"]


def report_counts(request, targets: list[str], extra: list[str] = ()) -> None:
    """Print the targets' counts (and ``extra`` lines) past pytest's output capture."""
    capture = request.config.pluginmanager.getplugin("capturemanager")
    with capture.global_and_fixture_disabled():
        for line in [*summary_lines(targets), *extra]:
            print("\n" + line, end="")
        print()


def serve_module(target, request, measured: list[str]) -> Iterator:
    """A module fixture's body: ``target`` connected; after the module, its counts printed, its node alive."""
    target.connect()
    yield target
    report_counts(request, [target.name], measured)
    target.spinning.destroy()
    assert target.process.alive(), target.process.log()[-3000:]

"""The package's import graph, read from the source with ``ast`` (nothing is imported), and the rules it must
keep: no cycles (function-level and ``TYPE_CHECKING`` imports count), a ROS-free core, a reason on every lazy
import, and the layer table of ``docs/architecture.md`` (:data:`LAYERS`).
"""

from __future__ import annotations

import ast
import functools
import io
import re
import tokenize
from collections import deque
from dataclasses import dataclass
from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parents[2]
PACKAGE = "maru_planner"
ROS_TOP_LEVEL = frozenset(
    {"rclpy", "rosidl_runtime_py", "ament_index_python", "launch", "launch_ros", "tf2_ros", "message_filters"}
)
ROS_MESSAGE_SUFFIXES = ("_msgs", "_srvs", "_interfaces")
LAZY_REASON = re.compile(r"#\s*lazy:\s*\S")


@dataclass(frozen=True)
class Import:
    """One imported module as written in ``importer`` at ``line`` (resolved to a module name)."""

    importer: str
    target: str
    path: Path
    line: int
    in_function: bool
    type_only: bool
    justified: bool


def module_files(root: Path, package: str) -> dict[str, Path]:
    """Every module of ``package`` under ``root`` by dotted name (a package by its ``__init__.py``)."""
    modules = {}
    for path in sorted((root / package).rglob("*.py")):
        parts = path.relative_to(root).with_suffix("").parts
        if parts[-1] == "__init__":
            parts = parts[:-1]
        modules[".".join(parts)] = path
    return modules


def _lazy_reason_lines(source: str) -> tuple[set[int], set[int]]:
    """Lines ending in a ``# lazy: <reason>`` comment, and lines right below such a comment-only line."""
    trailing, below = set(), set()
    for token in tokenize.generate_tokens(io.StringIO(source).readline):
        if token.type == tokenize.COMMENT and LAZY_REASON.match(token.string):
            row = token.start[0]
            if token.line[: token.start[1]].strip():
                trailing.add(row)
            else:
                below.add(row + 1)
    return trailing, below


def _is_type_checking(test: ast.expr) -> bool:
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def _resolve(importer: str, is_package: bool, node: ast.ImportFrom) -> str:
    if not node.level:
        return node.module or ""
    anchor = importer.split(".") if is_package else importer.split(".")[:-1]
    anchor = anchor[: len(anchor) - (node.level - 1)]
    return ".".join(anchor + ([node.module] if node.module else []))


def _targets(node: ast.Import | ast.ImportFrom, importer: str, is_package: bool, known: set[str]) -> list[str]:
    if isinstance(node, ast.Import):
        return [alias.name for alias in node.names]
    base = _resolve(importer, is_package, node)
    return [f"{base}.{a.name}" if f"{base}.{a.name}" in known else base for a in node.names]


def imports_of(importer: str, path: Path, known: set[str]) -> list[Import]:
    """The imports written in one module, each flagged function-level / type-only / justified.

    A ``# lazy: <reason>`` comment justifies the import on its line or, on a line of its own, the run
    of import statements right below it (blank lines between them, as isort puts between groups, included).
    """
    source = path.read_text()
    lines = source.splitlines()
    trailing, below = _lazy_reason_lines(source)
    is_package = path.name == "__init__.py"
    found: list[Import] = []

    def visit(node: ast.AST, in_function: bool, type_only: bool) -> None:
        if isinstance(node, ast.Import | ast.ImportFrom):
            justified = node.lineno in trailing or node.lineno in below
            if node.lineno in below and node.end_lineno is not None:
                following = node.end_lineno + 1
                while following <= len(lines) and not lines[following - 1].strip():
                    following += 1
                below.add(following)
            for target in dict.fromkeys(_targets(node, importer, is_package, known)):
                found.append(Import(importer, target, path, node.lineno, in_function, type_only, justified))
            return
        if isinstance(node, ast.If) and _is_type_checking(node.test):
            for child in node.body:
                visit(child, in_function, True)
            for child in node.orelse:
                visit(child, in_function, type_only)
            return
        inner = in_function or isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.Lambda)
        for child in ast.iter_child_nodes(node):
            visit(child, inner, type_only)

    visit(ast.parse(source, filename=str(path)), False, False)
    return found


def package_imports(root: Path, package: str) -> list[Import]:
    modules = module_files(root, package)
    known = set(modules)
    return [imp for name, path in modules.items() for imp in imports_of(name, path, known)]


def internal(target: str, package: str) -> bool:
    return target == package or target.startswith(package + ".")


def _strongly_connected(graph: dict[str, set[str]]) -> list[list[str]]:
    """Tarjan's components (iterative), each sorted; only those with more than one module."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    on_stack: set[str] = set()
    stack: list[str] = []
    components = []
    for start in sorted(graph):
        if start in index:
            continue
        work = [(start, iter(sorted(graph[start])))]
        index[start] = low[start] = len(index)
        stack.append(start)
        on_stack.add(start)
        while work:
            node, successors = work[-1]
            advanced = False
            for succ in successors:
                if succ not in index:
                    index[succ] = low[succ] = len(index)
                    stack.append(succ)
                    on_stack.add(succ)
                    work.append((succ, iter(sorted(graph[succ]))))
                    advanced = True
                    break
                if succ in on_stack:
                    low[node] = min(low[node], index[succ])
            if advanced:
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                component = []
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    component.append(member)
                    if member == node:
                        break
                if len(component) > 1:
                    components.append(sorted(component))
    return sorted(components)


def _shortest_cycle(start: str, graph: dict[str, set[str]], members: set[str]) -> list[str]:
    """Modules of the shortest cycle through ``start`` inside one component (start first)."""
    parent: dict[str, str] = {}
    queue = deque([start])
    while queue:
        node = queue.popleft()
        for succ in sorted(graph[node] & members):
            if succ == start:
                cycle = [node]
                while cycle[-1] != start:
                    cycle.append(parent[cycle[-1]])
                return cycle[::-1]
            if succ not in parent:
                parent[succ] = node
                queue.append(succ)
    raise AssertionError(f"{start} is in a component but on no cycle")


def import_cycles(imports: list[Import], package: str) -> list[list[Import]]:
    """One shortest cycle per strongly connected component, as the imports along it (``TYPE_CHECKING`` imports
    included: a cycle that only type checking closes is still two modules that cannot be read apart)."""
    runtime = [i for i in imports if internal(i.target, package) and i.target != i.importer]
    graph: dict[str, set[str]] = {}
    first_edge: dict[tuple[str, str], Import] = {}
    for imp in runtime:
        graph.setdefault(imp.importer, set()).add(imp.target)
        graph.setdefault(imp.target, set())
        first_edge.setdefault((imp.importer, imp.target), imp)
    cycles = []
    for component in _strongly_connected(graph):
        modules = _shortest_cycle(component[0], graph, set(component))
        cycles.append([first_edge[a, b] for a, b in zip(modules, modules[1:] + modules[:1])])
    return cycles


def _is_ros(target: str, adapters: str) -> bool:
    top = target.split(".")[0]
    return top in ROS_TOP_LEVEL or top.endswith(ROS_MESSAGE_SUFFIXES) or internal(target, adapters)


def ros_imports_in_core(imports: list[Import], package: str) -> list[Import]:
    """Imports of rclpy, ROS message packages or ``<package>.ros`` from outside ``<package>.ros``."""
    adapters = f"{package}.ros"
    return [i for i in imports if not internal(i.importer, adapters) and _is_ros(i.target, adapters)]


def unjustified_lazy_imports(imports: list[Import], package: str) -> list[Import]:
    """Function-level imports of the package's own modules without a ``# lazy: <reason>`` comment."""
    return [i for i in imports if i.in_function and internal(i.target, package) and not i.justified]


def listing(imports: list[Import]) -> str:
    return "\n".join(f"  {i.path.relative_to(REPO_ROOT)}:{i.line} imports {i.target}" for i in imports)


# --- layers ----------------------------------------------------------------------------------------------------
#: The layer table, top first: a module may import modules of its own entry and of any entry on a LOWER row, never
#: one on its own row (peers) or above. A module belongs to the longest entry its dotted name starts with (names
#: relative to the package; "" is the package's own ``__init__``). ``docs/architecture.md`` draws this table.
LAYERS: tuple[tuple[str, ...], ...] = (
    ("ros",),  # adapters: messages <-> core calls
    ("web",),  # the browser view (viser): plans through the runtime, shows scenes, plans and base runs
    ("runtime",),  # the planning service without ROS: robot, scene store, admission, worker pool, warm-up
    ("barn", "execution"),  # judged by physics: BARN in MuJoCo through the base stack, arm trajectories executed
    ("planning.cli", "planning.dual_arm", "planning.verified", "base.cli", "sim"),  # users of the facades: CLIs, demos
    ("viz",),  # pictures of everything below
    ("planning.motion_planner", "planning.queries"),  # the arm facade and the state queries
    ("planning.stages",),  # search -> simplify -> parameterize -> certify | verify
    ("planning.pipeline",),  # runs a list of stages
    ("planning.adapters",),  # request -> PlanningProblem
    ("planning.planners",),  # the registry and one module per planner (+ kernels/: search loops)
    ("planning",),  # the problem, its context, request checks, types, configuration, spaces, constraints
    ("base", "reactive", "bag", "physics"),  # mobile-base planners, the elastic strip, rosbag I/O, MuJoCo models
    ("trajectory",),  # path -> timed trajectory, one module per method
    ("collision",),  # exact checker, sphere model (+ certify/: continuous validation, kernels/: numba)
    ("robot.profiles",),  # the table of built-in robots
    ("robot.robots",),  # one module per robot
    ("robot",),  # RobotModel, SRDF, IK, attached bodies
    ("scene",),  # Scene, shapes, MoveIt scene formats
    ("params", "monitor", "paths", "cli_parser", "heap"),
    ("errors", ""),
)
#: Folders of numba code: a module in one imports only modules of these folders (and no other package module).
KERNELS = ("collision.kernels", "planning.planners.kernels")


def layer_of(module: str, package: str = PACKAGE, layers: tuple[tuple[str, ...], ...] = LAYERS) -> tuple[int, str]:
    """(row in ``layers``, entry) of ``module``: its longest matching entry."""
    name = module[len(package) + 1 :] if module != package else ""
    best: tuple[int, str] | None = None
    for row, entries in enumerate(layers):
        for entry in entries:
            if (name == entry or name.startswith(entry + ".") or entry == "") and (
                best is None or len(entry) > len(best[1])
            ):
                best = (row, entry)
    assert best is not None
    return best


@functools.cache
def is_reexport(path: Path) -> bool:
    """A module that only re-exports names defined elsewhere (an old import path kept, or a package's surface):
    a docstring, imports, ``__all__`` and at most an ``if __name__ == "__main__":`` block."""
    body = ast.parse(path.read_text()).body
    if not body:
        return True

    def plain(node: ast.stmt) -> bool:
        if isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant):
            return True
        if isinstance(node, ast.Import | ast.ImportFrom):
            return True
        if isinstance(node, ast.Assign) and [getattr(t, "id", None) for t in node.targets] == ["__all__"]:
            return True
        return isinstance(node, ast.If) and "__main__" in ast.unparse(node.test)

    return all(plain(node) for node in body)


def layer_violations(
    imports: list[Import], package: str = PACKAGE, layers: tuple[tuple[str, ...], ...] = LAYERS
) -> list[Import]:
    """Imports of a module on the importer's own row (a peer) or above it; re-export modules are exempt as
    importers (they sit with what they re-export), not as targets."""
    exempt = {i.importer for i in imports if i.path.name == "__init__.py" or is_reexport(i.path)}
    out = []
    for imp in imports:
        if not internal(imp.target, package) or imp.importer in exempt:
            continue
        row, entry = layer_of(imp.importer, package, layers)
        target_row, target_entry = layer_of(imp.target, package, layers)
        if entry != target_entry and target_row <= row:
            out.append(imp)
    return out


def kernel_violations(
    imports: list[Import], package: str = PACKAGE, kernels: tuple[str, ...] = KERNELS
) -> list[Import]:
    """Imports of a non-kernel package module by a module of a ``kernels`` folder."""

    def in_kernels(module: str) -> bool:
        name = module[len(package) + 1 :]
        return any(name == k or name.startswith(k + ".") for k in kernels)

    return [i for i in imports if in_kernels(i.importer) and internal(i.target, package) and not in_kernels(i.target)]


#: What ``ros/`` may not import: the arm stack's machinery. The nodes reach planning through ``runtime/`` and its
#: types (requests, results, configuration, the planner registry's table for their parameters).
ROS_FORBIDDEN = (
    "planning.motion_planner",
    "planning.pipeline",
    "planning.stages",
    "planning.adapters",
    "planning.problem",
    "planning.context",
    "planning.planners",
    "collision",
)
ROS_ALLOWED = ("planning.planners.registry",)


def ros_reach_violations(imports: list[Import], package: str = PACKAGE) -> list[Import]:
    """Imports from ``<package>.ros`` of the arm stack's machinery (:data:`ROS_FORBIDDEN`)."""

    def under(module: str, prefixes: tuple[str, ...]) -> bool:
        name = module[len(package) + 1 :]
        return any(name == p or name.startswith(p + ".") for p in prefixes)

    return [
        i
        for i in imports
        if internal(i.importer, f"{package}.ros")
        and under(i.target, ROS_FORBIDDEN)
        and not under(i.target, ROS_ALLOWED)
    ]

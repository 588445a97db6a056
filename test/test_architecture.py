"""Architecture rules: no import cycles, a ROS-free core, justified lazy imports, a clean type check.

The import graph is read from the source with ``ast`` (nothing is imported): module-level and
function-level imports both count, since a lazy import that dodges a cycle is still a cycle.
Imports under ``if TYPE_CHECKING:`` never run and are left out of the cycle check.
"""

from __future__ import annotations

import ast
import io
import re
import subprocess
import sys
import tokenize
from collections import deque
from dataclasses import dataclass
from pathlib import Path

import pytest

REPO_ROOT = Path(__file__).resolve().parent.parent
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


def _internal(target: str, package: str) -> bool:
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
    """One shortest cycle per strongly connected component, as the imports along it."""
    runtime = [i for i in imports if not i.type_only and _internal(i.target, package) and i.target != i.importer]
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
    return top in ROS_TOP_LEVEL or top.endswith(ROS_MESSAGE_SUFFIXES) or _internal(target, adapters)


def ros_imports_in_core(imports: list[Import], package: str) -> list[Import]:
    """Imports of rclpy, ROS message packages or ``<package>.ros`` from outside ``<package>.ros``."""
    adapters = f"{package}.ros"
    return [i for i in imports if not _internal(i.importer, adapters) and _is_ros(i.target, adapters)]


def unjustified_lazy_imports(imports: list[Import], package: str) -> list[Import]:
    """Function-level imports of the package's own modules without a ``# lazy: <reason>`` comment."""
    return [i for i in imports if i.in_function and _internal(i.target, package) and not i.justified]


def _listing(imports: list[Import]) -> str:
    return "\n".join(f"  {i.path.relative_to(REPO_ROOT)}:{i.line} imports {i.target}" for i in imports)


@pytest.fixture(scope="module")
def imports() -> list[Import]:
    return package_imports(REPO_ROOT, PACKAGE)


def test_the_graph_sees_the_whole_package(imports):
    importers = {i.importer for i in imports}
    assert {"maru_planner.planning.motion_planner", "maru_planner.ros.planning_node"} <= importers


def test_no_import_cycles(imports):
    cycles = import_cycles(imports, PACKAGE)
    report = "\n".join(" -> ".join([c[0].importer] + [i.target for i in c]) + "\n" + _listing(c) for c in cycles)
    if cycles:
        pytest.fail(f"{len(cycles)} import cycle(s):\n{report}", pytrace=False)


def test_core_does_not_import_ros(imports):
    offenders = ros_imports_in_core(imports, PACKAGE)
    if offenders:
        pytest.fail("ROS imports outside maru_planner/ros/:\n" + _listing(offenders), pytrace=False)


def test_function_level_imports_give_a_reason(imports):
    offenders = unjustified_lazy_imports(imports, PACKAGE)
    if offenders:
        pytest.fail(
            "function-level imports of maru_planner modules need a '# lazy: <reason>' comment on the line, "
            "or on its own line above them (or move them to the top of the module):\n" + _listing(offenders),
            pytrace=False,
        )


def test_type_check_passes():
    """mypy with the mypy.ini (files = maru_planner) reports no error."""
    result = subprocess.run(
        [sys.executable, "-m", "mypy", "--config-file", "mypy.ini"],
        cwd=REPO_ROOT,
        capture_output=True,
        text=True,
    )
    if result.returncode != 0:
        pytest.fail(result.stdout + result.stderr, pytrace=False)


# The checks above are only as good as their detection: each is shown failing on a tiny package.

FIXTURE_PACKAGE = {
    "pkg/__init__.py": "",
    "pkg/a.py": "from pkg import b\n",
    "pkg/b.py": "def f():\n    from pkg.c import g\n    return g\n",
    "pkg/c.py": "from . import a\n",
    "pkg/typed.py": "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from pkg import a\n",
    "pkg/lazy.py": (
        "def f():\n"
        "    # lazy: matplotlib is optional\n"
        "    import os\n"
        "\n"
        "    from pkg import a\n"
        "    x = 1\n"
        "    from pkg import typed  # lazy:\n"
        "def g():\n"
        "    from pkg import a  # lazy: optional too\n"
        "    from pkg import b\n"
    ),
    "pkg/core.py": "import rclpy\nfrom geometry_msgs.msg import Pose\nimport rosbags\nfrom pkg.ros import node\n",
    "pkg/ros/__init__.py": "",
    "pkg/ros/node.py": "import rclpy\n",
}


@pytest.fixture
def fixture_imports(tmp_path) -> list[Import]:
    for name, text in FIXTURE_PACKAGE.items():
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / name).write_text(text)
    return package_imports(tmp_path, "pkg")


def test_detects_a_cycle_through_a_lazy_and_a_relative_import(fixture_imports):
    cycles = import_cycles(fixture_imports, "pkg")
    assert [[(i.importer, i.target, i.line) for i in c] for c in cycles] == [
        [("pkg.a", "pkg.b", 1), ("pkg.b", "pkg.c", 2), ("pkg.c", "pkg.a", 1)]
    ]


def test_detects_ros_imports_in_the_core(fixture_imports):
    offenders = [(i.importer, i.target) for i in ros_imports_in_core(fixture_imports, "pkg")]
    assert offenders == [("pkg.core", "rclpy"), ("pkg.core", "geometry_msgs.msg"), ("pkg.core", "pkg.ros.node")]


def test_detects_function_level_imports_without_a_reason(fixture_imports):
    offenders = [(i.importer, i.target, i.line) for i in unjustified_lazy_imports(fixture_imports, "pkg")]
    assert offenders == [("pkg.b", "pkg.c", 2), ("pkg.lazy", "pkg.typed", 7), ("pkg.lazy", "pkg.b", 10)]

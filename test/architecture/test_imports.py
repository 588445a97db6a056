"""Architecture rules on the import graph (``import_graph.py``): no import cycles (lazy and ``TYPE_CHECKING``
imports included), a ROS-free core, justified lazy imports, the layer table, kernels that import only kernels,
modules of at most 600 lines, and a clean type check. Each rule is also shown failing on a tiny package.
"""

from __future__ import annotations

import subprocess
import sys

import pytest
from import_graph import (
    LAYERS,
    PACKAGE,
    REPO_ROOT,
    Import,
    import_cycles,
    kernel_violations,
    layer_of,
    layer_violations,
    listing,
    module_files,
    package_imports,
    ros_imports_in_core,
    ros_reach_violations,
    unjustified_lazy_imports,
)

MAX_MODULE_LINES = 600


@pytest.fixture(scope="module")
def imports() -> list[Import]:
    return package_imports(REPO_ROOT, PACKAGE)


def test_the_graph_sees_the_whole_package(imports):
    importers = {i.importer for i in imports}
    assert {"maru_planner.planning.motion_planner", "maru_planner.ros.planning_node"} <= importers


def test_no_import_cycles(imports):
    cycles = import_cycles(imports, PACKAGE)
    report = "\n".join(" -> ".join([c[0].importer] + [i.target for i in c]) + "\n" + listing(c) for c in cycles)
    if cycles:
        pytest.fail(f"{len(cycles)} import cycle(s):\n{report}", pytrace=False)


def test_core_does_not_import_ros(imports):
    offenders = ros_imports_in_core(imports, PACKAGE)
    if offenders:
        pytest.fail("ROS imports outside maru_planner/ros/:\n" + listing(offenders), pytrace=False)


def test_function_level_imports_give_a_reason(imports):
    offenders = unjustified_lazy_imports(imports, PACKAGE)
    if offenders:
        pytest.fail(
            "function-level imports of maru_planner modules need a '# lazy: <reason>' comment on the line, "
            "or on its own line above them (or move them to the top of the module):\n" + listing(offenders),
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
    "pkg/d.py": "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from pkg import e\n",
    "pkg/e.py": "from pkg import d\n",
    "pkg/high/__init__.py": "",
    "pkg/high/top.py": "from pkg.low import base\nfrom pkg.high import peer\n\nx = 1\n",
    "pkg/high/peer.py": "",
    "pkg/low/__init__.py": "",
    "pkg/low/base.py": "from pkg.high import top\nfrom pkg.side import other\n\ny = 1\n",
    "pkg/low/shim.py": '"""Old path."""\n\nfrom pkg.high.top import x\n\n__all__ = ["x"]\n',
    "pkg/side/__init__.py": "",
    "pkg/side/other.py": "",
    "pkg/kern/__init__.py": "",
    "pkg/kern/loop.py": "from pkg.kern import fk\nfrom pkg.low import base\n\nz = 1\n",
    "pkg/kern/fk.py": "",
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
        [("pkg.a", "pkg.b", 1), ("pkg.b", "pkg.c", 2), ("pkg.c", "pkg.a", 1)],
        [("pkg.d", "pkg.e", 3), ("pkg.e", "pkg.d", 1)],  # closed by a TYPE_CHECKING import: still a cycle
        [("pkg.high.top", "pkg.low.base", 1), ("pkg.low.base", "pkg.high.top", 1)],
    ]


def test_detects_ros_imports_in_the_core(fixture_imports):
    offenders = [(i.importer, i.target) for i in ros_imports_in_core(fixture_imports, "pkg")]
    assert offenders == [("pkg.core", "rclpy"), ("pkg.core", "geometry_msgs.msg"), ("pkg.core", "pkg.ros.node")]


def test_detects_function_level_imports_without_a_reason(fixture_imports):
    offenders = [(i.importer, i.target, i.line) for i in unjustified_lazy_imports(fixture_imports, "pkg")]
    assert offenders == [("pkg.b", "pkg.c", 2), ("pkg.lazy", "pkg.typed", 7), ("pkg.lazy", "pkg.b", 10)]


FIXTURE_LAYERS = (("high",), ("low", "side"), ("kern",), ("",))


def test_detects_imports_up_the_layers_and_between_peers(fixture_imports):
    offenders = layer_violations(fixture_imports, "pkg", FIXTURE_LAYERS)
    assert sorted((i.importer, i.target) for i in offenders) == [
        ("pkg.kern.loop", "pkg.low.base"),
        ("pkg.low.base", "pkg.high.top"),
        ("pkg.low.base", "pkg.side.other"),
    ]  # the re-export shim and the within-folder import are allowed


def test_detects_kernels_importing_other_code(fixture_imports):
    offenders = kernel_violations(fixture_imports, "pkg", ("kern",))
    assert [(i.importer, i.target) for i in offenders] == [("pkg.kern.loop", "pkg.low.base")]


def test_every_module_is_in_the_layer_table(imports):
    assert layer_of("maru_planner.planning.stages.search") == (next(
        row for row, entries in enumerate(LAYERS) if "planning.stages" in entries), "planning.stages")  # fmt: skip
    unplaced = sorted(m for m in module_files(REPO_ROOT, PACKAGE) if layer_of(m)[1] == "" and m.count(".") > 1)
    assert not unplaced, f"modules only the ground floor's catch-all holds (add their folder to LAYERS): {unplaced}"


def test_imports_follow_the_layers(imports):
    offenders = layer_violations(imports)
    if offenders:
        pytest.fail("imports of a peer or a higher layer (import_graph.LAYERS):\n" + listing(offenders), pytrace=False)


def test_kernels_import_only_kernels(imports):
    offenders = kernel_violations(imports)
    if offenders:
        pytest.fail("numba kernels importing non-kernel package code:\n" + listing(offenders), pytrace=False)


def test_no_module_is_over_600_lines():
    sizes = {m: len(p.read_text().splitlines()) for m, p in module_files(REPO_ROOT, PACKAGE).items()}
    over = {m: n for m, n in sizes.items() if n > MAX_MODULE_LINES}
    assert not over, f"modules over {MAX_MODULE_LINES} lines: {over}"


def test_ros_reaches_planning_through_the_runtime(imports):
    offenders = ros_reach_violations(imports)
    if offenders:
        pytest.fail("ros/ importing the arm stack's machinery (use runtime/):\n" + listing(offenders), pytrace=False)


def test_detects_ros_reaching_past_the_runtime(tmp_path):
    for name, text in {
        "pkg/__init__.py": "",
        "pkg/ros/__init__.py": "",
        "pkg/ros/node.py": "from pkg.runtime import service\nfrom pkg.planning.stages import search\n",
        "pkg/ros/params.py": "from pkg.planning.planners.registry import PLANNERS\n",
    }.items():
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / name).write_text(text)
    offenders = ros_reach_violations(package_imports(tmp_path, "pkg"), "pkg")
    assert [(i.importer, i.target) for i in offenders] == [("pkg.ros.node", "pkg.planning.stages")]


def test_the_documented_layer_table_is_the_checked_one():
    """docs/architecture.md's "Layers" table lists LAYERS' rows, top first, folder for folder."""
    import re

    text = (REPO_ROOT / "docs" / "architecture.md").read_text()
    rows = re.findall(r"^\| (\d+) \| ([^|]+) \|", text, flags=re.MULTILINE)
    documented = [tuple(f.strip("`/ ").replace("/", ".") for f in folders.split(",")) for _, folders in rows]
    checked = [tuple(entry for entry in entries if entry) for entries in LAYERS]
    assert [int(number) for number, _ in rows] == list(range(1, len(rows) + 1))
    assert documented == checked, "docs/architecture.md's layer table differs from import_graph.LAYERS"

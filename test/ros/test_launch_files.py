"""The three launch files: use_sim_time, namespace, params_file, autostart and rviz reach the nodes.

``launch`` / ``launch_ros`` are not installed here: stand-ins record what each launch file (and
``maru_planner.ros.launch_args``, which they share) asks for (arguments with their defaults, the nodes
with their parameters, namespace and condition).
"""

from __future__ import annotations

import importlib.util
import sys
import types
from pathlib import Path

import pytest

from maru_planner.paths import config_path

REPO_ROOT = Path(__file__).resolve().parents[2]
LAUNCH_FILES = {  # launch file -> (executable, its params file, its RViz config)
    "planning": ("planning_node", "planner.yaml", "planning.rviz"),
    "base_planner": ("base_planner_node", "base_planner.yaml", "base_planner.rviz"),
    "reactive": ("reactive_node", "reactive.yaml", "reactive.rviz"),
    "arm_sim": ("arm_sim_node", "arm_sim.yaml", "planning.rviz"),
    "mujoco_sim": ("mujoco_sim_node", "mujoco_sim.yaml", "reactive.rviz"),
}
COMMON_ARGUMENTS = {"use_sim_time": "false", "namespace": "", "autostart": "true", "rviz": "false"}


class Recorded:
    def __init__(self, *args, **kwargs):
        self.args, self.kwargs = args, kwargs


class Argument(Recorded):
    pass


class NodeAction(Recorded):
    pass


class Condition(Recorded):
    pass


def launch_items(name: str, monkeypatch) -> tuple[dict[str, str], list[NodeAction]]:
    """The declared arguments ({name: default}) and the nodes of ``launch/<name>.launch.py``."""
    fakes = {
        "launch": types.SimpleNamespace(LaunchDescription=Recorded),
        "launch.actions": types.SimpleNamespace(DeclareLaunchArgument=Argument),
        "launch.conditions": types.SimpleNamespace(IfCondition=Condition),
        "launch.substitutions": types.SimpleNamespace(
            LaunchConfiguration=lambda argument: f"<{argument}>", PythonExpression=lambda parts: "".join(parts)
        ),
        "launch_ros.actions": types.SimpleNamespace(Node=NodeAction),
        "ament_index_python.packages": types.SimpleNamespace(get_package_share_directory=lambda _: str(REPO_ROOT)),
    }
    for module_name, module in fakes.items():
        monkeypatch.setitem(sys.modules, module_name, module)
    monkeypatch.delitem(sys.modules, "maru_planner.ros.launch_args", raising=False)  # rebuilt on the stand-ins
    spec = importlib.util.spec_from_file_location(f"{name}_launch", REPO_ROOT / "launch" / f"{name}.launch.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    items = module.generate_launch_description().args[0]
    arguments = {a.args[0]: a.kwargs["default_value"] for a in items if isinstance(a, Argument)}
    return arguments, [n for n in items if isinstance(n, NodeAction)]


@pytest.mark.parametrize("name", sorted(LAUNCH_FILES))
def test_every_launch_file_declares_the_common_arguments(name, monkeypatch):
    arguments, _nodes = launch_items(name, monkeypatch)
    _executable, params_file, _rviz = LAUNCH_FILES[name]
    assert {key: arguments[key] for key in COMMON_ARGUMENTS} == COMMON_ARGUMENTS
    assert Path(arguments["params_file"]) == config_path(params_file)


@pytest.mark.parametrize("name", sorted(LAUNCH_FILES))
def test_the_node_gets_params_file_namespace_use_sim_time_and_autostart(name, monkeypatch):
    _arguments, nodes = launch_items(name, monkeypatch)
    executable = LAUNCH_FILES[name][0]
    started = [n for n in nodes if n.kwargs["executable"] == executable]
    assert started, f"{name}.launch.py starts no {executable}"
    for node in started:  # planning.launch.py has one per scene_file case, each under its condition
        assert node.kwargs["package"] == "maru_planner" and node.kwargs["name"] == executable
        assert node.kwargs["namespace"] == "<namespace>"
        file, overrides = node.kwargs["parameters"]
        assert file == "<params_file>"
        assert overrides["use_sim_time"] == "<use_sim_time>" and overrides["autostart"] == "<autostart>"


@pytest.mark.parametrize("name", sorted(LAUNCH_FILES))
def test_rviz_starts_with_the_nodes_config_only_when_asked(name, monkeypatch):
    _arguments, nodes = launch_items(name, monkeypatch)
    (rviz,) = [n for n in nodes if n.kwargs["executable"] == "rviz2"]
    assert rviz.kwargs["package"] == "rviz2" and rviz.kwargs["namespace"] == "<namespace>"
    flag, config = rviz.kwargs["arguments"]
    assert flag == "-d" and Path(config) == config_path("rviz", LAUNCH_FILES[name][2])
    assert Path(config).is_file()
    assert rviz.kwargs["condition"].args == ("<rviz>",)
    assert rviz.kwargs["parameters"] == [{"use_sim_time": "<use_sim_time>"}]


def test_planning_launch_passes_scene_file_only_when_given(monkeypatch):
    _arguments, nodes = launch_items("planning", monkeypatch)
    planning = [n for n in nodes if n.kwargs["executable"] == "planning_node"]
    by_condition = {n.kwargs["condition"].args[0]: n.kwargs["parameters"][1] for n in planning}
    common = {"use_sim_time": "<use_sim_time>", "autostart": "<autostart>"}
    with_scene = {**common, "scene_file": "<scene_file>"}
    assert by_condition == {"'<scene_file>' == ''": common, "'<scene_file>' != ''": with_scene}

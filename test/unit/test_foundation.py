"""Foundation checks: lint, pre-commit hooks, the core is ROS-free, loopback DDS, packaging metadata."""

from __future__ import annotations

import importlib
import os
import pkgutil
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import maru_planner

REPO_ROOT = Path(__file__).resolve().parents[2]


def _core_modules() -> list[str]:
    names = []
    for info in pkgutil.walk_packages(maru_planner.__path__, "maru_planner."):
        if info.name.startswith("maru_planner.ros.") and info.name != "maru_planner.ros.env":
            continue
        names.append(info.name)
    return names


def test_core_imports_without_rclpy():
    """Every core module imports with rclpy (and ROS message packages) made unimportable."""
    code = f"""
import sys, importlib
class Block:
    blocked = ("rclpy", "maru_planner_interfaces")
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in self.blocked:
            raise ImportError("blocked for this test: " + name)
        return None
sys.meta_path.insert(0, Block())
failed = []
for name in {_core_modules()!r}:
    try:
        importlib.import_module(name)
    except ImportError as exc:
        failed.append(f"{{name}}: {{exc}}")
print("\\n".join(failed))
sys.exit(1 if failed else 0)
"""
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=REPO_ROOT)
    assert result.returncode == 0, "core modules needing ROS:\n" + result.stdout + result.stderr


def test_loopback_environment_is_set_for_this_run():
    assert os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] == "LOCALHOST"
    profile = Path(os.environ["FASTRTPS_DEFAULT_PROFILES_FILE"])
    assert profile.is_file()
    assert 1 <= int(os.environ["ROS_DOMAIN_ID"]) <= 100
    ns = {"f": "http://www.eprosima.com/XMLSchemas/fastRTPS_Profiles"}
    root = ET.parse(profile).getroot()
    addresses = [a.text for a in root.iterfind(".//f:interfaceWhiteList/f:address", ns)]
    assert addresses == ["127.0.0.1"]
    assert root.find(".//f:useBuiltinTransports", ns).text == "false"


def test_package_xml_is_ament_python_format3():
    root = ET.parse(REPO_ROOT / "package.xml").getroot()
    assert root.get("format") == "3"
    assert root.findtext("name") == "maru_planner"
    assert root.find("export/build_type").text == "ament_python"
    exec_deps = {e.text for e in root.findall("exec_depend")}
    assert {"rclpy", "maru_planner_interfaces", "trajectory_msgs", "sensor_msgs"} <= exec_deps


def test_console_scripts_point_at_existing_modules():
    setup_py = (REPO_ROOT / "setup.py").read_text()
    modules = [line.split("=")[1].split(":")[0].strip() for line in setup_py.splitlines() if " = maru_planner" in line]
    assert modules, "no console_scripts found in setup.py"
    missing = [m for m in modules if importlib.util.find_spec(m) is None]
    assert not missing, f"console_scripts name missing modules: {missing}"

"""colcon finds and builds both packages of the repository, and a node runs from the install space."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

REPO_ROOT = Path(__file__).resolve().parents[2]
COLCON = Path(sys.executable).parent / "colcon"
PACKAGES = {"maru_planner": "ros.ament_python", "maru_planner_interfaces": "ros.ament_cmake"}
# README's command, from the repository root: the root is maru_planner's package, where a crawl stops
BASE_PATHS = [".", "interfaces"]
INTERFACES_BUILD = REPO_ROOT / "build" / "maru_planner_interfaces"  # scripts/build_interfaces.sh's build tree
INTERFACES_LOCK = "/tmp/maru_interfaces.lock"

pytestmark = pytest.mark.ros


def test_colcon_finds_both_packages(tmp_path):
    listed = subprocess.run(
        [str(COLCON), "--log-base", str(tmp_path), "list", "--base-paths", *BASE_PATHS],
        cwd=REPO_ROOT,
        capture_output=True,
        text=True,
        check=True,
        timeout=120,
    ).stdout
    found = {line.split("\t")[0]: line.split("\t")[2].strip("()") for line in listed.splitlines()}
    assert found == PACKAGES


@pytest.fixture(scope="module")
def install_space(tmp_path_factory) -> Path:
    """colcon's install space; the interfaces are built in the tree where make setup compiled them.

    colcon re-runs CMake there and rebuilds only what changed (a fresh tree: 2-3 min of compiling), under the
    lock that rebuilds of the interfaces take, so no other build uses that tree meanwhile.
    """
    out = tmp_path_factory.mktemp("colcon")
    INTERFACES_BUILD.mkdir(parents=True, exist_ok=True)
    (out / "build").mkdir()
    (out / "build" / "maru_planner_interfaces").symlink_to(INTERFACES_BUILD, target_is_directory=True)
    build = subprocess.run(
        ["flock", INTERFACES_LOCK, "bash", str(REPO_ROOT / "scripts" / "colcon_build.sh"), str(out)],
        capture_output=True,
        text=True,
        timeout=900,
    )
    assert build.returncode == 0, build.stdout[-3000:] + build.stderr[-3000:]
    return out / "install"


def _install_env(install: Path) -> dict[str, str]:
    """What sourcing the install space's setup script gives a Python node (the wheels are the underlay)."""
    env = dict(os.environ)
    site = [str(install / pkg / "lib" / "python3.11" / "site-packages") for pkg in PACKAGES]
    env["PYTHONPATH"] = os.pathsep.join(site + [env.get("PYTHONPATH", "")]).rstrip(os.pathsep)
    prefixes = [str(install / pkg) for pkg in PACKAGES]
    env["AMENT_PREFIX_PATH"] = os.pathsep.join(prefixes + [env.get("AMENT_PREFIX_PATH", sys.prefix)])
    libs = str(install / "maru_planner_interfaces" / "lib")
    env["LD_LIBRARY_PATH"] = os.pathsep.join([libs, env.get("LD_LIBRARY_PATH", "")]).rstrip(os.pathsep)
    env.pop("_ROS_WHEELS_BOOTSTRAP_COMPLETE", None)
    return env


def test_install_space_holds_the_package_its_data_and_the_interfaces(install_space):
    share = install_space / "maru_planner" / "share" / "maru_planner"
    data_files = (
        "launch/planning.launch.py",
        "config/planner.yaml",
        "config/rviz/planning.rviz",
        "config/maps/house_250.yaml",
    )
    for relative in ("package.xml", "urdf/maru1_upper_body.urdf", *data_files):
        assert (share / relative).is_file(), relative
    probe = subprocess.run(
        [
            sys.executable,
            "-c",
            "import maru_planner, maru_planner_interfaces.action as a; from maru_planner.paths import share_dir;"
            "print(maru_planner.__file__); print(a.__file__); print(share_dir())",
        ],
        capture_output=True,
        text=True,
        env=_install_env(install_space),
        cwd="/",
        timeout=120,
    )
    assert probe.returncode == 0, probe.stderr
    package_file, interfaces_file, share_dir = probe.stdout.split()
    assert package_file.startswith(str(install_space)) and interfaces_file.startswith(str(install_space))
    assert Path(share_dir) == share


def test_planning_node_runs_from_the_install_space(install_space, spinning_node, tmp_path):
    from maru_planner_interfaces.srv import GetScene

    script = install_space / "maru_planner" / "lib" / "maru_planner" / "planning_node"
    log = open(tmp_path / "planning_node.log", "w")
    proc = subprocess.Popen(
        # its own namespace: none of its services or actions (plan_motion) may answer another test's clients. The
        # install space has no numba cache of its own: on the sphere checker (the default) its three processes took
        # 65-85 s here to compile the kernels at configure, ~12 s on the exact one; each worker process compiles its
        # own, so one planning thread in the node's process; the source tree's tests plan on both models and with
        # worker processes, this one is about the installed files
        [
            str(script),
            "--ros-args",
            "-r",
            "__ns:=/installed",
            "-p",
            "collision_model:=exact",
            "-p",
            "workers:=1",
            "-p",
            "worker_processes:=false",
        ],  # fmt: skip
        stdout=log,
        stderr=subprocess.STDOUT,
        stdin=subprocess.DEVNULL,
        env=_install_env(install_space),
        cwd=str(tmp_path),
    )
    try:
        client = spinning_node.node.create_client(GetScene, "/installed/get_scene")
        deadline = time.monotonic() + 120.0
        while not client.wait_for_service(timeout_sec=0.5):
            assert proc.poll() is None, (tmp_path / "planning_node.log").read_text()[-3000:]
            assert time.monotonic() < deadline, "planning_node from the install space never offered get_scene"
        response = spinning_node.call(client, GetScene.Request(), timeout=60.0)
        assert "obstacles" in response.scene_yaml
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=20)
        except subprocess.TimeoutExpired:  # never left running for the tests after this one
            proc.kill()
            proc.wait()
        log.close()

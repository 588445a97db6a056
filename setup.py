"""ament_python package maru_planner (also pip-installable into a venv: `pip install -e .`).

Run from the repository root (colcon and pip do): the data file paths below are relative to it. Only the
maru_planner package tree is installed, never test/, bench/ or interfaces/.
"""

import os
from glob import glob

from setuptools import find_packages, setup

PACKAGE = "maru_planner"


def tree(directory: str) -> list[tuple[str, list[str]]]:
    """data_files entries installing ``directory`` (config/ with rviz/ and maps/, urdf/) under share/maru_planner."""
    entries = []
    for root, _dirs, files in os.walk(directory):
        if files:
            entries.append((os.path.join("share", PACKAGE, root), [os.path.join(root, f) for f in files]))
    return entries


setup(
    name=PACKAGE,
    version="0.1.0",
    packages=find_packages(include=[PACKAGE, PACKAGE + ".*"]),
    package_data={PACKAGE: ["robot/robots/*.yaml"]},
    data_files=[
        ("share/ament_index/resource_index/packages", ["resource/" + PACKAGE]),
        ("share/" + PACKAGE, ["package.xml"]),
        ("share/" + PACKAGE + "/launch", glob("launch/*.py")),
    ]
    + tree("config")
    + tree("urdf"),
    install_requires=["setuptools"],
    zip_safe=True,
    maintainer="maru_planner developers",
    maintainer_email="dev@maru-planner.invalid",
    description="Motion planning for humanoid and mobile-manipulator robots (OMPL, Pinocchio, coal, ROS 2).",
    license="Apache-2.0",
    tests_require=["pytest"],
    entry_points={
        "console_scripts": [
            "planning_node = maru_planner.ros.planning_node:main",
            "reactive_node = maru_planner.ros.reactive_node:main",
            "base_planner_node = maru_planner.ros.base_planner_node:main",
            "maru-plan = maru_planner.planning.cli:main",
            "maru-reactive-sim = maru_planner.sim.cli:main",
            "maru-base-plan = maru_planner.base.cli:main",
            "maru-demo = maru_planner.ros.demo:main",
            "arm_sim_node = maru_planner.ros.arm_sim_node:main",
            "mujoco_sim_node = maru_planner.ros.mujoco_sim_node:main",
            "maru-barn = maru_planner.barn.cli:main",
            "maru-view = maru_planner.web.cli:main",
            "base_view = maru_planner.ros.plan_view_bridge:main",
        ],
    },
)

"""Kernel warm-up before the first request (maru_planner.runtime.warm_up)."""

from __future__ import annotations

import dataclasses

import pytest

from maru_planner.planning import MotionPlanner, PlannerConfig
from maru_planner.runtime import warm_up as warm


@pytest.fixture
def fresh_process(monkeypatch):
    """As if this process had warmed up for no config yet."""
    monkeypatch.setattr(warm, "warmed_configs", set())


def test_warm_up_plans_with_each_planner_the_config_runs_once_per_process(maru1, fresh_process):
    config = PlannerConfig(collision_model="spheres")
    done = warm.warm_up(maru1, config)
    assert not done.error
    assert done.plans == tuple(
        (planner_id, scene, "SUCCESS")
        for scene in ("one box", "many boxes")
        for planner_id in ("RRTConnect", "CompiledRRTConnect", "RCRRT")
    )
    assert "kernels warmed up" in done.summary()
    again = warm.warm_up(maru1, dataclasses.replace(config, resolution=0.05))  # same kind of config: loaded already
    assert again.plans == () and "already loaded" in again.summary()
    exact = warm.warm_up(maru1, PlannerConfig(collision_model="exact"))
    assert [planner_id for planner_id, _, _ in exact.plans] == ["RRTConnect", "RRTConnect"]


def test_warm_up_scenes_reach_the_large_scene_paths(maru1):
    from maru_planner.collision.certify import NEAR_PATH_MIN_OBSTACLES
    from maru_planner.collision.spheres import GRID_MIN_OBSTACLES

    scene = warm.boxes(maru1, warm.MANY_BOXES)
    assert len(scene.obstacles) == warm.MANY_BOXES >= max(NEAR_PATH_MIN_OBSTACLES, GRID_MIN_OBSTACLES)
    planner = MotionPlanner.from_scene(maru1, scene, PlannerConfig())  # the default: spheres, exact-verified
    # none dropped by either checker's broad phase, and the sphere kernels look them up in their grid
    assert len(planner.exact_checker.reachable_obstacles) == warm.MANY_BOXES
    assert len(planner.checker.primitives.names) == warm.MANY_BOXES and planner.checker.uses_grid
    exact = MotionPlanner.from_scene(maru1, scene, PlannerConfig(collision_model="exact"))
    assert len(exact.checker.reachable_obstacles) == warm.MANY_BOXES


def test_a_failed_warm_up_is_reported_not_raised_and_retried_next_time(maru1, fresh_process, monkeypatch):
    monkeypatch.setattr(warm, "SAMPLE_TRIES", 0)
    done = warm.warm_up(maru1, PlannerConfig())
    assert done.plans == () and "no free start and goal" in done.error
    assert done.summary().startswith("kernel warm-up stopped")
    monkeypatch.setattr(warm, "SAMPLE_TRIES", 200)
    assert warm.warm_up(maru1, PlannerConfig()).plans  # not remembered as warmed


def test_cli_warms_both_checkers(capsys, fresh_process):
    assert warm.main([]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert [line.split(":")[0] for line in lines] == [
        "[warm-up] exact checker",
        "[warm-up] spheres checker",
        "[warm-up] base planners",
    ]
    assert all("kernels warmed up" in line for line in lines)

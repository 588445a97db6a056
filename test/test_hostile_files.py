"""Hostile scene, map and world files through the loaders the CLIs use, in this process (issue 18).

Property-based (hypothesis, fixed seed, bounded examples): each generated file either loads or
raises a typed error (or OSError for a file that cannot be read) with a one-line message quoting at
most a short excerpt; any other exception is what a CLI would print as a traceback. The inputs count
towards the CLI that reads them: scene files maru-plan, map and biped world files maru-base-plan,
simulator worlds maru-reactive-sim.
"""

from __future__ import annotations

import pytest
from hostile_inputs import (
    SUITE_EXAMPLES,
    Files,
    biped_worlds,
    loader_outcome,
    map_files,
    report_counts,
    run_batch,
    scene_documents,
    sim_worlds,
)

from maru_planner.errors import MaruError

TYPED = (MaruError, OSError)


@pytest.fixture(scope="module")
def files(tmp_path_factory, request):
    yield Files(tmp_path_factory.mktemp("hostile_files"))
    report_counts(request, ["maru-plan", "maru-base-plan", "maru-reactive-sim"])


def test_scene_files(files):
    from maru_planner.planning.cli import load_scene

    def load(document):
        path = files.document(document)
        return loader_outcome(lambda: load_scene(path), f"scene {document!r:.200}", TYPED)

    run_batch("maru-plan", scene_documents(), load, SUITE_EXAMPLES["scene_files"])


def test_map_files(files):
    from maru_planner.base.grid import OccupancyGrid

    def load(generated):
        path = files.map_file(generated)
        return loader_outcome(lambda: OccupancyGrid.from_yaml(path), f"map {generated!r:.200}", TYPED)

    run_batch("maru-base-plan", map_files(), load, SUITE_EXAMPLES["map_files"])


def test_biped_world_files(files):
    from maru_planner.base.biped.world import load_world

    def load(document):
        path = files.document(document)
        return loader_outcome(lambda: load_world(path), f"biped world {document!r:.200}", TYPED)

    run_batch("maru-base-plan", biped_worlds(), load, SUITE_EXAMPLES["biped_files"])


def test_simulator_world_files(files):
    from maru_planner.sim import World

    def load(document):
        path = files.document(document)
        return loader_outcome(lambda: World.from_yaml(path), f"sim world {document!r:.200}", TYPED)

    run_batch("maru-reactive-sim", sim_worlds(), load, SUITE_EXAMPLES["sim_files"])

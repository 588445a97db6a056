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

from maru_planner.base.biped.world import load_world
from maru_planner.base.grid import OccupancyGrid
from maru_planner.errors import MaruError
from maru_planner.planning.cli import load_scene
from maru_planner.sim import World

TYPED = (MaruError, OSError)


@pytest.fixture(scope="module")
def files(tmp_path_factory, request):
    yield Files(tmp_path_factory.mktemp("hostile_files"))
    report_counts(request, ["maru-plan", "maru-base-plan", "maru-reactive-sim"])


LOADERS = {  # file kind -> (the CLI that reads it, generator, Files writer, loader, SUITE_EXAMPLES key)
    "scene": ("maru-plan", scene_documents, Files.document, load_scene, "scene_files"),
    "map": ("maru-base-plan", map_files, Files.map_file, OccupancyGrid.from_yaml, "map_files"),
    "biped world": ("maru-base-plan", biped_worlds, Files.document, load_world, "biped_files"),
    "sim world": ("maru-reactive-sim", sim_worlds, Files.document, World.from_yaml, "sim_files"),
}


@pytest.mark.parametrize("kind", LOADERS)
def test_generated_files_load_or_raise_a_typed_error(files, kind):
    cli, generator, write, loader, examples = LOADERS[kind]

    def load(generated):
        path = write(files, generated)
        return loader_outcome(lambda: loader(path), f"{kind} {generated!r:.200}", TYPED)

    run_batch(cli, generator(), load, SUITE_EXAMPLES[examples])

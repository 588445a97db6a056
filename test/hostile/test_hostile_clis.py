"""maru-plan, maru-base-plan and maru-reactive-sim on hostile command lines (issue 18).

Property-based argument vectors (hypothesis, fixed seed, bounded examples): a plausible command
with up to three options replaced by hostile values (numbers, names, generated scene/map/world
files, unwritable output paths). Each runs ``main`` in this process: a documented exit code, on bad
input exactly one stderr line naming the program, never an exception (a traceback for a user), no
internal-error exit, no run far past its budget. A few of them also run as real processes.
"""

from __future__ import annotations

import subprocess
import sys

import pytest
from hostile_inputs import (
    SUITE_EXAMPLES,
    maru_base_plan_argv,
    maru_plan_argv,
    maru_reactive_sim_argv,
    number_or_zero,
    option_value,
    report_counts,
    run_batch,
)
from hostile_inputs import cli_outcome as outcome_of

from maru_planner.base import cli as base_cli
from maru_planner.planning import cli as plan_cli
from maru_planner.sim import cli as sim_cli

AS_PROCESSES = 2  # per CLI: 1-5 s of start-up each
CLIS = {  # prog: (main, module, argv strategy, exit codes, bad-input code, internal code, budget option)
    "maru-plan": (plan_cli.main, "maru_planner.planning.cli", maru_plan_argv, {0, 1, 2, 3, 130}, 2, 3, "--time"),
    "maru-base-plan": (base_cli.main, "maru_planner.base.cli", maru_base_plan_argv, {0, 1, 2, 3}, 2, None,
                       "--time-limit"),
    "maru-reactive-sim": (sim_cli.main, "maru_planner.sim.cli", maru_reactive_sim_argv, {0, 2, 130}, 2, None,
                          "--max-time"),
}  # fmt: skip


@pytest.fixture(scope="module")
def report(request):
    yield
    report_counts(request, list(CLIS))


@pytest.mark.filterwarnings("ignore::RuntimeWarning")
@pytest.mark.parametrize("prog", list(CLIS))
def test_hostile_command_lines_in_process(prog, tmp_path, monkeypatch, report):
    main, _, argv, codes, bad_input, internal, budget_option = CLIS[prog]
    monkeypatch.chdir(tmp_path)

    def run(args: list[str]):
        budget = number_or_zero(option_value(args, budget_option, "0"))
        return outcome_of(main, args, prog, codes, bad_input, internal, budget)

    run_batch(prog, argv(tmp_path), run, SUITE_EXAMPLES[prog])


@pytest.mark.parametrize("prog", list(CLIS))
def test_hostile_command_lines_as_processes(prog, tmp_path, report):
    """A few drawn command lines through a real process: stderr and the exit status as a user sees them."""
    _, module, argv, codes, bad_input, internal, budget_option = CLIS[prog]

    def as_process(args: list[str]) -> int:
        """The CLI as its own process, its stderr replayed into ours (where ``cli_outcome`` reads it)."""
        proc = subprocess.run([sys.executable, "-m", module, *args], capture_output=True, text=True,
                              cwd=tmp_path, timeout=300)  # fmt: skip
        sys.stderr.write(proc.stderr + ("Traceback in stdout\n" if "Traceback" in proc.stdout else ""))
        return proc.returncode

    def send(args: list[str]):
        return outcome_of(as_process, args, prog, codes, bad_input, internal, 30.0)

    run_batch(prog, argv(tmp_path), send, AS_PROCESSES, seed_value=1818)

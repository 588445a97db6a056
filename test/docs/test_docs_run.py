"""Every runnable shell and Python block of README.md and docs/*.md runs as written (doc_blocks.py says how blocks
are marked); ``MARU_DOCS_SLOW=1`` runs the slow ones too."""

from __future__ import annotations

import os
import subprocess
from collections.abc import Iterator
from pathlib import Path

import pytest
from doc_blocks import (
    Block,
    all_blocks,
    exec_block,
    failure_text,
    in_process,
    make_scratch,
    run_block,
    runnable,
    start_block,
    stop,
    untagged_commands,
)

BLOCKS = all_blocks()
RUNNABLE = runnable(BLOCKS)
SLOW = os.environ.get("MARU_DOCS_SLOW") == "1"


class DocSession:
    """The background blocks (servers) of the page being run, started when a later block of that page needs them, and
    the texts of the blocks that passed."""

    def __init__(self, scratch: Path):
        self.scratch = scratch
        self.running: dict[str, tuple[subprocess.Popen[bytes], Path]] = {}  # block id -> (server, its log)
        self.passed: dict[str, str] = {}  # block text -> the id of the block that ran it

    def before(self, block: Block) -> None:
        """Stop other pages' servers; start this page's servers that come before ``block``."""
        for key in [k for k in self.running if not k.startswith(f"{block.id.rsplit(':', 1)[0]}:")]:
            stop(self.running.pop(key)[0])
        for earlier in RUNNABLE:
            wanted = "background" in earlier.marks and (SLOW or "slow" not in earlier.marks)
            if earlier.page == block.page and earlier.line < block.line and wanted:
                self.start(earlier)

    def start(self, block: Block) -> subprocess.Popen[bytes]:
        if block.id not in self.running:
            log = self.scratch / f"server_{block.page.stem}_{block.line}.log"
            self.running[block.id] = (start_block(block, self.scratch, log), log)
        return self.running[block.id][0]

    def stop_all(self) -> None:
        for process, _ in self.running.values():
            stop(process)
        self.running.clear()

    def logs(self) -> str:
        """The last lines of every running server's log (for a failure message)."""
        return "\n".join(f"--- {key} ---\n" + "\n".join(log.read_text().splitlines()[-20:])
                         for key, (_, log) in self.running.items())  # fmt: skip


@pytest.fixture(scope="module")
def scratch(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return make_scratch(tmp_path_factory.mktemp("docs") / "tree")


@pytest.fixture(scope="module")
def session(scratch: Path) -> Iterator[DocSession]:
    started = DocSession(scratch)
    yield started
    started.stop_all()


def test_untagged_fences_hold_no_commands():
    assert not untagged_commands(BLOCKS), "tag these fences bash (runnable, or <!-- synopsis -->)"


@pytest.mark.parametrize("block", RUNNABLE, ids=[b.id for b in RUNNABLE])
def test_block_runs(block: Block, scratch: Path, session: DocSession, monkeypatch: pytest.MonkeyPatch):
    if "slow" in block.marks and not SLOW:
        pytest.skip("slow block: MARU_DOCS_SLOW=1 runs it")
    session.before(block)
    if "background" in block.marks:
        server = session.start(block)
        assert server.poll() is None, f"{block.id}: the server exited {server.returncode}\n{session.logs()}"
        return
    if block.text in session.passed:
        return  # the same text ran (and passed) at session.passed[block.text]
    if in_process(block):
        monkeypatch.setenv("MPLBACKEND", "Agg")
        monkeypatch.chdir(scratch)
        exec_block(block)
    else:
        done = run_block(block, scratch)
        assert done.returncode == 0, failure_text(block, done) + ("\n" + session.logs() if session.running else "")
    session.passed[block.text] = block.id

"""The shell and Python blocks of README.md and docs/*.md, and a scratch tree to run them in.

A fenced block tagged ``bash``/``sh``/``shell`` or ``python``/``py`` is a runnable example unless an HTML comment
on the line before its fence (invisible on GitHub) says otherwise:

- ``<!-- synopsis -->`` (any text may follow): a usage line or a fragment, never run;
- ``<!-- slow -->``: runs only with ``MARU_DOCS_SLOW=1`` (longer than ~10 s);
- ``<!-- background -->``: a server (a node) started before the blocks after it in the same page and stopped at the
  end of that page's blocks; ``<!-- slow background -->``: a server only the slow blocks need.

Blocks run in a scratch tree: symlinks to the repository's read-only folders, copies of ``bench/*.py`` (so that
``bench/results/`` is the scratch one) and nothing else, so an example's outputs never land in the repository.
Shell blocks and Python blocks that use ROS (rclpy, ``maru_planner.ros``) run as their own processes; the other
Python blocks run in the test's process (a fresh namespace each, the imports shared: seconds saved per block), as
pytest-markdown-docs runs them. A block whose text equals one already run (the README repeats a page's command)
runs once.
"""

from __future__ import annotations

import os
import re
import shutil
import signal
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
PAGES = [REPO / "README.md", *sorted((REPO / "docs").glob("*.md"))]
SHELL = {"bash", "sh", "shell"}
PYTHON = {"python", "py"}
FENCE = re.compile(r"^(\s*)(```+|~~~+)\s*([\w+-]*)")
MARK = re.compile(r"^\s*<!--\s*((?:(?:synopsis|slow|background)\b\s*)+).*-->\s*$")
# what the scratch tree links to (read-only for the examples); bench/ is copied instead; no Makefile: its setup would
# install the package from the scratch tree into the shared .venv
LINKED = (".venv", "maru_planner", "config", "urdf", "interfaces", "launch", "scripts", "docs", "test", "resource",
          "package.xml", "setup.py", "setup.cfg", "requirements.txt", "README.md")  # fmt: skip
# the first word of a command line, for untagged fences that should be tagged (and run or marked)
COMMAND = re.compile(r"^\s*(\$ )?(\.venv/bin/|maru-|python|make |ros2 |colcon |source |cd |pip )")
BLOCK_TIMEOUT = 300.0


@dataclass(frozen=True)
class Block:
    page: Path
    line: int  # 1-based line of the opening fence
    language: str  # "shell", "python" or the fence's tag ("" when untagged)
    text: str
    marks: frozenset[str]  # of "synopsis", "slow", "background" (none: a block run by the fast lane)

    @property
    def id(self) -> str:
        page = self.page.relative_to(REPO) if self.page.is_relative_to(REPO) else self.page
        return f"{page}:{self.line}"


def blocks_of(page: Path) -> list[Block]:
    """Every fenced block of ``page`` with its language and the mark on the line before its fence."""
    lines = page.read_text().splitlines()
    found, i = [], 0
    while i < len(lines):
        opening = FENCE.match(lines[i])
        if not opening:
            i += 1
            continue
        indent, fence, tag = opening.groups()
        end = next((j for j in range(i + 1, len(lines)) if lines[j].strip().startswith(fence)), len(lines))
        body = "\n".join(line[len(indent) :] if line.startswith(indent) else line for line in lines[i + 1 : end])
        mark = MARK.match(lines[i - 1]) if i > 0 else None
        language = "shell" if tag in SHELL else "python" if tag in PYTHON else tag
        found.append(Block(page, i + 1, language, body + "\n", frozenset(mark.group(1).split() if mark else ())))
        i = end + 1
    return found


def all_blocks() -> list[Block]:
    return [block for page in PAGES for block in blocks_of(page)]


def runnable(blocks: list[Block]) -> list[Block]:
    return [b for b in blocks if b.language in ("shell", "python") and "synopsis" not in b.marks]


def untagged_commands(blocks: list[Block]) -> list[str]:
    """Untagged fences whose first line looks like a command: they must be tagged, then run or marked."""
    return [b.id for b in blocks if b.language == "" and b.text.strip() and COMMAND.match(b.text.splitlines()[0])]


def make_scratch(root: Path) -> Path:
    """A tree beside nothing of the repository's: links to its read-only parts, a copy of bench/'s scripts."""
    root.mkdir(parents=True, exist_ok=True)
    for name in LINKED:
        if (REPO / name).exists():
            (root / name).symlink_to(REPO / name)
    (root / "bench").mkdir()
    for script in (REPO / "bench").iterdir():
        if script.is_file():
            shutil.copy2(script, root / "bench" / script.name)
    return root


def block_environment(scratch: Path) -> dict[str, str]:
    """This process's environment (loopback DDS from test/conftest.py) with the venv first on PATH."""
    env = dict(os.environ)
    env["PATH"] = f"{scratch / '.venv' / 'bin'}{os.pathsep}{env.get('PATH', '')}"
    env["TMPDIR"] = str(scratch)
    env["MPLBACKEND"] = "Agg"
    env.pop("_ROS_WHEELS_BOOTSTRAP_COMPLETE", None)
    return env


def command_of(block: Block, scratch: Path) -> list[str]:
    script = scratch / f"block_{block.page.stem}_{block.line}.{'sh' if block.language == 'shell' else 'py'}"
    script.write_text(block.text)
    if block.language == "shell":
        return ["bash", "-euo", "pipefail", str(script)]
    return [str(scratch / ".venv" / "bin" / "python"), str(script)]


def in_process(block: Block) -> bool:
    """A Python block without ROS: run by exec in the test's process."""
    return block.language == "python" and "rclpy" not in block.text and "maru_planner.ros" not in block.text


def exec_block(block: Block) -> None:
    """Run a Python block in this process, in a fresh namespace (the caller sets the working directory)."""
    code = compile(block.text, f"<{block.id}>", "exec")
    exec(code, {"__name__": "__main__"})  # noqa: S102 - the documentation's own example, as a user runs it


def run_block(block: Block, scratch: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run(command_of(block, scratch), cwd=scratch, env=block_environment(scratch), text=True,
                          capture_output=True, timeout=BLOCK_TIMEOUT, stdin=subprocess.DEVNULL)  # fmt: skip


def start_block(block: Block, scratch: Path, log: Path) -> subprocess.Popen[bytes]:
    """A background block (a server) in its own process group, its output to ``log``."""
    with log.open("wb") as out:
        return subprocess.Popen(command_of(block, scratch), cwd=scratch, env=block_environment(scratch), stdout=out,
                                stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL, start_new_session=True)  # fmt: skip


def stop(process: subprocess.Popen[bytes]) -> None:
    """SIGINT to the server's process group (a node shuts down cleanly), then SIGKILL if it lingers."""
    if process.poll() is not None:
        return
    os.killpg(process.pid, signal.SIGINT)
    try:
        process.wait(timeout=10)
    except subprocess.TimeoutExpired:
        os.killpg(process.pid, signal.SIGKILL)
        process.wait(timeout=10)


def failure_text(block: Block, done: subprocess.CompletedProcess[str]) -> str:
    tail = "\n".join((done.stdout + done.stderr).splitlines()[-30:])
    return f"{block.id} ({block.language}) exited {done.returncode}:\n{block.text}\n--- output (tail) ---\n{tail}"


def describe(block: Block) -> str:
    """``page:line  language  marks`` ("run" for a block the fast lane runs, "text" for a block never run)."""
    runs = block.language in ("shell", "python")
    return f"{block.id:40} {block.language or '-':8} {(' '.join(sorted(block.marks)) or 'run') if runs else 'text'}"


if __name__ == "__main__":  # list the blocks and their marks
    print("\n".join(describe(b) for b in all_blocks()))
    sys.exit(0)

"""maru_planner.heap: freed C memory inside the heap is given back to the operating system."""

from __future__ import annotations

import os
import platform
import subprocess
import sys

import pytest
from conftest import rss_mb

from maru_planner import heap

pytestmark = pytest.mark.skipif(platform.libc_ver()[0] != "glibc", reason="glibc's malloc only")

BLOCK = 64 * 1024  # below glibc's mmap threshold: these come from the heap, not from mmap
BLOCKS = 2_000  # 128 MB


def test_memory_freed_below_a_live_block_is_given_back():
    blocks = [bytearray(BLOCK) for _ in range(BLOCKS)]
    for block in blocks:  # touch every page
        block[::4096] = b"\x01" * len(block[::4096])
    pinned = blocks[-1]  # keeps the heap's top in use: glibc cannot shrink the heap by itself
    del blocks
    held = rss_mb(os.getpid())
    assert heap.release_free_memory()
    assert held - rss_mb(os.getpid()) > BLOCKS * BLOCK / 1e6 / 2
    assert pinned[0] == 1


ARENA_COUNT = """
import ctypes, re, sys, tempfile, threading
from maru_planner import heap
if sys.argv[1] == "limited":
    assert heap.limit_arenas(1)
threads = [threading.Thread(target=lambda: [bytearray(1000) for _ in range(20000)]) for _ in range(8)]
for thread in threads:
    thread.start()
for thread in threads:
    thread.join()
libc = ctypes.CDLL("libc.so.6")
libc.fopen.restype = ctypes.c_void_p
with tempfile.NamedTemporaryFile(suffix=".xml") as report:
    stream = ctypes.c_void_p(libc.fopen(report.name.encode(), b"w"))
    libc.malloc_info(0, stream)
    libc.fclose(stream)
    print(len(re.findall("<heap nr=", open(report.name).read())))
"""


def _arenas_after_eight_threads(mode: str) -> int:
    done = subprocess.run([sys.executable, "-c", ARENA_COUNT, mode], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    return int(done.stdout)


def test_limited_arenas_hold_for_every_thread():
    assert _arenas_after_eight_threads("limited") == 1
    assert _arenas_after_eight_threads("default") > 1  # the control: threads do get arenas of their own

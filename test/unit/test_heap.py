"""maru_planner.heap: freed C memory inside the heap is given back to the operating system."""

from __future__ import annotations

import platform

import pytest

from maru_planner import heap

pytestmark = pytest.mark.skipif(platform.libc_ver()[0] != "glibc", reason="glibc's malloc only")

BLOCK = 64 * 1024  # below glibc's mmap threshold: these come from the heap, not from mmap
BLOCKS = 2_000  # 128 MB


def _rss_mb() -> float:
    with open("/proc/self/statm") as statm:
        return int(statm.read().split()[1]) * 4096 / 1e6


def test_memory_freed_below_a_live_block_is_given_back():
    blocks = [bytearray(BLOCK) for _ in range(BLOCKS)]
    for block in blocks:  # touch every page
        block[::4096] = b"\x01" * len(block[::4096])
    pinned = blocks[-1]  # keeps the heap's top in use: glibc cannot shrink the heap by itself
    del blocks
    held = _rss_mb()
    assert heap.release_free_memory()
    assert held - _rss_mb() > BLOCKS * BLOCK / 1e6 / 2
    assert pinned[0] == 1


def test_arenas_can_be_limited():
    assert heap.limit_arenas(8)  # glibc's own default on a one-core machine: harmless to this test process

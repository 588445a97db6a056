"""The C heap of a long-running node process (glibc's malloc; elsewhere these do nothing).

glibc keeps memory that was freed inside its heaps for later allocations instead of giving it back, and it gives
each thread that allocates while another does an arena of its own (up to 8 per core), each keeping its own freed
memory. A node that built its planners (robot models, numba's compiled kernels, OMPL set-ups) and then served
requests on several executor threads held tens of megabytes that no object used: planning_node is 338 MB idle
with :func:`release_free_memory` after building its planners, 366 MB without (``bench/robustness.py``'s node).
"""

from __future__ import annotations

import ctypes
import ctypes.util
import functools

M_ARENA_MAX = -8  # glibc's malloc.h


@functools.cache
def _glibc() -> ctypes.CDLL | None:
    name = ctypes.util.find_library("c")
    if name is None:
        return None
    libc = ctypes.CDLL(name)
    return libc if hasattr(libc, "malloc_trim") and hasattr(libc, "mallopt") else None


def limit_arenas(arenas: int) -> bool:
    """At most ``arenas`` malloc arenas in this process (before its threads start); whether it applied."""
    libc = _glibc()
    return libc is not None and libc.mallopt(M_ARENA_MAX, arenas) == 1


def release_free_memory() -> bool:
    """Give memory freed in every arena back to the operating system; whether any was given back."""
    libc = _glibc()
    return libc is not None and libc.malloc_trim(0) == 1

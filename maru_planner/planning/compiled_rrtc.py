"""Moved to :mod:`maru_planner.planning.planners.compiled_rrtc`; this path is kept for existing imports."""

from maru_planner.planning.planners.compiled_rrtc import (
    CALL_SECONDS,
    COMPILED_RRTC_PARAMS,
    DEFAULT_RANGE,
    EXACT_NEAR,
    FIRST_EDGES,
    CompiledRRTConnect,
    next_batch,
)

__all__ = [
    "DEFAULT_RANGE",
    "EXACT_NEAR",
    "COMPILED_RRTC_PARAMS",
    "FIRST_EDGES",
    "CALL_SECONDS",
    "CompiledRRTConnect",
    "next_batch",
]

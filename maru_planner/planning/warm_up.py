"""Moved to :mod:`maru_planner.runtime.warm_up`; this path keeps working, also as
``python -m maru_planner.planning.warm_up`` (``make setup`` runs it)."""

import sys

from maru_planner.runtime.warm_up import (
    BOX,
    BUDGET,
    EDGE_STEP,
    MANY_BOXES,
    SAMPLE_TRIES,
    SEED,
    STEP,
    WarmUp,
    main,
    warm_up,
)

__all__ = ["BOX", "BUDGET", "EDGE_STEP", "MANY_BOXES", "SAMPLE_TRIES", "SEED", "STEP", "WarmUp", "main", "warm_up"]

if __name__ == "__main__":
    sys.exit(main())

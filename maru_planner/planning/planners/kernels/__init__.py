"""numba search loops only (RRT-Connect, RC-RRT, shortcut); their collision code is maru_planner.collision.kernels."""

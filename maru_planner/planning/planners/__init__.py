"""Arm planners: the registry (:mod:`.registry`) and one module per planner, each given a PlanningProblem.

Importing this package fills the registry: every module named in :data:`BUILT_IN` registers its planners (in this
order, the order the CLIs, node parameters and ``query_planners`` list them). A planner of your own registers
itself with :func:`~maru_planner.planning.planners.registry.register` from any module you import.
"""

from importlib import import_module

BUILT_IN = ("ompl_planners", "rc_rrt", "compiled_rrtc", "cbirrt")

for _name in BUILT_IN:
    import_module(f"{__name__}.{_name}")

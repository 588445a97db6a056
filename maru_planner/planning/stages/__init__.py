"""The stages a plan goes through, in order, each one file with one entry point ``stage(problem, result)``.

Path stages (raise a typed error to fail the request): search -> simplify -> parameterize (or, with path
constraints: search -> simplify -> prove -> time_dense). Check stages (return the result, a failure with its path
dropped): certify (proof on the exact model, local repair) or verify (re-check on the exact model, re-plan).
:mod:`~maru_planner.planning.pipeline` runs them; :class:`~maru_planner.planning.motion_planner.MotionPlanner`
chooses the lists.
"""

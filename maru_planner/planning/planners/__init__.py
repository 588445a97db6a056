"""Arm planners: the registry and one module per planner; each is given a PlanningProblem."""

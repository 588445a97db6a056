"""The robots known by name, one module each (its profile, and whatever is particular to it).

:mod:`maru_planner.robot.profiles` lists them; adding a robot is one module here and one entry there.
"""

"""The robots known by name: one profile file ``<name>.yaml`` each, and a module ``<name>.py`` for a robot with code
or public names of its own (Maru-1's description and IK, Panda's MotionBenchMaker fingers, ``TIAGO_ARM``,
``UR5_JOINTS``).

:mod:`maru_planner.robot.profiles` lists them; adding a robot is one YAML file here.
"""

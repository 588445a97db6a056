"""maru_planner: motion planning for humanoid and mobile-manipulator robots.

The core (everything outside ``maru_planner.ros``: errors, params, shapes, robot, scene, collision,
planning, base, reactive, sim, bag, viz) imports no ROS; ``maru_planner.ros`` holds the thin ROS 2
adapters. Layers, contracts and how to extend them: ``docs/architecture.md``.
"""

__version__ = "0.1.0"

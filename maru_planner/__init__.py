"""maru_planner: motion planning for humanoid and mobile-manipulator robots.

The core (robot, scene, collision, planning, reactive, base, sim, bag, viz)
imports no ROS; ``maru_planner.ros`` holds the thin ROS 2 adapters.
"""

__version__ = "0.1.0"

"""Old home of the robot and scene pictures, now :mod:`maru_planner.viz.robot` (re-exported here).

``python -m maru_planner.robot.render --out docs/maru1_scenes.png`` still works; it is
``python -m maru_planner.viz.robot``.
"""

from maru_planner.viz.robot import draw_configuration, draw_geometry, main, render_paper_tasks

__all__ = ["draw_configuration", "draw_geometry", "main", "render_paper_tasks"]

if __name__ == "__main__":
    raise SystemExit(main())

"""Matplotlib 3D pictures of a robot's collision geometry and a scene (any shape of the shape table).

    python -m maru_planner.viz.robot --out docs/maru1_scenes.png

draws the two paper-000 tasks: start and goal postures with the desk (and box),
and the straight joint-space line's midpoint with its colliding links in red.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import coal
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pinocchio as pin  # noqa: E402
from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # noqa: E402

from maru_planner.collision import CollisionChecker  # noqa: E402
from maru_planner.paths import config_path  # noqa: E402
from maru_planner.robot.model import RobotModel  # noqa: E402
from maru_planner.scene import Scene  # noqa: E402
from maru_planner.scene.shapes import box_faces, posed  # noqa: E402


def _surface(ax, X, Y, Z, T, color, alpha):
    pts = np.stack([X, Y, Z], axis=-1) @ T[:3, :3].T + T[:3, 3]
    ax.plot_surface(pts[..., 0], pts[..., 1], pts[..., 2], color=color, alpha=alpha, linewidth=0, shade=True)


def draw_geometry(ax, geometry: coal.CollisionGeometry, T: np.ndarray, color, alpha=0.6) -> None:
    """Draw one coal shape at pose T (4x4); meshes are drawn as their bounding box."""
    u, v = np.meshgrid(np.linspace(0, 2 * np.pi, 16), np.linspace(0, np.pi, 9))
    if isinstance(geometry, coal.Box):
        faces = posed(box_faces(np.asarray(geometry.halfSide)), T)
        ax.add_collection3d(Poly3DCollection(faces, facecolor=color, alpha=alpha, edgecolor="k", linewidth=0.2))
    elif isinstance(geometry, coal.Sphere):
        r = geometry.radius
        _surface(ax, r * np.cos(u) * np.sin(v), r * np.sin(u) * np.sin(v), r * np.cos(v), T, color, alpha)
    elif isinstance(geometry, coal.Cylinder):
        r, h = geometry.radius, geometry.halfLength
        a, z = np.meshgrid(np.linspace(0, 2 * np.pi, 16), np.linspace(-h, h, 2))
        _surface(ax, r * np.cos(a), r * np.sin(a), z, T, color, alpha)
    else:
        geometry.computeLocalAABB()
        box = geometry.aabb_local
        center = (np.asarray(box.min_) + np.asarray(box.max_)) / 2
        Tc = T.copy()
        Tc[:3, 3] = T[:3, :3] @ center + T[:3, 3]
        faces = posed(box_faces((np.asarray(box.max_) - np.asarray(box.min_)) / 2), Tc)
        ax.add_collection3d(Poly3DCollection(faces, facecolor=color, alpha=alpha * 0.5, edgecolor="k"))


def draw_configuration(
    ax, robot: RobotModel, scene: Scene | None, q: np.ndarray, color, *, highlight=(), alpha=0.6
) -> None:
    """Draw the robot's links at q (links named in ``highlight`` in red) and the scene's obstacles (if given)."""
    data, geom_data = robot.model.createData(), pin.GeometryData(robot.collision_model)
    pin.updateGeometryPlacements(robot.model, data, robot.collision_model, geom_data, np.asarray(q, dtype=float))
    for k, obj in enumerate(robot.collision_model.geometryObjects):
        link = robot.model.frames[obj.parentFrame].name
        draw_geometry(ax, obj.geometry, geom_data.oMg[k].homogeneous, "tab:red" if link in highlight else color, alpha)
    for obstacle in scene.obstacles.values() if scene is not None else ():
        facecolor = "tab:red" if obstacle.name in highlight else "burlywood"
        ax.add_collection3d(
            Poly3DCollection(obstacle.faces(), facecolor=facecolor, alpha=0.2, edgecolor="k", linewidth=0.2)
        )


def _frame_axes(ax, title, limits):
    ax.set_title(title, fontsize=9)
    for setter, (lo, hi) in zip((ax.set_xlim, ax.set_ylim, ax.set_zlim), limits):
        setter(lo, hi)
    ax.set_box_aspect([hi - lo for lo, hi in limits])
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    ax.set_zlabel("z")
    ax.view_init(elev=28, azim=-60)


def render_paper_tasks(out: Path) -> Path:
    robot = RobotModel.maru1()
    down = [-1.57, 1.57, 1.57, 0, -1.57, -1.57]
    s6, g6 = np.array([0, 0, 1.57, 1.57, 0, -1.57, -1.57, *down]), np.array([0, *down, *down])
    s13 = np.array([-0.9, -0.7, 1.57, 0.7, 0.7, -0.9, -0.9, -0.8, 1.57, 2.0, 0.7, -1.9, -1.25])
    g13 = np.array([0.9, -0.8, 1.57, 1.14, 0.7, -1.24, -1.9, -0.7, 1.57, 2.44, 0.7, -2.24, -1.25])
    tasks = [
        ("6-DOF: start (blue), goal (green)", "maru6_desk.yaml", s6, g6),
        ("13-DOF: start (blue), goal (green)", "maru13_desk_box.yaml", s13, g13),
    ]
    limits = ((-0.4, 0.9), (-0.8, 0.8), (-0.5, 0.6))
    fig = plt.figure(figsize=(15, 5))
    for i, (title, scene_file, start, goal) in enumerate(tasks):
        scene = Scene.from_yaml(config_path("scenes", scene_file))
        ax = fig.add_subplot(1, 3, i + 1, projection="3d")
        draw_configuration(ax, robot, scene, start, "tab:blue")
        draw_configuration(ax, robot, None, goal, "tab:green")
        _frame_axes(ax, title, limits)
    scene = Scene.from_yaml(config_path("scenes", "maru13_desk_box.yaml"))
    middle = (s13 + g13) / 2
    hits = {name for pair in CollisionChecker(robot, scene).colliding_pairs(middle) for name in pair}
    ax = fig.add_subplot(1, 3, 3, projection="3d")
    draw_configuration(ax, robot, scene, middle, "tab:gray", highlight=hits)
    _frame_axes(ax, "13-DOF: straight line's midpoint (collisions red)", limits)
    fig.suptitle("Maru-1 upper body (base_link = waist, z up) and the paper-000 scenes")
    fig.tight_layout()
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=100)
    plt.close(fig)
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description="Render the paper-000 tasks' postures and scenes.")
    parser.add_argument("--out", type=Path, default=Path("docs/maru1_scenes.png"))
    args = parser.parse_args(argv)
    print(render_paper_tasks(args.out))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

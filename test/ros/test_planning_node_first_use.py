"""A robot geometry the sphere cache has never seen (a user's own URDF, a fresh machine): planning_node fits its
sphere model once, before its worker processes start (they load it), says so in its log and keeps it on disk for
the next start."""

from __future__ import annotations

from conftest import PAPER_GOAL, PAPER_START, connected_planning_client


def start_node(node_process, namespace: str):
    from maru_planner.paths import config_path

    return node_process(
        "maru_planner.ros.planning_node",
        ["--ros-args", "-r", f"__ns:={namespace}", "--params-file", str(config_path("planner.yaml"))],
    )


def test_the_sphere_model_is_fitted_once_and_kept_for_the_next_start(node_process, rclpy_session, tester, tmp_path,
                                                                     monkeypatch):  # fmt: skip
    from maru_planner_interfaces.msg import PlanningError

    monkeypatch.setenv("MARU_PLANNER_CACHE", str(tmp_path))  # an empty cache; the node processes inherit it
    first = start_node(node_process, "/first_use")
    client = connected_planning_client(tester, first, namespace="/first_use")
    response = client.plan(PAPER_GOAL, start=PAPER_START, group="upper_body", time_budget=10.0, seed=1)
    assert response.error.code == PlanningError.SUCCESS, response.error.message
    assert first.log().count("fitting the sphere model of maru1") == 1, first.log()
    assert len(list((tmp_path / "spheres").glob("*.npz"))) == 1

    second = start_node(node_process, "/second_use")
    connected_planning_client(tester, second, namespace="/second_use")
    assert "fitting the sphere model" not in second.log(), second.log()
    assert first.alive() and second.alive()

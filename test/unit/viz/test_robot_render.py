"""The scene picture renders (robot + obstacles) to a PNG."""

from __future__ import annotations

from maru_planner.viz.robot import render_paper_tasks


def test_render_writes_png(tmp_path):
    out = render_paper_tasks(tmp_path / "scenes.png")
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and out.stat().st_size > 20000

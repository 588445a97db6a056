"""Fixed-seed plans are identical to the ones recorded before the structure step (issue 35): the paper's 13-DOF
problem with four planners and 20 MotionBenchMaker problems, path by path (``golden_paths.py`` records them)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from golden_paths import GOLDEN, MBM_TARBALL, maru13_outcomes, mbm_outcomes


def _golden() -> dict:
    return json.loads(GOLDEN.read_text())


def _assert_same(name: str, got: dict, want: dict) -> None:
    assert got["status"] == want["status"], f"{name}: {got.get('message')}"
    if "path" not in want:
        return
    np.testing.assert_allclose(got["path"], want["path"], rtol=0, atol=1e-9, err_msg=name)
    assert got["points"] == want["points"], name
    assert got["duration"] == pytest.approx(want["duration"], abs=1e-9), name
    np.testing.assert_allclose(got["final"], want["final"], rtol=0, atol=1e-9, err_msg=name)


def test_maru13_paths_are_unchanged():
    golden = _golden()
    for name, got in maru13_outcomes().items():
        _assert_same(name, got, golden[name])


@pytest.mark.skipif(not MBM_TARBALL.is_file(), reason="MotionBenchMaker tarball not present")
def test_motionbenchmaker_paths_are_unchanged():
    golden = _golden()
    outcomes = mbm_outcomes()
    assert len(outcomes) == 20
    for name, got in outcomes.items():
        _assert_same(name, got, golden[name])

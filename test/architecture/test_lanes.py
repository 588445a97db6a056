"""The tests are in lanes that mirror the package (``make test`` runs each, ``make test-fast`` the unit lane): no test
module outside them, and the unit lane's folders are the package's."""

from __future__ import annotations

from pathlib import Path

TEST_DIR = Path(__file__).resolve().parents[1]
PACKAGE_DIR = TEST_DIR.parent / "maru_planner"
LANES = ("unit", "ros", "hostile", "architecture", "docs")


def test_every_test_module_is_in_a_lane():
    outside = sorted(p.name for p in TEST_DIR.glob("test_*.py"))
    assert not outside, f"test modules outside test/{{{','.join(LANES)}}}/: {outside}"
    assert sorted(p.name for p in TEST_DIR.iterdir() if p.is_dir() and p.name not in ("data", "__pycache__")) == sorted(
        LANES
    )


def test_the_unit_lane_mirrors_the_package():
    folders = [p.relative_to(TEST_DIR / "unit") for p in (TEST_DIR / "unit").rglob("*") if p.is_dir()]
    strays = sorted(str(f) for f in folders if f.name != "__pycache__" and not (PACKAGE_DIR / f).is_dir())
    assert not strays, f"test/unit/ folders with no package folder of the same path: {strays}"


def test_test_module_names_are_unique():
    names = [p.name for p in TEST_DIR.rglob("test_*.py")]
    assert len(names) == len(set(names)), "two test modules share a name (pytest imports them by base name)"

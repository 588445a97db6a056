"""The numbers the docs quote from bench/results/ are the results' own (doc_includes.py)."""

from __future__ import annotations

from doc_includes import PAGES, REPO, includes, nth_table, stale_pages


def test_included_tables_equal_the_results():
    assert not stale_pages(), "run: .venv/bin/python test/docs/doc_includes.py (refreshes the included tables)"


def test_every_include_names_an_existing_table():
    for page in PAGES:
        for include in includes(page):
            path, n = include.split(" table=")
            assert nth_table(REPO / path, int(n)), f"{page.name}: {include} is empty"

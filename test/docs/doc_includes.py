"""Tables the docs quote from bench/results/*.md, kept equal to them (one source for every number).

A page includes the n-th table of a result file between two HTML comments (invisible on GitHub)::

    <!-- include bench/results/service_latency.md table=1 -->
    | measure | median ms | ... |
    <!-- end include -->

``python test/docs/doc_includes.py`` rewrites every include from the result files (after a benchmark run);
``test_docs_numbers.py`` fails while one differs.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
PAGES = [REPO / "README.md", *sorted((REPO / "docs").glob("*.md"))]
INCLUDE = re.compile(r"(<!-- include (\S+) table=(\d+) -->\n)(.*?)(<!-- end include -->)", re.DOTALL)


def nth_table(path: Path, n: int) -> str:
    """The ``n``-th (1-based) run of consecutive ``|`` lines of a Markdown file, with a final newline."""
    tables: list[list[str]] = []
    previous_was_row = False
    for line in path.read_text().splitlines():
        row = line.startswith("|")
        if row and not previous_was_row:
            tables.append([])
        if row:
            tables[-1].append(line)
        previous_was_row = row
    if not 1 <= n <= len(tables):
        raise ValueError(f"{path.relative_to(REPO)} has {len(tables)} tables, not a table {n}")
    return "\n".join(tables[n - 1]) + "\n"


def refreshed(text: str) -> str:
    """``text`` with every include replaced by the current table of its result file."""
    return INCLUDE.sub(lambda m: m.group(1) + nth_table(REPO / m.group(2), int(m.group(3))) + m.group(5), text)


def includes(page: Path) -> list[str]:
    return [f"{m.group(2)} table={m.group(3)}" for m in INCLUDE.finditer(page.read_text())]


def stale_pages() -> list[str]:
    """Pages whose includes differ from the result files."""
    return [str(p.relative_to(REPO)) for p in PAGES if refreshed(p.read_text()) != p.read_text()]


if __name__ == "__main__":
    for page in PAGES:
        text = page.read_text()
        if refreshed(text) != text:
            page.write_text(refreshed(text))
            print(f"refreshed {page.relative_to(REPO)}")
    sys.exit(0)

"""The collector finds blocks, their languages and marks as doc_blocks.py documents them."""

from __future__ import annotations

from pathlib import Path

from doc_blocks import blocks_of, runnable, untagged_commands

PAGE = """# A page

<!-- synopsis: a usage line -->
```bash
maru-plan --start Q...
```
<!-- slow background -->
```bash
.venv/bin/planning_node
```
Text between.
```python
print("runs")
```
```
maru-plan --help
```
```yaml
key: value
```
"""


def test_blocks_marks_and_languages(tmp_path: Path):
    page = tmp_path / "page.md"
    page.write_text(PAGE)
    blocks = blocks_of(page)
    assert [(b.line, b.language, sorted(b.marks)) for b in blocks] == [
        (4, "shell", ["synopsis"]),
        (8, "shell", ["background", "slow"]),
        (12, "python", []),
        (15, "", []),
        (18, "yaml", []),
    ]
    assert blocks[2].text == 'print("runs")\n'
    assert [b.line for b in runnable(blocks)] == [8, 12]
    assert [block_id.rsplit(":", 1)[1] for block_id in untagged_commands(blocks)] == ["15"]

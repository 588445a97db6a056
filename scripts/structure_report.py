"""Structure of a checkout of this repository as numbers: modules, the largest one, lines per folder, import
cycles and layer violations by ``test/architecture/import_graph.py``'s rules (this checkout's table, applied to the
given one). Usage: ``python scripts/structure_report.py [REPO_ROOT ...]`` (default: this checkout); one column each.
"""

from __future__ import annotations

import sys
from collections import Counter
from pathlib import Path

HERE = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(HERE / "test" / "architecture"))

from import_graph import PACKAGE, import_cycles, layer_violations, module_files, package_imports  # noqa: E402


def report(root: Path) -> dict[str, object]:
    modules = module_files(root, PACKAGE)
    lines = {name: len(path.read_text().splitlines()) for name, path in modules.items()}
    per_folder: Counter[str] = Counter()
    for name, count in lines.items():
        parts = name.split(".")
        per_folder[parts[1] if len(parts) > 2 else "(top level)"] += count
    imports = package_imports(root, PACKAGE)
    largest = max(lines, key=lines.__getitem__)
    return {
        "modules": len(modules),
        "lines": sum(lines.values()),
        "largest module": f"{largest.removeprefix(PACKAGE + '.')} ({lines[largest]})",
        "modules over 600 lines": sum(n > 600 for n in lines.values()),
        "import cycles (type-only included)": len(import_cycles(imports, PACKAGE)),
        "layer violations": len(layer_violations(imports)),
        **{f"lines in {folder}/": n for folder, n in sorted(per_folder.items())},
    }


def main(argv: list[str]) -> int:
    roots = [Path(a).resolve() for a in argv] or [HERE]
    columns = [report(root) for root in roots]
    keys = list(dict.fromkeys(k for c in columns for k in c))
    print("| | " + " | ".join(str(r) for r in roots) + " |")
    print("|---|" + "---|" * len(roots))
    for key in keys:
        print(f"| {key} | " + " | ".join(str(c.get(key, 0)) for c in columns) + " |")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

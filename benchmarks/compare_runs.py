"""Compare two run folders file by file: are their results the same?

Usage: python benchmarks/compare_runs.py RUN_A RUN_B

Every CSV, JSON and Markdown file under either folder is compared after dropping what
measures the run rather than its result: wall-clock fields (keys or columns whose name
holds ``seconds``, ``wall`` or ``time``; numbers of seconds written into a text, such
as ``0.09 / 0.32 s``), and the provenance of ``run.json`` (start and end times, host,
versions, commit). Prints one line per file (``same``,
``differs: <first difference>``, ``only in A/B``) and exits 1 if any file differs (2, with
one line, if either path is not a folder or neither holds such a file).
Used to check that a refactoring left ``crmgrasp reproduce``'s results unchanged.
"""

from __future__ import annotations

import csv
import io
import json
import re
import sys
from pathlib import Path
from typing import Any

TIMING = re.compile(
    r"seconds|wall|time|rate_per|per_s\b|_s$|started|ended|finished|host|python|version|commit|source_sha|argv|cwd|^pid$"
)
"""Names of fields that measure the run (clock, machine, provenance), not its result."""


NUMBER = r"\d+(\.\d+)?(e-?\d+)?"
SECONDS = re.compile(rf"({NUMBER} / )?{NUMBER} ?s\b")
"""A number of seconds written into a text (``0.09 / 0.32 s``)."""


def _clean(value: Any) -> Any:
    if isinstance(value, dict):
        return {k: _clean(v) for k, v in value.items() if not TIMING.search(str(k))}
    if isinstance(value, list):
        return [_clean(v) for v in value]
    if isinstance(value, str):
        return SECONDS.sub("<s>", value)
    return value


def _csv(text: str) -> list[list[str]]:
    rows = list(csv.reader(io.StringIO(text)))
    if not rows:
        return rows
    keep = [i for i, name in enumerate(rows[0]) if not TIMING.search(name)]
    return [[r[i] for i in keep if i < len(r)] for r in rows]


def _markdown(text: str) -> list[str]:
    """Markdown reports with timing columns dropped where a table names them."""
    out, drop = [], []
    for line in text.splitlines():
        if line.startswith("|"):
            cells = line.strip("|").split("|")
            if not set(line) <= set("|-: "):
                if not drop and any(TIMING.search(c.strip()) for c in cells):
                    drop = [i for i, c in enumerate(cells) if TIMING.search(c.strip())]
            out.append(SECONDS.sub("<s>", "|".join(c for i, c in enumerate(cells) if i not in drop)))
        else:
            drop = []
            out.append(SECONDS.sub("<s>", line))
    return out


def load(path: Path) -> Any:
    text = path.read_text(encoding="utf-8")
    if path.suffix == ".json":
        return _clean(json.loads(text))
    if path.suffix == ".csv":
        return _csv(text)
    return _markdown(text)


def first_difference(a: Any, b: Any, where: str = "") -> str | None:
    if isinstance(a, dict) and isinstance(b, dict):
        for key in sorted(set(a) | set(b)):
            d = first_difference(a.get(key), b.get(key), f"{where}.{key}")
            if d:
                return d
        return None
    if isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            return f"{where}: {len(a)} vs {len(b)} items"
        for i, (x, y) in enumerate(zip(a, b)):
            d = first_difference(x, y, f"{where}[{i}]")
            if d:
                return d
        return None
    return None if a == b else f"{where}: {a!r:.80} vs {b!r:.80}"


def main(argv: list[str]) -> int:
    if len(argv) != 2:
        print(__doc__.strip().splitlines()[2])
        return 2
    a, b = (Path(p) for p in argv)
    for root in (a, b):
        if not root.is_dir():
            print(f"compare_runs: {str(root)!r} is not a folder")
            return 2
    names = sorted(
        {p.relative_to(root) for root in (a, b) for p in root.rglob("*") if p.suffix in {".csv", ".json", ".md"}}
    )
    if not names:  # two empty folders would otherwise read as "0 of 0 files the same"
        print("compare_runs: neither folder holds a CSV, JSON or Markdown file")
        return 2
    bad = 0
    for name in names:
        pa, pb = a / name, b / name
        if not pa.exists() or not pb.exists():
            print(f"{name}: only in {'B' if not pa.exists() else 'A'}")
            bad += 1
            continue
        diff = first_difference(load(pa), load(pb))
        print(f"{name}: {'same' if diff is None else 'differs: ' + diff}")
        bad += diff is not None
    print(f"{len(names) - bad} of {len(names)} files the same")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

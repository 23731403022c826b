"""Hostile ``.pomdp`` files: every line of a file written by ``write_cassandra`` replaced by
each of [`EDITS`][], then read back with ``read_cassandra``.

``crmgrasp pomdp`` exports a task's POMDP in Cassandra's format, and ``read_cassandra`` reads
such a file back (to hand it to a POMDP solver or to ``pomdp_py``). A file edited by hand or
cut short must give one ``CrmgraspError`` line naming it, or read as a POMDP. Two files are
edited: one written from a small POMDP (two aliased states and a goal) and one of ``paper-box``'s
POMDP built on a 0.05 m grid from 50 starts. Each header line and the first [`PER_KIND`][] lines
of each kind of entry (``T:``, ``O:``, ``R:``) get every edit: the line deleted, replaced by
junk, given an extra field, its digits changed (``0`` to ``-1``, ``1`` to ``99`` or ``1e400``,
``2`` to ``-2`` or ``0``), its probabilities made NaN, its colons removed. Three whole files
follow: empty, bytes that are not UTF-8, and sizes that no memory holds. Each variant is read
in this process with Python's warnings raised as errors (``benchmarks/task_file_fuzz.py``'s
``attempt``). A variant passes if it reads, or raises a ``CrmgraspError`` of one line under 400
characters. The script prints one JSON object and exits 1 if a variant failed.

Measured 2026-12-07 on the 2-core machine: 446 variants in 1.4 s, none failed. On the code of
411076d, 20 failed:
- a negative or zero size, or an index past the sizes, reached numpy and scipy as a
  ``ValueError`` or an ``IndexError`` (18);
- 10^10 states asked numpy for 74.5 GiB, a ``MemoryError`` (2).

Usage: ``python benchmarks/pomdp_file_fuzz.py``.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np
from scipy import sparse

sys.path.insert(0, str(Path(__file__).resolve().parent))
import task_file_fuzz
from crmgrasp.planners.pomdp import POMDP, read_cassandra, write_cassandra

EDITS: tuple[Callable[[str], str], ...] = (
    lambda line: "",
    lambda line: "x",
    lambda line: line + " 9",
    lambda line: line.replace("0", "-1"),
    lambda line: line.replace("1", "99"),
    lambda line: line.replace("1", "1e400"),
    lambda line: line.replace("2", "-2"),
    lambda line: line.replace("2", "0"),
    lambda line: line.replace("0.5", "nan").replace("1.0", "nan"),
    lambda line: line.replace(":", ""),
)
"""What each line is replaced by in turn."""

WHOLE = ("", "\udcff\udcfe", "states: 10000000000\nactions: 1\nobservations: 1\nstart: 1\n")
"""Whole files: empty, bytes that are not UTF-8 (written as such) and a size no memory holds."""


def small() -> POMDP:
    """Two aliased states and a goal, two actions: every line kind of the format."""
    t = [sparse.csr_matrix(np.array([[0, 0, 1], [0, 1, 0], [0, 0, 1]], dtype=float)) for _ in range(2)]
    z = np.zeros((2, 3, 3))
    z[:] = [[0, 1, 0], [0, 1, 0], [0, 0, 1]]
    return POMDP(3, 2, 3, t, z, np.array([0.5, 0.5, 0.0]), np.array([False, False, True]), goal_obs=2)


def task_pomdp() -> POMDP:
    """``paper-box``'s POMDP on a coarse grid (``crmgrasp pomdp --cell 0.05``)."""
    from crmgrasp import make_task
    from crmgrasp.planners.pomdp_task import build_task_pomdp

    return build_task_pomdp(make_task("paper-box"), cell=0.05, samples=2, n_starts=50).model


PER_KIND = 5
"""Lines edited of each kind of entry (``T:``, ``O:``, ``R:``): the first five; every header line."""


def variants(text: str) -> Iterator[tuple[str, str]]:
    """Per line edited (every header line, the first [`PER_KIND`][] of each kind of entry) and
    edit: a label and the edited file; then [`WHOLE`][]."""
    lines = text.splitlines()
    seen: dict[str, int] = {}
    for i, line in enumerate(lines):
        kind = line.split(":", 1)[0] if line[:2] in ("T:", "O:", "R:") else "header"
        seen[kind] = seen.get(kind, 0) + 1
        if kind != "header" and seen[kind] > PER_KIND:
            continue
        for k, edit in enumerate(EDITS):
            yield f"line {i + 1}, edit {k}", "\n".join([*lines[:i], edit(line), *lines[i + 1 :]]) + "\n"
    for k, whole in enumerate(WHOLE):
        yield f"whole file {k}", whole


def main(argv: list[str] | None = None) -> dict[str, object]:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.parse_args(argv)
    t0, count, failures = time.perf_counter(), 0, []
    with tempfile.TemporaryDirectory() as scratch:
        for name, model in (("small", small()), ("paper-box", task_pomdp())):
            text = write_cassandra(model, Path(scratch) / "m.pomdp").read_text()
            for label, body in variants(text):
                path = Path(scratch) / "v.pomdp"
                path.write_bytes(body.encode("utf-8", "surrogateescape"))
                count += 1
                problem = task_file_fuzz.attempt(lambda path=path: read_cassandra(path))
                if problem is not None:
                    failures.append({"file": name, "variant": label, "problem": problem})
    out = {
        "variants": count,
        "failed": len(failures),
        "seconds": round(time.perf_counter() - t0, 1),
        "failures": failures[:40],
    }
    print(json.dumps(out, indent=1))
    return out


if __name__ == "__main__":
    sys.exit(1 if main()["failed"] else 0)

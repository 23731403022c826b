"""Recording finished units in a run folder: the append-only journal against rewriting
``run.json`` after every unit (the peer: how run folders recorded units before).

A study of many units records each as it finishes (:meth:`RunFolder.complete`). Prints one
JSON object: units per second over the first and the last 1,000 of ``N`` units (default
10,000) for the journal and for the peer, each run's ``last_over_first`` (1.0: a flat rate)
and ``journal_over_peer_last`` (how much faster the journal records the last units).

Usage: ``python benchmarks/bench_journal.py [N]``.
"""

from __future__ import annotations

import json
import sys
import tempfile
import time
from pathlib import Path

from crmgrasp.experiments.runs import RunFolder


def _rates(n: int, rewrite: bool) -> tuple[float, float]:
    """Units per second over the first and the last ``w = min(1000, n // 2)`` of ``n`` units."""
    w = min(1000, n // 2)
    info = {"status": "ok", "error": None, "file": "units/x.json"}
    with tempfile.TemporaryDirectory() as tmp:
        run = RunFolder(Path(tmp) / "run", "sweep", "bench", {}, argv=[])
        marks = []
        for i in range(n):
            if i in (0, n - w):
                marks.append(time.perf_counter())
            run.complete(f"sarsa-k2-0000 seed {i}", info)
            if rewrite:
                run._save()  # the peer: the whole record rewritten after each unit
            if i in (w - 1, n - 1):
                marks.append(time.perf_counter())
        run.finish("complete")
    return w / (marks[1] - marks[0]), w / (marks[3] - marks[2])


def main(n: int = 10_000) -> dict:
    journal, peer = _rates(n, False), _rates(n, True)
    return {
        "units": n,
        "journal_units_per_s_first_last": [round(r) for r in journal],
        "journal_last_over_first": round(journal[1] / journal[0], 2),
        "rewrite_units_per_s_first_last": [round(r) for r in peer],
        "rewrite_last_over_first": round(peer[1] / peer[0], 2),
        "journal_over_peer_last": round(journal[1] / peer[1], 1),
    }


if __name__ == "__main__":
    print(json.dumps(main(*(int(a) for a in sys.argv[1:2])), indent=2))

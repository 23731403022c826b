"""The reference values' search on compiled kernels against the readable rules.

[`crmgrasp.planners.references`][] expands each state by every CRM at once through its
object's kernel (``Kernel.successors``). For each task below this times the belief-space
optimum and the clairvoyant bound on the same sampled starts (worlds on a family task) on
``backend="auto"`` (compiled where a kernel exists) and on ``backend="reference"`` (the
readable rules: the peer), each in a fresh process of its own (so that no cache or
garbage of one run slows or speeds the other), after a first call on two starts that loads
the kernels (about a second once per process; ``cold_seconds_two_starts``). The values must
be the same on both (the run stops otherwise).

With ``--before DIR`` (a checkout of an earlier commit, e.g. ``git worktree add /tmp/before
031b740``) the same timing runs once more on that checkout's package (its references take no
backend: the default path), and its values must agree too.

Prints one JSON object: per task the starts, the values, seconds on each backend (and before)
and their ratios. Usage: ``python benchmarks/bench_references.py [--quick] [--before DIR]``
(about 4 minutes on 2 cores; ``--quick``: smaller sets, about 30 s).
"""

from __future__ import annotations

import argparse
import inspect
import json
import os
import subprocess
import sys
import time

from crmgrasp.planners.references import belief_optimum, clairvoyant_bound, sample_starts
from crmgrasp.tasks import make_task
from crmgrasp.tasks.offsets import offset_grid

CASES = (
    ("paper-box", None, 4000),
    ("u-handle", 17, 100),
    ("polygon-family", None, 300),
    ("triangles-3f", None, 100),
    ("cup-3d", None, 400),
    ("box-3d", None, 60),
    ("box-3d-3f", None, 40),
)
"""(task, offsets per pair of an offset grid or None for the task's CRMs, starts)."""


def one(name: str, grid: int | None, n: int, backend: str) -> dict:
    """One timing, in this process: the two-start call, then the optimum and the bound."""
    task = make_task(name) if grid is None else offset_grid(make_task(name), grid)
    starts = sample_starts(task, n, 0)
    kw = {"backend": backend} if "backend" in inspect.signature(belief_optimum).parameters else {}
    t0 = time.perf_counter()
    belief_optimum(task, starts[:2], **kw)  # loads this task's kernels
    cold = time.perf_counter() - t0
    t0 = time.perf_counter()
    values = belief_optimum(task, starts, **kw), clairvoyant_bound(task, starts, **kw)
    return {"task": task.name, "values": values, "seconds": time.perf_counter() - t0, "cold": cold}


def _fresh(name: str, grid: int | None, n: int, backend: str, source: str | None = None) -> dict:
    """[`one`][] in a fresh Python process (on the package in ``source``/src where given)."""
    args = [sys.executable, __file__, "--one", name, str(grid or 0), str(n), backend]
    env = dict(os.environ, PYTHONPATH=os.path.join(source, "src")) if source else None
    done = subprocess.run(args, capture_output=True, text=True, check=True, env=env)
    return json.loads(done.stdout)


def main(quick: bool = False, run: object = _fresh, before: str | None = None) -> dict:
    """Every case of [`CASES`][] on both backends (``run``: how one timing runs), and on the
    checkout ``before`` where given."""
    out: dict = {}
    for name, grid, n in CASES:
        n = max(4, n // 10) if quick else n
        auto, ref = (run(name, grid, n, b) for b in ("auto", "reference"))  # type: ignore[operator]
        old = run(name, grid, n, "auto", before) if before else None  # type: ignore[operator]
        for other in (ref, old):
            if other is not None and auto["values"] != other["values"]:
                raise SystemExit(f"{auto['task']}: the runs disagree: {auto['values']} against {other['values']}")
        out[auto["task"]] = {
            "starts": n,
            "belief_optimum": auto["values"][0],
            "clairvoyant_bound": auto["values"][1],
            "seconds_auto": round(auto["seconds"], 3),
            "seconds_reference": round(ref["seconds"], 3),
            "reference_over_auto": round(ref["seconds"] / auto["seconds"], 2),
            "cold_seconds_two_starts": round(auto["cold"], 3),
        }
        if old is not None:
            out[auto["task"]] |= {
                "seconds_before": round(old["seconds"], 3),
                "before_over_auto": round(old["seconds"] / auto["seconds"], 2),
            }
        print(f"{auto['task']}: {ref['seconds']:.2f} s readable, {auto['seconds']:.2f} s compiled", file=sys.stderr)
    return out


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="a tenth of the starts")
    ap.add_argument("--before", metavar="DIR", help="also time the checkout in DIR (its src/ package)")
    ap.add_argument("--one", nargs=4, metavar=("TASK", "GRID", "STARTS", "BACKEND"), help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.one:
        name, grid, n, backend = a.one
        print(json.dumps(one(name, int(grid) or None, int(n), backend)))
    else:
        print(json.dumps(main(a.quick, before=a.before), indent=2))

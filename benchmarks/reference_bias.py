"""How optimistic the belief-space optimum on sampled worlds is, on object families.

``belief_optimum(task, worlds)`` is exact over a finite set of sampled worlds: the belief is
the set of sampled worlds consistent with the history, so once a history is left with one
world the optimum acts as if it knew it. On a family, whose worlds vary continuously, the
optimum over ``n`` worlds is a sample-average approximation of the family's optimum ``J*``
(the least expected cost of a policy of observation histories): its expectation is at most
``J*`` and rises toward it as ``n`` grows (the bounds of stochastic programming, Mak, Morton
and Wood 1999). So, per size ``n``:

* **lower**: the in-sample optimum over disjoint blocks of ``n`` worlds from one pool
  (``pool`` worlds, seed 10,000, the worlds of ``family_learning.py`` first), its mean per
  world: an estimate of ``E[optimum on n worlds] <= J*``;
* **upper**: the belief-space policy over the pool's first ``n`` worlds (``BeliefPolicy``,
  which restarts its belief when a world leaves it, or with ``--fallback nearest`` keeps the
  worlds that explain all but the fewest observations) run on ``heldout`` fresh worlds (seed
  20,000): the cost of a policy, so an estimate of a value ``>= J*``.

``J*`` lies between the two. A learner's mean cost ``L`` on fresh worlds against the
in-sample optimum on ``n`` worlds, ``L / lower - 1``, bounds its gap to ``J*`` from above
(in expectation); larger ``n`` tightens it. Each is given over all worlds and over the
graspable ones only (a world is graspable when some sequence of at most ``max_steps`` CRMs
grasps it knowing the true configuration; every policy spends the step limit on the
others). Also printed: the clairvoyant bound (full information, ``<= J*``) on the pool and
on the held-out worlds (the two samples differ in how hard their worlds are: compare each
estimate with its own sample's bound), the standard deviation of the block optima (their mean's standard error is
that over the square root of ``blocks``), the standard error of the upper estimate (over the
held-out worlds), and the wall time per size.

Usage: ``python benchmarks/reference_bias.py [--task NAME ...] [--sizes 50,100,200,400]
[--pool 400] [--heldout 300] [--offset-grid N] [--fallback restart|nearest]`` (every size must divide the pool;
``--offset-grid N``: each task's CRMs replaced by ``N`` offsets per coordinate and contact
pair, the continuous-offsets target's reference). Prints one JSON object;
progress on stderr.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time

import numpy as np

from crmgrasp.experiments._episodes import episode_records
from crmgrasp.planners.references import (
    FALLBACKS,
    BeliefPolicy,
    clairvoyant_bound,
    sample_starts,
    ungraspable_fraction,
)
from crmgrasp.tasks import make_task
from crmgrasp.tasks.offsets import offset_grid


def _costs(task: object, planner: BeliefPolicy, worlds: list) -> np.ndarray:
    """CRMs per episode of ``planner`` from each world."""
    return np.array([len(r.actions) for r in episode_records(task, lambda: planner, worlds, 0)], dtype=float)  # type: ignore[arg-type]


def _r(x: float) -> float:
    return round(float(x), 4)


def task_rows(
    name: str, sizes: list[int], pool: int, heldout: int, grid: int | None = None, fallback: str = "restart"
) -> dict:
    """The lower and upper estimates per size for one task (see the module docstring), its
    CRMs a grid of ``grid`` offsets per coordinate and pair if given, the upper estimate's
    policy with ``fallback``."""
    task = make_task(name) if grid is None else offset_grid(make_task(name), grid)
    worlds = sample_starts(task, pool, 10_000)
    fresh = sample_starts(task, heldout, 20_000)
    ok = np.array([ungraspable_fraction(task, [w]) == 0.0 for w in worlds])
    ok_fresh = np.array([ungraspable_fraction(task, [w]) == 0.0 for w in fresh])
    out: dict = {
        "pool": pool,
        "graspable_pool": int(ok.sum()),
        "heldout": heldout,
        "graspable_heldout": int(ok_fresh.sum()),
        "clairvoyant_pool": _r(clairvoyant_bound(task, worlds)),
        "clairvoyant_heldout": _r(clairvoyant_bound(task, fresh)),
    }
    for n in sizes:
        t0 = time.perf_counter()
        blocks = [worlds[i : i + n] for i in range(0, pool, n)]
        inside = np.concatenate([_costs(task, BeliefPolicy(task, b), b) for b in blocks])
        means = inside.reshape(-1, n).mean(axis=1)
        upper = _costs(task, BeliefPolicy(task, worlds[:n], fallback), fresh)
        out[str(n)] = {
            "blocks": len(means),
            "lower": _r(inside.mean()),
            "lower_sd": _r(statistics.stdev(means)) if len(means) > 1 else None,
            "lower_graspable": _r(inside[ok].mean()),
            "upper": _r(upper.mean()),
            "upper_se": _r(upper.std(ddof=1) / np.sqrt(len(upper))),
            "upper_graspable": _r(upper[ok_fresh].mean()),
            "seconds": round(time.perf_counter() - t0, 1),
        }
        print(f"{name}: n = {n}: {out[str(n)]}", file=sys.stderr, flush=True)
    return out


def main(
    tasks: list[str], sizes: list[int], pool: int, heldout: int, grid: int | None = None, fallback: str = "restart"
) -> dict:
    """Every task; see the module docstring."""
    bad = [n for n in sizes if n <= 0 or pool % n]
    if bad:
        raise SystemExit(f"every size must divide the pool ({pool}); not {bad}")
    return {
        "sizes": sizes,
        "offset_grid": grid,
        "fallback": fallback,
        **{name: task_rows(name, sizes, pool, heldout, grid, fallback) for name in tasks},
    }


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--task", action="append", dest="tasks")
    ap.add_argument("--sizes", default="50,100,200,400")
    ap.add_argument("--pool", type=int, default=400)
    ap.add_argument("--heldout", type=int, default=300)
    ap.add_argument("--offset-grid", type=int, default=None)
    ap.add_argument("--fallback", choices=FALLBACKS, default="restart")
    a = ap.parse_args()
    res = main(
        a.tasks or ["u-handle", "polygon-family"],
        [int(s) for s in a.sizes.split(",")],
        a.pool,
        a.heldout,
        a.offset_grid,
        a.fallback,
    )
    print(json.dumps(res, indent=1))

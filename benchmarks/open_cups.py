"""Open cups against closed ones: what the opening changes.

``open-cup-3d`` and ``cup-3d`` draw their sizes and poses alike (radius, height, the upright
coin, the pose, from the same ranges and in the same order; the streams part once two starts
take different tries), so they differ in the opening alone. On WORLDS worlds of each
(``sample_starts(task, WORLDS, SEED)``) this prints the clairvoyant bound, the belief-space
optimum (CRMs per episode) and the share of worlds no sequence of at most ``max_steps`` CRMs
grasps; and, for the optimal policy's episodes on the open cups, how many of its grasps hold a
contact on an inner surface (strictly inside the cup's convex hull by more than 1e-6 m: the inner
wall or the inner bottom, reached through the opening).

Usage: ``python benchmarks/open_cups.py [--worlds 300] [--seed 0]``. Prints one JSON object;
about 1 minute on 2 cores at the defaults.
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np
from scipy.spatial import ConvexHull

from crmgrasp.experiments._episodes import episode_records
from crmgrasp.planners.references import BeliefPolicy, clairvoyant_bound, sample_starts, ungraspable_fraction
from crmgrasp.tasks import make_task

INSIDE = 1e-6
"""Metres inside the convex hull from which a contact counts as on an inner surface."""


def _inner(world: object, config: object) -> bool:
    """Whether a contact of ``config`` lies strictly inside the world's cup's convex hull."""
    hull = ConvexHull(np.array(world.task.obj.vertices))  # type: ignore[attr-defined]
    return any(max(float(e[:3] @ np.array(c.x) + e[3]) for e in hull.equations) < -INSIDE for c in config)  # type: ignore[attr-defined]


def row(name: str, worlds: int, seed: int, inner: bool) -> dict:
    task = make_task(name)
    t0 = time.perf_counter()
    starts = sample_starts(task, worlds, seed)
    policy = BeliefPolicy(task, starts)
    records = episode_records(task, lambda: policy, starts, 0)
    out = {
        "clairvoyant": round(clairvoyant_bound(task, starts), 4),
        "optimum": round(float(np.mean([len(r.actions) for r in records])), 4),
        "ungraspable": round(ungraspable_fraction(task, starts), 4),
        "optimum_success": round(float(np.mean([r.success for r in records])), 4),
    }
    if inner:
        won = [(w, r) for w, r in zip(starts, records, strict=True) if r.success]
        out["grasps_with_an_inner_contact"] = sum(_inner(w, r.final) for w, r in won)
        out["grasps"] = len(won)
    out["seconds"] = round(time.perf_counter() - t0, 1)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--worlds", type=int, default=300)
    ap.add_argument("--seed", type=int, default=0)
    a = ap.parse_args()
    print(
        json.dumps(
            {
                "worlds": a.worlds,
                "seed": a.seed,
                "open-cup-3d": row("open-cup-3d", a.worlds, a.seed, True),
                "cup-3d": row("cup-3d", a.worlds, a.seed, False),
            },
            indent=2,
        )
    )


if __name__ == "__main__":
    main()

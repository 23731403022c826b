"""Which CRM set lets a tripod reach a grasp: starts any one or two CRMs of a set grasp.

For ``cup-3d-3f`` and ``box-3d-3f`` (docs/model-3d.md section 9), STARTS worlds drawn with
seed SEED; per world and CRM set, whether some CRM grasps from the start (its outcome
feasible and its least friction at most ``mu_goal``), else whether some second CRM grasps
from a feasible first outcome (noise-free, the readable rules). Two sets: the tripod tasks'
[`tripod_crms`][crmgrasp.tasks.spatial.tripod_crms] (18 oppositions, three lateral offsets
per ordered pair) and the two-finger set's pattern grown to three contacts (six centred
oppositions and each contact's four 0.05 m slides, 18 CRMs).

Usage: ``python benchmarks/tripod_crms.py [STARTS] [SEED]`` (defaults 30 and 5; a few
minutes on one core: every feasible outcome costs a least friction, about 12 linear
programs). Prints one JSON object.
"""

from __future__ import annotations

import json
import sys
from typing import Any

import numpy as np

from crmgrasp.model.spatial import CRM3D
from crmgrasp.tasks import make_task
from crmgrasp.tasks.spatial import tripod_crms

SLIDES = ((0.05, 0.0), (-0.05, 0.0), (0.0, 0.05), (0.0, -0.05))
CENTRED_AND_SLIDES = tuple(
    [CRM3D(c, f, (0.0, 0.0)) for c in "abc" for f in "abc" if c != f] + [CRM3D(c, c, r) for c in "abc" for r in SLIDES]
)


def _grasps(inst: Any, config: Any, crm: CRM3D) -> tuple[bool, Any]:
    out = inst.execute(config, crm, config)
    ok = out.error.name == "NONE"
    return ok and inst.quality(out.config) <= inst.mu_goal, out.config if ok else None


def reach(name: str, actions: tuple[CRM3D, ...], starts: int, seed: int) -> dict[str, int]:
    """Starts of ``name`` from which one CRM, or two, of ``actions`` grasp."""
    task, rng = make_task(name), np.random.default_rng(seed)
    one = two = 0
    for _ in range(starts):
        inst, config = task.sample_world(rng)
        firsts, first = [], False
        for crm in actions:
            got, after = _grasps(inst, config, crm)
            if got:
                first = True
                break
            if after is not None:
                firsts.append(after)
        second = first or any(_grasps(inst, c, crm)[0] for c in firsts for crm in actions)
        one, two = one + first, two + second
    return {"one_crm": one, "two_crms": two, "starts": starts}


def main(starts: int = 30, seed: int = 5) -> dict[str, Any]:
    sets = {"tripod_crms": tripod_crms(), "centred_oppositions_and_slides": CENTRED_AND_SLIDES}
    out: dict[str, Any] = {"seed": seed}
    for name in ("cup-3d-3f", "box-3d-3f"):
        out[name] = {label: reach(name, actions, starts, seed) for label, actions in sets.items()}
        print(name, out[name], file=sys.stderr, flush=True)
    return out


if __name__ == "__main__":
    print(json.dumps(main(*(int(a) for a in sys.argv[1:3])), indent=2))

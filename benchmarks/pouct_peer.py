"""pomdp_py's POUCT as an online peer, beside the belief-space optimum and the learners.

``crmgrasp.planners.pouct.POUCTPolicy`` plans each CRM with pomdp_py's POUCT over the task's own
simulator and start distribution (a particle belief filtered by the sensed observations). It
spends no task episode, but knows the model, as the belief-space optimum does. Protocol: per
task and simulation budget, EPISODES worlds (``sample_starts(task, EPISODES, 1)``); the policy's
generator is seeded with 1. The belief-space optimal policy (``BeliefPolicy`` over the
references' 4,000 sampled starts) runs the same worlds. Printed: CRMs per episode and success,
the gap to the belief-space policy on the same worlds, and the wall time per decision.

``--exported`` runs ``ModelPOUCTPolicy`` instead: POUCT on the explicit POMDP of the task that
``crmgrasp pomdp --task paper-box --cell 0.01`` builds (4,000 sampled starts, seed 0), written to a
Cassandra ``.pomdp`` file and read back (the file must give the same model, or the run stops), with
the model's exact belief; beside it the row gives that model's PBVI policy on the same worlds
(``pbvi_same_worlds``). The sampled POMDP is built for one polygonal object: paper-box, not the
families.

Usage: ``python benchmarks/pouct_peer.py [--task paper-box --task box-family] [--sims 50
--sims 200 --sims 1000] [--episodes 200] [--particles 1000] [--exported]``. Needs the extra
``crmgrasp[pomdp]``. Prints one JSON object; progress on stderr. About 6 min at the defaults,
40 s with ``--exported``.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from crmgrasp.planners.pomdp import read_cassandra, write_cassandra
from crmgrasp.planners.pomdp_task import POMDPAgent, TaskPOMDP, build_task_pomdp
from crmgrasp.planners.pouct import ModelPOUCTPolicy, POUCTPolicy, POUCTSettings
from crmgrasp.planners.references import BeliefPolicy, sample_starts
from crmgrasp.sim import run_episode
from crmgrasp.tasks import make_task


def exported(task: Any) -> TaskPOMDP:
    """The task's sampled POMDP as ``crmgrasp pomdp`` exports it, its model read back from the file."""
    if task.family is not None:
        raise SystemExit(f"--exported: task {task.name!r} draws an object per episode; the sampled POMDP needs one")
    tp = build_task_pomdp(task, cell=0.01, n_starts=4000, seed=0)
    with tempfile.TemporaryDirectory() as tmp:
        model = read_cassandra(write_cassandra(tp.model, Path(tmp) / "task.pomdp"))
    same = all((x != y).nnz == 0 for x, y in zip(tp.model.T, model.T, strict=True))
    if not (same and np.array_equal(tp.model.Z, model.Z) and np.array_equal(tp.model.b0, model.b0)):
        raise SystemExit("the .pomdp file does not give back the model it was written from")
    return TaskPOMDP(task, model, tp.cells, tp.z0, tp.bins)


def one(name: str, sims: int, episodes: int, particles: int, model: TaskPOMDP | None = None) -> dict:
    task = make_task(name)
    worlds = sample_starts(task, episodes, 1)
    settings = POUCTSettings(num_sims=sims, particles=particles)
    extra: dict[str, Any] = {}
    if model is None:
        policy: Any = POUCTPolicy(task, np.random.default_rng(1), settings)
    else:
        policy = ModelPOUCTPolicy(model, np.random.default_rng(1), settings)
        pbvi = POMDPAgent(model, n_beliefs=300, seed=0)
        extra["pbvi_same_worlds"] = round(float(np.mean([pbvi.run(w)[0] for w in worlds])), 3)
    t0 = time.perf_counter()
    rng = np.random.default_rng(2)
    runs = [run_episode(task, policy, rng, start=w) for w in worlds]
    seconds = time.perf_counter() - t0
    steps = [e.steps for e in runs]
    mean = float(np.mean(steps))
    optimum = _belief_optimum(task, worlds)
    row = {
        "task": name,
        "planner": "POUCT on the simulator" if model is None else "POUCT on the exported POMDP",
        "num_sims": sims,
        "episodes": episodes,
        "mean_crms": round(mean, 3),
        "success": round(float(np.mean([e.success for e in runs])), 4),
        "belief_policy_same_worlds": round(optimum, 3),
        "gap_to_belief_policy": round(mean / optimum - 1.0, 4),
        "seconds_per_decision": round(seconds / max(1, sum(steps)), 4),
        **({"belief_refills": policy.refills} if model is None else extra),
    }
    print(row, file=sys.stderr)
    return row


_OPTIMA: dict[str, float] = {}


def _belief_optimum(task, worlds) -> float:
    """The belief-space optimal policy (over 4,000 sampled starts, the references' prior),
    executed on ``worlds``: CRMs per episode."""
    if task.name not in _OPTIMA:
        planner = BeliefPolicy(task, sample_starts(task, 4000, 0))
        rng = np.random.default_rng(2)
        _OPTIMA[task.name] = float(np.mean([run_episode(task, planner, rng, start=w).steps for w in worlds]))
    return _OPTIMA[task.name]


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--task", action="append", help="task (repeatable; default paper-box and box-family)")
    p.add_argument("--sims", action="append", type=int, help="simulations per decision (repeatable)")
    p.add_argument("--episodes", type=int, default=200)
    p.add_argument("--particles", type=int, default=1000)
    p.add_argument("--exported", action="store_true", help="POUCT on the exported POMDP (paper-box)")
    a = p.parse_args()
    names = a.task or (["paper-box"] if a.exported else ["paper-box", "box-family"])
    rows = [
        one(name, sims, a.episodes, a.particles, exported(make_task(name)) if a.exported else None)
        for name in names
        for sims in (a.sims or [50, 200, 1000])
    ]
    print(json.dumps({"rows": rows}, indent=1))


if __name__ == "__main__":
    main()

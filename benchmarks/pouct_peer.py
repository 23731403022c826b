"""pomdp_py's POUCT as an online peer, beside the belief-space optimum and the learners.

``crmgrasp.planners.pouct.POUCTPolicy`` plans each CRM with pomdp_py's POUCT over the task's own
simulator and start distribution (a particle belief filtered by the sensed observations). It
spends no task episode, but knows the model, as the belief-space optimum does. Protocol: per
task and simulation budget, EPISODES worlds (``sample_starts(task, EPISODES, 1)``); the policy's
generator is seeded with 1. The belief-space optimal policy (``BeliefPolicy`` over the
references' 4,000 sampled starts) runs the same worlds. Printed: CRMs per episode and success,
the gap to the belief-space policy on the same worlds, and the wall time per decision.

Usage: ``python benchmarks/pouct_peer.py [--task paper-box --task box-family] [--sims 50
--sims 200 --sims 1000] [--episodes 200] [--particles 1000]``. Needs the extra
``crmgrasp[pomdp]``. Prints one JSON object; progress on stderr. About 6 min at the defaults.
"""

from __future__ import annotations

import argparse
import json
import sys
import time

import numpy as np

from crmgrasp.planners.pouct import POUCTPolicy, POUCTSettings
from crmgrasp.planners.references import BeliefPolicy, sample_starts
from crmgrasp.sim import run_episode
from crmgrasp.tasks import make_task


def one(name: str, sims: int, episodes: int, particles: int) -> dict:
    task = make_task(name)
    worlds = sample_starts(task, episodes, 1)
    policy = POUCTPolicy(task, np.random.default_rng(1), POUCTSettings(num_sims=sims, particles=particles))
    t0 = time.perf_counter()
    rng = np.random.default_rng(2)
    runs = [run_episode(task, policy, rng, start=w) for w in worlds]
    seconds = time.perf_counter() - t0
    steps = [e.steps for e in runs]
    mean = float(np.mean(steps))
    optimum = _belief_optimum(task, worlds)
    row = {
        "task": name,
        "num_sims": sims,
        "episodes": episodes,
        "mean_crms": round(mean, 3),
        "success": round(float(np.mean([e.success for e in runs])), 4),
        "belief_policy_same_worlds": round(optimum, 3),
        "gap_to_belief_policy": round(mean / optimum - 1.0, 4),
        "seconds_per_decision": round(seconds / max(1, sum(steps)), 4),
        "belief_refills": policy.refills,
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
    a = p.parse_args()
    rows = [
        one(name, sims, a.episodes, a.particles)
        for name in (a.task or ["paper-box", "box-family"])
        for sims in (a.sims or [50, 200, 1000])
    ]
    print(json.dumps({"rows": rows}, indent=1))


if __name__ == "__main__":
    main()

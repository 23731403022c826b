"""pomdp_py's POUCT as an online peer, beside the belief-space optimum and the learners.

``crmgrasp.planners.pouct.POUCTPolicy`` plans each CRM with pomdp_py's POUCT over the task's own
simulator and start distribution (a particle belief filtered by the sensed observations). It
spends no task episode, but knows the model, as the belief-space optimum does. Protocol: per
task and simulation budget, EPISODES episodes from the first EPISODES of the checkpoint starts
of ``benchmarks/learner_seeds.py`` (``checkpoint_generators(0)``, the starts every learner's
greedy policy is scored on); the policy's generator is seeded with 1. Printed: CRMs per episode
and success, against the task's belief-space optimum (``reference_mean_steps``, on 4,000
starts), and the wall time per decision.

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

from crmgrasp.agents.training import checkpoint_generators
from crmgrasp.planners.pouct import POUCTPolicy, POUCTSettings
from crmgrasp.sim import run_episode
from crmgrasp.tasks import make_task


def one(name: str, sims: int, episodes: int, particles: int) -> dict:
    task = make_task(name)
    starts, _ = checkpoint_generators(0)
    policy = POUCTPolicy(task, np.random.default_rng(1), POUCTSettings(num_sims=sims, particles=particles))
    t0 = time.perf_counter()
    steps, success = [], []
    for _ in range(episodes):
        ep = run_episode(task, policy, starts)
        steps.append(ep.steps)
        success.append(ep.success)
    seconds = time.perf_counter() - t0
    mean = float(np.mean(steps))
    ref = task.reference_mean_steps
    row = {
        "task": name,
        "num_sims": sims,
        "episodes": episodes,
        "mean_crms": round(mean, 3),
        "success": round(float(np.mean(success)), 4),
        "belief_optimum": ref,
        "gap_to_optimum": round(mean / ref - 1.0, 4) if ref else None,
        "seconds_per_decision": round(seconds / max(1, sum(steps)), 4),
        "belief_refills": policy.refills,
    }
    print(row, file=sys.stderr)
    return row


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

"""Run-to-run spread of the deep-RL peer (needs the extra ``crmgrasp[deep]``).

Trains RecurrentPPO with the comparison's settings (``crmgrasp.experiments.compare.
DEFAULT_DEEP``, 120,000 steps) from seeds 0, 1, ..., evaluates each deterministic
policy on the 20,000 fresh starts ``crmgrasp compare --seed 0`` uses, and prints one
JSON object: per seed the mean CRMs, its 95% interval and the training time.

Usage: ``python benchmarks/deep_seeds.py [SEEDS]`` (default 3; about 70 s per seed on 2 cores).
``main``'s ``total_steps`` and ``starts`` shrink it (the tests' smoke run).
"""

import dataclasses
import json
import sys

import numpy as np

from crmgrasp import paper_box
from crmgrasp.agents.deep import evaluate_recurrent, train_recurrent_ppo
from crmgrasp.experiments.compare import DEFAULT_DEEP
from crmgrasp.planners.references import sample_starts


def main(seeds: int = 3, total_steps: int | None = None, starts: int = 20_000) -> dict:
    task = paper_box()
    fresh = sample_starts(task, starts, 1)
    config = DEFAULT_DEEP if total_steps is None else dataclasses.replace(DEFAULT_DEEP, total_steps=total_steps)
    out: dict = {"total_steps": config.total_steps, "starts": len(fresh), "seeds": {}}
    for seed in range(seeds):
        run = train_recurrent_ppo(task, seed, config)
        steps, ok = evaluate_recurrent(run.model, task, fresh, np.random.default_rng(1))
        half = 1.96 * steps.std(ddof=1) / np.sqrt(len(steps))
        out["seeds"][seed] = {
            "mean_crms": round(float(steps.mean()), 3),
            "ci95": [round(float(steps.mean() - half), 3), round(float(steps.mean() + half), 3)],
            "success_rate": round(float(ok.mean()), 4),
            "train_seconds": round(run.seconds, 1),
        }
    print(json.dumps(out, indent=2))
    return out


if __name__ == "__main__":
    main(*[int(a) for a in sys.argv[1:2]])

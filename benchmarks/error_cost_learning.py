"""Learning at a high error cost: the sample-efficient learner against the belief-space optimum of the cost.

An errored CRM (aperture or palm) costs ``1 + c`` (``Task.error_cost = c``). Per task and
cost, as ``crmgrasp reproduce cost-of-failure`` does: the belief-space optimal policy of the
cost over WORLDS sampled worlds (seed 0) and, per seed, one LEARNER agent (``pooled-vi``, k = 1,
or ``backoff-vi``, k = 6; the mirror quotient where the task declares one, no prior) that learns
for EPISODES task episodes with the cost; both run the same TEST held-out worlds (seed 1). Printed per task and cost:
the optimum's mean cost (CRMs plus ``c`` per error), success and errors per episode; per seed
the learned greedy policy's mean cost, its gap to the optimum's, success and errors; the seeds
within 15% of the optimum with at least 95% success (issue 29's target).

Usage: ``python benchmarks/error_cost_learning.py [--task notch-or-box --task box-family]
[--cost 30] [--episodes 3000] [--seeds 5] [--first 0] [--worlds 400] [--test 1000] [--learner backoff-vi]
[--param KEY=NUMBER ...] [--k K]`` (``--param``: a learner parameter, e.g. ``explore=1`` for ``backoff-vi``;
``--k``: the history order instead of [`ORDERS`][]'s). Prints one JSON object; progress on stderr.
About 5 min at the defaults on 2 cores.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
import time

from crmgrasp._validation import setting
from crmgrasp.agents.training import train_trials
from crmgrasp.experiments._episodes import episode_records, greedy_records
from crmgrasp.experiments.cost_of_failure import policy_rows
from crmgrasp.planners.references import BeliefPolicy, sample_starts
from crmgrasp.tasks import make_task

ORDERS = {"pooled-vi": 1, "backoff-vi": 6}
"""The history order each learner runs with."""


def one(
    name: str,
    cost: float,
    episodes: int,
    seeds: int,
    n_worlds: int,
    n_test: int,
    learner: str = "pooled-vi",
    extra: dict | None = None,
    first: int = 0,
    k: int | None = None,
) -> dict:
    task = dataclasses.replace(make_task(name), error_cost=float(cost))
    worlds, test = sample_starts(task, n_worlds, 0), sample_starts(task, n_test, 1)
    belief = BeliefPolicy(task, worlds)
    optimum = policy_rows(episode_records(task, lambda: belief, test, 0), cost)
    params = {**({"symmetric": True} if task.symmetry is not None else {}), **(extra or {})}
    rows = []
    k = ORDERS[learner] if k is None else k
    for seed in range(first, first + seeds):
        t0 = time.perf_counter()
        res = train_trials(task, learner, trials=1, episodes=episodes, seed=seed, k=k, eval_episodes=0, params=params)
        (records,) = greedy_records(task, res.agents, test, seed, k=k)
        got = policy_rows(records, cost)
        row = {
            "seed": seed,
            "mean_cost": round(got["mean_cost"], 3),
            "gap": round(got["mean_cost"] / optimum["mean_cost"] - 1.0, 4),
            "success": round(got["success_rate"], 4),
            "errors_per_episode": round(got["errors_per_episode"], 3),
            "seconds": round(time.perf_counter() - t0, 1),
        }
        rows.append(row)
        print(f"{name} c={cost:g} seed {seed}: {row}", file=sys.stderr)
    return {
        "task": name,
        "learner": learner,
        "k": k,
        "params": extra or {},
        "cost": cost,
        "optimum": {
            k: round(v, 4) for k, v in optimum.items() if k in ("mean_cost", "success_rate", "errors_per_episode")
        },
        "per_seed": rows,
        "seeds_within_15pct_and_95pct_success": sum(r["gap"] <= 0.15 and r["success"] >= 0.95 for r in rows),
    }


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--task", action="append", help="task (repeatable; default notch-or-box and box-family)")
    p.add_argument("--cost", action="append", type=float, help="error cost c (repeatable; default 30)")
    p.add_argument("--episodes", type=int, default=3000)
    p.add_argument("--seeds", type=int, default=5)
    p.add_argument("--first", type=int, default=0, help="first seed (default 0)")
    p.add_argument("--worlds", type=int, default=400)
    p.add_argument("--test", type=int, default=1000)
    p.add_argument("--learner", choices=tuple(ORDERS), default="pooled-vi")
    p.add_argument("--param", action="append", default=[], metavar="KEY=NUMBER|true|false", type=setting)
    p.add_argument("--k", type=int, default=None, help="the learner's history order (default: ORDERS)")
    a = p.parse_args()
    extra = dict(a.param)
    out = [
        one(name, cost, a.episodes, a.seeds, a.worlds, a.test, a.learner, extra, a.first, a.k)
        for name in (a.task or ["notch-or-box", "box-family"])
        for cost in (a.cost or [30.0])
    ]
    print(json.dumps({"episodes": a.episodes, "rows": out}, indent=1))


if __name__ == "__main__":
    main()

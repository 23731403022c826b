"""Where a learner's gap to the belief-space optimum is made: hand over between the two
policies after a number of CRMs.

For each task: W evaluation worlds and the belief-space optimal policy over them (or over
``--pool`` P worlds, the W first), as in ``benchmarks/family_learning.py``. For each seed, one
learner trains on EPISODES task episodes (no prior; on the mirror quotient where the task
declares one). Then, on the same worlds, noise-free:

* ``learner then optimum, t``: the learner's greedy policy chooses the first ``t`` CRMs and the
  optimum the rest;
* ``optimum then learner, t``: the other way round.

Both policies see every percept: the learner keeps its k-order history and the optimum its
belief, told which CRM was taken (``BeliefPolicy.tell(percept, action=...)``). With the world
among those the optimum plans over, its belief keeps the true world after any CRM. The gap
on the graspable worlds is reported as in ``family_learning.py`` (the learner alone: ``t`` =
the step limit), with the graspable worlds not grasped within the step limit. Reading: if
``learner then optimum, 1`` is near 0, the learner's first CRM is as good as the optimum's;
the rise of ``learner then optimum, t`` with ``t`` shows how much its first ``t`` choices
cost when the optimum finishes, and ``optimum then learner, t`` how much its choices from
CRM ``t + 1`` on cost after the optimum's start.

Usage: ``python benchmarks/handover.py [--task NAME ...] [--seeds 3] [--first 0] [--episodes
3000] [--worlds 300] [--pool P] [--learner backoff-vi] [--k 2] [--after 1,2,3,4,6]``. Prints
one JSON object; progress on stderr.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from crmgrasp._validation import CrmgraspError
from crmgrasp.agents.base import Agent
from crmgrasp.agents.training import AGENTS, encoder_for, train_trials
from crmgrasp.model.history import KOrderEncoder
from crmgrasp.planners.references import BeliefPolicy, sample_starts, ungraspable_fraction
from crmgrasp.sim import Percept, Policy, run_episode
from crmgrasp.tasks import Task, make_task


class Handover:
    """The learner's greedy choice for the first ``after`` CRMs and the optimum's after them
    (``learner_first``), or the other way round; both are told every percept."""

    def __init__(
        self,
        agent: Agent,
        encoder: KOrderEncoder,
        rng: np.random.Generator,
        optimum: BeliefPolicy,
        after: int,
        learner_first: bool,
    ) -> None:
        self.agent, self.encoder, self.rng, self.optimum = agent, encoder, rng, optimum
        self.after, self.learner_first = after, learner_first
        self._hist: tuple[int, ...] = ()
        self._n = self._a = 0

    def begin(self, first: Percept) -> None:
        self._hist = self.encoder.start(first.obs_index)
        self.agent.begin_episode()
        self.optimum.begin(first)
        self._n = 0

    def act(self) -> int:
        mine = self.agent.greedy(self.encoder.encode(self._hist), self.rng)  # drawn every step: same ties
        learner_acts = (self._n < self.after) == self.learner_first
        self._a = mine if learner_acts else self.optimum.act()  # the optimum plans only where it acts
        self._n += 1
        return self._a

    def tell(self, percept: Percept) -> None:
        self._hist = self.encoder.push(self._hist, self._a, percept.obs_index)
        self.optimum.tell(percept, action=self._a)


def _score(
    task: Task,
    make: Callable[[], Policy],
    worlds: Sequence[Any],
    graspable: np.ndarray,
    optimum: np.ndarray,
    seed: int,
) -> dict:
    """Graspable gap and graspable worlds not grasped of the policy ``make()`` on ``worlds``."""
    rng = np.random.default_rng(seed)
    eps = [run_episode(task, make(), rng, start=w) for w in worlds]
    steps = np.array([ep.steps for ep in eps], dtype=float)
    won = np.array([ep.success for ep in eps])
    gap = float(steps[graspable].mean() / optimum[graspable].mean() - 1.0)
    return {"gap_graspable": round(gap, 4), "lost": int((graspable & ~won).sum())}


def task_rows(
    name: str, learner: str, k: int, episodes: int, seeds: range, n_worlds: int, pool: int, after: tuple[int, ...]
) -> dict:
    """One task: every seed's learner, alone and handed over after each ``t`` in ``after``."""
    task = make_task(name)
    t0 = time.perf_counter()
    planned = sample_starts(task, max(pool, n_worlds), 10_000)
    worlds = planned[:n_worlds]
    graspable = np.array([ungraspable_fraction(task, [w]) == 0.0 for w in worlds])
    planner = BeliefPolicy(task, planned)
    optimum = np.array([run_episode(task, planner, np.random.default_rng(0), start=w).steps for w in worlds], float)
    seconds = time.perf_counter() - t0
    print(f"{name}: optimum over {len(planned)} worlds in {seconds:.0f} s", file=sys.stderr, flush=True)
    encoder = encoder_for(task, k)
    params = {"symmetric": task.symmetry is not None}
    limit = task.max_steps
    variants = [("learner alone", limit, True)]
    variants += [(f"learner then optimum, {t}", t, True) for t in after]
    variants += [(f"optimum then learner, {t}", t, False) for t in after]
    per: dict[str, list[dict]] = {label: [] for label, _, _ in variants}
    for seed in seeds:
        res = train_trials(task, learner, trials=1, episodes=episodes, seed=seed, k=k, eval_episodes=0, params=params)
        agent = res.agents[0]
        for label, t, first in variants:

            def make(t: int = t, first: bool = first, agent: Agent = agent, seed: int = seed) -> Handover:
                return Handover(agent, encoder, np.random.default_rng([seed, 0]), planner, t, first)

            per[label].append(_score(task, make, worlds, graspable, optimum, seed))
        print(f"{name}: seed {seed}: alone {per['learner alone'][-1]}", file=sys.stderr, flush=True)
    out: dict = {"worlds": n_worlds, "pool": len(planned), "graspable": int(graspable.sum())}
    out |= {"learner": learner, "k": k}
    for label, rows in per.items():
        out[label] = {
            "gap_graspable": [r["gap_graspable"] for r in rows],
            "median_gap_graspable": statistics.median(r["gap_graspable"] for r in rows),
            "lost": [r["lost"] for r in rows],
        }
    return out


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--task", action="append", dest="tasks")
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--first", type=int, default=0)
    ap.add_argument("--episodes", type=int, default=3000)
    ap.add_argument("--worlds", type=int, default=300)
    ap.add_argument("--pool", type=int, default=0, help="worlds the optimum plans over (default: --worlds)")
    ap.add_argument("--learner", default="backoff-vi")
    ap.add_argument("--k", type=int, default=2)
    ap.add_argument("--after", default="1,2,3,4,6", help="comma-separated CRM counts at which to hand over")
    a = ap.parse_args()
    try:
        after = tuple(int(v) for v in a.after.split(","))
    except ValueError:
        ap.error(f"--after takes comma-separated integers, got {a.after!r}")
    if any(t < 0 for t in after):
        ap.error(f"--after takes CRM counts >= 0, got {a.after!r}")
    for flag in ("seeds", "episodes", "worlds"):
        if getattr(a, flag) < 1:
            ap.error(f"--{flag} must be at least 1, got {getattr(a, flag)}")
    seeds = range(a.first, a.first + a.seeds)
    res = {"episodes": a.episodes, "seeds": [a.first, a.first + a.seeds - 1]}
    tasks = a.tasks or ["polygon-family", "u-handle"]
    if a.learner not in AGENTS:
        ap.error(f"unknown learner {a.learner!r}; known: {', '.join(AGENTS)}")
    try:
        for name in tasks:
            make_task(name)  # every name checked before the first long run
        for name in tasks:
            res[name] = task_rows(name, a.learner, a.k, a.episodes, seeds, a.worlds, a.pool, after)
    except CrmgraspError as exc:  # an unknown task or learner, a bad k: one line, exit 2
        ap.error(str(exc))
    print(json.dumps(res, indent=1))

"""Sample efficiency from scratch across seeds: crmgrasp's learners and the peers, on the
same checkpoint starts and the same episode streams.

Protocol: for each seed ``first .. first + SEEDS - 1``, TRIALS independent
agents (one by default) learn for EPISODES episodes of the task itself, k = 1 histories,
no prior; after each checkpoint (5, 10, 15, 20, 30, ... episodes) the greedy policy is
evaluated on the same 1,000 fixed starts (``checkpoint_generators(seed)``: the same for
every learner and every checkpoint) and averaged over the seed's trials. Per learner:

* ``to_5pct``: per seed, the first checkpoint from which the greedy policy stays within
  5% of the task's reference (the belief-space optimum: paper-box 1.66, box-family 1.75)
  at every later checkpoint (``None``: not by the budget);
* ``median_to_5pct`` (``None`` counted as beyond the budget), ``by_10``, ``by_20``,
  ``by_budget``: seeds whose ``to_5pct`` is at most 10, 20, the budget;
* ``within_at_10``, ``within_at_20``: seeds whose greedy policy is within 5% at that
  checkpoint (whether or not it stays there);
* ``mean_at``: the greedy CRMs per episode at each checkpoint, mean over seeds;
* ``training_curve_to_5pct``: per seed, the first episode after which the 10-episode
  moving average of the training curve (mean over the seed's trials) stays within 5%;
* ``seconds``: wall time of all its seeds.

Learners: ``pooled-vi`` (``--preset fastest``: k = 1, mirror quotient, a greedy policy that
never repeats a CRM that erred since the contacts last moved), the same greedy policy without
that rule, ``pooled-vi`` without the quotient (nor the rule), ``model-vi`` (mirror quotient),
Dyna-Q with value-iteration sweeps (with and without the quotient), and the peers without the
quotient, as a generic tabular learner sees the task: PSRL and UCBVI
(``crmgrasp.agents.peers``, written from their papers: rlberry 0.7.3 pins gymnasium < 0.30 and
ships neither), SARSA and Q-learning (k = 1, the paper's alpha 0.3, Q0 = 0, greedy; the
textbook updates MushroomRL implements: mushroom-rl 1.10.2 pins numpy 1.24.4 and cannot share
this environment; ``benchmarks/mushroom_peer.py`` runs MushroomRL's own in a venv of their own,
on this protocol).

Usage: ``python benchmarks/learner_seeds.py [--episodes 200] [--seeds 10] [--first 0]
[--trials 1] [--task paper-box --task box-family] [--only NAME ...]``. Prints one JSON
object; progress on stderr.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time

import numpy as np

from crmgrasp.agents.presets import PRESETS
from crmgrasp.agents.training import (
    DEFAULT_CHECKPOINTS,
    build_agent,
    checkpoint_generators,
    checkpoints_to_within,
    encoder_for,
    episodes_to_within,
    evaluate,
    train_trials,
)
from crmgrasp.tasks import make_task

LEARNERS: dict[str, tuple[str, dict]] = {
    "pooled-vi (fastest)": ("pooled-vi", {"symmetric": True, **dict(PRESETS["fastest"].params)}),
    "pooled-vi, no skip_errored": ("pooled-vi", {"symmetric": True}),
    "pooled-vi, no quotient": ("pooled-vi", {}),
    "model-vi": ("model-vi", {"symmetric": True}),
    "dyna-q sweeps": ("dyna-q", {"planning": "sweep", "n_planning": 50, "symmetric": True}),
    "dyna-q sweeps, no quotient": ("dyna-q", {"planning": "sweep", "n_planning": 50}),
    "psrl": ("psrl", {}),
    "ucbvi": ("ucbvi", {}),
    "sarsa": ("sarsa", {}),
    "q-learning": ("q", {}),
    "model-vi + prior (500 box-family episodes)": ("model-vi", {"symmetric": True, "prior_task": "box-family"}),
}
"""Label -> (agent, parameters); k = 1 for all. The last is not from scratch: a prior
learned in 500 episodes on box-family (each seed its own, ``prior_seed`` = the seed), on
paper-box only; its row adds ``within_at_0``, the seeds whose prior alone (0 task
episodes) is within 5%."""


def run_learner(task_name: str, agent: str, params: dict, episodes: int, seeds: range, trials: int) -> dict:
    """One learner on one task over the seeds (see the module docstring)."""
    task = make_task(task_name)
    ref = task.reference_mean_steps
    assert ref is not None, f"{task_name} has no reference"
    checks = tuple(c for c in DEFAULT_CHECKPOINTS if c <= episodes)
    t0 = time.perf_counter()
    to5, curves, at0, curve5 = [], [], [], []
    prior = "prior_task" in params
    for seed in seeds:
        if prior:
            params = {**params, "prior_seed": seed}
            agent_0 = build_agent(task, encoder_for(task, 1), agent, params)
            steps = evaluate(task, agent_0, encoder_for(task, 1), 1000, *checkpoint_generators(seed))[0]
            at0.append(float(steps.mean()))
        res = train_trials(
            task,
            agent,
            trials=trials,
            episodes=episodes,
            seed=seed,
            k=1,
            eval_episodes=0,
            params=params,
            checkpoints=checks,
            checkpoint_episodes=1000,
        )
        curve = res.checkpoint_steps.mean(axis=0)
        curve5.append(episodes_to_within(res.curve, ref))
        curves.append(curve)
        to5.append(checkpoints_to_within(res.checkpoints, curve, ref))
    bound = 1.05 * ref + 1e-12
    row = {} if not prior else {"within_at_0": sum(v <= bound for v in at0), "prior_episodes": 500}
    return {
        **row,
        **summary(to5, curves, checks, episodes, ref, time.perf_counter() - t0),
        "training_curve_to_5pct": curve5,
    }


def summary(to5: list, curves: list, checks: tuple[int, ...], episodes: int, ref: float, seconds: float) -> dict:
    """The columns of one learner over the seeds: ``to5`` the seeds' first checkpoints within 5%
    (None: not by ``episodes``), ``curves`` their greedy CRMs at each of ``checks`` (module
    docstring); ``benchmarks/mushroom_peer.py`` reports the same."""
    at, bound = np.array(curves), 1.05 * ref + 1e-12

    def within_at(c: int) -> int | None:
        return int((at[:, checks.index(c)] <= bound).sum()) if c in checks else None

    return {
        "to_5pct": to5,
        "median_to_5pct": statistics.median(episodes + 1 if v is None else v for v in to5),
        "by_10": sum(v is not None and v <= 10 for v in to5),
        "by_20": sum(v is not None and v <= 20 for v in to5),
        "by_budget": sum(v is not None for v in to5),
        "within_at_10": within_at(10),
        "within_at_20": within_at(20),
        "mean_at": {c: round(float(v), 3) for c, v in zip(checks, at.mean(axis=0), strict=True)},
        "seconds": round(seconds, 1),
    }


def main(
    episodes: int = 200,
    seeds: int = 10,
    first: int = 0,
    trials: int = 1,
    tasks: tuple[str, ...] = ("paper-box", "box-family"),
    only: tuple[str, ...] = (),
) -> dict:
    """Every learner (or those in ``only``) on every task; see the module docstring."""
    out: dict = {"episodes": episodes, "seeds": [first, first + seeds - 1], "trials_per_seed": trials}
    for task_name in tasks:
        out[task_name] = {}
        for label, (agent, params) in LEARNERS.items():
            if (only and label not in only) or ("prior_task" in params and task_name != "paper-box"):
                continue
            print(f"{task_name}: {label} ...", file=sys.stderr, flush=True)
            row = run_learner(task_name, agent, params, episodes, range(first, first + seeds), trials)
            out[task_name][label] = row
    return out


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--episodes", type=int, default=200)
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--first", type=int, default=0)
    ap.add_argument("--trials", type=int, default=1)
    ap.add_argument("--task", action="append", dest="tasks")
    ap.add_argument("--only", action="append", default=[], choices=tuple(LEARNERS))
    a = ap.parse_args()
    print(
        json.dumps(
            main(a.episodes, a.seeds, a.first, a.trials, tuple(a.tasks or ("paper-box", "box-family")), tuple(a.only)),
            indent=1,
        )
    )

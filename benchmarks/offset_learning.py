"""A learner on a grid of offsets with the continuous-offsets target's budget of 5,000 episodes.

``crmgrasp reproduce continuous-offsets`` learns from 2,000 episodes per trial. This script
reruns its learner (model-vi, k = 1, mirror quotient where declared, 5 trials) with the
issue's budget, 5,000 task episodes per trial, on the U handle (grid of 9 offsets per pair)
and cup-3d (3 x 3 per pair), and runs each greedy policy from the optimum's own 100 starts.
``--learner backoff-vi`` runs the whole-history learner instead (k = 6, mirror quotient
where declared, the same trials, seed and starts); ``--learner refine-vi`` the learner that
chooses its offsets (k = 1, mirror quotient where declared), on the grid of 33 offsets per pair
from its five (U handle) and of 9 x 9 from its 3 x 3 (cup-3d), its optimum being the grid's.

Prints one JSON object: per task, CRMs per episode per trial, their median, the grid's
belief-space optimum on those starts and the median's gap to it. Usage:
``python benchmarks/offset_learning.py [--episodes 5000] [--learner model-vi|backoff-vi|refine-vi]
[--task u-handle|cup-3d ...] [--grid N] [--param KEY=NUMBER ...] [--heldout N] [--k K]`` (model-vi about 8
minutes on 2 cores; ``--grid``: every task's grid, offsets per coordinate; ``--param``: a learner
parameter, e.g. ``start_level=3`` or ``refine_after=1`` for refine-vi; ``--heldout N``: also
score each greedy policy on N fresh worlds, those of ``reference_bias.py --heldout N``; ``--k``:
the learner's history order instead of [`ORDERS`][]'s; ``--grid 0``: the task's own hand-picked
CRMs instead of a grid).

With ``--counts`` (``backoff-vi`` only) each trial also reports how much of its own data its
greedy choices rest on: at every decision of its greedy policy on the optimum's starts, the
outcomes the long level has counted for the chosen CRM in that history (0 where the history
has no long node, so that the CRM's model is the k = 1 level's alone). Per trial: the
decisions, the median of those counts and the share of decisions below 5.
"""

from __future__ import annotations

import argparse
import json
from typing import Any

import numpy as np

from crmgrasp._validation import setting
from crmgrasp.agents.training import train_trials
from crmgrasp.experiments._episodes import greedy_records
from crmgrasp.experiments.continuous_offsets import ContinuousOffsetsConfig
from crmgrasp.planners.references import belief_optimum, sample_starts
from crmgrasp.tasks import Task, make_task
from crmgrasp.tasks.offsets import offset_grid

GRIDS = {"u-handle": 9, "cup-3d": 3}
ORDERS = {"model-vi": 1, "backoff-vi": 6, "refine-vi": 1}
"""The learners this script runs, with their history order."""
REFINE = {"u-handle": (33, 2), "cup-3d": (9, 1)}
"""refine-vi's grid and start level per task."""


class OwnCounts:
    """A trained ``backoff-vi`` agent (on a mirror quotient or not) whose greedy choices record
    the outcomes its long level has counted for the chosen CRM in the history (``seen``)."""

    def __init__(self, agent: Any, task: Task) -> None:
        self.agent, self.seen = agent, []
        self.inner = getattr(agent, "inner", agent)
        self.amap = list(task.symmetry.actions) if task.symmetry is not None else []
        self.skip_errored = bool(getattr(agent, "skip_errored", False))
        if not hasattr(self.inner, "counts"):
            raise SystemExit(f"--counts needs backoff-vi, got {self.inner.name}")

    def begin_episode(self) -> None:
        self.agent.begin_episode()

    def greedy(self, state: int, rng: np.random.Generator, banned: Any = ()) -> int:
        a = self.agent.greedy(state, rng, banned) if banned else self.agent.greedy(state, rng)
        c, b = state, a
        if self.inner is not self.agent:  # the representative's frame: the lower of the code and its mirror's
            m = self.agent.mirror(state)
            c, b = (m, self.amap[a]) if m < state else (state, a)
        self.seen.append(sum(self.inner.counts.get((c, b), {}).values()))
        return a


def per_trial(
    task: Task,
    learner: str,
    cfg: ContinuousOffsetsConfig,
    params: dict[str, Any],
    heldout: int = 0,
    k: int | None = None,
    counts: bool = False,
) -> tuple[list[float], list[float], list[dict[str, float]]]:
    """CRMs per episode of each trial's greedy policy on the optimum's starts, on ``heldout``
    fresh worlds (seed 20,000: ``reference_bias.py``'s held-out worlds; none for 0), and with
    ``counts`` each trial's own counts behind its choices on the starts (module docstring)."""
    k = ORDERS[learner] if k is None else k
    params = {"symmetric": task.symmetry is not None, **params}
    res = train_trials(
        task, learner, trials=cfg.trials, episodes=cfg.episodes, seed=cfg.seed, k=k, eval_episodes=0, params=params
    )
    agents = [OwnCounts(a, task) for a in res.agents] if counts else res.agents

    def means(worlds: list) -> list[float]:
        records = greedy_records(task, agents, worlds, cfg.seed, k=k) if worlds else []
        return [float(np.mean([len(r.actions) for r in trial])) for trial in records]

    on_starts = means(sample_starts(task, cfg.starts, cfg.seed))
    own = []
    for a in agents if counts else []:  # the choices on the optimum's starts alone
        v = np.array(a.seen)  # type: ignore[union-attr]
        own.append({"decisions": len(v), "median": float(np.median(v)), "below_5": round(float(np.mean(v < 5)), 4)})
    return on_starts, means(sample_starts(task, heldout, 20_000) if heldout else []), own


def main(
    episodes: int = 5000,
    trials: int = 5,
    starts: int = 100,
    learner: str = "model-vi",
    refine: dict[str, tuple[int, int]] | None = None,
    tasks: tuple[str, ...] = tuple(GRIDS),
    grid: int | None = None,
    params: dict[str, Any] | None = None,
    heldout: int = 0,
    k: int | None = None,
    counts: bool = False,
) -> dict[str, Any]:
    """Per task: the learner's CRMs per episode per trial, their median, the optimum and the
    gap. ``refine``: refine-vi's grid and start level per task (default [`REFINE`][]);
    ``grid``: every task's grid instead (0: the task's own CRMs); ``params``: the learner's
    parameters (refine-vi's ``start_level`` overrides ``refine``'s); ``heldout``: also each
    greedy policy on that many fresh worlds; ``k``: the history order instead of [`ORDERS`][]'s;
    ``counts``: the own counts behind the greedy choices (module docstring)."""
    refine = REFINE if refine is None else refine
    cfg = ContinuousOffsetsConfig(trials=trials, episodes=episodes, starts=starts)
    out: dict[str, Any] = {
        "episodes": episodes,
        "trials": trials,
        "starts": starts,
        "learner": learner,
        "params": params or {},
        "k": ORDERS[learner] if k is None else k,
    }
    for name in tasks:
        mine = dict(params or {})
        if learner == "refine-vi":
            mine.setdefault("start_level", refine[name][1])
        n = grid if grid is not None else (refine[name][0] if learner == "refine-vi" else GRIDS[name])
        task = offset_grid(make_task(name), n) if n else make_task(name)
        optimum = belief_optimum(task, sample_starts(task, starts, cfg.seed))
        values, fresh, own = per_trial(task, learner, cfg, mine, heldout, k, counts)
        median = float(np.median(values))
        out[task.name] = {
            "per_trial": values,
            "median": median,
            "optimum": optimum,
            "gap": round(median / optimum - 1.0, 4),
        }
        if heldout:
            out[task.name].update(heldout=heldout, heldout_per_trial=fresh, heldout_median=float(np.median(fresh)))
        if counts:
            out[task.name]["own_counts"] = own
    return out


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--episodes", type=int, default=5000)
    ap.add_argument("--learner", choices=tuple(ORDERS), default="model-vi")
    ap.add_argument("--task", action="append", dest="tasks", choices=tuple(GRIDS))
    ap.add_argument("--grid", type=int, default=None, help="offsets per coordinate and pair, every task (0: own CRMs)")
    ap.add_argument("--param", action="append", default=[], metavar="KEY=NUMBER|true|false", type=setting)
    ap.add_argument("--heldout", type=int, default=0, help="also score each policy on this many fresh worlds")
    ap.add_argument("--k", type=int, default=None, help="the learner's history order (default: ORDERS)")
    ap.add_argument("--counts", action="store_true", help="the own counts behind each greedy choice (backoff-vi)")
    a = ap.parse_args()
    if a.grid is not None and a.grid < 0:
        ap.error(f"--grid must be at least 0, got {a.grid}")
    extra = dict(a.param)
    tasks = tuple(a.tasks or GRIDS)
    res = main(
        a.episodes, learner=a.learner, tasks=tasks, grid=a.grid, params=extra, heldout=a.heldout, k=a.k, counts=a.counts
    )
    print(json.dumps(res, indent=2))

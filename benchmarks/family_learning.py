"""Learning from scratch on object families and in 3-D: the gap to the belief-space
optimum on all worlds and on the graspable worlds only.

For each task: W evaluation worlds are sampled once (``sample_starts(task, W, 10_000)``);
a world is graspable when some sequence of at most ``max_steps`` CRMs grasps it knowing
the true configuration (``graspable_starts``). The belief-space optimal policy over
those worlds (``BeliefPolicy``) runs on each: its mean is the optimum. For each seed, one
agent per learner trains for EPISODES episodes of the task itself (k from [`ORDERS`][], on the mirror
quotient where the task declares one, no prior), then its greedy policy runs on the same
worlds. The gap is ``mean(learner) / mean(optimum) - 1``, over all worlds and over the
graspable ones (an ungraspable world costs the step limit to both, which dilutes the
gap). Per learner and task: the gaps per seed, their median, the seeds within 10% on the
graspable worlds, success, the graspable worlds the policy does not grasp within the step
limit (``fails_graspable``) and the part of the graspable gap they make
(``gap_from_fails``: their CRMs beyond the optimum's over the optimum's total), the CRMs that
erred on the graspable worlds (``errored_graspable``; the optimum's: ``optimum_errored_graspable``),
and the wall time of training.

With ``--pool P`` (P > W) the optimum's policy plans over P worlds, the W evaluation worlds
first, and is scored on the W. The optimum over sampled worlds is optimistic, less so the
more worlds it has (``benchmarks/reference_bias.py``): with a larger pool the gap comes
closer to the gap to the family's own optimum, of which it stays an upper bound in
expectation. A learner may then come out below the optimum on the W worlds.

With ``--planner N`` a realizable reference runs too: the belief-space policy planned over N
worlds drawn apart from the evaluation worlds (seed 30,000), with ``fallback="nearest"`` (where
no planned world explains the history, the worlds that explain all but the fewest
observations; ``--fallback restart``: the planned worlds with the current observation, which
is much quicker over tens of thousands of worlds), on the same W worlds. It knows the family
(it plans on simulated worlds of it) but not the worlds it runs on, so its cost is that of a
policy, at least the family's optimum in expectation, where the optimum above is at most that.
Per learner the graspable gap to this planner is reported as well
(``gap_to_planner_graspable``): below zero, the learner from episodes does better on these
worlds than a planner given the family.

Usage: ``python benchmarks/family_learning.py [--episodes 3000] [--seeds 10] [--first 0]
[--worlds 300] [--pool P] [--planner N] [--task NAME ...] [--learner NAME ...] [--param KEY=NUMBER ...]
[--k K] [--fallback nearest|restart] [--mirror]`` (``--param``:
a learner parameter, e.g. ``explore=1`` for ``backoff-vi``, given to every learner run; ``--k``: every
learner's history order instead of [`ORDERS`][]; ``--mirror``: the learners on the mirror quotient of
a spatial task that declares none, ``crmgrasp.tasks.spatial.mirrored``).
Prints one JSON object; progress on stderr.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from typing import Any

import numpy as np

from crmgrasp._validation import CrmgraspError, setting
from crmgrasp.agents.training import train_trials
from crmgrasp.experiments._episodes import episode_records, greedy_records
from crmgrasp.planners.references import FALLBACKS, BeliefPolicy, graspable_starts, sample_starts
from crmgrasp.tasks import make_task
from crmgrasp.tasks.spatial import MIRROR_INVARIANT, mirrored

TASKS = (
    "box-family",
    "cup-family",
    "polygon-family",
    "u-handle",
    "l-shape",
    "t-shape",
    "star",
    "mixed",
    "box-3d",
    "cup-3d",
)
"""The two-finger families that two fingers can grasp, and the spatial tasks; not
``triangles`` and ``odd-polygons`` (no two-finger grasp at friction 0.15 on any world:
every learner and the optimum spend the step limit) nor, by default, the three-finger twins
(``crmgrasp reproduce third-contact``)."""
THREE_FINGERS = ("triangles-3f", "odd-polygons-3f", "box-family-3f", "cup-family-3f", "box-3d-3f", "cup-3d-3f")
"""Three-finger twins a run may name with ``--task`` (not run by default)."""
MESHES = ("open-cup-3d",)
"""Tasks on meshes a run may name with ``--task`` (not run by default: added after the first table)."""
LEARNERS = ("backoff-vi", "pooled-vi", "model-vi")
ORDERS = {"backoff-vi": 2}
"""History order per learner (1 where not listed): ``backoff-vi`` runs with k = 2, as ``--preset
families`` does (docs/results.md compares k = 6, ``--k 6``)."""


def _steps(records: list) -> np.ndarray:
    return np.array([len(r.actions) for r in records], dtype=float)


def _errored(records: list) -> np.ndarray:
    return np.array([sum(r.errors) for r in records], dtype=float)


def _optimum(task: Any, planned: list, worlds: list) -> tuple[np.ndarray, np.ndarray]:
    """CRMs and errored CRMs per world of the belief-space optimal policy over ``planned``: one
    planner for every world (its memo is shared), freed on return, before ``--planner`` builds
    its own (the memo is a run's largest object)."""
    planner = BeliefPolicy(task, planned)
    records = episode_records(task, lambda: planner, worlds, 0)
    return _steps(records), _errored(records)


def planner_row(
    task: Any, n: int, worlds: list, graspable: np.ndarray, optimum: np.ndarray, fallback: str = "nearest"
) -> tuple[dict, np.ndarray]:
    """The realizable reference of ``--planner n`` (module docstring): its summary and its
    CRMs per evaluation world."""
    t0 = time.perf_counter()
    planner = BeliefPolicy(task, sample_starts(task, n, 30_000), fallback=fallback)
    records = episode_records(task, lambda: planner, worlds, 0)
    steps, won = _steps(records), np.array([r.success for r in records])
    row = {
        "planned_worlds": n,
        "fallback": fallback,
        "mean": round(float(steps.mean()), 4),
        "mean_graspable": round(float(steps[graspable].mean()), 4),
        "over_optimum_graspable": round(float(steps[graspable].mean() / optimum[graspable].mean() - 1.0), 4),
        "fails_graspable": int((graspable & ~won).sum()),
        "seconds": round(time.perf_counter() - t0, 1),
    }
    print(
        f"{task.name}: planner over {n} other worlds: graspable {row['mean_graspable']} ({row['seconds']:.0f} s)",
        file=sys.stderr,
    )
    return row, steps


def task_row(
    name: str,
    learners: tuple[str, ...],
    episodes: int,
    seeds: range,
    n_worlds: int,
    extra: dict | None = None,
    pool: int = 0,
    k: int | None = None,
    n_planner: int = 0,
    fallback: str = "nearest",
    mirror: bool = False,
) -> dict:
    """One task: the optimum, then every learner over the seeds (see the module docstring);
    ``mirror``: the task's mirror symmetry declared ([`crmgrasp.tasks.spatial.mirrored`][])."""
    task = mirrored(make_task(name)) if mirror else make_task(name)
    t_task = time.perf_counter()
    planned = sample_starts(task, max(pool, n_worlds), 10_000)  # the evaluation worlds first
    worlds = planned[:n_worlds]
    graspable = graspable_starts(task, worlds)
    optimum, optimum_errored = _optimum(task, planned, worlds)
    print(
        f"{name}: optimum over {len(planned)} worlds planned and run in {time.perf_counter() - t_task:.0f} s",
        file=sys.stderr,
        flush=True,
    )
    row: dict = {
        "worlds": n_worlds,
        "pool": len(planned),
        "graspable": int(graspable.sum()),
        "optimum": round(float(optimum.mean()), 4),
        "optimum_graspable": round(float(optimum[graspable].mean()), 4),
        "optimum_errored_graspable": int(optimum_errored[graspable].sum()),
    }
    reference = None
    if n_planner:
        row["planner"], reference = planner_row(task, n_planner, worlds, graspable, optimum, fallback)
    params = {"symmetric": task.symmetry is not None, **(extra or {})}
    for agent in learners:
        order = ORDERS.get(agent, 1) if k is None else k
        gaps, gaps_g, success, fails, from_fails, errored, seconds = [], [], [], [], [], [], 0.0
        to_planner: list[float] = []
        for seed in seeds:
            t0 = time.perf_counter()
            res = train_trials(
                task, agent, trials=1, episodes=episodes, seed=seed, k=order, eval_episodes=0, params=params
            )
            seconds += time.perf_counter() - t0
            records = greedy_records(task, res.agents, worlds, seed, k=order)[0]
            steps = _steps(records)
            gaps.append(round(float(steps.mean() / optimum.mean() - 1.0), 4))
            gaps_g.append(round(float(steps[graspable].mean() / optimum[graspable].mean() - 1.0), 4))
            won = np.array([r.success for r in records])
            success.append(float(won.mean()))
            lost = graspable & ~won  # graspable worlds the policy never grasps (it runs to the step limit)
            fails.append(int(lost.sum()))
            from_fails.append(round(float((steps[lost] - optimum[lost]).sum() / optimum[graspable].sum()), 4))
            errored.append(int(_errored(records)[graspable].sum()))
            if reference is not None:
                to_planner.append(round(float(steps[graspable].mean() / reference[graspable].mean() - 1.0), 4))
            print(
                f"{name}: {agent} seed {seed}: graspable gap {gaps_g[-1]:.1%}, {fails[-1]} graspable worlds "
                f"not grasped ({seconds:.0f} s of training so far)",
                file=sys.stderr,
                flush=True,
            )
        row[agent] = {
            "k": order,
            "gap": gaps,
            "gap_graspable": gaps_g,
            "median_gap": statistics.median(gaps),
            "median_gap_graspable": statistics.median(gaps_g),
            "seeds_within_10pct_graspable": sum(g <= 0.10 for g in gaps_g),
            "success": round(float(np.mean(success)), 4),
            "fails_graspable": fails,
            "gap_from_fails": from_fails,
            "errored_graspable": errored,
            "train_seconds": round(seconds, 1),
        }
        if reference is not None:
            row[agent]["gap_to_planner_graspable"] = to_planner
            row[agent]["median_gap_to_planner_graspable"] = statistics.median(to_planner)
        print(f"{name}: {agent}: median gap {row[agent]['median_gap_graspable']:.1%} (graspable)", file=sys.stderr)
    return row


def main(
    episodes: int = 3000,
    seeds: int = 10,
    first: int = 0,
    n_worlds: int = 300,
    tasks: tuple[str, ...] = TASKS,
    learners: tuple[str, ...] = LEARNERS,
    extra: dict | None = None,
    pool: int = 0,
    k: int | None = None,
    n_planner: int = 0,
    fallback: str = "nearest",
    mirror: bool = False,
) -> dict:
    """Every task and learner; see the module docstring."""
    out: dict = {"episodes": episodes, "seeds": [first, first + seeds - 1], "worlds": n_worlds, "params": extra or {}}
    if k is not None:
        out["k"] = k
    if mirror:
        out["mirror"] = True
    for name in tasks:
        print(f"{name} ...", file=sys.stderr, flush=True)
        seeds_run = range(first, first + seeds)
        out[name] = task_row(name, learners, episodes, seeds_run, n_worlds, extra, pool, k, n_planner, fallback, mirror)
    return out


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--episodes", type=int, default=3000)
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--first", type=int, default=0)
    ap.add_argument("--worlds", type=int, default=300)
    ap.add_argument("--pool", type=int, default=0, help="worlds the optimum plans over (default: --worlds)")
    ap.add_argument("--task", action="append", dest="tasks", choices=TASKS + THREE_FINGERS + MESHES)
    ap.add_argument("--learner", action="append", dest="learners")
    ap.add_argument("--param", action="append", default=[], metavar="KEY=NUMBER|true|false", type=setting)
    ap.add_argument("--k", type=int, default=None, help="every learner's history order (default: ORDERS)")
    ap.add_argument("--planner", type=int, default=0, help="worlds of a realizable planner's reference (0: none)")
    ap.add_argument("--fallback", choices=FALLBACKS, default="nearest", help="the planner's belief when it empties")
    ap.add_argument(
        "--mirror", action="store_true", help=f"declare the mirror symmetry on {', '.join(MIRROR_INVARIANT)}"
    )
    a = ap.parse_args()
    if a.planner < 0:
        ap.error(f"--planner must be >= 0, got {a.planner}")
    if a.mirror:
        try:
            for name in a.tasks or TASKS:
                mirrored(make_task(name))
        except CrmgraspError as exc:
            ap.error(str(exc))
    extra = dict(a.param)
    res = main(
        a.episodes,
        a.seeds,
        a.first,
        a.worlds,
        tuple(a.tasks or TASKS),
        tuple(a.learners or LEARNERS),
        extra,
        a.pool,
        a.k,
        a.planner,
        a.fallback,
        a.mirror,
    )
    print(json.dumps(res, indent=1))

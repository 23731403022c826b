"""Cost of failure: the paper's Discussion prediction, tested.

The paper predicts: if one CRM sequence grasps most instances and failure is cheap,
the agent tries it first everywhere and falls back when it fails; if failures are
expensive, it first takes steps to tell the situations apart. Here an errored CRM
(aperture or palm) costs ``1 + c`` instead of 1 ([`crmgrasp.tasks.Task.error_cost`][]),
for ``c`` in [`COSTS`][], and for each ``c`` two policies are measured on the same
held-out worlds: the exact belief-space optimum of the cost (over sampled worlds,
[`BeliefPolicy`][crmgrasp.planners.references.BeliefPolicy]) and a learner's greedy policy.

Two tasks: ``notch-or-box``, designed so that the prediction can show (two objects
alike at the touched corner, a CRM that grasps the common one and errs on the rare
one, and an error-free slide whose outcome tells them apart), and ``box-family``
(where no error-free CRM tells the situations apart).

**Classification of an episode** by its first CRM ([`classify`][]):

* ``try-first``: the first CRM grasps or ends in an error: an attempt, which
  either works or fails and is fallen back from;
* ``sense-first``: the first CRM neither grasps nor errors, *and* it is a sensing
  move: among the episodes with the same first observation and first CRM, the
  policy's second CRM differs between outcomes (the most common second CRM after
  one outcome is not the one after another), so the CRM was taken to tell situations
  apart;
* ``other``: the first CRM neither grasps nor errors and what follows does not depend
  on its outcome (a fixed preparatory move).
"""

from __future__ import annotations

import dataclasses
from collections import Counter, defaultdict
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from crmgrasp._io import write_csv, write_json
from crmgrasp._progress import Progress
from crmgrasp._validation import CrmgraspError
from crmgrasp.experiments._episodes import (
    MODEL_VI_LABEL,
    EpisodeRecord,
    episode_records,
    greedy_records,
    train_model_vi,
)
from crmgrasp.experiments.configs import CheckedConfig, checked_config
from crmgrasp.planners.references import BeliefPolicy, sample_starts
from crmgrasp.sim import Policy
from crmgrasp.tasks import Task, make_task

__all__ = ["COSTS", "EpisodeRecord", "episode_records", "classify", "CostConfig", "cost_of_failure", "policy_rows"]

COSTS = (0.0, 1.0, 3.0, 10.0, 30.0)
"""The extra costs of an errored CRM that the experiment sweeps (reward units)."""

KINDS = ("try-first", "sense-first", "other")


def _sensing_moves(records: Sequence[EpisodeRecord]) -> set[tuple[int, int]]:
    """``(first observation, first CRM)`` pairs whose clean outcomes (no grasp, no
    error) lead to different most-common second CRMs."""
    seconds: dict[tuple[int, int], dict[int, Counter[int]]] = defaultdict(lambda: defaultdict(Counter))
    for r in records:
        if len(r.actions) >= 2 and not r.errors[0]:
            seconds[(r.first_obs, r.actions[0])][r.observations[0]][r.actions[1]] += 1
    out = set()
    for key, by_outcome in seconds.items():
        modal = {counts.most_common(1)[0][0] for counts in by_outcome.values()}
        if len(modal) >= 2:
            out.add(key)
    return out


def classify(records: Sequence[EpisodeRecord]) -> list[str]:
    """The kind of each episode (module docstring): ``try-first``, ``sense-first`` or
    ``other``. Sensing is judged over all of ``records`` (one policy's episodes)."""
    sensing = _sensing_moves(records)
    kinds = []
    for r in records:
        grasped_at_once = r.success and len(r.actions) == 1
        if grasped_at_once or r.errors[0]:
            kinds.append("try-first")
        elif (r.first_obs, r.actions[0]) in sensing:
            kinds.append("sense-first")
        else:
            kinds.append("other")
    return kinds


def policy_rows(records: Sequence[EpisodeRecord], cost: float) -> dict[str, float]:
    """Mean CRMs, errors per episode, mean cost, success rate and the share of each kind."""
    kinds = Counter(classify(records))
    n = len(records)
    crms = np.array([len(r.actions) for r in records], dtype=float)
    errors = np.array([sum(r.errors) for r in records], dtype=float)
    return {
        "cost": cost,
        "mean_crms": float(crms.mean()),
        "errors_per_episode": float(errors.mean()),
        "mean_cost": float((crms + cost * errors).mean()),
        "success_rate": float(np.mean([r.success for r in records])),
        "sense_first_fraction": kinds["sense-first"] / n,
        "try_first_fraction": kinds["try-first"] / n,
        "other_fraction": kinds["other"] / n,
    }


@dataclass(frozen=True)
class CostConfig(CheckedConfig):
    """Settings: the tasks (the first is the summary's headline), the costs, the sampled
    worlds of the belief-space optimum, the held-out worlds both policies run on, and the
    learner's budget (model-vi, k = 1, mirror quotient where the task declares one)."""

    tasks: tuple[str, ...] = ("notch-or-box", "box-family")
    costs: tuple[float, ...] = COSTS
    worlds: int = 400
    test_worlds: int = 1000
    trials: int = 10
    episodes: int = 400
    seed: int = 0

    @classmethod
    def quick(cls, seed: int = 0) -> CostConfig:
        """A small budget for smoke runs (about 10 s)."""
        return cls(worlds=120, test_worlds=200, trials=3, episodes=150, seed=seed)


def cost_of_failure(
    out_dir: str | Path, cfg: CostConfig = CostConfig(), progress: Progress | None = None
) -> dict[str, Any]:
    """Run the experiment on each task of ``cfg``; write ``cost_of_failure.csv``,
    ``cost_of_failure.png`` and ``summary.json`` to ``out_dir``; return the summary:
    per task (``tasks``) ``rows`` (the learner's), ``optimal_rows`` (the belief-space
    optimum's), ``switch`` (the optimum's errors per episode fall and its sense-first
    share rises from the lowest to the highest cost), ``errors_fall`` and
    ``prepare_first_rises`` (the share of ``other`` episodes); the first task's
    ``rows``, ``optimal_rows`` and ``switch`` also at the top level."""
    cfg = checked_config(cfg, CostConfig)
    if not cfg.tasks:
        raise CrmgraspError("cost of failure needs at least one task")
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    stage = progress.stage("cost of failure", len(cfg.tasks) * len(cfg.costs), "costs") if progress else None
    per_task = {name: _one_task(make_task(name), cfg, stage) for name in cfg.tasks}
    if stage is not None:
        stage.end()
    head = per_task[cfg.tasks[0]]
    summary = {
        "task": cfg.tasks[0],
        "budget": f"{cfg.trials} trials x {cfg.episodes} episodes; optimum over {cfg.worlds} worlds; "
        f"{cfg.test_worlds} held-out worlds; seed {cfg.seed}",
        "rows": head["rows"],
        "optimal_rows": head["optimal_rows"],
        "switch": head["switch"],
        "tasks": per_task,
    }
    fields = ["task", "policy", *head["rows"][0]]
    table = [
        {"task": name, "policy": who, **r}
        for name, t in per_task.items()
        for who, key in (("learned", "rows"), ("belief-optimal", "optimal_rows"))
        for r in t[key]
    ]
    write_csv(out / "cost_of_failure.csv", fields, [[row[f] for f in fields] for row in table])
    write_json(out / "summary.json", summary)
    _figure(out / "cost_of_failure.png", summary)
    return summary


def _always(policy: Policy) -> Callable[[], Policy]:
    """A factory that returns ``policy`` itself every time (it restarts at each ``begin``)."""
    return lambda: policy


def _one_task(base: Task, cfg: CostConfig, stage: Any) -> dict[str, Any]:
    """The optimum's and the learner's rows on one task, and what changed with the cost."""
    optimal, learned = [], []
    for c in cfg.costs:
        task = dataclasses.replace(base, error_cost=float(c))
        worlds, test = sample_starts(task, cfg.worlds, cfg.seed), sample_starts(task, cfg.test_worlds, cfg.seed + 1)
        belief = BeliefPolicy(task, worlds)  # one solver for every episode: it restarts its belief at each begin
        optimal.append(policy_rows(episode_records(task, _always(belief), test, cfg.seed), c))
        learned.append(policy_rows(_learned_records(task, test, cfg), c))
        if stage is not None:
            stage.advance(1)
    first, last = optimal[0], optimal[-1]
    errors_fall = last["errors_per_episode"] < first["errors_per_episode"]
    return {
        "learner": MODEL_VI_LABEL if base.symmetry is not None else "model-vi k=1",
        "rows": learned,
        "optimal_rows": optimal,
        "errors_fall": bool(errors_fall),
        "switch": bool(errors_fall and last["sense_first_fraction"] > first["sense_first_fraction"]),
        "prepare_first_rises": bool(last["other_fraction"] > first["other_fraction"]),
    }


def _learned_records(task: Task, test: Sequence[Any], cfg: CostConfig) -> list[EpisodeRecord]:
    agents = train_model_vi(task, cfg.trials, cfg.episodes, cfg.seed)
    per_agent = greedy_records(task, agents, test, cfg.seed, ties=np.random.default_rng)
    return [r for records in per_agent for r in records]


def _panels(axes: Any, t: dict[str, Any], name: str) -> None:
    """Errors, first-CRM kinds and CRMs per episode against the cost, on one task."""
    costs = [r["cost"] for r in t["rows"]]
    x = np.arange(len(costs))
    for rows, style, who in ((t["optimal_rows"], "-", "optimum"), (t["rows"], "--", "learned")):
        axes[0].plot(x, [r["errors_per_episode"] for r in rows], "o" + style, color="black", label=who)
        axes[2].plot(x, [r["mean_crms"] for r in rows], "o" + style, color="black", label=who)
        for key, color, kind in (
            ("try_first_fraction", "tab:red", "try first"),
            ("sense_first_fraction", "tab:green", "sense first"),
            ("other_fraction", "tab:blue", "prepare first"),
        ):
            axes[1].plot(x, [r[key] for r in rows], "o" + style, color=color, label=f"{kind} ({who})")
    titles = ("errored CRMs per episode", "share of episodes by first CRM", "CRMs per episode")
    for ax, label in zip(axes, titles, strict=True):
        ax.set_xticks(x, [f"{c:g}" for c in costs])
        ax.set_xlabel("extra cost c of an errored CRM")
        ax.set_title(f"{name}: {label}", fontsize=9)
        ax.grid(alpha=0.3)
    axes[1].set_ylim(-0.05, 1.05)
    lo = min(r["mean_crms"] for r in t["rows"] + t["optimal_rows"])
    axes[2].set_ylim(lo - 0.2, lo + 1.2)
    axes[1].legend(fontsize=7, ncols=2)
    axes[0].legend(fontsize=8)


def _figure(path: Path, s: dict[str, Any]) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from crmgrasp._io import save_figure

    names = list(s["tasks"])
    fig, grid = plt.subplots(len(names), 3, figsize=(12, 3.4 * len(names)), squeeze=False)
    for axes, name in zip(grid, names, strict=True):
        _panels(axes, s["tasks"][name], name)
    fig.suptitle(f"Cost of failure ({s['budget']})", fontsize=9)
    fig.tight_layout()
    save_figure(fig, path)
    plt.close(fig)

"""Generalization: one policy for a family of objects, tested where it was not trained.

For each family task, a learner (``model-vi``, k = 1, on the mirror quotient) trains on
a finite set of ``train_objects`` objects drawn from the family (each episode picks
one of them uniformly, with a fresh start), then its greedy policy runs on:

* the training objects, fresh starts: ``learner_mean_crms`` (in distribution);
* ``heldout`` new objects from the same family: ``heldout_mean_crms``;
* objects with sizes outside the training ranges ([`OUT_OF_RANGE`][]):
  ``out_of_range_mean_crms``;

beside the family's references on the held-out worlds (``belief_optimum``,
``clairvoyant_bound``), a policy trained on one object alone and run on that object
(``per_instance_mean_crms``, against the family policy on the same object,
``family_policy_on_instance_mean_crms``) and, where the CRMs and bins agree, the
paper-box policy applied unchanged (``paper_box_policy_mean_crms``), and the
belief-space planner's k = 1 policy ([`korder_search`][crmgrasp.planners.korder.korder_search] on
``planner_worlds`` worlds of the whole family) on the same held-out worlds
(``planner_heldout_mean_crms``, ``planner_gap_to_optimum``; on the worlds it planned
on: ``planner_planned_mean_crms`` against their optimum ``planner_planned_optimum``).

A second learner, from episodes only: the same k = 1 policy search started blank
(``init="blank"``: policy search on ``search_worlds`` fixed worlds of the training
objects, PEGASUS-style), reported as ``search_mean_crms`` (training objects, fresh
starts), ``search_heldout_mean_crms``, ``search_gap_to_optimum`` and ``search_episodes``
(episodes it ran).

Held-out against in-distribution, per learner: ``heldout_gap`` is the raw ratio of the
two means minus 1; since the held-out worlds and the training objects' fresh starts are
different samples of unequal difficulty, ``heldout_gap_normalized`` divides each mean by
its own worlds' belief-space optimum first (``belief_optimum``, ``seen_belief_optimum``)
before taking the ratio.
``strategy.csv`` lists, for the family policy on the held-out worlds, each first
observation, the first CRM taken there, each outcome and the CRM that follows it: the
observations the policy uses to tell the objects apart.
"""

from __future__ import annotations

import dataclasses
from collections import Counter, defaultdict
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from crmgrasp._io import write_csv, write_json
from crmgrasp._progress import Progress
from crmgrasp.agents.base import Agent
from crmgrasp.experiments._episodes import MODEL_VI_LABEL, EpisodeRecord, greedy_records, train_model_vi
from crmgrasp.experiments.configs import CheckedConfig, checked_config
from crmgrasp.model import families as fam
from crmgrasp.model.families import Pose, SamplerFamily
from crmgrasp.planners.korder import korder_search
from crmgrasp.planners.references import belief_optimum, clairvoyant_bound, sample_starts
from crmgrasp.tasks import Task, make_task

__all__ = ["GeneralizationConfig", "OUT_OF_RANGE", "generalization", "strategy_rows"]

OUT_OF_RANGE: dict[str, Any] = {
    "box-family": fam.BoxFamily(length=(0.40, 0.50), width=(0.14, 0.155)),
    "cup-family": fam.DiscFamily(radius=(0.07, 0.078)),
    "l-shape": fam.LShapeFamily(arm=(0.24, 0.32), thickness=(0.06, 0.07)),
    "u-handle": fam.UHandleFamily(width=(0.26, 0.32), height=(0.18, 0.24), thickness=(0.05, 0.06)),
}
"""Per family task, a family of the same kind with sizes beyond its training ranges
(still narrow enough for the hand)."""


@dataclass(frozen=True)
class GeneralizationConfig(CheckedConfig):
    """Families, training objects, learner budget (trials x episodes), worlds for the
    references and evaluations, seed."""

    families: tuple[str, ...] = ("box-family", "cup-family", "l-shape", "u-handle")
    train_objects: int = 500
    trials: int = 5
    episodes: int = 600
    heldout: int = 400
    seed: int = 0
    planner_worlds: int = 1000
    """Worlds of the whole family the k = 1 policy search plans on (0: no planner)."""
    search_worlds: int = 10_000
    """Worlds of the training objects the k = 1 policy search learns on from episodes,
    starting blank (0: not run)."""

    @classmethod
    def quick(cls, seed: int = 0) -> GeneralizationConfig:
        """A small budget for smoke runs."""
        return cls(
            families=("box-family", "cup-family"),
            train_objects=10,
            trials=2,
            episodes=100,
            heldout=100,
            seed=seed,
            planner_worlds=100,
            search_worlds=200,
        )


def _finite(task: Task, n: int, seed: int) -> Task:
    """``task`` restricted to ``n`` objects drawn from its family (each episode picks one)."""
    assert task.family is not None
    rng = np.random.default_rng([seed, 7])
    shapes = [task.family.sample(rng) for _ in range(n)]

    def pick(r: np.random.Generator) -> Any:
        return shapes[int(r.random() * len(shapes))]

    still = Pose(angle=(0.0, 0.0), offset=(0.0, 0.0))  # the shapes are placed already
    family = SamplerFamily(pick, shapes[0], task.family.min_width(), pose=still)
    return dataclasses.replace(task, name=f"{task.name}-train{n}", family=family)


def _train(task: Task, cfg: GeneralizationConfig) -> list[Agent]:
    return train_model_vi(task, cfg.trials, cfg.episodes, cfg.seed)


def _run(task: Task, agents: Sequence[Agent], worlds: Sequence[Any], seed: int) -> list[EpisodeRecord]:
    return [r for records in greedy_records(task, agents, worlds, seed) for r in records]


def _mean(records: Sequence[EpisodeRecord]) -> float:
    return float(np.mean([len(r.actions) for r in records]))


def strategy_rows(task: Task, records: Sequence[EpisodeRecord]) -> list[list[Any]]:
    """``[first observation, first CRM, share, outcome, share of it, next CRM]`` rows:
    how the policy's second CRM depends on what its first one revealed."""
    d, names = task.discretizer, task.action_names()
    by_first: dict[tuple[int, int], list[EpisodeRecord]] = defaultdict(list)
    for r in records:
        by_first[(r.first_obs, r.actions[0])].append(r)
    rows = []
    for (o0, a0), group in sorted(by_first.items(), key=lambda kv: -len(kv[1])):
        outcomes: dict[str, Counter[str]] = defaultdict(Counter)
        for r in group:
            if r.success and len(r.actions) == 1:
                outcomes["grasp"]["-"] += 1
            elif len(r.actions) >= 2:
                outcomes[d.label(r.observations[0])][names[r.actions[1]]] += 1
        for outcome, nxt in sorted(outcomes.items(), key=lambda kv: -sum(kv[1].values())):
            count = sum(nxt.values())
            rows.append(
                [
                    d.label(o0),
                    names[a0],
                    round(len(group) / len(records), 4),
                    outcome,
                    round(count / len(group), 4),
                    nxt.most_common(1)[0][0],
                ]
            )
    return rows


def _family_summary(name: str, cfg: GeneralizationConfig, out: Path) -> dict[str, Any]:
    task = make_task(name)
    train = _finite(task, cfg.train_objects, cfg.seed)
    agents = _train(train, cfg)
    seen = sample_starts(train, cfg.heldout, cfg.seed + 1)
    heldout = sample_starts(task, cfg.heldout, cfg.seed + 2)
    records_seen, records_new = _run(train, agents, seen, cfg.seed), _run(task, agents, heldout, cfg.seed)
    s: dict[str, Any] = {
        "learner_mean_crms": _mean(records_seen),
        "heldout_mean_crms": _mean(records_new),
        "success_rate": float(np.mean([r.success for r in records_new])),
        "belief_optimum": belief_optimum(task, heldout),
        "clairvoyant_bound": clairvoyant_bound(task, heldout),
        "seen_belief_optimum": belief_optimum(train, seen),
    }
    _gaps(s, "")
    if cfg.search_worlds:
        found = korder_search(train, sample_starts(train, cfg.search_worlds, cfg.seed + 6), 1, init="blank")
        s["search_episodes"] = found.episodes
        s["search_trained_mean_crms"] = found.mean_cost
        s["search_mean_crms"] = _mean(_run(train, [found.policy], seen, cfg.seed))
        s["search_heldout_mean_crms"] = _mean(_run(task, [found.policy], heldout, cfg.seed))
        _gaps(s, "search_")
    if cfg.planner_worlds:
        planned = korder_search(task, sample_starts(task, cfg.planner_worlds, cfg.seed + 5), 1)
        s["planner_planned_mean_crms"] = planned.mean_cost
        s["planner_planned_optimum"] = planned.belief_optimum
        s["planner_heldout_mean_crms"] = _mean(_run(task, [planned.policy], heldout, cfg.seed))
        s["planner_gap_to_optimum"] = s["planner_heldout_mean_crms"] / s["belief_optimum"] - 1.0
    if name in OUT_OF_RANGE:
        wide = dataclasses.replace(task, family=OUT_OF_RANGE[name])
        s["out_of_range_mean_crms"] = _mean(
            _run(wide, agents, sample_starts(wide, cfg.heldout, cfg.seed + 3), cfg.seed)
        )
    one = task.with_object(task.obj)  # the family's nominal object
    own = _train(one, cfg)
    starts = sample_starts(one, cfg.heldout, cfg.seed + 4)
    s["per_instance_mean_crms"] = _mean(_run(one, own, starts, cfg.seed))
    s["family_policy_on_instance_mean_crms"] = _mean(_run(one, agents, starts, cfg.seed))
    paper = make_task("paper-box")
    if paper.actions == task.actions and paper.discretizer == task.discretizer:
        s["paper_box_policy_mean_crms"] = _mean(_run(task, _train(paper, cfg), heldout, cfg.seed))
    rows = strategy_rows(task, records_new)
    write_csv(
        out / f"strategy_{name}.csv",
        ["first_observation", "first_crm", "share", "outcome", "outcome_share", "next_crm"],
        rows,
    )
    return s


def _gaps(s: dict[str, Any], p: str) -> None:
    """The learner ``p``'s held-out gap, raw and against each set's optimum, and its gap to the optimum."""
    seen, new, opt = s[f"{p}mean_crms" if p else "learner_mean_crms"], s[f"{p}heldout_mean_crms"], s["belief_optimum"]
    s[f"{p}heldout_gap"] = new / seen - 1.0
    s[f"{p}heldout_gap_normalized"] = new / opt / (seen / s["seen_belief_optimum"]) - 1.0
    s[f"{p}gap_to_optimum"] = new / opt - 1.0


def generalization(
    out_dir: str | Path, cfg: GeneralizationConfig = GeneralizationConfig(), progress: Progress | None = None
) -> dict[str, Any]:
    """Run the experiment on every family of ``cfg``; write ``generalization.csv``,
    ``strategy_<family>.csv``, ``generalization.png`` and ``summary.json``; return the
    summary (per family the numbers of the module docstring)."""
    cfg = checked_config(cfg, GeneralizationConfig)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    stage = progress.stage("generalization", len(cfg.families), "families") if progress else None
    families: dict[str, Any] = {}
    for name in cfg.families:
        families[name] = _family_summary(name, cfg, out)
        if stage is not None:
            stage.advance(1)
    if stage is not None:
        stage.end()
    summary = {
        "learner": MODEL_VI_LABEL,
        "budget": f"{cfg.trials} trials x {cfg.episodes} episodes on {cfg.train_objects} training objects; "
        f"{cfg.heldout} worlds per evaluation; policy search on {cfg.search_worlds} worlds; seed {cfg.seed}",
        "families": families,
    }
    keys = sorted({k for v in families.values() for k in v})
    write_csv(
        out / "generalization.csv", ["family", *keys], [[n, *(v.get(k, "") for k in keys)] for n, v in families.items()]
    )
    write_json(out / "summary.json", summary)
    _figure(out / "generalization.png", summary)
    return summary


def _figure(path: Path, s: dict[str, Any]) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from crmgrasp._io import save_figure

    bars = [
        ("clairvoyant_bound", "clairvoyant bound", "0.85"),
        ("belief_optimum", "belief-space optimum", "0.6"),
        ("learner_mean_crms", "model-vi: training objects", "tab:blue"),
        ("heldout_mean_crms", "model-vi: held-out objects", "tab:orange"),
        ("out_of_range_mean_crms", "model-vi: sizes out of range", "tab:red"),
        ("search_heldout_mean_crms", "held-out: k = 1 policy search from episodes", "tab:purple"),
        ("planner_heldout_mean_crms", "held-out: k = 1 policy planned on sampled worlds", "tab:green"),
    ]
    import textwrap

    names = list(s["families"])
    fig, ax = plt.subplots(figsize=(max(6.4, 2.2 + 1.8 * len(names)), 5.0), layout="constrained")
    width = 0.8 / len(bars)
    for i, (key, label, color) in enumerate(bars):
        vals = [s["families"][n].get(key, np.nan) for n in names]
        ax.bar(np.arange(len(names)) + (i - (len(bars) - 1) / 2) * width, vals, width, label=label, color=color)
    ax.set_xticks(np.arange(len(names)), names)
    ax.set_ylabel("CRMs per episode")
    fig.legend(fontsize=8, ncols=2, loc="outside lower center")  # below the axes: it covers no bar
    title = f"One policy per family ({s['budget']})"
    ax.set_title("\n".join(textwrap.wrap(title, 90)), fontsize=9)  # wrapped: never clipped
    save_figure(fig, path)
    plt.close(fig)

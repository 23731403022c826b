"""Spatial CRMs: learning to grasp boxes and cups on a table in 3-D (docs/model-3d.md).

On ``box-3d`` and ``cup-3d`` (each episode a new solid: boxes of random size and yaw;
closed cylinders of random radius and height, upright or lying), two learners train:
the paper's SARSA (k = 2, alpha 0.3, gamma 0.9) and ``model-vi``
(k = 1). Their greedy policies are evaluated at checkpoints during learning (the same
evaluation starts at every checkpoint) and, at the end, on held-out worlds whose
belief-space optimum and clairvoyant bound are computed exactly
([`crmgrasp.planners.references`][]). Writes ``spatial.png`` (greedy CRMs per episode
against the references, one panel per task), ``spatial_strategy.png`` and
``spatial_strategy.gif`` (``model-vi``'s greedy policy on held-out cups, one row
per start, each CRM a 3-D panel), ``curves.csv`` and ``summary.json``.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from crmgrasp._io import atomic_path, save_figure, write_csv, write_json
from crmgrasp._progress import Progress
from crmgrasp.agents.base import Agent, LearnerPolicy
from crmgrasp.agents.training import TrialResult, encoder_for, train_trials
from crmgrasp.experiments._episodes import greedy_records
from crmgrasp.experiments.configs import CheckedConfig, checked_config
from crmgrasp.experiments.stats import bootstrap_ci
from crmgrasp.planners.references import belief_optimum, clairvoyant_bound, sample_starts, ungraspable_fraction
from crmgrasp.sim import run_episode
from crmgrasp.tasks import Task, World, make_task

__all__ = ["SpatialConfig", "spatial", "LEARNERS"]

LEARNERS = {"paper SARSA k=2": ("sarsa", 2), "model-vi k=1": ("model-vi", 1)}
"""Label -> (agent, k) of the learners compared."""


@dataclass(frozen=True)
class SpatialConfig(CheckedConfig):
    """Tasks, and per task the training episodes and the held-out worlds (the optimum's
    cost grows fast with them on boxes), trials, checkpoints, seed."""

    tasks: tuple[str, ...] = ("cup-3d", "box-3d")
    trials: int = 5
    episodes: tuple[int, ...] = (6000, 3000)
    heldout: tuple[int, ...] = (300, 150)
    checkpoints: tuple[int, ...] = (10, 20, 50, 100, 200, 500, 1000, 2000, 4000, 6000)
    checkpoint_episodes: int = 100
    seed: int = 0

    @classmethod
    def quick(cls, seed: int = 0) -> SpatialConfig:
        """A small budget for smoke runs."""
        return cls(trials=2, episodes=(300, 150), heldout=(80, 40), checkpoints=(20, 100, 300), seed=seed)


def _learner(
    task: Task, learner: str, k: int, episodes: int, worlds: list[World], opt: float, cfg: SpatialConfig
) -> tuple[TrialResult, dict[str, Any], np.ndarray]:
    """Train ``cfg.trials`` agents of ``learner`` on ``task`` and run each greedy policy on
    ``worlds``: the training result, the learner's summary entry (greedy CRMs with a 95%
    interval over the trials, success, gap to the optimum ``opt``) and the trials' means."""
    res = train_trials(
        task,
        learner,
        trials=cfg.trials,
        episodes=episodes,
        seed=cfg.seed,
        k=k,
        eval_episodes=0,
        checkpoints=cfg.checkpoints,
        checkpoint_episodes=cfg.checkpoint_episodes,
    )
    records = greedy_records(task, res.agents, worlds, cfg.seed, lambda t: np.random.default_rng(cfg.seed + t), k)
    means = np.array([np.mean([len(r.actions) for r in rs]) for rs in records])
    lo, hi = bootstrap_ci(means, cfg.seed)  # over trials: nan, none given, below MIN_TRIALS
    entry = {
        "greedy_mean_crms": float(means.mean()),
        "greedy_ci95": [lo, hi],
        "success_rate": float(np.mean([np.mean([r.success for r in rs]) for rs in records])),
        "gap_to_optimum": float(means.mean() / opt - 1.0),
    }
    return res, entry, means


def spatial(
    out_dir: str | Path, cfg: SpatialConfig = SpatialConfig(), progress: Progress | None = None
) -> dict[str, Any]:
    """Train, evaluate against the references, draw; return the summary: per task,
    ``belief_optimum``, ``clairvoyant_bound``, ``ungraspable_fraction`` and per learner
    ``greedy_mean_crms`` (with a 95% interval over trials), ``success_rate`` and
    ``gap_to_optimum``."""
    cfg = checked_config(cfg, SpatialConfig)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    stage = progress.stage("spatial", len(cfg.tasks) * (len(LEARNERS) + 1), "stages") if progress else None
    summary: dict[str, Any] = {
        "budget": (
            f"{cfg.trials} trials x {'/'.join(map(str, cfg.episodes))} episodes; held-out worlds "
            f"{'/'.join(map(str, cfg.heldout))} ({', '.join(cfg.tasks)}); seed {cfg.seed}"
        ),
        "tasks": {},
    }
    curves: list[list[Any]] = []
    best: dict[str, Agent] = {}
    for name, episodes, n_worlds in zip(cfg.tasks, cfg.episodes, cfg.heldout, strict=True):
        task = make_task(name)
        worlds: list[World] = sample_starts(task, n_worlds, cfg.seed + 1)  # type: ignore[assignment]
        opt = belief_optimum(task, worlds)
        row: dict[str, Any] = {
            "belief_optimum": opt,
            "clairvoyant_bound": clairvoyant_bound(task, worlds),
            "ungraspable_fraction": ungraspable_fraction(task, worlds),
            "heldout_worlds": n_worlds,
            "episodes": episodes,
            "learners": {},
        }
        if stage is not None:
            stage.advance(1)
        for label, (learner, k) in LEARNERS.items():
            res, row["learners"][label], means = _learner(task, learner, k, episodes, worlds, opt, cfg)
            ckpt = res.checkpoint_steps.mean(axis=0)
            curves += [[name, label, int(e), float(v)] for e, v in zip(res.checkpoints, ckpt, strict=True)]
            if learner == "model-vi" and name == cfg.tasks[0]:
                best[name] = res.agents[int(np.argmin(means))]
            if stage is not None:
                stage.advance(1)
        summary["tasks"][name] = row
    write_csv(out / "curves.csv", ["task", "learner", "episode", "greedy_mean_crms"], curves)
    _figure(out, summary, curves, cfg)
    for name, agent in best.items():
        _strategy(out, make_task(name), agent, cfg.seed)
    write_json(out / "summary.json", summary)
    if stage is not None:
        stage.end()
    return summary


def _figure(out: Path, summary: dict[str, Any], curves: list[list[Any]], cfg: SpatialConfig) -> None:
    from matplotlib.figure import Figure
    from matplotlib.ticker import FixedLocator, FuncFormatter, NullFormatter

    from crmgrasp.plotting import learner_color

    fig = Figure(figsize=(5.2 * len(cfg.tasks), 4.2), layout="constrained")
    axes = fig.subplots(1, len(cfg.tasks), squeeze=False)[0]
    for ax, name in zip(axes, cfg.tasks, strict=True):
        row = summary["tasks"][name]
        for label in LEARNERS:
            pts = [(e, v) for t, lab, e, v in curves if t == name and lab == label]
            ax.plot(*zip(*pts, strict=True), "o-", color=learner_color(label.split()[0].lower()), label=label, ms=4)
        ax.axhline(row["belief_optimum"], color="k", ls="--", lw=1, label="belief-space optimum")
        ax.axhline(row["clairvoyant_bound"], color="0.5", ls=":", lw=1, label="clairvoyant bound")
        ax.set_xscale("log")
        ax.xaxis.set_major_locator(FixedLocator(sorted({e for t, _, e, _ in curves if t == name})))
        ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:,.0f}"))  # the checkpoints, plainly
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.set_xlabel("training episode")
        ax.set_ylabel(f"greedy CRMs per episode ({cfg.checkpoint_episodes} evaluation starts)")
        ax.set_title(f"{name}: {cfg.trials} trials x {row['episodes']} episodes", fontsize=10)
        ax.legend(fontsize=7)
    fig.suptitle(
        f"Spatial CRMs, seed {cfg.seed}: greedy checkpoints on {cfg.checkpoint_episodes} fixed starts (the summary's "
        f"learned numbers are on the held-out worlds); references on {', '.join(map(str, cfg.heldout))} worlds",
        fontsize=9,
    )
    save_figure(fig, out / "spatial.png")


def _strategy(out: Path, task: Task, agent: Agent, seed: int) -> None:
    """The greedy policy on up to three held-out worlds (one upright, one lying, one
    more), each CRM a 3-D panel; the longest as a GIF."""
    from crmgrasp.plotting.spatial import rollout_animation3d, rollout_panels3d

    encoder = encoder_for(task, 1)
    rng = np.random.default_rng(seed + 7)
    rows: list[tuple[str, Any, list[Any]]] = []  # (label, solid, steps)
    kinds: set[str] = set()
    names = task.action_names()
    for _ in range(200):
        w = task.sample_world(rng)
        ep = run_episode(task, LearnerPolicy(agent, encoder, rng, learn=False), rng, start=w, trace=True)
        kind = "upright" if abs(getattr(w.task.obj, "axis", (0, 0, 1))[2]) > 0.99 else "lying"
        key = f"{kind} {min(ep.steps, 3)}"
        if not ep.success or key in kinds:
            continue
        kinds.add(key)
        steps = [
            (
                t.before.state.config,
                t.after.state.config if int(t.after.error) == 0 else None,
                f"{names[t.action]} -> {t.after.error.name.lower()}",  # type: ignore[index]
            )
            for t in ep.trace
        ]
        rows.append((f"{kind}, grasped in {ep.steps}", w.task.obj, steps))
        if len(rows) == 3:
            break
    if not rows:
        return
    save_figure(rollout_panels3d(task.hand, rows), out / "spatial_strategy.png")  # type: ignore[arg-type]
    _, solid, steps = max(rows, key=lambda r: len(r[2]))
    with atomic_path(out / "spatial_strategy.gif") as tmp:
        rollout_animation3d(solid, task.hand, steps, tmp)  # type: ignore[arg-type]

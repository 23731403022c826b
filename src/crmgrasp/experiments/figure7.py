"""Paper Figure 7: mean CRMs per episode versus episode, averaged over trials.

The paper's SARSA (k = 2, alpha 0.3, gamma 0.9, Q0 = 0, greedy) with a standard
error band, and on the same axes the other learners: Q-learning, SARSA(lambda),
Dyna-Q with sampled planning, Dyna-Q with value-iteration sweeps (k = 1), and the
random and fixed-sequence baselines. Every trial's final greedy policy is then
evaluated on fresh episodes. A second panel is the history-order ablation
(SARSA with k = 0, 1, 2, 3): memoryless policies cannot resolve the aliasing.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from crmgrasp._io import save_figure, write_csv, write_json
from crmgrasp._progress import Progress
from crmgrasp.experiments.configs import CheckedConfig, checked_config
from crmgrasp.experiments.learning import SYMMETRIC_DYNA_Q, LearnerSpec, LearnRun, _mean_sem, best_policy, learn, usable
from crmgrasp.experiments.stats import budget
from crmgrasp.plotting import checkpoint_figure, learning_curve_figure
from crmgrasp.tasks import Task, make_task

__all__ = ["Figure7Config", "figure_7_learning_curve", "DEFAULT_LEARNERS", "PAPER_LEARNER"]

PAPER_LEARNER = LearnerSpec("sarsa", 2, {}, "SARSA k=2 (paper)")

DEFAULT_LEARNERS: tuple[LearnerSpec, ...] = (
    PAPER_LEARNER,
    LearnerSpec("q", 2, {}, "Q-learning k=2"),
    LearnerSpec("sarsa-lambda", 2, {"lam": 0.9, "trace": "replacing"}, "SARSA(0.9) k=2"),
    LearnerSpec("dyna-q", 2, {"n_planning": 20}, "Dyna-Q k=2 (20 samples)"),
    LearnerSpec("dyna-q", 1, {"planning": "sweep", "n_planning": 50}, "Dyna-Q k=1 (VI sweeps)"),
    SYMMETRIC_DYNA_Q,
    LearnerSpec("fixed", 2, {}, "fixed sequence"),
    LearnerSpec("random", 2, {}, "random"),
)


@dataclass(frozen=True)
class Figure7Config(CheckedConfig):
    """Parameters of Figure 7."""

    task: str = "paper-box"
    trials: int = 20
    """Independent trials per learner (the paper: 20)."""
    episodes: int = 2000
    """Training episodes per trial."""
    eval_episodes: int = 1000
    """Greedy evaluation episodes per trial."""
    seed: int = 0
    learners: tuple[LearnerSpec, ...] = DEFAULT_LEARNERS
    ablation_ks: tuple[int, ...] = (0, 1, 2, 3)
    """History orders of the SARSA ablation."""
    checkpoint_episodes: int = 100
    """Fixed evaluation starts per greedy checkpoint (the same starts at every
    checkpoint, for every trial and learner)."""


def _ms(run: LearnRun) -> tuple[Any, Any]:
    return _mean_sem(run.result.checkpoint_steps)


def figure_7_learning_curve(
    out_dir: str | Path,
    config: Figure7Config = Figure7Config(),
    *,
    backend: str = "auto",
    progress: Progress | None = None,
    jobs: int = 1,
) -> dict[str, Any]:
    """Run every learner; write ``curves.csv``, ``checkpoints.csv``, ``learners.csv``,
    ``figure7.png``, ``figure7_greedy.png``, ``figure7_k_ablation.png``,
    ``policy.json`` (the paper SARSA's best trial) and ``config.json``."""
    config = checked_config(config, Figure7Config)
    task = make_task(config.task)
    out = Path(out_dir)
    kw: dict[str, Any] = dict(
        trials=config.trials,
        episodes=config.episodes,
        seed=config.seed,
        eval_episodes=config.eval_episodes,
        checkpoint_episodes=config.checkpoint_episodes,
        backend=backend,
        progress=progress,
        jobs=jobs,
    )
    runs: list[LearnRun] = [learn(task, spec, **kw) for spec in usable(task, config.learners)]
    ablation = [learn(task, LearnerSpec("sarsa", k, {}, f"SARSA k={k}"), **kw) for k in config.ablation_ks]
    everything = runs + [r for r in ablation if r.spec.k not in {s.k for s in config.learners if s.agent == "sarsa"}]
    _write_tables(out, config, everything)
    _write_figures(out, task, config, runs, ablation, everything)
    policy = best_policy(task, runs[0])
    if policy is not None:
        policy.save(out / "policy.json")
    summary = _summary(task, config, runs, ablation, everything)
    write_json(
        out / "config.json",
        {
            "experiment": "figure7",
            "config": {**asdict(config), "learners": [asdict(s) for s in config.learners]},
            "learners": [r.summary for r in everything],
            "summary": summary,
        },
    )
    return summary


LEARNER_COLUMNS = [
    "label",
    "agent",
    "k",
    "final_mean_steps",
    "greedy_mean_steps",
    "greedy_sem_steps",
    "greedy_success_rate",
    "episodes_to_5pct",
    "greedy_episodes_to_5pct",
    "seconds",
]
"""The columns of ``learners.csv``: entries of each run's summary."""


def _write_tables(out: Path, config: Figure7Config, everything: list[LearnRun]) -> None:
    """``curves.csv`` (mean and standard error per episode), ``learners.csv`` and
    ``checkpoints.csv`` (the greedy policies' mean and standard error per checkpoint)."""
    header = ["episode"] + [f"{r.spec.name} {q}" for r in everything for q in ("mean", "sem")]
    rows = (
        [e + 1] + [float(v) for r in everything for v in (r.result.curve[e], r.result.sem[e])]
        for e in range(config.episodes)
    )
    write_csv(out / "curves.csv", header, rows)
    write_csv(out / "learners.csv", LEARNER_COLUMNS, ([r.summary[c] for c in LEARNER_COLUMNS] for r in everything))
    ckpt = everything[0].result.checkpoints
    write_csv(
        out / "checkpoints.csv",
        header,
        ([int(c)] + [float(v) for r in everything for v in (_ms(r)[0][j], _ms(r)[1][j])] for j, c in enumerate(ckpt)),
    )


def _write_figures(
    out: Path,
    task: Task,
    config: Figure7Config,
    runs: list[LearnRun],
    ablation: list[LearnRun],
    everything: list[LearnRun],
) -> None:
    """``figure7.png`` (the learners' curves, the paper SARSA highlighted), ``figure7_k_ablation.png``
    (SARSA over history orders) and ``figure7_greedy.png`` (the greedy policies at the checkpoints)."""
    ref = task.reference_mean_steps
    fig = learning_curve_figure(
        {r.spec.name: (r.result.curve, r.result.sem) for r in runs},
        ref,
        f"{task.name}: CRMs per episode, mean of {budget(config.trials, config.episodes, config.seed)} "
        "(paper Fig. 7; bands: standard error over trials)",
        highlight=runs[0].spec.name,
        paper=(60.0, 1.8),
    )
    save_figure(fig, out / "figure7.png", dpi=120)
    fig = learning_curve_figure(
        {r.spec.name: (r.result.curve, r.result.sem) for r in ablation},
        ref,
        f"History order ablation (SARSA, {budget(config.trials, config.episodes, config.seed)})",
    )
    save_figure(fig, out / "figure7_k_ablation.png", dpi=120)
    fig = checkpoint_figure(
        runs[0].result.checkpoints,
        {r.spec.name: _ms(r) for r in everything if r.spec.agent not in ("random", "fixed")},
        ref,
        f"Greedy policy after N training episodes, {config.checkpoint_episodes} fixed starts x {config.trials} trials, "
        f"seed {config.seed}",
    )
    save_figure(fig, out / "figure7_greedy.png", dpi=120)


def _summary(
    task: Task, config: Figure7Config, runs: list[LearnRun], ablation: list[LearnRun], everything: list[LearnRun]
) -> dict[str, Any]:
    """The references on 4,000 starts, the paper SARSA's results, the learners fastest to within
    5% (by their own episodes and by the greedy checkpoints) and each history order's greedy cost."""
    from crmgrasp.planners.references import belief_optimum, clairvoyant_bound, sample_starts

    starts = sample_starts(task, 4000, config.seed)
    paper = runs[0].summary
    summary: dict[str, Any] = {
        "belief_optimum_4000_starts": round(belief_optimum(task, starts), 4),
        "clairvoyant_bound_4000_starts": round(clairvoyant_bound(task, starts), 4),
        "paper_sarsa_greedy_mean_steps": round(paper["greedy_mean_steps"], 3),
        "paper_sarsa_final_mean_steps": round(paper["final_mean_steps"], 3),
        "paper_sarsa_episodes_to_5pct": paper["episodes_to_5pct"],
        "paper_sarsa_greedy_episodes_to_5pct": paper["greedy_episodes_to_5pct"],
    }
    best = min(everything, key=lambda r: r.summary["episodes_to_5pct"] or float("inf"))
    summary["best_learner"] = best.spec.name
    summary["best_episodes_to_5pct"] = best.summary["episodes_to_5pct"]
    summary["best_greedy_mean_steps"] = round(best.summary["greedy_mean_steps"], 3)
    gbest = min(everything, key=lambda r: r.summary["greedy_episodes_to_5pct"] or float("inf"))
    summary["best_greedy_learner"] = gbest.spec.name
    summary["best_greedy_episodes_to_5pct"] = gbest.summary["greedy_episodes_to_5pct"]
    for r in ablation:
        summary[f"sarsa_k{r.spec.k}_greedy_mean_steps"] = round(r.summary["greedy_mean_steps"], 3)
    return summary

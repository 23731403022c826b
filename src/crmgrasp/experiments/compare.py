"""Every method on one task, same seeds, one table: learners, baselines, the grasp
controller, the belief-space policy and the sampled POMDP's PBVI policy (1 cm cells)
executed on the same fresh starts (``trials x eval_episodes`` of them, seed + 1),
and the two exact references (clairvoyant
bound, belief-space optimum) on the sampled starts.

Writes ``compare.csv``, ``compare.md`` (the same table) and ``compare.png`` (the
learning curves with the references and the controller as horizontal lines), and
``config.json``.
"""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from crmgrasp._io import atomic_write_text, save_figure, write_csv, write_json
from crmgrasp._progress import Progress
from crmgrasp.agents.controller import run_controller
from crmgrasp.agents.deep import (
    RecurrentPolicy,
    RecurrentPPOConfig,
    deep_available,
    evaluate_recurrent,
    train_recurrent_ppo,
)
from crmgrasp.agents.training import episodes_to_within
from crmgrasp.experiments.configs import CheckedConfig, checked_config
from crmgrasp.experiments.learning import SYMMETRIC_DYNA_Q, LearnerSpec, learn, usable
from crmgrasp.experiments.runs import RunFolder
from crmgrasp.experiments.stats import MIN_TRIALS, bootstrap_ci, budget, fmt, iqm, normal_ci
from crmgrasp.model.geometry import Polygon
from crmgrasp.planners.pomdp_task import POMDPAgent, build_task_pomdp
from crmgrasp.planners.references import BeliefPolicy, belief_optimum, clairvoyant_bound, sample_starts
from crmgrasp.plotting import learning_curve_figure
from crmgrasp.tasks import Task, make_task

__all__ = ["CompareConfig", "compare", "COMPARE_LEARNERS"]

COMPARE_LEARNERS: tuple[LearnerSpec, ...] = (
    LearnerSpec("sarsa", 2, {}, "SARSA k=2 (paper)"),
    LearnerSpec("sarsa-lambda", 2, {"lam": 0.9, "trace": "replacing"}, "SARSA(0.9) k=2"),
    LearnerSpec("dyna-q", 1, {"planning": "sweep", "n_planning": 50}, "Dyna-Q k=1 (VI sweeps)"),
    SYMMETRIC_DYNA_Q,
    LearnerSpec("fixed", 2, {}, "fixed sequence"),
    LearnerSpec("random", 2, {}, "random"),
)

DEFAULT_DEEP = RecurrentPPOConfig(total_steps=120_000)
"""The deep-RL peer of the full comparison."""

EVAL_OPTIMUM = "belief-space optimum, evaluation starts"
"""The row of the belief-space optimum computed on the starts the executed planners ran on."""

COLUMNS = [
    "method",
    "kind",
    "mean_crms",
    "ci95_low",
    "ci95_high",
    "ci_over",
    "iqm_crms",
    "success_rate",
    "episodes_to_5pct",
    "greedy_episodes_to_5pct",
    "seconds",
]


@dataclass(frozen=True)
class CompareConfig(CheckedConfig):
    """Parameters of the comparison (``quick`` shrinks every budget)."""

    task: str = "paper-box"
    seed: int = 0
    trials: int = 20
    episodes: int = 2000
    eval_episodes: int = 1000
    reference_starts: int = 4000
    learners: tuple[LearnerSpec, ...] = COMPARE_LEARNERS
    deep: RecurrentPPOConfig | None = DEFAULT_DEEP
    """The deep-RL peer (skipped when None or when the extra ``crmgrasp[deep]`` is missing)."""

    @classmethod
    def quick(cls, task: str = "paper-box", seed: int = 0) -> CompareConfig:
        """Small budgets: 5 trials x 300 episodes, 200 evaluation episodes, 1,000 starts,
        RecurrentPPO for 4,096 steps."""
        deep = RecurrentPPOConfig(total_steps=4096, checkpoint_episodes=50)
        return cls(task=task, seed=seed, trials=5, episodes=300, eval_episodes=200, reference_starts=1000, deep=deep)


def _note(progress: Progress | None, text: str) -> None:
    if progress is not None:
        progress.note(text)


def _fixed_row(name: str, kind: str, steps: np.ndarray, ok: float, t0: float) -> list[Any]:
    """A table row of a fixed policy: interval over its episodes."""
    m, lo, hi = normal_ci(steps)
    return [name, kind, m, lo, hi, "episodes", None, ok, None, None, round(time.perf_counter() - t0, 3)]


def compare(
    out_dir: str | Path,
    config: CompareConfig = CompareConfig(),
    *,
    backend: str = "auto",
    progress: Progress | None = None,
    task: Task | None = None,
    store: RunFolder | None = None,
    jobs: int = 1,
) -> dict[str, Any]:
    """Run every method (learners and the deep-RL peer on the kernel ``backend``); write
    the table and the figure; return a summary. ``task`` overrides the registered task
    ``config.task`` names (a task from a file); with a run folder ``store``, each
    learner's trials are saved there as they finish and reused by a resumed run."""
    config = checked_config(config, CompareConfig)
    task = make_task(config.task) if task is None else task
    rows, curves = _learner_rows(task, config, backend, progress, store, jobs)
    t0 = time.perf_counter()
    steps, ok = run_controller(task, config.trials * config.eval_episodes, np.random.default_rng(config.seed))
    rows.append(_fixed_row("grasp controller", "baseline", steps, float(ok.mean()), t0))
    controller = rows[-1][2]
    starts = sample_starts(task, config.reference_starts, config.seed)
    fresh = sample_starts(task, config.trials * config.eval_episodes, config.seed + 1)
    _note(progress, "compare: the deep-RL peer (RecurrentPPO) ...")
    deep_rows, deep_info = _deep_row(task, config, fresh, curves, controller, Path(out_dir), backend)
    rows += deep_rows
    _note(progress, "compare: belief-space policy, sampled POMDP, exact references ...")
    planners, pomdp = _planner_rows(task, config, starts, fresh)
    rows += planners
    refs, on_eval = _reference_rows(task, starts, fresh, rows)
    _write_outputs(Path(out_dir), task, config, rows, curves, {**refs, "grasp controller": controller})
    best = min((r for r in rows if r[1] == "learner"), key=lambda r: r[2])
    summary = {
        "best_learner": best[0],
        "best_learner_mean_crms": round(best[2], 3),
        "belief_optimum": round(refs["belief-space optimum"], 4),
        "belief_optimum_evaluation_starts": round(on_eval, 4),
        "clairvoyant_bound": round(refs["clairvoyant bound"], 4),
        "grasp_controller_mean_crms": round(controller, 3),
        "belief_policy_executed_mean_crms": round(planners[0][2], 3),
        **pomdp,
        "best_learner_vs_optimum_pct": round(100 * (best[2] / refs["belief-space optimum"] - 1), 2),
        "deep_rl": deep_info,
    }
    config_json = {**asdict(config), "learners": [asdict(s) for s in config.learners]}
    write_json(Path(out_dir) / "config.json", {"experiment": "compare", "config": config_json, "summary": summary})
    return summary


def _learner_rows(
    task: Task,
    config: CompareConfig,
    backend: str,
    progress: Progress | None,
    store: RunFolder | None,
    jobs: int,
) -> tuple[list[list[Any]], dict[str, tuple[np.ndarray, np.ndarray]]]:
    """Each usable learner and baseline of ``config.learners``: its table row (interval over
    the trials' greedy means), and each learner's curve for the figure."""
    rows: list[list[Any]] = []
    curves = {}
    for spec in usable(task, config.learners):
        run = learn(
            task,
            spec,
            trials=config.trials,
            episodes=config.episodes,
            seed=config.seed,
            eval_episodes=config.eval_episodes,
            backend=backend,
            progress=progress,
            store=store.sub(spec.name) if store is not None else None,
            jobs=jobs,
        )
        res, s = run.result, run.summary
        per_trial = res.greedy_steps.mean(axis=1)
        lo, hi = bootstrap_ci(per_trial, config.seed)
        kind = "baseline" if spec.agent in ("random", "fixed") else "learner"
        success = float(res.greedy_success.mean())
        to5 = (s["episodes_to_5pct"], s["greedy_episodes_to_5pct"], s["seconds"])
        rows.append([spec.name, kind, float(per_trial.mean()), lo, hi, "trials", iqm(per_trial), success, *to5])
        if kind == "learner":
            curves[spec.name] = (res.curve, res.sem)
    return rows, curves


def _planner_rows(
    task: Task, config: CompareConfig, starts: list, fresh: list
) -> tuple[list[list[Any]], dict[str, Any]]:
    """The belief-space policy over ``starts`` and, on one polygonal object, the sampled
    POMDP's PBVI policy, each executed on ``fresh``: their rows (the belief-space policy
    first) and the POMDP's summary entries."""
    t0 = time.perf_counter()
    rows = [_executed_row("belief-space policy, executed", BeliefPolicy(task, starts).run, fresh, t0)]
    t0 = time.perf_counter()
    if task.family is not None or not isinstance(task.obj, Polygon):
        skipped = "skipped: the sampled POMDP needs one polygonal object"
        return rows, {"pomdp_executed_mean_crms": "skipped", "pomdp_model_value": "skipped", "pomdp_counts": skipped}
    tp = build_task_pomdp(task, cell=0.01, samples=20, n_starts=config.reference_starts, seed=config.seed)
    agent = POMDPAgent(tp, n_beliefs=300, seed=config.seed)
    label = f"sampled POMDP ({tp.model.n_states} states), PBVI, executed"
    rows.append(_executed_row(label, agent.run, fresh, t0))
    pomdp = {
        "pomdp_executed_mean_crms": round(rows[-1][2], 3),
        "pomdp_model_value": round(agent.model_value(), 4),
        "pomdp_counts": tp.model.counts,
    }
    return rows, pomdp


def _reference_rows(task: Task, starts: list, fresh: list, rows: list[list[Any]]) -> tuple[dict[str, float], float]:
    """Append the exact references' rows to ``rows``: the belief-space optimum and the
    clairvoyant bound on ``starts``, then the optimum of ``fresh`` (the starts every executed
    row ran on: the gap to it is the method's). Returns the two references on ``starts``, by
    name, and the optimum of ``fresh``."""
    refs = {}
    for name, fn in (("belief-space optimum", belief_optimum), ("clairvoyant bound", clairvoyant_bound)):
        t0 = time.perf_counter()
        refs[name] = fn(task, starts)
        seconds = round(time.perf_counter() - t0, 3)
        rows.append([name, "reference", refs[name], None, None, "exact", None, 1.0, None, None, seconds])
    t0 = time.perf_counter()
    on_eval = belief_optimum(task, fresh)
    seconds = round(time.perf_counter() - t0, 3)
    rows.append([EVAL_OPTIMUM, "reference", on_eval, None, None, "exact", None, 1.0, None, None, seconds])
    return refs, on_eval


def _write_outputs(
    out: Path, task: Task, config: CompareConfig, rows: list[list[Any]], curves: dict, hlines: dict[str, float]
) -> None:
    """``compare.csv``, ``compare.md`` and ``compare.png`` (the learners' curves, ``hlines`` as
    horizontal lines)."""
    write_csv(out / "compare.csv", COLUMNS, rows)
    atomic_write_text(out / "compare.md", _markdown(rows, config))
    title = f"{task.name}: learners ({budget(config.trials, config.episodes, config.seed)}), references and the "
    fig = learning_curve_figure(curves, None, title + "grasp controller", hlines=hlines)
    save_figure(fig, out / "compare.png", dpi=120)


def _deep_row(
    task: Task, config: CompareConfig, fresh: list, curves: dict, controller: float, out: Path, backend: str
) -> tuple[list[list[Any]], str | dict]:
    """RecurrentPPO's row (if it runs) and a summary of it; writes ``deep_curve.csv`` and
    ``deep_checkpoints.csv`` and adds its curve (100-episode moving average: one run is
    noisier than the tabular learners' trial means)."""
    if config.deep is None:
        return [], "not run (deep=None)"
    if not deep_available():
        return [], "skipped: needs pip install 'crmgrasp[deep]'"
    t0 = time.perf_counter()
    run = train_recurrent_ppo(task, config.seed, config.deep, backend=backend)
    steps, ok = evaluate_recurrent(run.model, task, fresh, np.random.default_rng(config.seed + 1))
    m, lo, hi = normal_ci(steps)  # one training run: the interval is over episodes only
    ref = task.reference_mean_steps
    to5 = episodes_to_within(run.episode_steps, ref) if ref else None
    greedy5 = run.greedy_episodes_to_within(ref) if ref else None
    name = f"RecurrentPPO (LSTM {config.deep.lstm_hidden}), {config.deep.total_steps} steps"
    window = min(100, max(1, len(run.episode_steps)))
    smooth = np.convolve(run.episode_steps, np.ones(window) / window, mode="valid")
    curves[f"{name}, one run (its own episodes)"] = (run.episode_steps, np.zeros(len(run.episode_steps)))
    RecurrentPolicy(run.model, task).save(out / "recurrent_ppo.zip")
    write_csv(out / "deep_curve.csv", ["episode", "crms"], [[i + 1, int(v)] for i, v in enumerate(run.episode_steps)])
    write_csv(
        out / "deep_checkpoints.csv", ["episode", "greedy_mean_steps"], zip(run.checkpoints, run.checkpoint_steps)
    )
    above = np.flatnonzero(smooth > controller)
    if len(above) and above[-1] == len(smooth) - 1:
        below: int | None = None  # the average ends above the controller: never
    else:
        below = int(above[-1] + window + 1) if len(above) else window
    seconds = round(time.perf_counter() - t0, 3)
    row = [name, "learner", m, lo, hi, "episodes (1 run)", None, float(ok.mean()), to5, greedy5, seconds]
    info = {
        "mean_crms": round(m, 3),
        "failures": int((~ok).sum()),
        "training_episodes": len(run.episode_steps),
        "episodes_until_average_stays_below_controller": below,
        "greedy_episodes_to_5pct": greedy5,
        "train_seconds": round(run.seconds, 2),
    }
    return [row], info


def _executed_row(name: str, run: Any, starts: list, t0: float) -> list[Any]:
    """A planner's table row: ``run(start) -> (CRMs, success)`` over ``starts``; time since ``t0``."""
    executed = [run(c) for c in starts]
    ok = float(np.mean([g for _, g in executed]))
    return _fixed_row(name, "planner", np.array([n for n, _ in executed], dtype=float), ok, t0)


def _markdown(rows: list[list[Any]], config: CompareConfig) -> str:
    """The table for reading: rounded, ``never`` for a threshold not reached, and a
    learner not within 5% of the optimum at the end of its budget marked."""
    lines = [
        f"# {config.task}: method comparison ({budget(config.trials, config.episodes, config.seed)})",
        "",
        f"Learners: {budget(config.trials, config.episodes)}; greedy evaluation on {config.eval_episodes:,} "
        f"episodes per trial; 95% intervals by bootstrap over the trials (n/a, none given, with fewer than "
        f"{MIN_TRIALS}; over the episodes for fixed policies "
        f"and the single deep-RL run). References: exact and noise-free, on {config.reference_starts:,} sampled "
        f"starts. The executed planners and the deep peer run on {config.trials * config.eval_episodes:,} other "
        "starts of the same distribution, learners and the controller on starts of their own, so a method can "
        f"come out below the references by sampling alone; *{EVAL_OPTIMUM}* is the optimum of the executed "
        "planners' own starts, which they compare to. "
        "`episodes_to_5pct`: first episode after which the 10-episode average stays within 5% of "
        'the belief-space optimum; "never" = not within the budget.',
        "",
        "| " + " | ".join(COLUMNS) + " |",
        "|" + " --- |" * len(COLUMNS),
    ]
    for r in rows:
        learner = r[1] == "learner"
        cells = ["-" if v is None and not (learner and i in (8, 9)) else fmt(v) for i, v in enumerate(r)]
        if learner and r[5] == "trials" and r[8] is None:
            cells[8] = f"never (not converged at {budget(config.trials, config.episodes)})"
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"

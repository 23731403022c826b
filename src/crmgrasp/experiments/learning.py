"""One learning run (a learner on a task over many trials) and its files.

Used by ``crmgrasp learn`` and by Figure 7. Files written to the output folder:

* ``curve.csv``: ``episode,mean_steps,sem_steps`` (CRMs per training episode,
  mean and standard error over trials);
* ``summary.json``: agent, task, k, parameters, trials, episodes, seed,
  ``final_mean_steps`` (mean of the last 10 points of the curve),
  ``greedy_mean_steps`` (greedy evaluation on ``eval_episodes`` fresh episodes,
  averaged over trials), ``greedy_success_rate``, ``episodes_to_5pct`` (first
  episode after which the 10-episode moving average stays at or below 1.05 x the
  task's ``reference_mean_steps``), ``greedy_episodes_to_5pct`` (first
  checkpoint from which the greedy policy, evaluated on the same fixed starts at
  every checkpoint and averaged over trials, stays at or below that bound), wall
  time;
* ``checkpoints.csv``: ``episode,greedy_mean_steps,greedy_sem_steps``;
* ``policy.json``: the greedy policy of the trial with the best greedy score;
* ``learning_curve.png``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from crmgrasp._io import save_figure, write_csv, write_json
from crmgrasp.agents import GreedyPolicy, TabularAgent, episodes_to_within, train_trials, train_trials_lockstep
from crmgrasp.agents.symmetric import SymmetricAgent
from crmgrasp.agents.training import DEFAULT_CHECKPOINTS, TrialResult, checkpoints_to_within
from crmgrasp.tasks import Task

__all__ = ["LearnerSpec", "LearnRun", "learn", "write_learn_outputs", "SYMMETRIC_DYNA_Q", "usable"]


@dataclass(frozen=True)
class LearnerSpec:
    """A learner to run: registered agent name, history order and parameters."""

    agent: str
    k: int = 2
    params: dict[str, Any] = field(default_factory=dict)
    label: str = ""

    @property
    def name(self) -> str:
        """Display name (``label`` or ``agent k=K``)."""
        return self.label or f"{self.agent} k={self.k}"


SYMMETRIC_DYNA_Q = LearnerSpec(
    "dyna-q", 1, {"planning": "sweep", "n_planning": 50, "symmetric": True}, "Dyna-Q k=1 (VI sweeps, mirror quotient)"
)
"""The fastest learner on paper-box: Dyna-Q with value-iteration sweeps on the mirror quotient."""


def usable(task: Task, specs: tuple[LearnerSpec, ...]) -> tuple[LearnerSpec, ...]:
    """``specs`` without the symmetric learners when ``task`` declares no symmetry."""
    return tuple(s for s in specs if task.symmetry is not None or not s.params.get("symmetric"))


@dataclass
class LearnRun:
    """A finished learning run."""

    spec: LearnerSpec
    result: TrialResult
    summary: dict[str, Any]


def learn(
    task: Task,
    spec: LearnerSpec,
    *,
    trials: int,
    episodes: int,
    seed: int,
    eval_episodes: int = 1000,
    checkpoint_episodes: int = 100,
    lockstep: bool = False,
    backend: str = "auto",
) -> LearnRun:
    """Train ``trials`` independent agents and summarise them. Episodes step through the
    task's kernel on ``backend`` (:func:`crmgrasp.kernels.kernel_for`), one trial after
    another or, with ``lockstep``, all trials together. Every choice gives the same
    results."""
    t0 = time.perf_counter()
    trainer = train_trials_lockstep if lockstep else train_trials
    res = trainer(
        task,
        spec.agent,
        trials=trials,
        episodes=episodes,
        seed=seed,
        k=spec.k,
        eval_episodes=eval_episodes,
        params=spec.params,
        checkpoints=DEFAULT_CHECKPOINTS if checkpoint_episodes else (),
        checkpoint_episodes=checkpoint_episodes,
        backend=backend,
    )
    curve = res.curve
    ref = task.reference_mean_steps
    per_trial = res.greedy_steps.mean(axis=1) if eval_episodes else np.full(trials, np.nan)
    params: dict[str, Any] = getattr(res.agents[0], "params", dict)()
    summary = {
        "agent": spec.agent,
        "label": spec.name,
        "task": task.name,
        "k": spec.k,
        "params": params,
        "trials": trials,
        "episodes": episodes,
        "seed": seed,
        "eval_episodes": eval_episodes,
        "final_mean_steps": float(curve[-10:].mean()),
        "greedy_mean_steps": float(per_trial.mean()),
        "greedy_sem_steps": float(per_trial.std(ddof=1) / np.sqrt(trials)) if trials > 1 else 0.0,
        "greedy_success_rate": float(res.greedy_success.mean()) if eval_episodes else float("nan"),
        "reference_mean_steps": ref,
        "episodes_to_5pct": episodes_to_within(curve, ref) if ref else None,
        "greedy_episodes_to_5pct": (
            checkpoints_to_within(res.checkpoints, res.checkpoint_steps.mean(axis=0), ref) if ref else None
        ),
        "checkpoint_episodes": checkpoint_episodes,
        "seconds": round(time.perf_counter() - t0, 3),
    }
    return LearnRun(spec, res, summary)


def best_policy(task: Task, run: LearnRun) -> GreedyPolicy | None:
    """Greedy policy of the trial with the lowest greedy mean (tabular agents only)."""
    agents = run.result.agents
    if not isinstance(agents[0], (TabularAgent, SymmetricAgent)):
        return None
    best = int(np.argmin(run.result.greedy_steps.mean(axis=1))) if run.result.greedy_steps.size else 0
    return GreedyPolicy.from_agent(task, run.spec.k, agents[best])  # type: ignore[arg-type]


def write_learn_outputs(task: Task, run: LearnRun, out_dir: str | Path) -> list[Path]:
    """Write ``curve.csv``, ``summary.json``, ``policy.json`` (tabular learners) and
    ``learning_curve.png``; return the paths."""
    from crmgrasp.plotting import learning_curve_figure

    out = Path(out_dir)
    res = run.result
    paths = [
        write_csv(
            out / "curve.csv",
            ["episode", "mean_steps", "sem_steps"],
            ([e + 1, float(m), float(s)] for e, (m, s) in enumerate(zip(res.curve, res.sem))),
        ),
        write_json(out / "summary.json", run.summary),
        write_csv(
            out / "checkpoints.csv",
            ["episode", "greedy_mean_steps", "greedy_sem_steps"],
            ([int(c), float(m), float(v)] for c, m, v in zip(res.checkpoints, *_mean_sem(res.checkpoint_steps))),
        ),
    ]
    policy = best_policy(task, run)
    if policy is not None:
        paths.append(policy.save(out / "policy.json"))
    fig = learning_curve_figure(
        {run.spec.name: (res.curve, res.sem)},
        task.reference_mean_steps,
        f"{run.spec.name} on {task.name}, {run.summary['trials']} trials",
    )
    paths.append(save_figure(fig, out / "learning_curve.png", dpi=120))
    return paths


def _mean_sem(values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Mean and standard error over the first axis (trials)."""
    n = values.shape[0]
    sem = values.std(axis=0, ddof=1) / np.sqrt(n) if n > 1 else np.zeros(values.shape[1:])
    return values.mean(axis=0), sem

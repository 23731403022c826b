"""One learning run (a learner on a task over many trials) and its files.

Used by ``crmgrasp learn`` and by Figure 7. Files written to the output folder:

* ``curve.csv``: ``episode,mean_steps,sem_steps`` (CRMs per training episode,
  mean and standard error over trials);
* ``summary.json``: agent, task, k, parameters, trials, episodes, seed,
  ``final_mean_steps`` (mean of the last 10 points of the curve),
  ``greedy_mean_steps`` (greedy evaluation on ``eval_episodes`` fresh episodes,
  averaged over trials) with ``greedy_ci95_over_trials`` (bootstrap over the
  per-trial means) and ``greedy_iqm_steps``, ``greedy_success_rate``, ``episodes_to_5pct`` (first
  episode after which the 10-episode moving average stays at or below 1.05 x the
  task's ``reference_mean_steps``), ``greedy_episodes_to_5pct`` (first
  checkpoint from which the greedy policy, evaluated on the same fixed starts at
  every checkpoint and averaged over trials, stays at or below that bound; ``null``
  = never), ``converged`` (whether ``episodes_to_5pct`` was reached), wall time,
  ``prior`` (the prior's task, episodes, weight and seed when the run used one:
  episodes on another task, learned once and shared by every trial; null when the run
  learned from scratch), ``hand`` (``kinematic``, or the hand the episodes ran on:
  ``mujoco``) and ``faults`` (episodes that hand ended early, by kind: physics faults
  and lost contacts; training and evaluation together);
* ``checkpoints.csv``: ``episode,greedy_mean_steps,greedy_sem_steps``;
* ``policy.json``: the greedy policy of the trial with the best greedy score (a deep
  learner's: ``policy.zip``, [`crmgrasp.agents.deep_trials`][]);
* ``learning_curve.png``.
"""

from __future__ import annotations

import time
from collections import Counter
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np

from crmgrasp._io import atomic_path, save_figure, write_csv, write_json
from crmgrasp._progress import Progress
from crmgrasp._validation import CrmgraspError, is_finite_number
from crmgrasp.agents import GreedyPolicy, TabularAgent, episodes_to_within, train_trials, train_trials_lockstep
from crmgrasp.agents.deep import DEEP_AGENTS
from crmgrasp.agents.deep_trials import SavedDeepPolicy, deep_settings, train_deep_trials
from crmgrasp.agents.symmetric import SymmetricAgent
from crmgrasp.agents.training import (
    DEFAULT_CHECKPOINTS,
    PRIOR_KEYS,
    TrialResult,
    build_agent,
    check_budget,
    checkpoints_to_within,
    encoder_for,
    prior_settings,
)
from crmgrasp.experiments.parallel import run_parallel, usable_jobs
from crmgrasp.experiments.runs import RunFolder
from crmgrasp.experiments.stats import bootstrap_ci, budget, iqm
from crmgrasp.hardware import hand_steps
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
"""Dyna-Q with value-iteration sweeps on the mirror quotient (the comparison's model-free-plus-planning learner)."""


def usable(task: Task, specs: tuple[LearnerSpec, ...]) -> tuple[LearnerSpec, ...]:
    """``specs`` without the symmetric learners when ``task`` declares no symmetry."""
    return tuple(s for s in specs if task.symmetry is not None or not s.params.get("symmetric"))


@dataclass
class LearnRun:
    """A finished learning run: curves and evaluations of every trial (``result``; its
    ``agents`` are empty, the trials may have run in other processes or earlier
    sessions), the summary, and the policy of the trial with the best greedy score
    (tabular and deep learners; else ``None``)."""

    spec: LearnerSpec
    result: TrialResult
    summary: dict[str, Any]
    policy: GreedyPolicy | SavedDeepPolicy | None = None


@dataclass
class _Part:
    """The results of one group of trials."""

    steps: np.ndarray
    success: np.ndarray
    greedy_steps: np.ndarray
    greedy_success: np.ndarray
    checkpoints: np.ndarray
    checkpoint_steps: np.ndarray
    policy: GreedyPolicy | SavedDeepPolicy | None
    score: float
    faults: dict[str, int] = field(default_factory=dict)


_ARRAYS = ("steps", "success", "greedy_steps", "greedy_success", "checkpoints", "checkpoint_steps")


def _part(task: Task, spec: LearnerSpec, res: TrialResult) -> _Part:
    arrays: list[Any] = [getattr(res, a) for a in _ARRAYS]
    scores = res.greedy_steps.mean(axis=1) if res.greedy_steps.size else np.zeros(len(res.agents))
    best = int(np.argmin(scores))
    agent: Any = res.agents[best]
    policy: GreedyPolicy | SavedDeepPolicy | None = agent if isinstance(agent, SavedDeepPolicy) else None
    if isinstance(agent, (TabularAgent, SymmetricAgent)):
        policy = GreedyPolicy.from_agent(task, spec.k, agent)
    return _Part(*arrays, policy, float(scores[best]), res.faults)  # type: ignore[misc,call-arg]


def _save_part(store: RunFolder, unit: str, part: _Part) -> None:
    stem = store.path / "trials" / unit.replace("trials ", "").replace("-", "_")
    with atomic_path(stem.with_suffix(".npz")) as tmp, open(tmp, "wb") as fh:
        np.savez(fh, **{a: getattr(part, a) for a in _ARRAYS})
    if part.policy is not None:
        part.policy.save(_policy_file(stem, part.policy.file_name))
    store.complete(unit, {"file": str(stem.relative_to(store.path)), "score": part.score, "faults": part.faults})


def _bad_array(arrays: list[np.ndarray], n: int, episodes: int, evals: int, max_steps: int) -> str | None:
    """The name of the first of a saved group's arrays (``_ARRAYS``' order) that is not what
    training writes for ``n`` trials of ``episodes`` episodes and ``evals`` evaluation
    episodes (shapes, kinds, CRM counts and checkpoint means in ``[0, max_steps]``, checkpoints
    increasing within the episodes); None if all are."""
    steps, success, gsteps, gsucc, ckpts, csteps = arrays

    def counts(a: np.ndarray, shape: tuple[int, ...]) -> bool:
        return a.shape == shape and a.dtype.kind in "iu" and bool(((a >= 0) & (a <= max_steps)).all())

    checks = (
        counts(steps, (n, episodes)),
        success.shape == (n, episodes) and success.dtype == bool,
        counts(gsteps, (n, evals)),
        gsucc.shape == (n, evals) and gsucc.dtype == bool,
        ckpts.ndim == 1
        and ckpts.dtype.kind in "iu"
        and bool(((ckpts >= 1) & (ckpts <= episodes)).all() and (np.diff(ckpts) > 0).all()),
        csteps.shape == (n, ckpts.size)
        and csteps.dtype.kind == "f"
        and bool(((csteps >= 0) & (csteps <= max_steps)).all()),
    )
    return next((name for name, ok in zip(_ARRAYS, checks, strict=True) if not ok), None)


def _load_part(task: Task, store: RunFolder, unit: str, info: Any, trials: int, episodes: int, evals: int) -> _Part:
    if not isinstance(info, dict) or not isinstance(info.get("file"), str) or "score" not in info:
        raise CrmgraspError(f"run record of {str(store.path)!r} is damaged ({unit})")
    stem = store.path / info["file"]
    try:
        with np.load(stem.with_suffix(".npz"), allow_pickle=False) as z:
            arrays = [z[a] for a in _ARRAYS]
    except (OSError, ValueError, KeyError) as exc:
        raise CrmgraspError(f"cannot resume: {unit} of {str(store.path)!r} is damaged ({exc})") from None
    bad = _bad_array(arrays, trials, episodes, evals, task.max_steps)
    if bad is not None:
        raise CrmgraspError(f"cannot resume: {unit} of {str(store.path)!r} is damaged ({bad})")
    policy = _load_policy(task, stem)
    faults, score = info.get("faults", {}), info["score"]
    if not isinstance(faults, dict) or not all(isinstance(v, int) for v in faults.values()):
        raise CrmgraspError(f"run record of {str(store.path)!r} is damaged ({unit}: faults)")
    if not is_finite_number(score):
        raise CrmgraspError(f"run record of {str(store.path)!r} is damaged ({unit}: score)")
    return _Part(*arrays, policy, float(score), faults)  # type: ignore[misc,call-arg]


def _policy_file(stem: Path, file_name: str) -> Path:
    """Where a group of trials keeps its best policy: ``<group>.policy.json`` or ``.policy.zip``."""
    return stem.with_suffix(".policy" + Path(file_name).suffix)


def _load_policy(task: Task, stem: Path) -> GreedyPolicy | SavedDeepPolicy | None:
    """A saved group's best policy, checked as its loader checks it (None if it saved none)."""
    tabular, deep = _policy_file(stem, GreedyPolicy.file_name), _policy_file(stem, SavedDeepPolicy.file_name)
    if tabular.exists():
        return GreedyPolicy.load(tabular, task)
    if deep.exists():
        from crmgrasp.agents.deep import RecurrentPolicy

        RecurrentPolicy.load(deep, task)  # a damaged or foreign file: one line, before it is used
        return SavedDeepPolicy(deep.read_bytes())
    return None


def _groups(trials: int, lockstep: bool) -> list[tuple[int, int]]:
    """``(first, count)`` of each group of trials run (and saved) together: at most 50
    groups (10 in lockstep, which gains from large groups)."""
    size = -(-trials // (10 if lockstep else 50))
    return [(f, min(size, trials - f)) for f in range(0, trials, size)]


@dataclass(frozen=True)
class _GroupJob:
    """Trains one group of trials (picklable: runs in a worker process too)."""

    task: Task
    spec: LearnerSpec
    lockstep: bool
    episodes: int
    seed: int
    eval_episodes: int
    checkpoint_episodes: int
    backend: str
    hand: str = "kinematic"

    def __call__(self, first: int, n: int, progress: Progress | None = None) -> _Part:
        common: dict[str, Any] = {
            "trials": n,
            "episodes": self.episodes,
            "seed": self.seed,
            "eval_episodes": self.eval_episodes,
            "params": self.spec.params,
            "checkpoints": DEFAULT_CHECKPOINTS if self.checkpoint_episodes else (),
            "checkpoint_episodes": self.checkpoint_episodes,
            "backend": self.backend,
            "first_trial": first,
            "progress": progress,
        }
        if self.spec.agent in DEEP_AGENTS:
            return _part(self.task, self.spec, train_deep_trials(self.task, self.spec.agent, **common))
        trainer = train_trials_lockstep if self.lockstep else train_trials
        if self.hand != "kinematic":
            common["stepper"] = hand_steps(self.hand)
        return _part(self.task, self.spec, trainer(self.task, self.spec.agent, k=self.spec.k, **common))


def check_hand(hand: str, lockstep: bool = False, agent: str | None = None) -> None:
    """One-line errors for a hand that cannot run: unknown, its extra missing, or with
    ``lockstep`` (which steps the kinematic model only); and for a deep learner ``agent``
    with ``lockstep`` or another hand (it trains on the kinematic model's environments)."""
    if hand_steps(hand) is not None and lockstep:
        raise CrmgraspError(f"lockstep steps the kinematic model only, not the {hand} hand")
    if agent in DEEP_AGENTS and (lockstep or hand != "kinematic"):
        what = "lockstep" if lockstep else f"the {hand} hand"
        raise CrmgraspError(f"the deep learner {agent!r} trains on the kinematic model's environments, not with {what}")


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
    store: RunFolder | None = None,
    progress: Progress | None = None,
    jobs: int = 1,
    hand: str = "kinematic",
) -> LearnRun:
    """Train ``trials`` independent agents and summarise them. Episodes step through the
    task's kernel on ``backend`` ([`crmgrasp.kernels.kernel_for`][]), one trial after
    another or, with ``lockstep``, many trials together. Every choice gives the same
    results.

    With a run folder ``store``, each group of trials is saved as it completes
    (``trials/*.npz`` and the group's best policy) and groups already recorded there are
    loaded instead of trained: a resumed run gives the results of an uninterrupted one.
    ``progress`` shows the training episodes done. ``jobs`` worker processes (0: every
    usable core) train groups of trials at once; the results do not depend on it.
    ``hand`` runs every episode (training, checkpoints, evaluation) on another hand of
    [`crmgrasp.hardware.HANDS`][] (``mujoco``: the physics stand-in) instead of the
    kinematic model."""
    check_budget(trials, episodes, eval_episodes)
    usable_jobs(jobs)  # a bad value fails before any work
    check_hand(hand, lockstep, spec.agent)
    t0 = time.perf_counter()
    job = _GroupJob(task, spec, lockstep, episodes, seed, eval_episodes, checkpoint_episodes, backend, hand)
    stage = progress.stage(f"{spec.name} on {task.name}", trials * episodes, "episodes") if progress else None
    parts, pending = _recorded_parts(task, store, _groups(trials, lockstep), (episodes, eval_episodes), stage)

    def finished(first: int, unit: str, part: _Part) -> None:
        parts[first] = part
        if store is not None:
            _save_part(store, unit, part)

    if usable_jobs(jobs) > 1 and len(pending) > 1:
        calls = [((first, n, unit), partial(job, first, n)) for first, n, unit in pending]
        for (first, n, unit), part in run_parallel(calls, jobs):
            finished(first, unit, part)
            if stage:
                stage.advance(n * episodes)
    else:
        for first, n, unit in pending:
            finished(first, unit, job(first, n, stage))
    parts_list = [parts[f] for f in sorted(parts)]
    if stage:
        stage.end()
    if any(not np.array_equal(p.checkpoints, parts_list[0].checkpoints) for p in parts_list):
        where = str(store.path) if store is not None else "the run"
        raise CrmgraspError(f"cannot resume: the groups of trials of {where!r} differ in their checkpoints (damaged)")
    joined = {a: np.concatenate([getattr(p, a) for p in parts_list]) for a in _ARRAYS if a != "checkpoints"}
    res = TrialResult(agents=[], checkpoints=parts_list[0].checkpoints, **joined)  # type: ignore[arg-type]
    best = min(range(len(parts_list)), key=lambda i: (parts_list[i].score, i))
    summary = _summary(task, spec, res, trials, episodes, seed, eval_episodes, checkpoint_episodes)
    summary["hand"] = hand
    summary["faults"] = dict(sorted(sum((Counter(p.faults) for p in parts_list), Counter()).items()))
    summary["seconds"] = round(time.perf_counter() - t0, 3)
    return LearnRun(spec, res, summary, parts_list[best].policy)


def _recorded_parts(
    task: Task,
    store: RunFolder | None,
    groups: list[tuple[int, int]],
    budget: tuple[int, int],
    stage: Progress | None,
) -> tuple[dict[int, _Part], list[tuple[int, int, str]]]:
    """The groups of trials (first trial, count) that ``store`` records as done, loaded, by
    their first trial; and the others, still to train, with their unit names. ``budget``:
    training and evaluation episodes per trial."""
    episodes, evals = budget
    parts: dict[int, _Part] = {}
    pending = []
    for first, n in groups:
        unit = f"trials {first:05d}-{first + n - 1:05d}"
        info = store.done(unit) if store is not None else None
        if info is not None:
            parts[first] = _load_part(task, store, unit, info, n, episodes, evals)  # type: ignore[arg-type]
            if stage:
                stage.advance(n * episodes)
        else:
            pending.append((first, n, unit))
    return parts, pending


def _summary(
    task: Task,
    spec: LearnerSpec,
    res: TrialResult,
    trials: int,
    episodes: int,
    seed: int,
    eval_episodes: int,
    checkpoint_episodes: int,
) -> dict[str, Any]:
    curve = res.curve
    ref = task.reference_mean_steps
    per_trial = res.greedy_steps.mean(axis=1) if eval_episodes else np.full(trials, np.nan)
    deep = spec.agent in DEEP_AGENTS
    if deep:
        params = deep_settings(spec.agent, spec.params)
    else:
        agent = build_agent(task, encoder_for(task, spec.k), spec.agent, spec.params)
        params = getattr(agent, "params", dict)()
        params.update({key: spec.params[key] for key in PRIOR_KEYS if key in spec.params})  # not the agent's own
    return {
        "agent": spec.agent,
        "label": spec.name,
        "task": task.name,
        "k": None if deep else spec.k,
        "params": params,
        "trials": trials,
        "episodes": episodes,
        "seed": seed,
        "eval_episodes": eval_episodes,
        "final_mean_steps": float(curve[-10:].mean()),
        "greedy_mean_steps": float(per_trial.mean()),
        "greedy_sem_steps": float(per_trial.std(ddof=1) / np.sqrt(trials)) if trials > 1 else 0.0,
        "greedy_ci95_over_trials": list(bootstrap_ci(per_trial, seed)),
        "greedy_iqm_steps": iqm(per_trial),
        "greedy_success_rate": float(res.greedy_success.mean()) if eval_episodes else float("nan"),
        "reference_mean_steps": ref,
        "episodes_to_5pct": episodes_to_within(curve, ref) if ref else None,
        "greedy_episodes_to_5pct": (
            checkpoints_to_within(res.checkpoints, res.checkpoint_steps.mean(axis=0), ref) if ref else None
        ),
        "checkpoint_episodes": checkpoint_episodes,
        "converged": (episodes_to_within(curve, ref) is not None) if ref else None,
        "prior": prior_settings(spec.params),
    }


def best_policy(task: Task, run: LearnRun) -> GreedyPolicy | SavedDeepPolicy | None:
    """The policy of the trial with the lowest greedy mean (tabular and deep learners)."""
    return run.policy


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
        paths.append(policy.save(out / policy.file_name))
    title = f"{run.spec.name} on {task.name}, " + budget(*(run.summary[k] for k in ("trials", "episodes", "seed")))
    if task.reference_mean_steps is None:  # say why no optimum is drawn, and how to get one
        title += "\nno optimum line: the task states no reference_mean_steps (crmgrasp references computes it)"
    fig = learning_curve_figure({run.spec.name: (res.curve, res.sem)}, task.reference_mean_steps, title)
    paths.append(save_figure(fig, out / "learning_curve.png", dpi=120))
    return paths


def _mean_sem(values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Mean and standard error over the first axis (trials)."""
    n = values.shape[0]
    sem = values.std(axis=0, ddof=1) / np.sqrt(n) if n > 1 else np.zeros(values.shape[1:])
    return values.mean(axis=0), sem

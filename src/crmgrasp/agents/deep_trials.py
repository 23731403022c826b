"""Deep learners as trials of ``crmgrasp learn``: RecurrentPPO, PPO and SAC, counted in episodes.

[`train_deep_trials`][] gives what [`crmgrasp.agents.training.train_trials`][] gives for a
tabular learner (a [`TrialResult`][crmgrasp.agents.training.TrialResult]): each trial trains
one stable-baselines3 model until ``episodes`` task episodes have ended (the budget is
episodes, as for every learner of the package, not environment steps), with greedy
checkpoints on the same fixed starts after the same numbers of episodes, then evaluates it
greedily on ``eval_episodes`` fresh episodes. Each trial's model is seeded from the trial's
own generator ([`trial_generators`][crmgrasp.agents.training.trial_generators]), so trials
run in any grouping and process with the same results.

The learners ([`DEEP_AGENTS`][crmgrasp.agents.deep.DEEP_AGENTS]):

* ``recurrent-ppo``: sb3-contrib's RecurrentPPO, an LSTM policy that reads the episode's
  observations from its start (the deep peer of `crmgrasp compare`);
* ``ppo``: PPO with a two-layer MLP on the current observation only (no memory: the
  peer of a first-order learner without its last action);
* ``sac``: SAC, continuous actions only, on the same input.

Each acts in the task's CRMs or, with ``continuous=True`` (always for ``sac``), in its
continuous action space: a contact pair and a real offset, through the flat ``Box`` of
[`FlatCRMAction`][crmgrasp.envs.continuous.FlatCRMAction]. The input is
[`features`][crmgrasp.agents.deep.features] of the sensed observation. Needs the extra
``crmgrasp[deep]``.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from crmgrasp._progress import Progress
from crmgrasp._validation import CrmgraspError, known, shown
from crmgrasp.agents.deep import (
    DEEP_AGENTS,
    RecurrentPolicy,
    RecurrentPPOConfig,
    _modules,
    env_maker,
    evaluate_recurrent,
    make_model,
)
from crmgrasp.agents.training import TrialResult, check_budget, checkpoint_generators, trial_generators
from crmgrasp.tasks import Task

__all__ = [
    "DEEP_AGENTS",
    "deep_defaults",
    "deep_config",
    "check_deep",
    "deep_settings",
    "SavedDeepPolicy",
    "train_deep_trials",
]


_PARAMETERS = ("gamma", "continuous")


def deep_defaults(name: str) -> dict[str, object]:
    """The parameters deep learner ``name`` takes on the command line, with their defaults
    (the rest of [`RecurrentPPOConfig`][crmgrasp.agents.deep.RecurrentPPOConfig] keeps its own)."""
    base = RecurrentPPOConfig()
    return {"gamma": base.gamma, "continuous": not DEEP_AGENTS[name].discrete}


def deep_config(name: str, params: dict[str, object] | None = None) -> RecurrentPPOConfig:
    """The settings of deep learner ``name`` with ``params`` (``gamma``, ``continuous``) on
    top; one-line errors for an unknown learner, an unknown parameter or a discrete SAC."""
    known(name, DEEP_AGENTS, "deep learner")
    if params is not None and not isinstance(params, dict):
        raise CrmgraspError(f"deep learner parameters must be a dict, got {shown(params)}")
    given = dict(params or {})
    for key in given:
        if key not in _PARAMETERS:
            raise CrmgraspError(f"deep learner {name!r} has no parameter {key!r}; it takes {', '.join(_PARAMETERS)}")
    settings = {**deep_defaults(name), **given}
    if not settings["continuous"] and not DEEP_AGENTS[name].discrete:
        raise CrmgraspError(f"deep learner {name!r} acts in the continuous action space only (continuous=True)")
    return RecurrentPPOConfig(gamma=settings["gamma"], continuous=settings["continuous"])  # type: ignore[arg-type]


def check_deep(name: str, params: dict[str, object] | None = None) -> None:
    """One-line errors, before any work, for bad settings of deep learner ``name`` or a
    missing extra ``crmgrasp[deep]``."""
    deep_config(name, params)
    _modules()


def deep_settings(name: str, params: dict[str, object] | None = None) -> dict[str, Any]:
    """Every setting a run of deep learner ``name`` uses, as plain data (for ``summary.json``)."""
    out = asdict(deep_config(name, params))
    for unused in ("total_steps", "checkpoint_episodes"):  # the run's budget and checkpoints set these
        out.pop(unused)
    return {"algorithm": DEEP_AGENTS[name].algorithm, **out}


@dataclass(frozen=True)
class SavedDeepPolicy:
    """A trained deep policy as its policy file's bytes
    ([`RecurrentPolicy.to_bytes`][crmgrasp.agents.deep.RecurrentPolicy.to_bytes]): what a
    trial returns across processes and a run folder keeps."""

    data: bytes
    file_name: ClassVar[str] = "policy.zip"

    def save(self, path: str | Path) -> Path:
        """Write the policy file atomically to ``path``."""
        from crmgrasp._io import atomic_write_bytes

        return atomic_write_bytes(path, self.data)


@dataclass
class _Tally:
    """One trial's finished training episodes and its greedy checkpoints."""

    steps: np.ndarray
    success: np.ndarray
    checkpoint_steps: np.ndarray
    count: int = 0
    next_checkpoint: int = 0


def train_deep_trials(
    task: Task,
    agent: str,
    *,
    trials: int,
    episodes: int,
    seed: int,
    eval_episodes: int = 1000,
    params: dict[str, object] | None = None,
    checkpoints: tuple[int, ...] = (),
    checkpoint_episodes: int = 100,
    backend: str = "auto",
    first_trial: int = 0,
    progress: Progress | None = None,
) -> TrialResult:
    """Train ``trials`` models of deep learner ``agent`` for ``episodes`` task episodes each
    and evaluate each greedily on ``eval_episodes`` fresh episodes (module docstring). The
    checkpoints' starts are drawn once from
    [`checkpoint_generators`][crmgrasp.agents.training.checkpoint_generators] and each
    checkpoint reads them with the same noise stream; environments step through the kernel
    on ``backend``. The result's ``agents`` are [`SavedDeepPolicy`][] files."""
    check_budget(trials, episodes, eval_episodes)
    config = deep_config(agent, params)
    torch, _, vec, _ = _modules()
    ckpts = np.array(sorted({c for c in checkpoints if 1 <= c <= episodes}), dtype=np.int64)
    starts_rng = checkpoint_generators(seed)[0]
    fixed = [task.sample_world(starts_rng) for _ in range(checkpoint_episodes)] if len(ckpts) else []
    steps = np.empty((trials, episodes), dtype=np.int64)
    success = np.empty((trials, episodes), dtype=bool)
    gsteps = np.empty((trials, eval_episodes), dtype=np.int64)
    gsucc = np.empty((trials, eval_episodes), dtype=bool)
    csteps = np.empty((trials, len(ckpts)))
    policies = []
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        for t, (env_rng, _, eval_rng) in enumerate(trial_generators(seed, trials, first_trial)):
            tally = _Tally(steps[t], success[t], csteps[t])
            envs = vec.DummyVecEnv([env_maker(task, config, backend)] * config.n_envs)
            model = make_model(agent, envs, config, int(env_rng.integers(2**31 - 1)), episodes * task.max_steps)
            track = _tracker(task, tally, ckpts, fixed, seed, progress)
            model.learn(episodes * task.max_steps + config.n_envs * config.n_steps, callback=track)
            if tally.count < episodes:  # cannot happen: every episode ends within max_steps CRMs
                raise CrmgraspError(f"trial {first_trial + t} ended {tally.count} of {episodes} episodes")
            starts = [task.sample_world(eval_rng) for _ in range(eval_episodes)]
            gsteps[t], gsucc[t] = evaluate_recurrent(model, task, starts, eval_rng)
            policies.append(SavedDeepPolicy(RecurrentPolicy(model, task).to_bytes()))
    finally:
        torch.set_num_threads(threads)
    return TrialResult(steps, success, gsteps, gsucc, policies, ckpts, csteps)  # type: ignore[arg-type]


def _tracker(
    task: Task, tally: _Tally, ckpts: np.ndarray, fixed: list[Any], seed: int, progress: Progress | None
) -> Any:
    """A callback that records each finished training episode (CRMs, and success from its
    last step's ``min_friction``), evaluates the greedy policy when the count reaches a
    checkpoint, advances ``progress`` per episode, and stops training at the budget."""
    from stable_baselines3.common.callbacks import BaseCallback

    budget = len(tally.steps)

    class Track(BaseCallback):  # type: ignore[misc]
        def _on_step(self) -> bool:
            for done, info in zip(self.locals["dones"], self.locals["infos"]):
                if not done or tally.count >= budget:
                    continue
                tally.steps[tally.count] = int(info["steps"])
                tally.success[tally.count] = bool(task.grasped(info["min_friction"]))
                tally.count += 1
                if progress is not None:
                    progress.advance(1)
                while tally.next_checkpoint < len(ckpts) and ckpts[tally.next_checkpoint] <= tally.count:
                    rng = checkpoint_generators(seed)[1]  # the same noise stream at every checkpoint
                    got = evaluate_recurrent(self.model, task, fixed, rng)[0]
                    tally.checkpoint_steps[tally.next_checkpoint] = got.mean()
                    tally.next_checkpoint += 1
            return tally.count < budget

    return Track()

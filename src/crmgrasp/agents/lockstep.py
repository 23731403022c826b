"""Many independent trials in lockstep: one batched simulator call per step.

[`train_trials_lockstep`][] gives exactly the results of
[`train_trials`][crmgrasp.agents.training.train_trials] for the same arguments (the tests
compare curves and Q tables): each trial keeps its own agent and its own three
generators, and draws from them in the same order as the sequential loop; only
the CRM executions of all trials that are mid-episode go through the task's
kernel together ([`crmgrasp.kernels.rows.KernelRows`][] in the batched episode loop,
[`crmgrasp.sim.run_batch`][]), which is bit-identical to [`crmgrasp.sim.step`][].
"""

from __future__ import annotations

import numpy as np

from crmgrasp._progress import Progress
from crmgrasp._validation import CrmgraspError
from crmgrasp.agents.base import Agent, LearnerPolicy
from crmgrasp.agents.training import (
    PROGRESS_EVERY,
    TrialResult,
    build_agent,
    check_budget,
    checkpoint_generators,
    encoder_for,
    evaluate,
    trial_generators,
)
from crmgrasp.kernels import kernel_for
from crmgrasp.kernels.rows import KernelRows
from crmgrasp.model.history import KOrderEncoder
from crmgrasp.sim import Episode, RowPolicies, run_batch
from crmgrasp.tasks import Task

__all__ = ["train_trials_lockstep"]


class _Trial:
    """The mutable state of one trial between lockstep steps."""

    __slots__ = ("agent", "env_rng", "episode", "eval_rng", "next_checkpoint", "policy")

    def __init__(self, agent: Agent, encoder: KOrderEncoder, gens: tuple[np.random.Generator, ...]) -> None:
        self.agent = agent
        self.env_rng, agent_rng, self.eval_rng = gens
        self.policy = LearnerPolicy(agent, encoder, agent_rng)
        self.episode = 0
        self.next_checkpoint = 0


def train_trials_lockstep(
    task: Task,
    agent: str,
    *,
    trials: int,
    episodes: int,
    seed: int,
    k: int = 2,
    eval_episodes: int = 1000,
    params: dict[str, object] | None = None,
    checkpoints: tuple[int, ...] = (),
    checkpoint_episodes: int = 100,
    backend: str = "auto",
    first_trial: int = 0,
    progress: Progress | None = None,
) -> TrialResult:
    """Lockstep version of [`train_trials`][crmgrasp.agents.training.train_trials] (same
    arguments, same results); faster when ``trials`` is large (hundreds or more). Not for a
    family task: its trials' objects differ, and lockstep shares one batched kernel."""
    if task.family is not None:
        raise CrmgraspError(
            f"lockstep steps every trial through one batched kernel, but task {task.name!r} draws an object "
            "per episode: train without lockstep"
        )
    check_budget(trials, episodes, eval_episodes)
    encoder = encoder_for(task, k)
    kernel = kernel_for(task, backend)
    ckpts = np.array(sorted({c for c in checkpoints if 1 <= c <= episodes}), dtype=np.int64)
    steps = np.empty((trials, episodes), dtype=np.int64)
    success = np.empty((trials, episodes), dtype=bool)
    csteps = np.empty((trials, len(ckpts)))
    runs = [
        _Trial(build_agent(task, encoder, agent, params), encoder, g)
        for g in trial_generators(seed, trials, first_trial)
    ]
    finished = [0]

    def more(t: int, last: Episode | None) -> bool:
        """Record the trial's episode that ended (and run a checkpoint's evaluation after it);
        whether the trial runs another."""
        tr = runs[t]
        if last is None:
            return True
        steps[t, tr.episode], success[t, tr.episode] = last.steps, last.success
        tr.episode += 1
        finished[0] += 1
        if progress is not None and finished[0] == PROGRESS_EVERY:
            progress.advance(finished[0])
            finished[0] = 0
        j = tr.next_checkpoint
        if j < len(ckpts) and ckpts[j] == tr.episode:
            starts_rng, ties_rng = checkpoint_generators(seed)
            ck = evaluate(task, tr.agent, encoder, checkpoint_episodes, starts_rng, ties_rng, kernel=kernel)
            csteps[t, j] = ck[0].mean()
            tr.next_checkpoint += 1
        return tr.episode < episodes

    rows = KernelRows(task, kernel, [tr.env_rng for tr in runs])
    run_batch(rows, RowPolicies([tr.policy for tr in runs]), trials, more)
    if progress is not None:
        progress.advance(finished[0])
    gsteps = np.empty((trials, eval_episodes), dtype=np.int64)
    gsucc = np.empty((trials, eval_episodes), dtype=bool)
    for t, tr in enumerate(runs):
        gsteps[t], gsucc[t] = evaluate(task, tr.agent, encoder, eval_episodes, tr.eval_rng, kernel=kernel)
    return TrialResult(steps, success, gsteps, gsucc, [tr.agent for tr in runs], ckpts, csteps)

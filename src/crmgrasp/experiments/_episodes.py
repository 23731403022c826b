"""What the family experiments share: traced episodes as records, and the learners they
train (``model-vi``, k = 1, on the mirror quotient where the task declares one, or a
learner preset) with their greedy policies run on fixed worlds."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from crmgrasp.agents.base import Agent, LearnerPolicy
from crmgrasp.agents.presets import apply_preset
from crmgrasp.agents.training import encoder_for, train_trials
from crmgrasp.kernels import kernel_for
from crmgrasp.model.contacts import Config, Grip
from crmgrasp.sim import Policy, run_episode
from crmgrasp.tasks import Task

__all__ = ["EpisodeRecord", "episode_records", "train_model_vi", "train_preset", "greedy_records", "MODEL_VI_LABEL"]

MODEL_VI_LABEL = "model-vi k=1 (mirror quotient)"
"""How the experiments name the learner of [`train_model_vi`][]."""


@dataclass(frozen=True)
class EpisodeRecord:
    """One traced episode: the first observation (bin index), the CRMs taken, the
    observation (bin index) and error after each, success, and the final configuration."""

    first_obs: int
    actions: tuple[int, ...]
    observations: tuple[int, ...]
    errors: tuple[bool, ...]
    success: bool
    final: Config | Grip | None = None


def episode_records(
    task: Task, make_policy: Callable[[], Policy], worlds: Sequence[Any], seed: int
) -> list[EpisodeRecord]:
    """Run ``make_policy()`` from each world (noise-free: nothing is drawn) with traces."""
    kernel = kernel_for(task)
    rng = np.random.default_rng(seed)
    out = []
    for w in worlds:
        ep = run_episode(task, make_policy(), rng, start=w, trace=True, kernel=kernel)
        tr = ep.trace
        out.append(
            EpisodeRecord(
                tr[0].before.obs_index,
                tuple(int(t.action) for t in tr),  # type: ignore[arg-type]
                tuple(t.after.obs_index for t in tr),
                tuple(int(t.after.error) != 0 for t in tr),
                ep.success,
                tr[-1].after.state.config,
            )
        )
    return out


def train_model_vi(
    task: Task, trials: int, episodes: int, seed: int, learner: str = "model-vi", **params: object
) -> list[Agent]:
    """``trials`` model-vi agents (k = 1, mirror quotient where declared), trained on ``task``
    (or another k = 1 ``learner`` of ModelVI's kind, such as ``refine-vi``, with ``params``)."""
    params = {"symmetric": task.symmetry is not None, **params}
    res = train_trials(task, learner, trials=trials, episodes=episodes, seed=seed, k=1, eval_episodes=0, params=params)
    return res.agents


def train_preset(
    task: Task, preset: str, trials: int, episodes: int, seed: int, **params: object
) -> tuple[list[Agent], int]:
    """``trials`` agents of the learner preset ``preset`` (``crmgrasp learn --preset``:
    its agent, history order, mirror quotient and parameters, with ``params`` on top)
    trained on ``task``, and that history order."""
    choice = apply_preset(preset, task)
    params = {"symmetric": choice.symmetric, **dict(choice.params), **params}
    res = train_trials(
        task, choice.agent, trials=trials, episodes=episodes, seed=seed, k=choice.k, eval_episodes=0, params=params
    )
    return res.agents, choice.k


def greedy_records(
    task: Task,
    agents: Sequence[Agent],
    worlds: Sequence[Any],
    seed: int,
    ties: Callable[[int], Any] | None = None,
    k: int = 1,
) -> list[list[EpisodeRecord]]:
    """Per agent, its greedy policy's records on ``worlds`` (k-order histories, ``k``); in
    every episode agent ``t`` breaks ties with a fresh ``ties(t)`` (default
    ``default_rng([seed, t])``)."""
    encoder = encoder_for(task, k)
    draw = ties if ties is not None else (lambda t: np.random.default_rng([seed, t]))
    out = []
    for t, agent in enumerate(agents):

        def greedy(a: Agent = agent, i: int = t) -> Policy:
            return LearnerPolicy(a, encoder, draw(i), learn=False)

        out.append(episode_records(task, greedy, worlds, seed + t))
    return out

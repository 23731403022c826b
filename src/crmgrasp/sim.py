"""Pure episode dynamics of a task: ``reset`` and ``step`` on an immutable state.

The Gymnasium environment and the fast training loops both use these functions,
so they produce the same episodes from the same generator.

Sensing: each configuration is read once. The observation ``o_t`` is computed from
that reading, and the CRM executed at time ``t`` builds its goal line from the same
reading (SPEC section 4). With the task's noise off, readings are exact and draw
nothing from the generator.

Draw order: ``reset`` draws the start (the task's sampler) then one reading;
``step`` draws one reading of the configuration after the CRM.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .contacts import Config
from .hand import Outcome, execute_crm
from .quality import min_friction
from .sensing import Error, Observation, observe
from .tasks import Task

__all__ = ["SimState", "StepResult", "reset", "step"]


class SimState(NamedTuple):
    """True configuration, its sensed reading, and CRMs executed so far."""

    config: Config
    sensed: Config
    steps: int


class StepResult(NamedTuple):
    """Outcome of one CRM (reward -1 per CRM)."""

    state: SimState
    observation: Observation
    error: Error
    obs_index: int
    reward: float
    terminated: bool
    truncated: bool
    min_friction: float
    outcome: Outcome


def reset(task: Task, rng: np.random.Generator) -> tuple[SimState, Observation, int]:
    """Draw a start; return the state, its observation and discretized index (error none)."""
    config = task.sample_start(rng)
    sensed = task.noise.sense(config, rng)
    obs = observe(sensed)
    return SimState(config, sensed, 0), obs, task.discretizer.index(obs, Error.NONE)


def step(task: Task, state: SimState, action: int, rng: np.random.Generator) -> StepResult:
    """Execute ``task.actions[action]`` from ``state``.

    ``terminated`` when the true configuration is a grasp (``min_friction <=
    mu_goal``); ``truncated`` when ``max_steps`` CRMs have been executed without.
    """
    out = execute_crm(task.obj, task.hand, state.config, task.actions[action], state.sensed)
    noise = task.noise
    sensed = noise.sense(out.config, rng) if noise.sigma_n or noise.sigma_p else out.config
    obs = observe(sensed)
    mu = min_friction(out.config)
    steps = state.steps + 1
    terminated = mu <= task.mu_goal
    return StepResult(
        SimState(out.config, sensed, steps),
        obs,
        out.error,
        task.discretizer.index(obs, out.error),
        -1.0,
        terminated,
        (not terminated) and steps >= task.max_steps,
        mu,
        out,
    )

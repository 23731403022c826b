"""Pure episode dynamics of a task: ``reset`` and ``step`` on an immutable state.

This is the reference definition of an episode: the environments, training,
evaluation, planners and runners step through it, or through a kernel of
:mod:`crmgrasp.kernels` that is tested equal to it bit for bit.

Sensing: each configuration is read once. The observation ``o_t`` is computed from
that reading, and the CRM executed at time ``t`` builds its goal line from the same
reading (SPEC section 4). With the task's noise off, readings are exact and draw
nothing from the generator.

Draw order: ``reset`` draws the start (the task's sampler) then one reading;
``step`` draws one reading of the configuration after the CRM.
"""

from __future__ import annotations

from typing import Any, NamedTuple, overload

import numpy as np
from numpy.typing import NDArray

from .contacts import Config
from .hand import Error, Outcome, execute_crm
from .quality import min_friction
from .sensing import Observation, observe
from .tasks import Task

__all__ = ["SimState", "StepResult", "begin", "reset", "step", "episode_end"]


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


def begin(task: Task, config: Config, rng: np.random.Generator) -> tuple[SimState, Observation, int]:
    """Start an episode at ``config``: one reading; the state, its observation and
    discretized index (error none)."""
    sensed = task.noise.sense(config, rng)
    obs = observe(sensed)
    return SimState(config, sensed, 0), obs, task.discretizer.index(obs, Error.NONE)


def reset(task: Task, rng: np.random.Generator) -> tuple[SimState, Observation, int]:
    """Draw a start (the task's scalar sampler), then :func:`begin`."""
    return begin(task, task.sample_start(rng), rng)


def step(task: Task, state: SimState, action: int, rng: np.random.Generator) -> StepResult:
    """Execute ``task.actions[action]`` from ``state``.

    ``terminated`` when the true configuration is a grasp (``min_friction <=
    mu_goal``); ``truncated`` when ``max_steps`` CRMs have been executed without.
    """
    out = execute_crm(task.obj, task.hand, state.config, task.actions[action], state.sensed)
    sensed = task.noise.sense(out.config, rng)
    obs = observe(sensed)
    mu = min_friction(out.config)
    steps = state.steps + 1
    terminated, truncated = episode_end(task, mu, steps)
    return StepResult(
        SimState(out.config, sensed, steps),
        obs,
        out.error,
        task.discretizer.index(obs, out.error),
        -1.0,
        terminated,
        truncated,
        mu,
        out,
    )


@overload
def episode_end(task: Task, mu: float, steps: int) -> tuple[bool, bool]: ...


@overload
def episode_end(
    task: Task, mu: NDArray[np.float64], steps: NDArray[np.int64]
) -> tuple[NDArray[np.bool_], NDArray[np.bool_]]: ...


def episode_end(task: Task, mu: Any, steps: Any) -> tuple[Any, Any]:
    """``(terminated, truncated)`` after a CRM: terminated when the true configuration is
    a grasp (:meth:`Task.grasped`), truncated when ``steps >= max_steps`` CRMs have been
    executed without one. Works on numbers or, elementwise, on arrays."""
    terminated = task.grasped(mu)
    return terminated, (steps >= task.max_steps) > terminated  # a > b on booleans: a and not b

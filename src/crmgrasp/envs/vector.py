"""A Gymnasium vector environment of N independent CRM grasping episodes, stepped
by the task's kernel ([`crmgrasp.kernels.Kernel.step_batch`][]).

``gymnasium.make_vec("crmgrasp/PaperBox-v0", num_envs=1024,
vectorization_mode="vector_entry_point")`` builds it. Observations are the single
environment's ``Dict`` batched (``rho``, ``m_a``, ``m_b`` of shape ``(N, 1)``,
``error`` of shape ``(N,)``); ``info`` holds arrays ``obs_index``,
``min_friction``, ``steps`` and ``config`` (``(N, W)``, the rows of the task's contact
model: ``W = 8`` in the plane, 12 in space).

Autoreset is ``NEXT_STEP`` (Gymnasium's default): the step after an episode ends
resets that sub-environment, ignores its action and returns the new start's
observation with reward 0, ``terminated`` and ``truncated`` false. Starts are
drawn in blocks of 2,048 with the kernel's vectorised sampler from
``self.np_random``: the same distribution as [`CRMGraspEnv`][crmgrasp.envs.single.CRMGraspEnv],
not the same stream. With sensing noise each step takes one reading per
sub-environment, after the resets. Every backend gives the same outputs bit for
bit (tested).
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
from gymnasium import spaces
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from crmgrasp._validation import CrmgraspError, boolean, optional_seed, shown
from crmgrasp.envs.single import observation_space
from crmgrasp.kernels import Kernel, kernel_for
from crmgrasp.sim import episode_end, step_reward
from crmgrasp.tasks import Task, as_task

__all__ = [
    "CRMGraspVectorEnv",
    "FamilyVectorEnv",
    "ContinuousVectorEnv",
    "ContinuousFamilyVectorEnv",
    "vector_env",
    "continuous_vector_env",
    "MAX_ENVS",
]

MAX_ENVS = 1_000_000
"""Most sub-environments one vector environment holds; more is refused before anything is
allocated. Measured peak memory (tracemalloc, reset and three steps): about 0.9 kB per
sub-environment on paper-box, 5.7 kB on box-family (a kernel per row)."""


def _no_options(options: Any) -> None:
    """A one-line error for reset options: a vector environment draws every start itself."""
    if options:
        raise CrmgraspError(f"the vector environment takes no reset options, got {shown(options)}")


class CRMGraspVectorEnv(VectorEnv):
    """``num_envs`` independent episodes of a task, batched (see the module docstring)."""

    metadata = {"render_modes": [], "autoreset_mode": AutoresetMode.NEXT_STEP}  # noqa: RUF012 - Gymnasium's convention
    _per_row_objects = False
    """Whether the rows may each hold their own object (a family task): [`FamilyVectorEnv`][]."""

    def __init__(
        self,
        num_envs: int = 1,
        task: Task | str = "paper-box",
        render_mode: str | None = None,
        backend: str = "auto",
        max_episode_steps: int | None = None,
        exact_friction: bool = True,
    ) -> None:
        """``max_episode_steps`` (given by ``gymnasium.make_vec`` from the registration)
        replaces the task's ``max_steps``: episodes are cut off inside the batch.
        ``exact_friction`` as in [`CRMGraspEnv`][crmgrasp.envs.single.CRMGraspEnv]: false, and
        the steps only decide the grasp (``info`` without ``min_friction``)."""
        if isinstance(num_envs, bool) or not isinstance(num_envs, int) or not 1 <= num_envs <= MAX_ENVS:
            raise CrmgraspError(f"num_envs must be an integer in [1, {MAX_ENVS:,}], got {num_envs!r}")
        if render_mode is not None:
            raise CrmgraspError("the vector environment does not render; use CRMGraspEnv")
        self.task = as_task(task, type(self).__name__)
        if self.task.family is not None and not self._per_row_objects:
            raise CrmgraspError(
                f"task {self.task.name!r} draws an object per episode: use {type(self).__name__}'s family "
                "version (vector_env, continuous_vector_env and gymnasium.make_vec pick it)"
            )
        if max_episode_steps is not None and max_episode_steps != self.task.max_steps:
            self.task = dataclasses.replace(self.task, max_steps=max_episode_steps)
        self._backend = backend
        self.exact_friction = boolean(exact_friction, "exact_friction")
        self._friction = "exact" if exact_friction else "decided"
        self.kernel: Kernel = kernel_for(self.task, backend, self._friction)
        self.num_envs = num_envs
        self.render_mode = None
        self.single_action_space = spaces.Discrete(len(self.task.actions))
        self.action_space = batch_space(self.single_action_space, num_envs)
        self.single_observation_space = observation_space(self.task.model)
        self.observation_space = batch_space(self.single_observation_space, num_envs)
        self._width = self.task.model.row_width
        self._cfg = np.zeros((num_envs, self._width))
        self._sensed = self._cfg
        self._steps = np.zeros(num_envs, dtype=np.int64)
        self._prev_done = np.zeros(num_envs, dtype=bool)
        self._ready = False
        self._buffer = np.empty((0, self._width))
        self._next = 0

    def _reseed(self, seed: Any, options: Any) -> None:
        """Check a reset's arguments and seed the shared generator (Gymnasium's ``reset``)."""
        if isinstance(seed, list):
            raise CrmgraspError("the vector environment takes one integer seed for its generator")
        _no_options(options)
        VectorEnv.reset(self, seed=optional_seed(seed))

    def _starts(self, n: int) -> np.ndarray:
        """``n`` fresh starts, served from a block drawn ``max(2048, n)`` at a time
        (starts are i.i.d., so block draws change cost, not distribution)."""
        if self._next + n > len(self._buffer):
            block = self.kernel.sample_starts(self.np_random, max(2048, n))
            self._buffer = np.concatenate([self._buffer[self._next :], block])
            self._next = 0
        out = self._buffer[self._next : self._next + n]
        self._next += n
        return out

    def _check_actions(self, actions: Any) -> np.ndarray:
        """``actions`` as checked integers (one line naming the problem otherwise)."""
        if not self._ready:
            raise CrmgraspError("call reset() before step()")
        return self.task.action_indices(actions, self.num_envs)

    def _batch(self, actions: np.ndarray, done: np.ndarray, starts: np.ndarray) -> Any:
        """The kernel's batched step of checked ``actions`` (indices into the task's CRMs)."""
        return self.kernel.step_batch(self._cfg, self._sensed, actions, done, starts, self.np_random)

    def _info(self, index: np.ndarray, mu: np.ndarray) -> dict[str, Any]:
        config = self._cfg.view()  # a read-only view: each step builds new rows
        config.flags.writeable = False
        info = {"obs_index": index, "min_friction": mu, "steps": self._steps.copy(), "config": config}
        if not self.exact_friction:  # then only frictions that decide the grasps
            del info["min_friction"]
        return info

    def reset(
        self, *, seed: int | list[int] | None = None, options: dict[str, Any] | None = None
    ) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        """Reset every sub-environment (``seed`` seeds the shared generator)."""
        self._reseed(seed, options)
        self._buffer, self._next = np.empty((0, self._width)), 0
        n = self.num_envs
        self._cfg = np.array(self._starts(n))
        self._sensed = self.kernel.read_rows(self._cfg, self.np_random)
        self._steps[:] = 0
        self._prev_done[:] = False
        self._ready = True
        err = np.zeros(n, dtype=np.int64)
        *values, index, mu = self.kernel.observe(self._cfg, self._sensed, err)
        return self.kernel.clip(values, err), self._info(index, mu)

    def step(self, actions: Any) -> tuple[dict[str, np.ndarray], np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        """One CRM in every sub-environment (or a reset where the last step ended it)."""
        a = self._check_actions(actions)
        done = self._prev_done  # these rows reset: their action is ignored
        starts = self._starts(int(np.count_nonzero(done)))
        res = self._batch(a, done, starts)
        self._cfg, self._sensed = res.config, res.sensed
        steps = self._steps
        steps += 1
        steps[done] = 0
        terminated, truncated = episode_end(self.task, res.min_friction, steps)
        terminated = terminated & ~done  # a reset row neither terminates nor truncates (its steps are 0)
        reward = np.where(done, 0.0, step_reward(self.task, terminated, res.obs["error"]))  # 0 on a reset row
        self._prev_done = terminated | truncated
        return res.obs, reward, terminated, truncated, self._info(res.obs_index, res.min_friction)


class FamilyVectorEnv(CRMGraspVectorEnv):
    """``num_envs`` episodes of a family task, each on its own object: the rows step one
    at a time through one [`FamilyKernel`][crmgrasp.kernels.family.FamilyKernel] each (a family
    draws the object of every episode, so rows cannot share a batched kernel). The
    interface, spaces and autoreset are those of [`CRMGraspVectorEnv`][]; all draws
    come from ``self.np_random``, row by row."""

    _per_row_objects = True

    def __init__(self, num_envs: int = 1, task: Task | str = "box-family", **kwargs: Any) -> None:
        super().__init__(num_envs, task, **kwargs)
        if self.task.family is None:
            raise CrmgraspError(f"task {self.task.name!r} has no object family; use CRMGraspVectorEnv")
        self._rows: list[Any] = [kernel_for(self.task, self._backend, self._friction) for _ in range(num_envs)]
        self._states: list[Any] = [None] * num_envs

    def _collect(self, results: list[Any]) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        self._states = [r.state for r in results]
        self._cfg = self.task.model.rows_of([r.state.config for r in results])
        values = np.array([r.observation for r in results]).T
        err = np.array([int(r.error) for r in results], dtype=np.int64)
        index = np.array([r.obs_index for r in results], dtype=np.int64)
        mu = np.array([r.min_friction for r in results])
        return self.kernel.clip(values, err), self._info(index, mu)

    def _begin(self, j: int) -> Any:
        kernel = self._rows[j]
        return kernel.begin(kernel.sample_start(self.np_random), self.np_random)

    def _one(self, j: int, actions: np.ndarray) -> Any:
        """Row ``j``'s step of checked ``actions`` (indices into the task's CRMs)."""
        return self._rows[j].step_one(self._states[j], int(actions[j]), self.np_random)

    def reset(
        self, *, seed: int | list[int] | None = None, options: dict[str, Any] | None = None
    ) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        """Reset every sub-environment: a new object and start per row."""
        self._reseed(seed, options)
        self._steps[:] = 0
        self._prev_done[:] = False
        self._ready = True
        return self._collect([self._begin(j) for j in range(self.num_envs)])

    def step(self, actions: Any) -> tuple[dict[str, np.ndarray], np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        """One CRM per row (or a new object and start where the last step ended it)."""
        a = self._check_actions(actions)
        done = self._prev_done
        results = [self._begin(j) if done[j] else self._one(j, a) for j in range(self.num_envs)]
        obs, info = self._collect(results)
        self._steps[:] = [r.state.steps for r in results]
        terminated = np.array([r.terminated for r in results]) & ~done
        truncated = np.array([r.truncated for r in results]) & ~done
        reward = np.where(done, 0.0, [r.reward for r in results])
        self._prev_done = terminated | truncated
        info["steps"] = self._steps.copy()
        return obs, reward, terminated, truncated, info


def _use_pair_offsets(env: CRMGraspVectorEnv) -> Any:
    """Give ``env`` the continuous action space, ``Dict(pair: MultiDiscrete, r: Box(N, d))``;
    return the [`PairOffsetActions`][crmgrasp.envs.continuous.PairOffsetActions] that checks
    and clips each row's action."""
    from crmgrasp.envs.continuous import PairOffsetActions

    actions = PairOffsetActions(env.task)
    env.single_action_space = actions.space
    env.action_space = batch_space(actions.space, env.num_envs)
    return actions


class _PairOffsets:
    """Actions checked as rows of an action table (the continuous action space)."""

    actions: Any
    num_envs: int
    _ready: bool

    def _check_actions(self, actions: Any) -> np.ndarray:
        if not self._ready:
            raise CrmgraspError("call reset() before step()")
        return self.actions.batch(actions, self.num_envs)  # type: ignore[no-any-return]


class ContinuousVectorEnv(_PairOffsets, CRMGraspVectorEnv):
    """[`CRMGraspVectorEnv`][] in the continuous action space: one compiled batched step
    ([`crmgrasp.kernels.Kernel.step_table`][]) of a contact pair and an offset per row."""

    def __init__(self, num_envs: int = 1, task: Task | str = "paper-box", **kwargs: Any) -> None:
        super().__init__(num_envs, task, **kwargs)
        self.actions = _use_pair_offsets(self)

    def _batch(self, actions: np.ndarray, done: np.ndarray, starts: np.ndarray) -> Any:
        return self.kernel.step_table(self._cfg, self._sensed, actions, done, starts, self.np_random)


class ContinuousFamilyVectorEnv(_PairOffsets, FamilyVectorEnv):
    """[`FamilyVectorEnv`][] in the continuous action space (each row's object its own)."""

    def __init__(self, num_envs: int = 1, task: Task | str = "box-family", **kwargs: Any) -> None:
        super().__init__(num_envs, task, **kwargs)
        self.actions = _use_pair_offsets(self)

    def _one(self, j: int, actions: np.ndarray) -> Any:
        return self._rows[j].step_row(self._states[j], actions[j : j + 1], self.np_random, checked=True)


def _pick(task: Task | str, single: type[CRMGraspVectorEnv], family: type[CRMGraspVectorEnv]) -> tuple[Task, type]:
    """``task`` as a [`Task`][crmgrasp.tasks.Task], and ``family`` if it draws an object per
    episode, else ``single``: the one place that picks a vector environment's class."""
    t = as_task(task, single.__name__)
    return t, single if t.family is None else family


def vector_env(num_envs: int = 1, task: Task | str = "paper-box", **kwargs: Any) -> CRMGraspVectorEnv:
    """The vector environment of ``task``: [`FamilyVectorEnv`][] for a family task, else
    [`CRMGraspVectorEnv`][] (the registered discrete ids' vector entry point, so
    ``gymnasium.make_vec(id, task=...)`` takes any task)."""
    t, cls = _pick(task, CRMGraspVectorEnv, FamilyVectorEnv)
    return cls(num_envs, t, **kwargs)  # type: ignore[no-any-return]


def continuous_vector_env(num_envs: int = 1, task: Task | str = "paper-box", **kwargs: Any) -> CRMGraspVectorEnv:
    """The continuous-action vector environment of ``task``: [`ContinuousFamilyVectorEnv`][]
    for a family task, else [`ContinuousVectorEnv`][] (the registered ``...Continuous-v0``
    ids' vector entry point)."""
    t, cls = _pick(task, ContinuousVectorEnv, ContinuousFamilyVectorEnv)
    return cls(num_envs, t, **kwargs)  # type: ignore[no-any-return]

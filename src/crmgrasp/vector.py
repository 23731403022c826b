"""A Gymnasium vector environment of N independent CRM grasping episodes, stepped
with the batched simulator (:func:`crmgrasp.batch.execute_columns`).

``gymnasium.make_vec("crmgrasp/PaperBox-v0", num_envs=1024,
vectorization_mode="vector_entry_point")`` builds it. Observations are the single
environment's ``Dict`` batched (``rho``, ``m_a``, ``m_b`` of shape ``(N, 1)``,
``error`` of shape ``(N,)``); ``info`` holds arrays ``obs_index``,
``min_friction``, ``steps`` and ``config`` (``(N, 8)``).

Autoreset is ``NEXT_STEP`` (Gymnasium's default): the step after an episode ends
resets that sub-environment, ignores its action and returns the new start's
observation with reward 0, ``terminated`` and ``truncated`` false. Starts are
drawn in blocks of 2,048 with the task sampler's vectorised ``batch`` method from
``self.np_random``: the same distribution as :class:`~crmgrasp.env.CRMGraspEnv`,
not the same stream. With sensing noise each step takes one reading per
sub-environment, after the resets.

With numba installed, a noise-free polygon task's step is one compiled pass per
row (:func:`crmgrasp._numba.step_rows`: the CRM or the next start, observation,
bins, clipping, min friction); otherwise the numpy path runs the batched kernel,
then :func:`crmgrasp.quality.observe_mu_columns` and
:meth:`crmgrasp.sensing.Discretizer.index_columns`. Both give the same outputs bit
for bit (tested).
"""

from __future__ import annotations

from typing import Any, cast

import numpy as np
from gymnasium import spaces
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from . import _numba
from ._validation import CrmgraspError
from .batch import execute_columns
from .geometry import Polygon
from .quality import observe_mu_columns
from .sensing import Error
from .tasks import Task, make_task

__all__ = ["CRMGraspVectorEnv"]


class CRMGraspVectorEnv(VectorEnv):
    """``num_envs`` independent episodes of a task, batched (see the module docstring)."""

    metadata = {"render_modes": [], "autoreset_mode": AutoresetMode.NEXT_STEP}  # noqa: RUF012 - Gymnasium's convention

    def __init__(self, num_envs: int = 1, task: Task | str = "paper-box", render_mode: str | None = None) -> None:
        if isinstance(num_envs, bool) or not isinstance(num_envs, int) or num_envs < 1:
            raise CrmgraspError(f"num_envs must be an integer >= 1, got {num_envs!r}")
        if render_mode is not None:
            raise CrmgraspError("the vector environment does not render; use CRMGraspEnv")
        self.task = make_task(task) if isinstance(task, str) else task
        self.num_envs = num_envs
        self.render_mode = None
        t = self.task
        n_actions = len(t.actions)
        self._c_is_b = np.array([a.ci == 1 for a in t.actions])
        self._f_is_b = np.array([a.fi == 1 for a in t.actions])
        self._r = np.array([a.r for a in t.actions])
        self._bound = 2.0 * t.hand.aperture
        d = t.discretizer
        self._bins = tuple(np.array(th, dtype=np.float64) for th in (d.rho, d.m_a, d.m_b))
        self.single_action_space = spaces.Discrete(n_actions)
        self.action_space = batch_space(self.single_action_space, num_envs)
        b = self._bound
        self.single_observation_space = spaces.Dict(
            {
                "rho": spaces.Box(0.0, 4.0, shape=(1,), dtype=np.float64),
                "m_a": spaces.Box(-b, b, shape=(1,), dtype=np.float64),
                "m_b": spaces.Box(-b, b, shape=(1,), dtype=np.float64),
                "error": spaces.Discrete(len(Error)),
            }
        )
        self.observation_space = batch_space(self.single_observation_space, num_envs)
        self._cfg = np.zeros((8, num_envs))
        self._sensed = self._cfg
        self._steps = np.zeros(num_envs, dtype=np.int64)
        self._prev_done = np.zeros(num_envs, dtype=bool)
        self._ready = False
        self._buffer = np.empty((8, 0))
        self._next = 0

    def _starts(self, n: int) -> np.ndarray:
        """``n`` fresh starts, served from a block drawn ``max(2048, n)`` at a time
        (starts are i.i.d., so block draws change cost, not distribution)."""
        if self._next + n > self._buffer.shape[1]:
            block = self.task.sample_starts(self.np_random, max(2048, n))
            self._buffer = np.concatenate([self._buffer[:, self._next :], block], axis=1)
            self._next = 0
        out = self._buffer[:, self._next : self._next + n]
        self._next += n
        return out

    def _sense(self, cols: np.ndarray) -> np.ndarray:
        noise = self.task.noise
        if not noise.active:
            return cols
        return np.ascontiguousarray(noise.sense_batch(cols.T, self.np_random).T)

    def _observe(self, errors: np.ndarray) -> tuple[dict[str, np.ndarray], np.ndarray, np.ndarray]:
        """Observations (clipped to the space), bin indices and min friction; call
        inside ``np.errstate(all="ignore")``."""
        s, c = self._sensed, self._cfg
        if _numba.AVAILABLE:
            n = self.num_envs
            rho, m_a, m_b, mu = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
            _numba.observe_rows(np.ascontiguousarray(c), np.ascontiguousarray(s), rho, m_a, m_b, mu)
        else:
            rho, m_a, m_b, mu = observe_mu_columns(c, s)
        index = self.task.discretizer.index_columns(rho, m_a, m_b, errors)
        b = self._bound  # rho = |n_a + n_b|^2 >= 0 needs no lower clip
        obs = {
            "rho": np.minimum(rho, 4.0, out=rho)[:, None],
            "m_a": np.minimum(np.maximum(m_a, -b, out=m_a), b, out=m_a)[:, None],
            "m_b": np.minimum(np.maximum(m_b, -b, out=m_b), b, out=m_b)[:, None],
            "error": errors.astype(np.int64),
        }
        return obs, index, mu

    def _info(self, index: np.ndarray, mu: np.ndarray) -> dict[str, Any]:
        config = self._cfg.T  # a read-only view: each step builds a new block
        config.flags.writeable = False
        return {"obs_index": index, "min_friction": mu, "steps": self._steps.copy(), "config": config}

    def reset(
        self, *, seed: int | list[int] | None = None, options: dict[str, Any] | None = None
    ) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        """Reset every sub-environment (``seed`` seeds the shared generator)."""
        if isinstance(seed, list):
            raise CrmgraspError("the vector environment takes one integer seed for its generator")
        super().reset(seed=seed)
        self._buffer, self._next = np.empty((8, 0)), 0
        self._cfg = np.array(self._starts(self.num_envs))
        self._sensed = self._sense(self._cfg)
        self._steps[:] = 0
        self._prev_done[:] = False
        self._ready = True
        with np.errstate(all="ignore"):
            obs, index, mu = self._observe(np.zeros(self.num_envs, dtype=np.int8))
        return obs, self._info(index, mu)

    def step(self, actions: Any) -> tuple[dict[str, np.ndarray], np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        """One CRM in every sub-environment (or a reset where the last step ended it)."""
        if not self._ready:
            raise CrmgraspError("call reset() before step()")
        a = np.asarray(actions)
        n_actions = len(self._r)
        if a.shape != (self.num_envs,) or a.dtype.kind not in "iu":
            raise CrmgraspError(f"actions must be {self.num_envs} integers, got shape {a.shape} dtype {a.dtype}")
        if a.min() < 0 or a.max() >= n_actions:
            raise CrmgraspError(f"actions must be in [0, {n_actions})")
        task = self.task
        done = self._prev_done
        rows = done.nonzero()[0]  # these reset: their action is ignored
        if _numba.AVAILABLE and isinstance(task.obj, Polygon) and not task.noise.active:
            return self._finish(*self._step_compiled(a, done, rows), done, rows)
        with np.errstate(all="ignore"):
            new, errors = execute_columns(
                task.obj, task.hand, self._cfg, self._sensed, self._c_is_b[a], self._f_is_b[a], self._r[a]
            )
            if len(rows):
                new[:, rows] = self._starts(len(rows))
                errors[rows] = 0
            self._cfg = new
            self._sensed = self._sense(new)
            obs, index, mu = self._observe(errors)
        return self._finish(obs, index, mu, done, rows)

    def _step_compiled(
        self, a: np.ndarray, done: np.ndarray, rows: np.ndarray
    ) -> tuple[dict[str, np.ndarray], np.ndarray, np.ndarray]:
        """The noise-free polygon step as one compiled pass (same results as the numpy path)."""
        n, task = self.num_envs, self.task
        starts = np.ascontiguousarray(self._starts(len(rows)))
        new = np.empty((8, n))
        obs = {
            "rho": np.empty((n, 1)),
            "m_a": np.empty((n, 1)),
            "m_b": np.empty((n, 1)),
            "error": np.empty(n, dtype=np.int64),
        }
        index, mu = np.empty(n, dtype=np.int64), np.empty(n)
        hand, obj = task.hand, cast(Polygon, task.obj)  # the caller checked
        _numba.step_rows(
            self._cfg,
            self._c_is_b[a],
            self._f_is_b[a],
            self._r[a],
            done,
            starts,
            obj._edge_arrays,
            obj.convex,
            hand.aperture,
            hand.palm_depth,
            hand.palm_normal_tol,
            self._bins,
            task.discretizer.abs_moments,
            self._bound,
            (new, obs["rho"], obs["m_a"], obs["m_b"], obs["error"], index, mu),
        )
        self._cfg = self._sensed = new
        return obs, index, mu

    def _finish(
        self, obs: dict[str, np.ndarray], index: np.ndarray, mu: np.ndarray, done: np.ndarray, rows: np.ndarray
    ) -> tuple[dict[str, np.ndarray], np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        """Step counters, termination, truncation, reward and ``info``."""
        steps = self._steps
        steps += 1
        steps[rows] = 0
        terminated = (mu <= self.task.mu_goal) > done  # a reset row neither terminates nor truncates
        truncated = (steps >= self.task.max_steps) > terminated  # its steps are 0 < max_steps
        reward = done - 1.0  # 0 on a reset row, -1 per CRM
        self._prev_done = terminated | truncated
        return obs, reward, terminated, truncated, self._info(index, mu)

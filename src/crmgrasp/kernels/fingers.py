"""The compiled kernel of a planar hand with three or more contacts on a polygon.

[`FingersKernel`][] runs the model's CRM transition, observation, bins and least friction
as compiled loops (`crmgrasp.kernels._fingers_jit`), batched and one step at a time,
with or without sensing noise (readings are drawn by the model, as on every path). Its
results equal the readable rules bit for bit (the tests check it).
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np
from numpy.typing import NDArray

import crmgrasp.kernels._fingers_jit as jit
from crmgrasp.kernels.base import F64, I64, FusedSingleStep, Kernel, bin_thresholds
from crmgrasp.kernels.polygon import kernel_edges, params, rebound
from crmgrasp.model import quality
from crmgrasp.model.geometry import Polygon
from crmgrasp.model.hand import CRM, Error
from crmgrasp.sim import OneStep, SimState, checked_state, episode_end, step_reward
from crmgrasp.tasks import Task

__all__ = ["FingersKernel", "compiled_least_friction"]

_ERRORS = tuple(Error)


def _quality_params() -> F64:
    """The least friction's constants, read from [`crmgrasp.model.quality`][] now."""
    fp = np.empty(jit.N_FP)
    fp[jit.CLOSURE_TOL], fp[jit.SPAN_TOL] = quality.CLOSURE_TOL, quality._SPAN_TOL
    fp[jit.THETA_MAX], fp[jit.ANGLE_TOL] = quality._THETA_MAX, quality.ANGLE_TOL
    fp[jit.ARM_MIN] = quality._ARM_MIN
    return fp


@functools.lru_cache(maxsize=1 << 14)
def _cached(config: Any, fp: tuple[float, ...], antipodal_tol: float) -> float:
    row = np.array([[v for c in config for v in c]], dtype=np.float64)
    return float(jit._mu(row, 0, len(config), np.array(fp), antipodal_tol))


def compiled_least_friction() -> Any:
    """The least friction of a planar configuration of three or more contacts, compiled:
    ``config -> float``, equal bit for bit to
    [`least_friction`][crmgrasp.model.quality.least_friction] (the fingers kernel's own),
    cached per configuration and constants as the readable rule is."""
    return functools.partial(_cached, fp=tuple(_quality_params().tolist()), antipodal_tol=quality.ANTIPODAL_TOL)


class _UniformFilter:
    """The uniform start rule of a [`FingersKernel`][]'s polygon, compiled
    ([`crmgrasp.tasks.starts.UniformFilter`][]): the same decisions as the readable rule."""

    kind = "uniform"

    def __init__(self, kernel: FingersKernel) -> None:
        obj = kernel.task.obj
        assert isinstance(obj, Polygon)
        self.k = kernel
        self.cum = np.array((*obj.vertex_arclengths(), obj.perimeter), dtype=np.float64)
        self.perimeter = obj.perimeter
        self.out = np.empty((1, 4 * kernel.n))

    def __call__(self, obj: Any, hand: Any, mu_goal: float, s: np.ndarray) -> Any:
        k = self.k
        if not jit.uniform_start(s, self.cum, self.perimeter, k.e, k.n, k.p, k.q, k.fp, mu_goal, self.out):
            return None
        return k.model.config_of(self.out[0].tolist())


class FingersKernel(Kernel):
    """Compiled CRMs, observations, bins and least friction of a hand with any number of
    contacts on a polygon; single steps compiled too (the reading from the model)."""

    name = "numba-fingers"

    def __init__(self, task: Task) -> None:
        super().__init__(task)
        assert isinstance(task.obj, Polygon)
        self.n = self.model.n_contacts
        self.e = kernel_edges(task.obj)
        self.p, self.q, _ = params(task)
        self.fp = _quality_params()
        d = task.discretizer
        self.th = bin_thresholds(d)
        self.strides = np.array(d._strides, dtype=np.int64)
        self.abs_m = d.abs_moments
        self._fresh()

    def _fresh(self) -> None:
        """The parts that belong to one object (at construction and after each move): its start rule."""
        self.start_filter = _UniformFilter(self)  # type: ignore[assignment]

    def rebind(self, instance: Task) -> FingersKernel:
        """The kernel of ``instance`` (the same hand, CRMs, bins and goal on another polygon;
        [`crmgrasp.kernels.polygon.rebound`][]: its start rule its own)."""
        return rebound(self, instance)

    def execute_crms(self, cfg: F64, sen: F64, c: I64, f: I64, r: F64) -> tuple[F64, NDArray[np.int8]]:
        rows = self.check_batch(cfg, sen, crms=(c, f, r))
        crms = [np.ascontiguousarray(np.broadcast_to(v, rows), dtype=t) for v, t in ((c, int), (f, int), (r, float))]
        new, err = np.empty((rows, 4 * self.n)), np.empty(rows, dtype=np.int8)
        true, seen = (np.ascontiguousarray(a, dtype=np.float64) for a in (cfg, sen))
        jit.execute_rows(true, seen, self.n, crms[0], crms[1], crms[2], self.e, self.p, self.q, new, err)
        return new, err

    def observe(self, cfg: F64, sen: F64, err: np.ndarray) -> tuple[np.ndarray, ...]:
        n = self.check_batch(cfg, sen, err)
        values = np.empty((1 + self.n, n))
        index, mu = np.empty(n, dtype=np.int64), np.empty(n)
        jit.observe_rows(
            np.ascontiguousarray(cfg, dtype=np.float64),
            np.ascontiguousarray(sen, dtype=np.float64),
            self.n,
            np.ascontiguousarray(err, dtype=np.int64),
            self.th,
            self.strides,
            self.abs_m,
            self.p,
            self.fp,
            values,
            index,
            mu,
        )
        return (*values, index, mu)

    def _after(self, config: Any, error: int, rng: np.random.Generator) -> tuple[Any, ...]:
        """A reading of ``config`` and its observation, bin index and least friction."""
        sensed = self.model.read(config, rng)
        row = np.array([self.model.row_of(config)])
        srow = row if sensed is config else np.array([self.model.row_of(sensed)])
        *values, index, mu = self.observe(row, srow, np.array([error]))
        return sensed, tuple(float(v[0]) for v in values), int(index[0]), float(mu[0])

    def begin(self, config: Any, rng: np.random.Generator) -> OneStep:
        sensed, obs, index, mu = self._after(self.trust(config), 0, rng)
        return OneStep(SimState(config, sensed, 0), obs, Error.NONE, index, mu)

    def step_one(self, state: SimState, action: int | CRM, rng: np.random.Generator) -> OneStep:
        checked_state(state)
        if isinstance(action, CRM):  # a CRM of the hand's continuous action space
            return self.step_row(state, self.crm_row(action), rng, checked=True)
        if type(action) is not int or not 0 <= action < len(self.acts):  # compiled code does not check indices
            action = self.task.action_index(action)
        return self.step_row(state, self.acts[action : action + 1], rng, checked=True)

    def step_row(self, state: SimState, row: F64, rng: np.random.Generator, checked: bool = False) -> OneStep:
        if not checked:
            self.check_row(state, row)
        srow = np.array([self.model.row_of(self.trust(state.config))])
        sensed = state.sensed if state.sensed is state.config else self.model.check_reading(state.sensed)
        sen = srow if sensed is state.config else np.array([self.model.row_of(sensed)])
        new, err = self.execute_table(srow, sen, row)
        code = int(err[0])
        config = state.config if code else self.trusted(self.model.config_of(new[0].tolist()))
        sensed, obs, index, mu = self._after(config, code, rng)
        steps = state.steps + 1
        terminated, truncated = episode_end(self.task, mu, steps)
        reward = step_reward(self.task, terminated, code)
        return OneStep(SimState(config, sensed, steps), obs, _ERRORS[code], index, mu, reward, terminated, truncated)


class FusedFingersKernel(FusedSingleStep, FingersKernel):
    """[`FingersKernel`][] for noise-free tasks: a single step (the CRM, its observation, bin
    and least friction) is one compiled call, and the configuration stays in a buffer from
    one step to the next ([`FusedSingleStep`][crmgrasp.kernels.base.FusedSingleStep])."""

    name = "numba-fingers-fused"

    def __init__(self, task: Task) -> None:
        n = task.model.n_contacts
        self._v, self._out, self._vals = np.empty((1, 4 * n)), np.empty((1, 4 * n)), np.empty((1 + n, 1))
        super().__init__(task)

    def _fresh(self) -> None:
        super()._fresh()
        self._forget()

    def _begin_call(self) -> tuple[int, float]:
        return jit.begin_one(self._v, self.n, self.th, self.strides, self.abs_m, self.p, self.fp, self._vals)  # type: ignore[no-any-return]

    def _step_call(self, action: int, table: F64) -> tuple[int, int, float]:
        return jit.step_one(  # type: ignore[no-any-return]
            self._v, action, table, self.n, self.e, self.th, self.strides, self.abs_m, self.p, self.q, self.fp,
            self._out, self._vals, self._known, self._mu,
        )  # fmt: skip

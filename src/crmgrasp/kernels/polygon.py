"""Compiled kernels for polygonal objects (numba): the one fast implementation of
each rule, wrapped in the [`Kernel`][crmgrasp.kernels.base.Kernel] interface.

[`params`][] gathers every constant the compiled code needs from the model's
own modules when a kernel is built, so the compiled functions
(`crmgrasp.kernels._polygon_jit`) hold no constant of their own.
"""

from __future__ import annotations

from typing import Any, TypeVar

import numpy as np
from numpy.typing import NDArray

import crmgrasp.kernels._polygon_jit as jit
from crmgrasp.kernels.base import F64, I64, UNSET, BatchStep, Kernel, bin_thresholds
from crmgrasp.model import quality, shape
from crmgrasp.model.contacts import config_from_row
from crmgrasp.model.geometry import Polygon
from crmgrasp.model.hand import CRM, Error
from crmgrasp.model.sensing import Observation
from crmgrasp.sim import OneStep, SimState, checked_state, episode_end, step_reward
from crmgrasp.tasks import Task

__all__ = ["PolygonKernel", "FusedPolygonKernel", "kernel_edges", "params", "rebound"]

_ERRORS = tuple(Error)  # code -> Error, faster than Error(code)
_new = tuple.__new__  # builds the step's NamedTuples without their Python-level __new__ (the hot path)


K = TypeVar("K", bound=Kernel)


def rebound(kernel: K, instance: Task) -> K:
    """A compiled polygon kernel (two or more contacts) moved onto ``instance``'s polygon,
    in place: its parameters stay, its edges and convexity become the new object's (what
    [`params`][] would give, without recomputing the rest), and ``_fresh`` then sets what
    else belongs to one object. The kernel itself is returned (a family's
    kernel steps one object at a time, so nothing else holds the old one)."""
    obj = instance.obj
    assert isinstance(obj, Polygon)
    vertices = np.array(obj.vertices)
    if len(vertices) != len(kernel.e):  # type: ignore[attr-defined]
        kernel.e = np.empty((len(vertices), 7))  # type: ignore[attr-defined]
    kernel.q[jit.CONVEX] = jit.edge_rows(vertices, kernel.e)  # type: ignore[attr-defined]
    kernel.task = instance
    kernel._fresh()  # type: ignore[attr-defined]
    return kernel


def kernel_edges(obj: Polygon) -> F64:
    """The polygon's edge rows as the kernel's own writable copy: [`rebound`][] writes the
    next object's into it, and the compiled functions then always take a writable array (a
    read-only one, the polygon's own, would have numba compile each of them a second time)."""
    return np.array(obj.edge_array, dtype=np.float64, order="C")


def params(task: Task) -> tuple[F64, NDArray[np.int64], F64]:
    """``(p, q, th)`` for the compiled functions: the float parameters and tolerances
    (read from [`crmgrasp.model.geometry`][], [`crmgrasp.model.hand`][], [`crmgrasp.model.quality`][]
    and the task now), the integer ones, and the bin thresholds padded with ``+inf``."""
    obj, hand, d = task.obj, task.hand, task.discretizer
    assert isinstance(obj, Polygon)
    p = np.empty(jit.N_P)
    p[jit.APERTURE], p[jit.DEPTH], p[jit.PALM_TOL] = hand.aperture, hand.palm_depth, hand.palm_normal_tol
    p[jit.EPS], p[jit.S_TOL], p[jit.LINE_TOL] = shape.EPS, shape.S_TOL, shape.LINE_TOL
    p[jit.ANTIPODAL_TOL], p[jit.MU_GOAL], p[jit.BOUND] = quality.ANTIPODAL_TOL, task.mu_goal, 2.0 * hand.aperture
    p[jit.MIN_SEP] = hand.min_separation
    q = np.empty(jit.N_Q, dtype=np.int64)
    q[jit.CONVEX], q[jit.ABS_M] = obj.convex, d.abs_moments
    q[jit.NA], q[jit.NB] = d.sizes[1], d.sizes[2]  # the two moments' bin counts
    th = bin_thresholds(d)
    return p, q, th


class PolygonKernel(Kernel):
    """Compiled CRMs, observations, bins, min friction and start filter on a polygon;
    the composite steps are the generic ones (any sensing noise)."""

    name = "numba-polygon"

    def __init__(self, task: Task) -> None:
        super().__init__(task)
        assert isinstance(task.obj, Polygon)
        self.e = kernel_edges(task.obj)
        self.p, self.q, self.th = params(task)
        self.start_filter = self._accept
        self._fresh()

    def rebind(self, instance: Task) -> PolygonKernel:
        """The kernel of ``instance`` (the same hand, CRMs, bins and goal on another
        polygon; [`rebound`][])."""
        return rebound(self, instance)

    def _fresh(self) -> None:
        """Set what belongs to one object, beyond its edges (at construction and after each
        [`rebound`][]): nothing here."""

    def execute_crms(self, cfg: F64, sen: F64, c: I64, f: I64, r: F64) -> tuple[F64, NDArray[np.int8]]:
        """The planar model's compiled CRMs: contact indices 0 (a) and 1 (b) become the
        compiled code's "is b" flags here, at its boundary."""
        n = self.check_batch(cfg, sen, crms=(c, f, r))
        cfg = np.ascontiguousarray(cfg, dtype=np.float64)
        new = np.empty_like(cfg)
        err = np.empty(n, dtype=np.int8)
        jit.execute_rows(
            cfg,
            np.ascontiguousarray(sen, dtype=np.float64),
            np.ascontiguousarray(np.broadcast_to(np.asarray(c) == 1, n)),
            np.ascontiguousarray(np.broadcast_to(np.asarray(f) == 1, n)),
            np.ascontiguousarray(np.broadcast_to(r, n), dtype=np.float64),
            self.e,
            self.p,
            self.q,
            new,
            err,
        )
        return new, err

    def observe(self, cfg: F64, sen: F64, err: np.ndarray) -> tuple[np.ndarray, ...]:
        n = self.check_batch(cfg, sen, err)
        rho, m_a, m_b, mu = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
        index = np.empty(n, dtype=np.int64)
        jit.observe_rows(
            np.ascontiguousarray(cfg, dtype=np.float64),
            np.ascontiguousarray(sen, dtype=np.float64),
            np.ascontiguousarray(err, dtype=np.int64),
            self.th,
            self.p,
            self.q,
            rho,
            m_a,
            m_b,
            index,
            mu,
        )
        return rho, m_a, m_b, index, mu

    def _accept(self, obj: Any, hand: Any, mu_goal: float, u: np.ndarray) -> F64:
        """[`crmgrasp.tasks.accept_corner_candidates`][], compiled."""
        out = np.empty((u.shape[1], 8))
        count = jit.corner_rows(np.ascontiguousarray(u), self.e, self.p, self.q, out)
        return out[:count]


class FusedPolygonKernel(PolygonKernel):
    """[`PolygonKernel`][] for noise-free tasks, whose single and batched steps are
    each one compiled call."""

    name = "numba-polygon-fused"

    def __init__(self, task: Task) -> None:
        # the configuration stepped from (columns 0-7) and the step's output (0-7: the new
        # configuration, 8-11: rho, m_a, m_b, min friction); swapped after a move
        self._v, self._out = np.empty((1, 12)), np.empty((1, 12))
        super().__init__(task)

    def _fresh(self) -> None:
        """A new object: no configuration in the buffer yet."""
        self._v_of: Any = UNSET

    def begin(self, config: Any, rng: np.random.Generator) -> OneStep:
        self._v[0, :8] = self.trust(config).a + config.b
        self._v_of = config
        index = jit.begin_one(self._v, self.th, self.p, self.q, self._out)
        _, _, _, _, _, _, _, _, rho, m_a, m_b, mu = self._out[0].tolist()
        state, obs = _new(SimState, (config, config, 0)), _new(Observation, (rho, m_a, m_b))
        return _new(OneStep, (state, obs, Error.NONE, index, mu, 0.0, False, False))

    def step_one(self, state: SimState, action: int | CRM, rng: np.random.Generator) -> OneStep:
        checked_state(state)
        if isinstance(action, CRM):  # a CRM of the hand's continuous action space
            return self._step(state, 0, self.crm_row(action))
        if type(action) is not int or not 0 <= action < len(self.acts):  # compiled code does not check indices
            action = self.task.action_index(action)
        return self._step(state, action, self.acts)

    def step_row(self, state: SimState, row: F64, rng: np.random.Generator, checked: bool = False) -> OneStep:
        if not checked:
            self.check_row(state, row)
        return self._step(state, 0, row)

    def _step(self, state: SimState, action: int, table: F64) -> OneStep:
        """The CRM ``table[action]`` from ``state``, one compiled call."""
        config = state.config
        if config is not self._v_of:
            self._v[0, :8] = self.trust(config)[0] + config[1]
            self._v_of = config
        code, index = jit.step_one(self._v, action, table, self.e, self.th, self.p, self.q, self._out)
        o = self._out[0].tolist()
        if not code:
            config = config_from_row(o)
            self._v, self._out = self._out, self._v  # the output is the next step's input
            self._v_of = config
        steps = state.steps + 1
        terminated, truncated = episode_end(self.task, o[11], steps)
        state, obs = _new(SimState, (config, config, steps)), _new(Observation, (o[8], o[9], o[10]))
        reward = step_reward(self.task, terminated, code)
        return _new(OneStep, (state, obs, _ERRORS[code], index, o[11], reward, terminated, truncated))

    def step_batch(
        self, cfg: F64, sen: F64, actions: I64, resets: NDArray[np.bool_], starts: F64, rng: np.random.Generator
    ) -> BatchStep:
        return self._rows(cfg, np.ascontiguousarray(actions, dtype=np.int64), self.acts, resets, starts)

    def step_table(
        self, cfg: F64, sen: F64, table: F64, resets: NDArray[np.bool_], starts: F64, rng: np.random.Generator
    ) -> BatchStep:
        rows = np.arange(len(cfg), dtype=np.int64)
        table = np.ascontiguousarray(table, dtype=np.float64).view()
        table.flags.writeable = False  # read-only as the task's own table: one compiled step_rows for both
        return self._rows(cfg, rows, table, resets, starts)

    def _rows(self, cfg: F64, actions: I64, table: F64, resets: NDArray[np.bool_], starts: F64) -> BatchStep:
        """The CRMs ``table[actions]`` of a batch, one compiled call."""
        n = len(cfg)
        new = np.empty((n, 8))
        err, index, mu = np.empty(n, dtype=np.int64), np.empty(n, dtype=np.int64), np.empty(n)
        obs: dict[str, np.ndarray] = {"rho": np.empty((n, 1)), "m_a": np.empty((n, 1)), "m_b": np.empty((n, 1))}
        obs["error"] = err
        jit.step_rows(
            np.ascontiguousarray(cfg),
            actions,
            table,
            np.ascontiguousarray(resets),
            np.ascontiguousarray(starts, dtype=np.float64).reshape(-1, 8),
            self.e,
            self.th,
            self.p,
            self.q,
            new,
            obs["rho"],
            obs["m_a"],
            obs["m_b"],
            err,
            index,
            mu,
        )
        return BatchStep(new, new, obs, index, mu)

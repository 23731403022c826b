"""The spatial kernel: the spatial model's rules row by row.

Rows are ``(N, 12)`` for two contacts: ``[x_a, n_a, x_b, n_b]`` (metres; inward unit
normals), six floats more per further contact. Each rule
is the task's ([`crmgrasp.tasks.spatial.SpatialTask`][], which calls
[`crmgrasp.model.spatial`][]): [`SpatialKernel`][] is the definition (any sensing noise);
[`FusedSpatialKernel`][] steps a noise-free task in compiled code
(`crmgrasp.kernels._spatial_jit`) with the same results bit for bit.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from crmgrasp.kernels.base import F64, UNSET, Successor, bin_thresholds, stepwise_successors
from crmgrasp.kernels.reference import ReferenceKernel
from crmgrasp.model.hand import Error
from crmgrasp.model.mesh import PARITY_RAY, TriangleMesh
from crmgrasp.model.sensing import Observation
from crmgrasp.model.solids import Cylinder
from crmgrasp.model.spatial import CRM3D, Config3D
from crmgrasp.sim import OneStep, SimState, checked_state, episode_end, step_reward
from crmgrasp.tasks.spatial import SurfaceStarts

__all__ = ["SpatialKernel", "FusedSpatialKernel", "spatial_params"]

_ERRORS = tuple(Error)


class SpatialKernel(ReferenceKernel):
    """The reference kernel on a spatial task's rows (the rows, CRMs and readings come
    from the task's [`SpatialModel`][crmgrasp.model.spatial_model.SpatialModel]), any number
    of contacts."""

    name = "spatial"


def spatial_params(task: Any) -> tuple[F64, NDArray[np.int64], F64, F64, F64]:
    """``(p, q, th, planes, cyl)`` for `crmgrasp.kernels._spatial_jit`: every
    parameter and tolerance read from the model's modules and the task now (the solid's
    own entries by [`solid_params`][])."""
    import crmgrasp.kernels._spatial_jit as jit
    from crmgrasp.model import quality, solids, spatial

    hand, d, starts = task.hand3d, task.discretizer, task.starts
    p = np.empty(jit.N_P)
    p[jit.APERTURE], p[jit.DEPTH], p[jit.PALM_TOL] = hand.aperture, hand.palm_depth, hand.palm_normal_tol
    p[jit.SURF], p[jit.ANTIPODAL_TOL], p[jit.MU_GOAL] = solids.SURFACE, quality.ANTIPODAL_TOL, task.mu_goal
    p[jit.MIN_SEP], p[jit.TABLE] = hand.min_separation, 0.0 if task.table is None else task.table
    p[jit.UP] = starts.up if isinstance(starts, SurfaceStarts) else np.inf
    p[jit.HX : jit.HZ + 1], p[jit.GX : jit.GZ + 1] = hand._h, hand._g
    p[jit.TIE], p[jit.PARALLEL] = solids.TIE, spatial.PARALLEL
    q = np.zeros(jit.N_Q, dtype=np.int64)
    q[jit.HAS_TABLE] = task.table is not None
    q[jit.ABS_M] = d.abs_moments
    q[jit.NA], q[jit.NB] = d.sizes[1], d.sizes[2]  # the two moments' bin counts
    th = bin_thresholds(d)
    planes, cyl = solid_params(task.solid, p, q)
    return p, q, th, planes, cyl


def solid_params(solid: Any, p: F64, q: NDArray[np.int64]) -> tuple[F64, F64]:
    """The solid's entries of ``p`` (its centre, and the distance beyond which every point
    is outside) and of ``q`` (its kind), written in place, and its ``(planes, cyl)`` arrays:
    a polyhedron's faces, a cylinder's axis and size, or a mesh's triangles ``[a, b, c, n]``
    and its inside test's ray (the layouts of `crmgrasp.kernels._spatial_jit`)."""
    import crmgrasp.kernels._spatial_jit as jit

    centre = solid.centre
    p[jit.CX : jit.CZ + 1] = centre
    p[jit.FAR] = 1.0 + max(map(abs, centre.tolist()))
    if isinstance(solid, TriangleMesh):
        q[jit.KIND] = jit.MESH
        v, f = solid.corner_array, solid.face_array
        triangles = np.hstack([v[f[:, 0]], v[f[:, 1]], v[f[:, 2]], solid.unit_normals])
        return np.ascontiguousarray(triangles), np.array([*PARITY_RAY, 0.0, 0.0, 0.0, 0.0, 0.0])
    if isinstance(solid, Cylinder):
        q[jit.KIND] = jit.CYLINDER
        return np.zeros((1, 4)), np.array([*solid.origin, *solid.axis, solid.radius, solid.height])
    q[jit.KIND] = jit.POLYHEDRON
    return np.ascontiguousarray(solid.planes, dtype=np.float64), np.zeros(8)


class FusedSpatialKernel(SpatialKernel):
    """The noise-free spatial step, begin and start decision, each one compiled call
    (`crmgrasp.kernels._spatial_jit`); batched rows go through [`SpatialKernel`][]."""

    name = "numba-spatial-fused"

    def __init__(self, task: Any) -> None:
        super().__init__(task)
        import crmgrasp.kernels._spatial_jit as _spatial_jit

        self._jit = _spatial_jit
        self.p, self.q, self.th, self.planes, self.cyl = spatial_params(task)
        self.acts4 = np.ascontiguousarray(self.acts)
        self._fresh()

    def _fresh(self) -> None:
        self._v, self._out = np.empty(16), np.empty(16)
        self._start_row = np.empty(12)  # a start try's configuration, read before the next try
        self._v_of: Any = UNSET
        self.start_filter = self._accept  # type: ignore[assignment]

    def rebind(self, instance: Any) -> FusedSpatialKernel:
        """This kernel moved onto ``instance`` (the same hand, CRMs, bins and table on another
        solid of the same kind), in place: the parameters kept, the solid's entries its own
        ([`solid_params`][], as [`spatial_params`][] would write them)."""
        self.task = instance
        self.planes, self.cyl = solid_params(instance.solid, self.p, self.q)
        self._v_of = UNSET
        return self

    def _load(self, config: Config3D) -> None:
        if config is not self._v_of:
            self._v[:12] = self.model.row_of(self.trust(config))
            self._v_of = config

    def begin(self, config: Any, rng: np.random.Generator) -> OneStep:
        self._load(config)
        index = self._jit.begin_one(self._v, self.th, self.p, self.q, self._v)
        rho, m_a, m_b, mu = self._v[12:16].tolist()
        return OneStep(SimState(config, config, 0), Observation(rho, m_a, m_b), Error.NONE, index, mu)

    def step_one(self, state: SimState, action: Any, rng: np.random.Generator) -> OneStep:
        checked_state(state)
        if isinstance(action, CRM3D):  # a CRM of the hand's continuous action space
            return self._step(state, 0, self.crm_row(action))
        if type(action) is not int or not 0 <= action < len(self.acts):  # compiled code does not check indices
            action = self.task.action_index(action)
        return self._step(state, action, self.acts4)

    def step_row(self, state: SimState, row: F64, rng: np.random.Generator, checked: bool = False) -> OneStep:
        if not checked:
            self.check_row(state, row)
        return self._step(state, 0, row)

    def _step(self, state: SimState, action: int, table: F64) -> OneStep:
        """The CRM ``table[action]`` from ``state``, one compiled call."""
        config = state.config
        self._load(config)  # type: ignore[arg-type]
        code, index = self._jit.step_one(
            self._v, action, table, self.planes, self.cyl, self.th, self.p, self.q, self._out
        )
        o = self._out.tolist()
        if not code:
            config = self.model.config_of(o)  # type: ignore[assignment]
            self._v, self._out = self._out, self._v  # the output is the next step's input
            self._v_of = config  # type: ignore[assignment]
        steps = state.steps + 1
        terminated, truncated = episode_end(self.task, o[15], steps)
        reward = step_reward(self.task, terminated, code)
        return OneStep(
            SimState(config, config, steps),
            Observation(o[12], o[13], o[14]),
            _ERRORS[code],
            index,
            o[15],
            reward,
            terminated,
            truncated,
        )

    def successors(self, config: Any) -> list[Successor]:
        """[`Kernel.successors`][crmgrasp.kernels.base.Kernel.successors] by the fused single
        step (the batched rows here run the readable rules)."""
        return stepwise_successors(self._step, config, self.acts4)

    def _accept(self, d: F64) -> Config3D | None:
        """[`SurfaceStarts`][crmgrasp.tasks.spatial.SurfaceStarts]' decision on one try, compiled."""
        out = self._start_row
        ok = self._jit.accept_start(np.ascontiguousarray(d), self.planes, self.cyl, self.p, self.q, out)
        return self.model.config_of(out.tolist()) if ok else None

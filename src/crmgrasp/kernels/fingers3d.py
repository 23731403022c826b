"""The compiled single step of a spatial hand with three or more contacts (a tripod).

[`FusedFingersSpatialKernel`][] steps a noise-free tripod task on a polyhedron, a
cylinder or a mesh: a CRM, its observation, bin and least friction are one compiled call
(`crmgrasp.kernels._fingers3d_jit`), and so is the decision on each start try. The results
equal the readable rules bit for bit (the tests check it). Made with ``decided=True``
([`crmgrasp.kernels.kernel_for`][]'s ``friction="decided"``), a step's least friction is one
that decides the grasp, from the search stopped once it is decided; everything else is the
same. Batched rows and sensing noise go through [`FingersSpatialKernel`][crmgrasp.kernels.closure.FingersSpatialKernel]
(the readable rules with the least friction compiled).
"""

from __future__ import annotations

from typing import Any

import numpy as np

import crmgrasp.kernels._fingers3d_jit as jit
from crmgrasp.kernels.base import F64, FusedSingleStep, Successor, stepwise_successors
from crmgrasp.kernels.closure import FingersSpatialKernel, closure_params, with_compiled_least_friction
from crmgrasp.kernels.spatial import solid_params, spatial_params
from crmgrasp.model.quality3d import EDGES
from crmgrasp.tasks import Task

__all__ = ["FusedFingersSpatialKernel"]


class FusedFingersSpatialKernel(FusedSingleStep, FingersSpatialKernel):
    """A noise-free step of three or more spatial contacts, its begin and each start try,
    one compiled call each; the configuration stays in a buffer from one step to the next
    ([`FusedSingleStep`][crmgrasp.kernels.base.FusedSingleStep])."""

    name = "numba-spatial-fingers-fused"

    def __init__(self, task: Task, decided: bool = False) -> None:
        self.decided = decided  # min_friction only decides the grasp (kernel_for's friction)
        super().__init__(task)
        self.n = n = self.model.n_contacts
        self.p, self.q, self.th, self.planes, self.cyl = spatial_params(task)
        self.strides = np.array(task.discretizer._strides, dtype=np.int64)
        self.abs_m = task.discretizer.abs_moments
        self.tol, self.edges = closure_params(), EDGES
        self._v, self._out, self._vals = np.empty(6 * n), np.empty(6 * n), np.empty((1 + n, 1))
        self._start_row = np.empty(6 * n)
        self._fresh()

    def _fresh(self) -> None:
        """No configuration held; the goal its least friction decides against (``mu_goal``
        where the step only decides the grasp, else -1: the exact least friction)."""
        self._forget()
        self._goal = self.task.mu_goal if self.decided else -1.0
        self.start_filter = self._accept  # type: ignore[assignment]

    def rebind(self, instance: Task) -> FusedFingersSpatialKernel:
        """This kernel moved onto ``instance`` (the same hand, CRMs, bins and table on another
        solid of the same kind), in place: the parameters kept (the tolerances read when the
        kernel was made), the solid's entries its own."""
        self.task = with_compiled_least_friction(instance, self.tol)
        self.planes, self.cyl = solid_params(instance.solid, self.p, self.q)  # type: ignore[attr-defined]
        self._fresh()
        return self

    def _begin_call(self) -> tuple[int, float]:
        return jit.begin_one(  # type: ignore[no-any-return]
            self._v, self.n, self.th, self.strides, self.abs_m, self.tol, self.edges, self._vals, self._goal
        )

    def _step_call(self, action: int, table: F64) -> tuple[int, int, float]:
        return jit.step_one(  # type: ignore[no-any-return]
            self._v, action, table, self.n, self.planes, self.cyl, self.th, self.strides, self.abs_m,
            self.p, self.q, self.tol, self.edges, self._out, self._vals, self._known, self._mu, self._goal,
        )  # fmt: skip

    def successors(self, config: Any) -> list[Successor]:
        """[`Kernel.successors`][crmgrasp.kernels.base.Kernel.successors] by the fused single
        step (the batched rows here run the readable rules but for the least friction)."""
        return stepwise_successors(self._step, config, self.acts)

    def _accept(self, d: F64) -> Any:
        """[`SurfaceStarts`][crmgrasp.tasks.spatial.SurfaceStarts]' decision on one try, compiled."""
        out = self._start_row
        ok = jit.accept_start(
            np.ascontiguousarray(d), self.n, self.planes, self.cyl, self.p, self.q, self.tol, self.edges,
            self.task.mu_goal, out,
        )  # fmt: skip
        return self.model.config_of(out.tolist()) if ok else None

"""The compiled least friction of three or more spatial contacts, and the kernel that uses it.

A spatial hand of three or more contacts (a tripod) spends much of a step on the least friction
of the new configuration: a few linear programs for three contacts
([`crmgrasp.model.tripod`][]), a search over the friction cone's half-angle with one per probe
for four ([`crmgrasp.model.quality3d.least_friction_3d`][]). [`FingersSpatialKernel`][] steps
such a task by its readable rules, but with the least friction computed in compiled code
(`crmgrasp.kernels._closure_jit` and `crmgrasp.kernels._tripod_jit`: the same frames,
programs, pivots and steps, bit for bit). It hands the compiled rule
to the task's [`SpatialModel`][crmgrasp.model.spatial_model.SpatialModel] (its
``least_friction``), so every path that asks for a configuration's quality (steps, starts,
success) takes it.
"""

from __future__ import annotations

import dataclasses
import functools
from typing import Any

import numpy as np
from numpy.typing import NDArray

from crmgrasp.kernels.spatial import SpatialKernel
from crmgrasp.tasks import Task

__all__ = [
    "CERTIFIED_GAP",
    "CERTIFIED_RANK_TOL",
    "DECIDED_MARGIN",
    "closure_params",
    "compiled_least_friction",
    "with_compiled_least_friction",
    "FingersSpatialKernel",
]

F64 = NDArray[np.float64]


CERTIFIED_GAP = 1e-8
"""The compiled rank test's shortcut: a Cholesky factorisation of ``W W^T - CERTIFIED_GAP I``
that succeeds proves ``sigma_min(W) >= 1e-4`` up to rounding (``W``'s entries are at most 1 in
magnitude, so the rounding of ``W W^T`` and of the factorisation is below 1e-12 for any cone
the spatial model builds); LAPACK's singular values are backward stable, so numpy's rank with
a tolerance below [`CERTIFIED_RANK_TOL`][] then counts every row. Not a model constant: it
decides only which of two computations gives the same answer."""

CERTIFIED_RANK_TOL = 1e-6
"""The shortcut is taken only while the model's rank tolerance is below this."""

DECIDED_MARGIN = 1e-9
"""The compiled start filter stops its search once ``tan`` of a bracket end is past
``mu_goal`` by this relative margin, far more than the few units in the last place by which
``math.tan`` may miss monotonicity."""


def closure_params() -> F64:
    """The tolerances of the compiled least friction (the layout of `crmgrasp.kernels._lp_jit`),
    read now from the model's modules ([`crmgrasp.model.quality3d`][], [`crmgrasp.model.tripod`][],
    [`crmgrasp.model.quality`][], [`crmgrasp.model.lp`][]), and
    this module's margins of the compiled shortcuts ([`CERTIFIED_GAP`][], [`CERTIFIED_RANK_TOL`][],
    [`DECIDED_MARGIN`][])."""
    import crmgrasp.kernels._lp_jit as jit
    from crmgrasp.model import lp, quality, quality3d, tripod

    tol = np.empty(jit.N_TOL)
    tol[jit.THETA_MAX], tol[jit.THETA_TOL] = quality3d._THETA_MAX_3D, quality3d.THETA_TOL_3D
    tol[jit.RANK_TOL], tol[jit.LP_TOL], tol[jit.ANTIPODAL_TOL] = quality.RANK_TOL, quality.LP_TOL, quality.ANTIPODAL_TOL
    tol[jit.OPT_TOL], tol[jit.PIVOT_TOL], tol[jit.FEASIBILITY_TOL] = lp.OPT_TOL, lp.PIVOT_TOL, lp.FEASIBILITY_TOL
    tol[jit.ARM_MIN], tol[jit.MAX_PIVOTS] = quality3d.ARM_MIN, lp.MAX_PIVOTS
    tol[jit.CERTIFIED_GAP], tol[jit.CERTIFIED_RANK_TOL] = CERTIFIED_GAP, CERTIFIED_RANK_TOL
    tol[jit.DECIDED_MARGIN] = DECIDED_MARGIN
    tol[jit.GUIDE_REACH], tol[jit.GUIDE_WIDEN] = quality3d.GUIDE_REACH, quality3d.GUIDE_WIDEN
    tol[jit.GUIDE_NEAR], tol[jit.GUIDE_FLOOR] = quality3d.GUIDE_NEAR, quality3d.GUIDE_FLOOR
    tol[jit.GUIDE_MAX], tol[jit.DEGENERATE_STREAK] = quality3d.GUIDE_MAX, lp.DEGENERATE_STREAK
    tol[jit.FIRST_PROBE] = quality3d.FIRST_PROBE
    tol[jit.COLLINEAR_TOL], tol[jit.MU_MAX], tol[jit.REL_TOL] = tripod.COLLINEAR_TOL, tripod.MU_MAX, tripod.REL_TOL
    tol[jit.MAX_PROGRAMS], tol[jit.TRIPOD_EXACT] = tripod.MAX_PROGRAMS, float(quality3d.TRIPOD_EXACT)
    return tol


@functools.lru_cache(maxsize=1 << 14)
def _cached(config: Any, tol: tuple[float, ...], edges: int) -> float:
    import crmgrasp.kernels._closure_jit as jit

    points = np.array([c.x for c in config], dtype=np.float64)
    normals = np.array([c.n for c in config], dtype=np.float64)
    return float(jit.least_friction(points, normals, edges, np.array(tol)))


def compiled_least_friction(tol: F64 | None = None) -> Any:
    """The least friction of a configuration of three or more spatial contacts, compiled:
    ``config -> float``, equal bit for bit to
    [`least_friction_3d`][crmgrasp.model.quality3d.least_friction_3d] with its default cone
    edges, cached per configuration and tolerances (``tol``: [`closure_params`][] by default)."""
    from crmgrasp.model.quality3d import EDGES

    key = tuple((closure_params() if tol is None else tol).tolist())
    return functools.partial(_cached, tol=key, edges=EDGES)


def with_compiled_least_friction(task: Task, tol: F64 | None = None) -> Task:
    """``task`` whose model's least friction is [`compiled_least_friction`][] with ``tol`` (a
    spatial task of three or more contacts; the same values, bit for bit)."""
    model = dataclasses.replace(task.model, least_friction=compiled_least_friction(tol))  # type: ignore[type-var]
    return task.with_model(model)


class FingersSpatialKernel(SpatialKernel):
    """[`SpatialKernel`][crmgrasp.kernels.spatial.SpatialKernel] on the task
    [`with_compiled_least_friction`][] (three or more contacts, any noise, any solid)."""

    name = "numba-spatial-fingers"

    def __init__(self, task: Task) -> None:
        super().__init__(with_compiled_least_friction(task))

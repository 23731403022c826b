"""The spatial kernel: the spatial model's rules row by row.

Rows are ``(N, 12)``: ``[x_a, n_a, x_b, n_b]`` (metres; inward unit normals). Each rule
is the task's (:class:`crmgrasp.tasks.spatial.SpatialTask`, which calls
:mod:`crmgrasp.model.spatial`): there is no compiled spatial kernel yet, so this is both
the definition and the only path (``backend="numba"`` is refused by
:func:`crmgrasp.kernels.kernel_for`).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from crmgrasp.kernels.base import F64, I64
from crmgrasp.kernels.reference import ReferenceKernel
from crmgrasp.model.spatial import CRM3D, Config3D, Contact3D

__all__ = ["SpatialKernel", "config3d_from_row"]


def config3d_from_row(row: Any) -> Config3D:
    """The :class:`Config3D` of a 12-row."""
    v = [float(x) for x in row]
    return Config3D(Contact3D(tuple(v[0:3]), tuple(v[3:6])), Contact3D(tuple(v[6:9]), tuple(v[9:12])))  # type: ignore[arg-type]


def _row(cfg: Config3D) -> list[float]:
    return [*cfg.a.x, *cfg.a.n, *cfg.b.x, *cfg.b.n]


class SpatialKernel(ReferenceKernel):
    """A spatial task's rules over 12-rows (the reference kernel's loops, with spatial
    rows, CRMs and readings)."""

    name = "spatial"
    width = 12

    @staticmethod
    def crm_of(c_is_b: bool, f_is_b: bool, r: Any) -> Any:
        return CRM3D("ab"[c_is_b], "ab"[f_is_b], (float(r[0]), float(r[1])))

    @staticmethod
    def row_of(config: Any) -> list[float]:
        return _row(config)

    @staticmethod
    def config_of(row: Any) -> Any:
        return config3d_from_row(row)

    def read_rows(self, rows: F64, rng: np.random.Generator) -> F64:
        return np.array([_row(self.task.read(config3d_from_row(r), rng)) for r in rows.tolist()]).reshape(-1, 12)

    def execute(self, cfg: F64, sen: F64, actions: I64) -> tuple[F64, NDArray[np.int8]]:
        """:meth:`execute_crms` of the task's actions (offsets ``r_1, r_2``: ``(N, 2)``)."""
        a = self.acts[actions]
        return self.execute_crms(cfg, sen, a[:, 0] != 0.0, a[:, 1] != 0.0, a[:, 2:4])

"""The reference kernel: the model's readable rules, row by row.

Every shape and every noise setting runs here; it is the definition that the
compiled kernels are tested against, and the path of any shape that has no
compiled kernel.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from crmgrasp.kernels.base import F64, I64, Kernel
from crmgrasp.model.contacts import config_from_row
from crmgrasp.model.hand import CRM, execute_crm
from crmgrasp.model.quality import min_friction
from crmgrasp.model.sensing import observe

__all__ = ["ReferenceKernel"]


class ReferenceKernel(Kernel):
    """:func:`crmgrasp.model.hand.execute_crm`, :func:`crmgrasp.model.sensing.observe`,
    :meth:`crmgrasp.model.sensing.Discretizer.index_of` and
    :func:`crmgrasp.model.quality.min_friction` per row."""

    name = "reference"

    def execute_crms(
        self, cfg: F64, sen: F64, c_is_b: NDArray[np.bool_], f_is_b: NDArray[np.bool_], r: F64
    ) -> tuple[F64, NDArray[np.int8]]:
        obj, hand = self.task.obj, self.task.hand
        new = np.array(cfg, dtype=np.float64, copy=True).reshape(-1, 8)
        err = np.zeros(len(new), dtype=np.int8)
        crms: dict[tuple[bool, bool, float], CRM] = {}
        rows = zip(
            new.tolist(),
            np.asarray(sen).tolist(),
            np.broadcast_to(c_is_b, len(new)).tolist(),
            np.broadcast_to(f_is_b, len(new)).tolist(),
            np.broadcast_to(r, len(new)).tolist(),
        )
        for j, (row, srow, cb, fb, rj) in enumerate(rows):
            key = (cb, fb, rj)
            crm = crms.get(key)
            if crm is None:
                crm = crms[key] = CRM("ab"[cb], "ab"[fb], rj)
            out = execute_crm(obj, hand, config_from_row(row), crm, config_from_row(srow))
            new[j] = (*out.config.a, *out.config.b)
            err[j] = out.error
        return new, err

    def observe(self, cfg: F64, sen: F64, err: np.ndarray) -> tuple[F64, F64, F64, I64, F64]:
        n = len(cfg)
        rho, m_a, m_b, mu = np.empty(n), np.empty(n), np.empty(n), np.empty(n)
        index = np.empty(n, dtype=np.int64)
        index_of = self.task.discretizer.index_of
        for j, (row, srow, e) in enumerate(zip(np.asarray(cfg).tolist(), np.asarray(sen).tolist(), err.tolist())):
            o = observe(config_from_row(srow))
            rho[j], m_a[j], m_b[j] = o
            index[j] = index_of(o.rho, o.m_a, o.m_b, e)
            mu[j] = min_friction(config_from_row(row))
        return rho, m_a, m_b, index, mu

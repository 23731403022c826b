"""The reference kernel: the model's readable rules, row by row.

Every shape and every noise setting runs here; it is the definition that the
compiled kernels are tested against, and the path of any shape that has no
compiled kernel.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from crmgrasp.kernels.base import F64, I64, Kernel

__all__ = ["ReferenceKernel"]


class ReferenceKernel(Kernel):
    """The task's own rules (`execute`, ``observe``, ``quality``:
    [`crmgrasp.model.hand.execute_crm`][], [`crmgrasp.model.sensing.observe`][],
    [`crmgrasp.model.quality.min_friction`][] on a planar task) and
    `crmgrasp.model.sensing.Discretizer.index_of`, row by row."""

    name = "reference"

    def crm_of(self, c: int, f: int, r: Any) -> Any:
        """The CRM of one row's ``(c, f, r)`` (the model's ``crm``)."""
        return self.model.crm(c, f, r)

    def row_of(self, config: Any) -> list[float]:
        """The row of a configuration (the model's ``row_of``)."""
        return self.model.row_of(config)

    def execute_crms(self, cfg: F64, sen: F64, c: I64, f: I64, r: F64) -> tuple[F64, NDArray[np.int8]]:
        self.check_batch(cfg, sen, crms=(c, f, r))
        new = np.array(cfg, dtype=np.float64, copy=True).reshape(-1, self.model.row_width)
        n = len(new)
        err = np.zeros(n, dtype=np.int8)
        crms: dict[tuple[int, int, Any], Any] = {}
        rr = np.broadcast_to(r, (n, *np.shape(r)[1:])).tolist()
        rows = zip(
            new.tolist(),
            np.asarray(sen).tolist(),
            np.broadcast_to(c, n).tolist(),
            np.broadcast_to(f, n).tolist(),
            rr,
        )
        for j, (row, srow, cj, fj, rj) in enumerate(rows):
            key = (cj, fj, tuple(rj) if isinstance(rj, list) else rj)
            crm = crms.get(key)
            if crm is None:
                crm = crms[key] = self.crm_of(cj, fj, key[2])
            out = self.task.execute(self.config_of(row), crm, self.config_of(srow))
            new[j] = self.row_of(out.config)
            err[j] = out.error
        return new, err

    def observe(self, cfg: F64, sen: F64, err: np.ndarray) -> tuple[np.ndarray, ...]:
        n = self.check_batch(cfg, sen, err)
        values, mu = np.empty((len(self.model.observation_names), n)), np.empty(n)
        index = np.empty(n, dtype=np.int64)
        bin_index, config_of = self.task.discretizer.index, self.config_of
        for j, (row, srow, e) in enumerate(zip(np.asarray(cfg).tolist(), np.asarray(sen).tolist(), err.tolist())):
            o = self.task.observe(config_of(srow))
            values[:, j] = o
            index[j] = bin_index(o, e)
            mu[j] = self.task.quality(config_of(row))
        return (*values, index, mu)

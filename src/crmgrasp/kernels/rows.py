"""Rows of one task's episodes through its batched kernel: the fast [`Rows`][crmgrasp.sim.Rows].

[`KernelRows`][] steps all live rows with one [`Kernel.execute`][crmgrasp.kernels.Kernel.execute]
and one [`observe`][crmgrasp.kernels.Kernel.observe] call, which are bit-identical to
[`crmgrasp.sim.step`][] per row; starts and readings draw from each row's own generator
([`crmgrasp.sim.reset`][] at a row's begin; with sensing noise one reading per row, in row
order, after the CRMs), so a row's results do not depend on the other rows.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence

import numpy as np

from crmgrasp.kernels.base import Kernel
from crmgrasp.model.hand import CRM, Error
from crmgrasp.sim import Episode, Percept, reset, step_reward
from crmgrasp.tasks import Task

__all__ = ["KernelRows"]


class KernelRows:
    """[`Rows`][crmgrasp.sim.Rows] of ``task`` (one object) through ``kernel``: row ``r``
    draws its starts and readings from ``rngs[r]`` (one generator may serve several rows:
    they draw in row order)."""

    def __init__(self, task: Task, kernel: Kernel, rngs: Sequence[np.random.Generator]) -> None:
        self.task, self.kernel, self.model, self.rngs = task, kernel, task.model, rngs
        n = len(rngs)
        self.cfg = np.zeros((n, self.model.row_width))  # true configurations, one row each
        self.sen = np.zeros((n, self.model.row_width))  # their sensed readings
        self.steps = [0] * n
        self.grasped = [False] * n

    def begin(self, row: int) -> Percept:
        """Draw the row's start and its reading ([`crmgrasp.sim.reset`][])."""
        first = reset(self.task, self.rngs[row])
        self.cfg[row] = self.model.row_of(first.state.config)
        self.sen[row] = self.model.row_of(first.state.sensed)
        self.steps[row], self.grasped[row] = 0, False
        return first.percept

    def step(self, rows: list[int], actions: Sequence[int | CRM]) -> Iterator[Percept]:
        """The task's actions (indices) in ``rows``, batched; the percepts come one at a time
        (each is told and dropped before the next is built)."""
        task, model, active = self.task, self.model, np.array(rows, dtype=np.int64)
        new, errors = self.kernel.execute(self.cfg[active], self.sen[active], task.action_indices(actions, len(rows)))
        self.cfg[active] = new
        if model.noise.active:  # one reading per row, from the row's own generator, in row order
            for i, r in enumerate(rows):
                self.sen[r] = model.row_of(model.read(model.config_of(new[i].tolist()), self.rngs[r]))
        else:
            self.sen[active] = new
        *values, index, mu = self.kernel.observe(new, self.sen[active], errors)
        done = task.grasped(mu)
        for i, (r, srow, *obs) in enumerate(zip(rows, self.sen[active].tolist(), *(v.tolist() for v in values))):
            steps = self.steps[r] = self.steps[r] + 1
            terminated = self.grasped[r] = bool(done[i])
            truncated = steps >= task.max_steps and not terminated
            err, sensed = Error(errors[i]), model.config_of(srow)
            reward = step_reward(task, terminated, errors[i])
            yield Percept(tuple(obs), err, int(index[i]), sensed, reward, terminated, truncated)

    def episode(self, row: int) -> Episode:
        """CRMs executed in the row's episode, and whether it ended in a grasp."""
        return Episode(self.steps[row], self.grasped[row])

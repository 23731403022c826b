"""The batched episode loop (`run_batch`) gives each row what the one loop (`run_episode`) gives."""

import dataclasses
import math

import numpy as np
import pytest

from crmgrasp import SensorNoise, make_task
from crmgrasp.kernels import kernel_for
from crmgrasp.kernels.rows import KernelRows
from crmgrasp.planners.references import sample_starts
from crmgrasp.sim import RowPolicies, StepperRows, run_batch, run_episode

from .strategies import BACKENDS


class Script:
    """A deterministic Policy that acts on what it perceived and records every percept."""

    def __init__(self, n_actions: int) -> None:
        self.n, self.seen, self._t = n_actions, [], 0

    def begin(self, first):
        self.seen.append(("begin", *self._keep(first)))
        self._t = first.obs_index

    def act(self):
        self._t = (self._t * 7 + 3) % 101
        return self._t % self.n

    def tell(self, percept):
        self.seen.append(self._keep(percept))
        self._t += percept.obs_index

    @staticmethod
    def _keep(p):
        return (p.observation, int(p.error), p.obs_index, p.reward, p.terminated, p.truncated)


@pytest.mark.parametrize("name", ["paper-box", "box-family", "triangles-3f", "box-3d"])
def test_stepper_rows_equal_run_episode(name):
    task = make_task(name)
    starts = sample_starts(task, 25, 4)
    n = len(task.actions)
    one = [Script(n) for _ in starts]
    episodes = [run_episode(task, p, np.random.default_rng(0), start=s) for p, s in zip(one, starts)]
    rows, batch = StepperRows(task, starts, np.random.default_rng(0)), [Script(n) for _ in starts]
    ended = []

    def more(r, last):  # one episode per row
        if last is not None:
            ended.append((r, last))
        return last is None

    run_batch(rows, RowPolicies(batch), len(starts), more)
    assert sorted(ended) == list(enumerate(episodes))
    assert [p.seen for p in batch] == [p.seen for p in one]


@pytest.mark.parametrize("noisy", [False, True])
@pytest.mark.parametrize("backend", BACKENDS)
def test_kernel_rows_equal_run_episode(backend, noisy):
    """Each row draws from its own generator: three episodes per row, batched, equal each
    row's episodes run alone."""
    task = make_task("paper-box")
    if noisy:
        task = dataclasses.replace(task, noise=SensorNoise(math.radians(3), 0.002))
    n, rows_n = len(task.actions), 6
    one = [Script(n) for _ in range(rows_n)]
    alone = []
    for r, p in enumerate(one):
        rng = np.random.default_rng(r)
        alone.append([run_episode(task, p, rng) for _ in range(3)])
    batch = [Script(n) for _ in range(rows_n)]
    got: list[list] = [[] for _ in range(rows_n)]

    def more(r, last):
        if last is not None:
            got[r].append(last)
        return len(got[r]) < 3

    rows = KernelRows(task, kernel_for(task, backend), [np.random.default_rng(r) for r in range(rows_n)])
    run_batch(rows, RowPolicies(batch), rows_n, more)
    assert got == alone
    assert [p.seen for p in batch] == [p.seen for p in one]


def test_run_batch_no_rows():
    """Rows that never begin: nothing is stepped."""
    task = make_task("paper-box")
    rows = StepperRows(task, sample_starts(task, 2, 0), np.random.default_rng(0))
    run_batch(rows, RowPolicies([Script(1), Script(1)]), 2, lambda r, last: False)
    assert rows.now == {}

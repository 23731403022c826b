"""The kernel of a task with an object family: a kernel moved onto each episode's object.

A family task draws its object per episode (`crmgrasp.tasks.Task.instance`), so
the rows of a batch would each need their own object. [`FamilyKernel`][] therefore
steps one episode at a time: `sample_start` draws the object and gives it a
kernel, the one [`crmgrasp.kernels.kernel_for`][] picks for the first object of that
type (compiled for polygons, the reference for discs) rebound to the new object
([`rebind`][crmgrasp.kernels.base.Kernel.rebind]: a compiled kernel moves itself, in place),
and every step goes to that kernel. Batched steps over rows
(`step_batch`, `sample_starts`) are refused with the reason.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

from crmgrasp._validation import CrmgraspError
from crmgrasp.kernels.base import F64, I64, BatchStep, Kernel
from crmgrasp.model.hand import CRM
from crmgrasp.sim import OneStep, SimState
from crmgrasp.tasks import Task

__all__ = ["FamilyKernel"]


class FamilyKernel(Kernel):
    """Steps a family task through per-object kernels ``make(instance)``."""

    name = "family"
    current: Kernel
    """The kernel of the current episode's object."""

    def __init__(self, task: Task, make: Callable[[Task], Kernel]) -> None:
        super().__init__(task)
        self._make = make
        self._templates: dict[type, Kernel] = {}
        self.use(task.with_object(task.obj))

    def _kernel(self, instance: Task) -> Kernel:
        """The kernel of one episode's object: ``make(instance)`` for the first object of its
        type, then that kernel rebound to each new object ([`Kernel.rebind`][]: the same
        path, as ``make`` chooses by the object's type, and the same results)."""
        template = self._templates.get(type(instance.obj))
        if template is None:
            template = self._templates[type(instance.obj)] = self._make(instance)
            return template
        return template.rebind(instance)

    @property
    def instance(self) -> Task:
        """The task on the current episode's object."""
        return self._instance

    def use(self, instance: Task) -> None:
        """Step ``instance`` (a task on one object of the family) from now on: its kernel
        becomes `current` (as [`crmgrasp.sim.FamilyStepper.use`][] does for the reference)."""
        self._instance, self.current = instance, self._kernel(instance)

    def execute_crms(self, cfg: F64, sen: F64, c: I64, f: I64, r: F64) -> tuple[F64, NDArray[np.int8]]:
        return self.current.execute_crms(cfg, sen, c, f, r)

    def observe(self, cfg: F64, sen: F64, err: np.ndarray) -> tuple[np.ndarray, ...]:
        return self.current.observe(cfg, sen, err)

    def sample_start(self, rng: np.random.Generator) -> Any:
        """Draw the episode's object (`Task.instance`), then a start on it."""
        self.use(self.task.instance(rng))
        return self.current.sample_start(rng)

    def sample_starts(self, rng: np.random.Generator, n: int) -> F64:
        raise CrmgraspError(f"task {self.task.name!r} draws an object per episode: starts come one at a time")

    def begin(self, config: Any, rng: np.random.Generator) -> OneStep:
        return self.current.begin(config, rng)

    def step_one(self, state: SimState, action: int | CRM, rng: np.random.Generator) -> OneStep:
        return self.current.step_one(state, action, rng)

    def step_row(self, state: SimState, row: F64, rng: np.random.Generator, checked: bool = False) -> OneStep:
        return self.current.step_row(state, row, rng, checked)

    def step_table(
        self, cfg: F64, sen: F64, table: F64, resets: NDArray[np.bool_], starts: F64, rng: np.random.Generator
    ) -> BatchStep:
        raise CrmgraspError(f"task {self.task.name!r} draws an object per episode: it steps one episode at a time")

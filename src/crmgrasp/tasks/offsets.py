"""A task's continuous action space on a grid: the discrete task whose CRMs are evenly
spaced offsets of each of its [`CRMRange`][crmgrasp.model.actions.CRMRange]s.

The references, learners and planners of the discrete action space run unchanged on a
gridded task, so the belief-space optimum over a fine grid prices a hand-picked CRM set
(``crmgrasp reproduce continuous-offsets``).
"""

from __future__ import annotations

import dataclasses
from typing import Any

from crmgrasp._validation import CrmgraspError
from crmgrasp.tasks.core import Symmetry, Task

__all__ = ["offset_grid", "grid_crms", "mirror_symmetry"]


def grid_crms(task: Task, n: int) -> tuple[Any, ...]:
    """The CRMs of ``n`` offsets per coordinate over each of ``task.crm_ranges`` (a fixed
    range gives its one CRM), in range order, without repeats."""
    out: list[Any] = []
    for rg in task.crm_ranges:
        points = [rg.low] if rg.fixed else rg.grid(n)
        for r in points:
            crm = task.model.range_crm(rg, r)
            if crm not in out:
                out.append(crm)
    return tuple(out)


def mirror_symmetry(task: Task, actions: tuple[Any, ...]) -> Symmetry | None:
    """The symmetry of ``task`` carried over to the CRM set ``actions``: the permutation
    that maps each CRM to its mirror, if ``task`` declares a symmetry and every mirror is
    in the set; else ``None``."""
    if task.symmetry is None:
        return None
    perm = []
    for crm in actions:
        try:
            perm.append(actions.index(task.mirror_crm(crm)))
        except ValueError:
            return None
    return Symmetry(tuple(perm))


def offset_grid(task: Task, n: int) -> Task:
    """``task`` with the CRMs [`grid_crms`][] ``(task, n)`` as its actions, named
    ``<name>-grid<n>``: its declared symmetry kept where the grid is mirror-closed
    ([`mirror_symmetry`][]), its reference mean dropped (another action set)."""
    if isinstance(n, bool) or not isinstance(n, int) or n < 1:
        raise CrmgraspError(f"offsets per pair must be an integer >= 1, got {n!r}")
    actions = grid_crms(task, n)
    return dataclasses.replace(
        task,
        name=f"{task.name}-grid{n}",
        actions=actions,
        symmetry=mirror_symmetry(task, actions),
        reference_mean_steps=None,
    )

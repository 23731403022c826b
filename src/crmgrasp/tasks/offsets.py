"""A task's continuous action space on a grid: the discrete task whose CRMs are evenly
spaced offsets of each of its [`CRMRange`][crmgrasp.model.actions.CRMRange]s.

The references, learners and planners of the discrete action space run unchanged on a
gridded task, so the belief-space optimum over a fine grid prices a hand-picked CRM set
(``crmgrasp reproduce continuous-offsets``).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

from crmgrasp._validation import CrmgraspError, integer
from crmgrasp.model.actions import MAX_GRID
from crmgrasp.tasks.core import Task, checked_task
from crmgrasp.tasks.symmetry import Symmetry, symmetry_of

__all__ = ["offset_grid", "grid_crms", "mirror_symmetry", "OffsetTree", "offset_tree", "MAX_DEPTH", "MAX_GRID_CRMS"]


MAX_GRID_CRMS = 100_000
"""The most CRMs a grid of offsets may make (a 3-D task's four pairs: up to 158 offsets per
coordinate)."""


def grid_crms(task: Task, n: int) -> tuple[Any, ...]:
    """The CRMs of ``n`` offsets per coordinate over each of ``task.crm_ranges`` (a fixed
    range gives its one CRM), in range order, without repeats; at most [`MAX_GRID_CRMS`][]
    of them (one-line error)."""
    n = integer(n, "offsets per pair", 1, MAX_GRID)
    count = sum(1 if rg.fixed else n ** len(rg.low) for rg in task.crm_ranges)
    if count > MAX_GRID_CRMS:
        raise CrmgraspError(
            f"{n} offsets per coordinate make {count:,} CRMs on task {task.name!r}; at most {MAX_GRID_CRMS:,}"
        )
    out: dict[Any, None] = {}
    for rg in task.crm_ranges:
        points = [rg.low] if rg.fixed else rg.grid(n)
        for r in points:
            out.setdefault(task.model.range_crm(rg, r), None)
    return tuple(out)


def mirror_symmetry(task: Task, actions: tuple[Any, ...]) -> Symmetry | None:
    """The symmetry of ``task`` carried over to the CRM set ``actions``: the permutation
    that maps each CRM to its mirror, if ``task`` declares a symmetry and every mirror is
    in the set; else ``None``."""
    if task.symmetry is None:
        return None
    try:
        return symmetry_of(actions, task.mirror_crm)
    except CrmgraspError:
        return None


def offset_grid(task: Task, n: int) -> Task:
    """``task`` with the CRMs [`grid_crms`][] ``(task, n)`` as its actions, named
    ``<name>-grid<n>``: its declared symmetry kept where the grid is mirror-closed
    ([`mirror_symmetry`][]), its reference mean dropped (another action set)."""
    actions = grid_crms(checked_task(task, "offset_grid"), n)
    return dataclasses.replace(
        task,
        name=f"{task.name}-grid{n}",
        actions=actions,
        symmetry=mirror_symmetry(task, actions),
        reference_mean_steps=None,
    )


MAX_DEPTH = 7
"""Deepest dyadic grid [`offset_tree`][] recognises: ``2**7 + 1 = 129`` offsets per coordinate."""


@dataclass(frozen=True)
class OffsetTree:
    """The dyadic refinement structure of a task whose CRMs are a grid of ``2**depth + 1``
    offsets per coordinate (what [`offset_grid`][] builds for such ``n``).

    Coordinate ``i`` of a grid point, ``0 <= i <= 2**depth``, first appears on the grid
    of ``2**l + 1`` offsets with ``l = depth - min(v(i), depth)``, ``v(i)`` the number of
    times 2 divides ``i`` (``v(0) = depth``); a point's ``level`` is the largest of its
    coordinates' (a fixed CRM has level 0). So the CRMs of level ``<= l`` are exactly the
    grid of ``2**l + 1`` offsets per coordinate. The ``children`` of a point of level
    ``l < depth`` are the grid points at ``h = 2**(depth - l - 1)`` grid steps from it in
    each coordinate (``-h``, ``0`` or ``+h``; not all ``0``), within the range: the
    ``3**dim - 1`` neighbours at half the spacing of its level, all of level ``l + 1``.

    Attributes
    ----------
    depth
        ``2**depth + 1`` offsets per coordinate.
    level
        Per action of the task, its level (``0 .. depth``).
    children
        Per action, the actions one level finer around it (empty at ``depth``).
    """

    depth: int
    level: tuple[int, ...]
    children: tuple[tuple[int, ...], ...]

    def coarse(self, level: int) -> tuple[int, ...]:
        """The actions of level at most ``level``: the grid of ``2**level + 1`` offsets per
        coordinate, in action order."""
        return tuple(a for a, lv in enumerate(self.level) if lv <= level)


def _level(i: int, depth: int) -> int:
    twos = depth if i == 0 else (i & -i).bit_length() - 1
    return depth - min(twos, depth)


def offset_tree(task: Task) -> OffsetTree:
    """The [`OffsetTree`][] of ``task``, whose CRMs must be exactly
    [`grid_crms`][] ``(task, 2**depth + 1)`` for a ``depth`` of 1 to [`MAX_DEPTH`][]
    (``--offset-grid`` 3, 5, 9, 17, 33, 65 or 129); a one-line error otherwise."""
    from itertools import product

    sizes = [rg.dim for rg in task.crm_ranges if not rg.fixed]
    for depth in range(1, MAX_DEPTH + 1):
        if any((2**depth + 1) ** dim > len(task.actions) for dim in sizes):
            continue  # one range's grid alone has more CRMs than the task: this and finer grids cannot match
        if grid_crms(task, 2**depth + 1) == task.actions:
            break
    else:
        raise CrmgraspError(
            f"task {task.name!r}: refining offsets needs its CRMs on a grid of 2**d + 1 offsets per pair "
            f"(--offset-grid 3, 5, 9, 17, 33, 65 or 129)"
        )
    n = 2**depth + 1
    index = {crm: a for a, crm in enumerate(task.actions)}
    level = [0] * len(task.actions)
    children: list[set[int]] = [set() for _ in task.actions]
    for rg in task.crm_ranges:
        if rg.fixed:
            continue
        points = rg.grid(n)
        at = {}
        for cell, r in zip(product(range(n), repeat=rg.dim), points, strict=True):
            a = index[task.model.range_crm(rg, r)]
            at[cell] = a
            level[a] = max(_level(i, depth) for i in cell)
        for cell, a in at.items():
            if level[a] == depth:
                continue
            h = 2 ** (depth - level[a] - 1)
            for step in product((-h, 0, h), repeat=rg.dim):
                near = at.get(tuple(i + s for i, s in zip(cell, step, strict=True)))
                if any(step) and near is not None:
                    children[a].add(near)
    return OffsetTree(depth, tuple(level), tuple(tuple(sorted(c)) for c in children))

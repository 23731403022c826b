"""A learner that chooses its CRMs' offsets: model-based value iteration on offsets that it
refines where they pay.

The paper's action space is ``C x C x [-r_max, r_max]``: a contact pair and a real offset.
`RefineVI` learns on a task whose CRMs are a dyadic grid of ``2**depth + 1`` offsets per
coordinate and pair (``--offset-grid 33``: spacing 1 cm over ``[-0.16, 0.16]`` m), but
starts from its coarse grid only (the CRMs of level ``<= start_level``,
[`crmgrasp.tasks.offsets.OffsetTree`][]; level 2: five offsets per coordinate) and adds
finer offsets one history at a time, around the offsets that work there (a zooming
search, as in hierarchical optimistic optimisation):

* every history ``s`` has its own set of **open** CRMs, at first the coarse grid;
* after each update in ``s``, if the greedy policy's best tried CRM ``a`` in ``s`` has been
  tried ``refine_after`` times, its children (the offsets around it at half its level's
  spacing, [`OffsetTree`][crmgrasp.tasks.offsets.OffsetTree]) open in ``s``;
* everything else is [`ModelVI`][crmgrasp.agents.model_based.ModelVI]: an open, untried
  CRM is worth ``q_act`` to the acting values, a closed one ``-inf`` (never chosen, never
  the value of a history), and the greedy policy picks the best tried CRM.

So a child is tried only where no tried CRM of its history is known to beat ``q_act``
(``ModelVI``'s mild optimism); where the coarse grid already grasps, nothing finer is
tried. The offsets it can reach are the grid's (``0.32 / 2**depth`` m apart); the ones it
tries are the few around the best of each history.
"""

from __future__ import annotations

import math
from collections.abc import Collection
from collections.abc import Set as AbstractSet
from typing import Any

import numpy as np

from crmgrasp._validation import CrmgraspError, integer
from crmgrasp.agents.base import greedy_choice
from crmgrasp.agents.model_based import ModelVI

__all__ = ["RefineVI", "CLOSED"]

CLOSED = -math.inf
"""Acting value of a CRM not yet open in a history."""


class RefineVI(ModelVI):
    """[`ModelVI`][crmgrasp.agents.model_based.ModelVI] over offsets opened history by
    history (see the module docstring). It needs the task's
    [`OffsetTree`][crmgrasp.tasks.offsets.OffsetTree], which
    [`crmgrasp.agents.training.build_agent`][] binds (`bind`) from the task it learns on.

    Parameters
    ----------
    n_actions
        Number of actions (the task's grid of CRMs).
    start_level
        The CRMs open in every history: the grid of ``2**start_level + 1`` offsets per
        coordinate (2 by default: five).
    refine_after
        Tries of a history's best CRM before its children open there (3 by default).
    **kwargs
        [`ModelVI`][crmgrasp.agents.model_based.ModelVI]'s parameters.
    """

    name = "refine-vi"

    def __init__(self, n_actions: int, start_level: int = 2, refine_after: int = 3, **kwargs: Any) -> None:
        super().__init__(n_actions, **kwargs)
        self.start_level = integer(start_level, "start_level", 0, 7)
        self.refine_after = integer(refine_after, "refine_after", 1, 1_000_000)
        self.children: tuple[tuple[int, ...], ...] = ()
        self.coarse: tuple[int, ...] = tuple(range(n_actions))
        self._coarse_set: frozenset[int] = frozenset(self.coarse)
        self.open: dict[int, set[int]] = {}
        """History code -> its open CRMs (histories not listed: the coarse grid)."""

    def params(self) -> dict[str, Any]:  # type: ignore[override]
        return {**super().params(), "start_level": self.start_level, "refine_after": self.refine_after}

    def bind(self, frame: Any) -> None:
        """Read the offset tree of the frame's task (before the first update)."""
        from crmgrasp.tasks.offsets import offset_tree

        tree = offset_tree(frame.task)
        if len(tree.level) != self.n_actions:
            raise CrmgraspError(f"refine-vi has {self.n_actions} actions, its task {len(tree.level)}")
        if self.start_level > tree.depth:
            raise CrmgraspError(f"start_level {self.start_level} is finer than the task's grid (depth {tree.depth})")
        self.children, self.coarse = tree.children, tree.coarse(self.start_level)
        self._coarse_set = frozenset(self.coarse)

    def set_prior(self, prior: Any, weight: float = 1.0) -> None:
        """[`ModelVI.set_prior`][crmgrasp.agents.model_based.ModelVI.set_prior], each
        prior pair's CRM opened in its history."""
        for s, a in prior:
            self.open.setdefault(s, set(self.coarse)).add(a)
        super().set_prior(prior, weight)

    def opened(self, s: int) -> AbstractSet[int]:
        """The CRMs open in history ``s`` (a view: not to be changed)."""
        return self.open.get(s) or self._coarse_set

    def _row(self, s: int) -> list[float]:
        row = self.q.get(s)
        if row is None:
            row = [CLOSED] * self.n_actions
            for a in self.opened(s):
                row[a] = self.q_act
            self.q[s] = row
            self.q_greedy[s] = [self.unknown] * self.n_actions
        return row

    # ----------------------------------------------------------------- acting
    def act(self, state: int, rng: np.random.Generator) -> int:
        """The best open CRM by the acting values (``epsilon``: a uniform open one)."""
        if self.epsilon > 0.0 and rng.random() < self.epsilon:
            acts = sorted(self.opened(state))
            return acts[int(rng.integers(len(acts)))]
        row = self.q.get(state)
        if row is None:
            return self.coarse[int(rng.integers(len(self.coarse)))]
        return greedy_choice(row, rng)

    def greedy(self, state: int, rng: np.random.Generator, banned: Collection[int] = ()) -> int:
        """The best tried CRM by the greedy values (a coarse one where none was tried),
        outside ``banned`` where given."""
        if not self.tried.get(state) and not banned:
            return self.coarse[int(rng.integers(len(self.coarse)))]
        return super().greedy(state, rng, banned)

    def update(
        self, s: int, a: int, r: float, s2: int, a2: int | None, terminal: bool, rng: np.random.Generator
    ) -> None:
        """Count the outcome, plan, and open the children of ``s``'s best tried CRM once it
        has been tried ``refine_after`` times (planning again if any opened)."""
        if a not in self.opened(s):
            raise CrmgraspError(f"refine-vi: CRM {a} is not open in history {s}")
        self._row(s)
        super().update(s, a, r, s2, a2, terminal, rng)
        if self._refine(s):
            self._plan()

    def _refine(self, s: int) -> bool:
        best = max(sorted(self.tried[s]), key=self.q_greedy[s].__getitem__)
        if sum(self.model[(s, best)].values()) < self.refine_after:
            return False
        opened = self.open.setdefault(s, set(self.coarse))
        new = [c for c in self.children[best] if c not in opened]
        row = self.q[s]
        for c in new:
            opened.add(c)
            row[c] = self.q_act
        return bool(new)

    def _plan(self) -> None:
        for s, _ in self.model:
            self._row(s)
        super()._plan()

"""Learning on the quotient of the k-order MDP by a task's mirror symmetry.

If a task declares a [`Symmetry`][crmgrasp.tasks.Symmetry] ``sigma``, the history
``h = (o_t, a_{t-1}, ..., a_{t-k})`` and its mirror ``sigma(h)`` (each observation's
``m_a`` and ``m_b`` bins swapped, each action mapped by ``sigma``) are the same
situation seen in a mirror: ``Q(h, a) = Q(sigma(h), sigma(a))`` for the optimal
values. `SymmetricAgent` keeps one table entry per pair ``{h, sigma(h)}``
(the smaller code is the representative): in a non-representative state it
mirrors the state before asking the inner learner and mirrors the chosen action
back, and it mirrors transitions before updating. Every real transition thus
trains both mirror images, and the policy is symmetric by construction, so the
pooled data come from the same (mirrored) visitation distribution; merely adding
mirrored copies of transitions to a learner that may act asymmetrically biases
its model of non-Markov histories (tried: some runs stall at 1.76 CRMs).

One exception is exact: at a start history that is its own mirror image (no CRM yet,
an observation whose mirror image is itself), the hidden state is drawn from the
task's start distribution, which a symmetric task makes mirror-symmetric, so
``(h, a) -> o`` and ``(h, sigma(a)) -> sigma(o)`` have the same probability whatever
the policy. An inner learner that sets ``mirror_start = True`` is taught every
transition from such a history twice, as taken and mirrored.
"""

from __future__ import annotations

from collections.abc import Collection
from typing import Any

import numpy as np

from crmgrasp._validation import CrmgraspError
from crmgrasp.agents.tabular import TabularAgent
from crmgrasp.model.history import KOrderEncoder
from crmgrasp.tasks import Task

__all__ = ["SymmetricAgent", "mirror_observation_map"]


def mirror_observation_map(task: Task) -> list[int]:
    """Discretized observation index -> index of its mirror image (padding maps to itself)."""
    d, axes = task.discretizer, task.model.mirror_axes
    out = []
    for i in range(d.size):
        bins, e = d.decode(i)
        out.append(d.compose([bins[j] for j in axes], e))  # two contacts: the m_a and m_b bins swapped
    return [*out, d.size]


class SymmetricAgent:
    """A tabular learner on the mirror quotient of ``task``'s k-order MDP (see the module docstring)."""

    def __init__(self, inner: TabularAgent, task: Task, encoder: KOrderEncoder) -> None:
        if task.symmetry is None:
            raise CrmgraspError(f"task {task.name!r} declares no symmetry; symmetric learning needs one")
        if not isinstance(inner, TabularAgent):
            raise CrmgraspError(f"symmetric learning needs a tabular learner, got {getattr(inner, 'name', inner)!r}")
        self.inner, self.encoder = inner, encoder
        self.name, self.n_actions = inner.name, inner.n_actions
        self._amap = [*task.symmetry.actions, len(task.actions)]  # the padding action maps to itself
        self._omap = mirror_observation_map(task)
        self._mirror: dict[int, int] = {}
        self._tie_start = bool(getattr(inner, "mirror_start", False)) and encoder.k >= 1

    def mirror(self, s: int) -> int:
        """Code of the mirror image of history code ``s``."""
        m = self._mirror.get(s)
        if m is None:
            h = self.encoder.decode(s)
            m = self.encoder.encode(tuple(self._omap[v] if i % 2 == 0 else self._amap[v] for i, v in enumerate(h)))
            self._mirror[s] = m
        return m

    def representative(self, s: int) -> tuple[int, bool]:
        """The representative of history code ``s`` (the smaller of ``s`` and its mirror image's
        code) and whether it is the mirror image."""
        m = self.mirror(s)
        return (m, True) if m < s else (s, False)

    def params(self) -> dict[str, Any]:
        """The inner learner's parameters and ``symmetric``."""
        return {**self.inner.params(), "symmetric": True}

    def begin_episode(self) -> None:
        """Forwarded to the inner learner."""
        self.inner.begin_episode()

    def act(self, state: int, rng: np.random.Generator, banned: Collection[int] = ()) -> int:
        """The inner learner's behaviour, in the representative's frame (``banned``, the CRMs to
        leave out, mirrored with it)."""
        c, flip = self.representative(state)
        if banned:
            a = self.inner.act(c, rng, {self._amap[b] for b in banned} if flip else banned)  # type: ignore[call-arg]
        else:
            a = self.inner.act(c, rng)
        return self._amap[a] if flip else a

    @property
    def skip_errored(self) -> bool:
        """The inner learner's ``skip_errored`` (false where it has none)."""
        return bool(getattr(self.inner, "skip_errored", False))

    @property
    def skip_errored_learning(self) -> bool:
        """The inner learner's ``skip_errored_learning`` (false where it has none)."""
        return bool(getattr(self.inner, "skip_errored_learning", False))

    def greedy(self, state: int, rng: np.random.Generator, banned: Collection[int] = ()) -> int:
        """The inner learner's greedy action, in the representative's frame (``banned``, the
        CRMs to leave out, mirrored with it)."""
        c, flip = self.representative(state)
        if banned:
            a = self.inner.greedy(c, rng, {self._amap[b] for b in banned} if flip else banned)  # type: ignore[call-arg]
        else:
            a = self.inner.greedy(c, rng)
        return self._amap[a] if flip else a

    def update(
        self, s: int, a: int, r: float, s2: int, a2: int | None, terminal: bool, rng: np.random.Generator
    ) -> None:
        """Update the inner learner on the transition mapped to representatives."""
        c, flip = self.representative(s)
        c2, flip2 = self.representative(s2)
        b = self._amap[a] if flip else a
        b2 = None if a2 is None else (self._amap[a2] if flip2 else a2)
        self.inner.update(c, b, r, c2, b2, terminal, rng)
        if self._tie_start and self._is_mirror_start(c) and self._amap[b] != b:
            c3, flip3 = self.representative(self.mirror(s2))  # the mirrored transition: a2 becomes sigma(a2)
            b3 = None if a2 is None else (a2 if flip3 else self._amap[a2])
            self.inner.update(c, self._amap[b], r, c3, b3, terminal, rng)

    def _is_mirror_start(self, c: int) -> bool:
        """Whether representative ``c`` is a start history (no CRM yet) that is its own mirror image."""
        return self.encoder.decode(c)[1] == self.n_actions and self.mirror(c) == c

    @property
    def q(self) -> dict[int, list[float]]:
        """The full table: every representative's row and its mirror image's."""
        return self.mirrored_table(self.inner.q)

    @property
    def greedy_table(self) -> dict[int, list[float]]:
        """The inner learner's greedy values, mirrored like [`q`][]."""
        return self.mirrored_table(self.inner.greedy_table)

    def mirrored_table(self, table: dict[int, list[float]]) -> dict[int, list[float]]:
        """A table of representatives' rows with every mirror image's row added (its actions mirrored)."""
        out = {}
        for s, row in table.items():
            out[s] = list(row)
            m = self.mirror(s)
            if m != s:
                out[m] = [row[self._amap[a]] for a in range(self.n_actions)]
        return out

    @property
    def tried(self) -> dict[int, set[int]]:
        """Tried actions, mirrored like [`q`][]."""
        return self.mirrored_sets(self.inner.tried)

    @property
    def greedy_tried(self) -> dict[int, set[int]]:
        """The inner learner's greedy choices per state, mirrored like [`q`][]."""
        return self.mirrored_sets(self.inner.greedy_tried)

    def mirrored_sets(self, sets: dict[int, set[int]]) -> dict[int, set[int]]:
        """Representatives' action sets with every mirror image's set added (mirrored)."""
        out = {}
        for s, acts in sets.items():
            out[s] = set(acts)
            m = self.mirror(s)
            if m != s:
                out[m] = {self._amap[a] for a in acts}
        return out

"""The agent interface shared by every learner and baseline.

An agent maps integer states (k-order history codes) to action indices:

* ``begin_episode()`` before each episode;
* ``act(state, rng) -> action``: the behaviour policy (may explore);
* ``update(s, a, r, s2, a2, terminal, rng)`` after each transition, where ``a2`` is
  the action already chosen in ``s2`` by ``act`` (``None`` when ``terminal``);
* ``greedy(state, rng) -> action``: the learned policy, for evaluation.

All randomness comes from the ``rng`` passed in.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np

__all__ = ["Agent", "greedy_choice"]


@runtime_checkable
class Agent(Protocol):
    """What the training loop needs from a learner or baseline."""

    name: str
    n_actions: int

    def begin_episode(self) -> None: ...

    def act(self, state: int, rng: np.random.Generator) -> int: ...

    def update(
        self, s: int, a: int, r: float, s2: int, a2: int | None, terminal: bool, rng: np.random.Generator
    ) -> None: ...

    def greedy(self, state: int, rng: np.random.Generator) -> int: ...


def greedy_choice(row: list[float], rng: np.random.Generator) -> int:
    """``argmax`` of ``row`` with ties broken uniformly at random (one draw only on ties)."""
    best = max(row)
    ties = [i for i, v in enumerate(row) if v == best]
    if len(ties) == 1:
        return ties[0]
    return ties[int(rng.integers(len(ties)))]

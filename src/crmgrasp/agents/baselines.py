"""Non-learning baselines: uniformly random CRMs, and a fixed CRM sequence."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from crmgrasp._validation import CrmgraspError

__all__ = ["RandomAgent", "FixedSequence"]


class RandomAgent:
    """Chooses a CRM uniformly at random every step; learns nothing."""

    name = "random"

    def __init__(self, n_actions: int) -> None:
        if isinstance(n_actions, bool) or not isinstance(n_actions, int) or n_actions < 1:
            raise CrmgraspError(f"n_actions must be an integer >= 1, got {n_actions!r}")
        self.n_actions = n_actions

    def params(self) -> dict[str, object]:
        return {}

    def begin_episode(self) -> None:
        """Nothing to reset."""

    def act(self, state: int, rng: np.random.Generator) -> int:
        return int(rng.integers(self.n_actions))

    greedy = act

    def update(
        self, s: int, a: int, r: float, s2: int, a2: int | None, terminal: bool, rng: np.random.Generator
    ) -> None:
        """Learns nothing."""


class FixedSequence:
    """Executes a fixed, observation-blind sequence of CRMs, cycling when exhausted.

    The default for paper-box, ``(0, 1, 2, 0, 3, 1)``, opposes a, then b, then
    moves a toward the corner and opposes again, then moves b and opposes.
    """

    name = "fixed"

    def __init__(self, n_actions: int, sequence: Sequence[int] = (0, 1, 2, 0, 3, 1)) -> None:
        self.n_actions = n_actions
        seq = tuple(int(a) for a in sequence)
        if not seq or any(not 0 <= a < n_actions for a in seq):
            raise CrmgraspError(f"sequence must be non-empty actions in [0, {n_actions}), got {sequence!r}")
        self.sequence = seq
        self._i = 0

    def params(self) -> dict[str, object]:
        return {"sequence": list(self.sequence)}

    def begin_episode(self) -> None:
        """Restart the sequence."""
        self._i = 0

    def act(self, state: int, rng: np.random.Generator) -> int:
        a = self.sequence[self._i % len(self.sequence)]
        self._i += 1
        return a

    def greedy(self, state: int, rng: np.random.Generator) -> int:
        return self.act(state, rng)

    def update(
        self, s: int, a: int, r: float, s2: int, a2: int | None, terminal: bool, rng: np.random.Generator
    ) -> None:
        """Learns nothing."""

"""Tabular learners over integer states: SARSA, Q-learning, SARSA(lambda), Dyna-Q.

Q is a sparse table ``{state: [Q(s, a) for a in actions]}``; an unseen state has
every value equal to ``q0`` (0 in the paper: optimistic under reward -1, so every
action is tried). Updates (Sutton and Barto, 1998):

* SARSA: ``Q(s,a) += alpha (r + gamma Q(s',a') - Q(s,a))``;
* Q-learning: ``Q(s,a) += alpha (r + gamma max_b Q(s',b) - Q(s,a))``;
* SARSA(lambda): ``delta = r + gamma Q(s',a') - Q(s,a)``; ``e(s,a) += 1``
  (accumulating) or ``e(s,a) = 1`` (replacing, which also clears the other actions'
  traces in ``s``); then ``Q += alpha delta e`` and ``e *= gamma lambda`` over all
  traced pairs;
* Dyna-Q: a Q-learning update, then ``n_planning`` updates on pairs drawn uniformly
  from those seen, with an outcome drawn from the empirical (maximum-likelihood)
  model of the pair: the k-order MDP is stochastic because of aliasing.

At a terminal transition the target is ``r``; at a truncation (step limit) the
update bootstraps from ``a'`` as usual. Behaviour is epsilon-greedy (epsilon 0 is
the paper's greedy) with random tie-breaking.
"""

from __future__ import annotations

import numpy as np

from crmgrasp._validation import CrmgraspError, finite
from crmgrasp.agents.base import greedy_choice

__all__ = ["TabularAgent", "Sarsa", "QLearning", "SarsaLambda", "DynaQ"]


def _unit(value: float, name: str, *, closed_low: bool = True) -> float:
    x = finite(value, name)
    if not ((0.0 <= x) if closed_low else (0.0 < x)) or x > 1.0:
        raise CrmgraspError(f"{name} must be in {'[' if closed_low else '('}0, 1], got {x}")
    return x


class TabularAgent:
    """Shared table, epsilon-greedy behaviour and greedy policy."""

    name = "tabular"

    def __init__(self, n_actions: int, alpha: float = 0.3, gamma: float = 0.9, epsilon: float = 0.0, q0: float = 0.0):
        if isinstance(n_actions, bool) or not isinstance(n_actions, int) or n_actions < 1:
            raise CrmgraspError(f"n_actions must be an integer >= 1, got {n_actions!r}")
        self.n_actions = n_actions
        self.alpha = _unit(alpha, "alpha", closed_low=False)
        self.gamma = _unit(gamma, "gamma")
        self.epsilon = _unit(epsilon, "epsilon")
        self.q0 = finite(q0, "q0")
        self.q: dict[int, list[float]] = {}
        self.tried: dict[int, set[int]] = {}

    def params(self) -> dict[str, float]:
        """Hyperparameters, for saving with results."""
        return {"alpha": self.alpha, "gamma": self.gamma, "epsilon": self.epsilon, "q0": self.q0}

    def row(self, s: int) -> list[float]:
        """The (mutable) row of ``s``, created on first use."""
        r = self.q.get(s)
        if r is None:
            r = self.q[s] = [self.q0] * self.n_actions
        return r

    @property
    def greedy_table(self) -> dict[int, list[float]]:
        """The values the greedy policy ranks tried actions by (the table itself)."""
        return self.q

    @property
    def greedy_tried(self) -> dict[int, set[int]]:
        """The actions the greedy policy chooses among in each state (the tried ones)."""
        return self.tried

    def value(self, s: int) -> list[float]:
        """Q values of ``s`` without creating a row."""
        return self.q.get(s) or [self.q0] * self.n_actions

    def begin_episode(self) -> None:
        """Nothing to reset for one-step methods."""

    def greedy(self, state: int, rng: np.random.Generator) -> int:
        """The learned policy: the best action among those tried in ``state`` (random
        tie-breaking); every action if none was tried. Untried actions keep their
        optimistic ``q0``, which drives exploration in [`act`][] but is no estimate."""
        tried = self.tried.get(state)
        row = self.value(state)
        if not tried or len(tried) == self.n_actions:
            return greedy_choice(row, rng)
        acts = sorted(tried)
        return acts[greedy_choice([row[a] for a in acts], rng)]

    def act(self, state: int, rng: np.random.Generator) -> int:
        """Behaviour: epsilon-greedy on all values, untried actions at their optimistic
        ``q0`` (no draw for exploration when epsilon is 0)."""
        if self.epsilon > 0.0 and rng.random() < self.epsilon:
            return int(rng.integers(self.n_actions))
        return greedy_choice(self.value(state), rng)

    def _mark(self, s: int, a: int) -> None:
        t = self.tried.get(s)
        if t is None:
            self.tried[s] = {a}
        else:
            t.add(a)

    def _target(self, s2: int, a2: int | None) -> float:
        """Bootstrap value of ``s2``: ``max_b Q(s2, b)`` (Q-learning); SARSA overrides it."""
        return max(self.value(s2))

    def _td(self, s: int, a: int, r: float, s2: int, a2: int | None, terminal: bool) -> None:
        """``Q(s,a) += alpha (r + gamma target(s2, a2) - Q(s,a))``, target ``r`` if terminal."""
        row = self.row(s)
        target = r if terminal else r + self.gamma * self._target(s2, a2)
        row[a] += self.alpha * (target - row[a])

    def update(
        self, s: int, a: int, r: float, s2: int, a2: int | None, terminal: bool, rng: np.random.Generator
    ) -> None:
        """One-step TD update toward ``r + gamma * target(s2, a2)`` (``r`` if terminal)."""
        self._mark(s, a)
        self._td(s, a, r, s2, a2, terminal)


class Sarsa(TabularAgent):
    """On-policy SARSA (the paper's learner: alpha 0.3, gamma 0.9, Q0 = 0, greedy)."""

    name = "sarsa"

    def _target(self, s2: int, a2: int | None) -> float:
        assert a2 is not None
        return self.value(s2)[a2]


class QLearning(TabularAgent):
    """Off-policy Q-learning (the base class's target, ``max_b Q(s', b)``)."""

    name = "q"


class SarsaLambda(TabularAgent):
    """SARSA(lambda) with replacing or accumulating eligibility traces."""

    name = "sarsa-lambda"

    def __init__(self, n_actions: int, lam: float = 0.9, trace: str = "replacing", **kwargs: float):
        super().__init__(n_actions, **kwargs)
        self.lam = _unit(lam, "lambda")
        if trace not in ("replacing", "accumulating"):
            raise CrmgraspError(f"trace must be 'replacing' or 'accumulating', got {trace!r}")
        self.trace = trace
        self.e: dict[tuple[int, int], float] = {}

    def params(self) -> dict[str, float | str]:  # type: ignore[override]
        return {**super().params(), "lambda": self.lam, "trace": self.trace}

    def begin_episode(self) -> None:
        """Clear the traces."""
        self.e.clear()

    def update(
        self, s: int, a: int, r: float, s2: int, a2: int | None, terminal: bool, rng: np.random.Generator
    ) -> None:
        """Trace update over every pair visited this episode."""
        self._mark(s, a)
        target = r if terminal else r + self.gamma * self.value(s2)[a2]  # type: ignore[index]
        delta = target - self.row(s)[a]
        if self.trace == "replacing":
            for b in range(self.n_actions):
                self.e.pop((s, b), None)
            self.e[(s, a)] = 1.0
        else:
            self.e[(s, a)] = self.e.get((s, a), 0.0) + 1.0
        decay = self.gamma * self.lam
        for (ts, ta), trace in self.e.items():
            self.q[ts][ta] += self.alpha * delta * trace
            self.e[(ts, ta)] = trace * decay


class DynaQ(TabularAgent):
    """Dyna-Q: Q-learning on real steps plus planning on a learned model.

    The model keeps, per state-action pair, the count of each observed outcome
    ``(r, s', terminal)``: the maximum-likelihood estimate of the k-order MDP.
    ``planning="sample"`` (classic Dyna-Q) makes ``n_planning`` Q-learning updates
    on pairs and outcomes drawn from it. ``planning="sweep"`` instead runs value
    iteration on the model after every real step (expected updates,
    ``Q(s,a) = sum_o p(o|s,a) (r + gamma max_b Q(s',b))``, in place, at most
    ``n_planning`` sweeps or until the largest change is below ``1e-6``): the
    certainty-equivalent values, with untried pairs kept at ``q0`` (optimism).
    """

    name = "dyna-q"

    def __init__(self, n_actions: int, n_planning: int = 20, planning: str = "sample", **kwargs: float):
        super().__init__(n_actions, **kwargs)
        if isinstance(n_planning, bool) or not isinstance(n_planning, int) or n_planning < 0:
            raise CrmgraspError(f"n_planning must be an integer >= 0, got {n_planning!r}")
        if planning not in ("sample", "sweep"):
            raise CrmgraspError(f"planning must be 'sample' or 'sweep', got {planning!r}")
        self.n_planning = n_planning
        self.planning = planning
        self.model: dict[tuple[int, int], dict[tuple[float, int, bool], int]] = {}
        self._pairs: list[tuple[int, int]] = []
        self._samples: dict[tuple[int, int], list[tuple[float, int, bool]]] = {}

    def params(self) -> dict[str, float | str]:  # type: ignore[override]
        return {**super().params(), "n_planning": self.n_planning, "planning": self.planning}

    def update(
        self, s: int, a: int, r: float, s2: int, a2: int | None, terminal: bool, rng: np.random.Generator
    ) -> None:
        """Real Q-learning update, model update, then planning."""
        self._mark(s, a)
        self._td(s, a, r, s2, None, terminal)
        outcome = (r, s2, terminal)
        counts = self.model.get((s, a))
        if counts is None:
            counts = self.model[(s, a)] = {}
            self._pairs.append((s, a))
            self._samples[(s, a)] = []
        counts[outcome] = counts.get(outcome, 0) + 1
        self._samples[(s, a)].append(outcome)
        if self.n_planning == 0:
            return
        if self.planning == "sweep":
            self._sweep()
            return
        picks = rng.random((self.n_planning, 2))
        for u, v in picks:
            ps, pa = self._pairs[int(u * len(self._pairs))]
            seen = self._samples[(ps, pa)]
            pr, ps2, pterm = seen[int(v * len(seen))]
            self._td(ps, pa, pr, ps2, None, pterm)

    def _sweep(self) -> None:
        gamma, q = self.gamma, self.q
        dist = [
            (q[s], a, [(c / sum(counts.values()), r, s2, term) for (r, s2, term), c in counts.items()])
            for (s, a), counts in self.model.items()
        ]
        for _ in range(self.n_planning):
            change = 0.0
            for row, a, outcomes in dist:
                new = 0.0
                for p, r, s2, term in outcomes:
                    new += p * (r if term else r + gamma * max(self.value(s2)))
                change = max(change, abs(new - row[a]))
                row[a] = new
            if change < 1e-6:
                break

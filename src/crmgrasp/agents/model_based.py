"""A sample-efficient learner: certainty-equivalent planning with two value functions.

`ModelVI` keeps the maximum-likelihood model of the k-order MDP (per
history-action pair, the count of each outcome ``(r, s', terminal)``, as
[`DynaQ`][crmgrasp.agents.tabular.DynaQ] does) and after every real step solves it by
value iteration, twice:

* **acting values** ``Q_act``: every untried pair is worth ``q_act`` (a mild optimism:
  -1.5 under reward -1 says "an untried CRM might grasp in one or two"), so the agent
  tries a CRM in a history only while no tried CRM is known to beat that; then it
  exploits;
* **greedy values** ``Q_greedy``: tried pairs only, and a history in which nothing
  was tried is worth ``unknown`` (pessimism, -10 = one full failed episode); the
  greedy policy (what `ModelVI.greedy` and evaluation use) picks the best *tried*
  action, so it never bets on a guess.

Both are ``Q(s,a) = sum_o p(o|s,a) (r + gamma V(s'))`` with ``V(s') = 0`` at a
terminal outcome, iterated in place from the previous solution until the largest
change is below ``1e-6`` or ``sweeps`` sweeps (compiled by default,
[`crmgrasp.kernels.planning.value_iteration`][]; ``compiled=False`` runs the readable
sweeps, the same values bit for bit). Optimism drives exploration, pessimism
makes the reported policy safe: separating the two is what lets the greedy policy be
near-optimal long before the acting policy stops exploring.

A **prior** (`ModelVI.set_prior`) adds pseudo-counts, ``weight`` per pair
spread over the pair's outcomes in a model learned elsewhere (e.g. on an object
family with the same CRMs and bins: [`crmgrasp.agents.training.build_agent`][]
with ``prior_task``); the agent's own counts outweigh it after a few visits.
"""

from __future__ import annotations

from collections.abc import Collection
from typing import Any

import numpy as np

from crmgrasp._validation import CrmgraspError, boolean, finite, integer, positive
from crmgrasp.agents.base import allowed_choice, greedy_choice
from crmgrasp.agents.tabular import TabularAgent

__all__ = ["ModelVI", "Model"]

TOL = 1e-6
"""Value iteration stops when no value changed by this much in a sweep (reward units)."""

Outcome = tuple[float, int, bool]
Model = dict[tuple[int, int], dict[Outcome, float]]
"""``(state, action) -> {(reward, next state, terminal): count}`` (counts may be fractional
where a prior adds pseudo-counts)."""


class ModelVI(TabularAgent):
    """Certainty-equivalent value iteration with optimistic acting and a pessimistic
    greedy policy (see the module docstring).

    Parameters
    ----------
    n_actions
        Number of actions.
    q_act
        Value of an untried pair for acting (reward units; -1.5 by default).
    unknown
        Greedy value of a history with no tried action (-10 by default).
    sweeps
        Most value-iteration sweeps after each step.
    compiled
        Run the compiled sweeps (the readable ones with False; the same values).
    skip_errored
        The greedy policy (evaluated, saved, run) never repeats a CRM that erred since the
        contacts last moved (False by default), as ``backoff-vi``'s
        ([`BackoffVI`][crmgrasp.agents.backoff.BackoffVI]); learning is unchanged.
    **kwargs
        [`TabularAgent`][crmgrasp.agents.tabular.TabularAgent]'s ``alpha``, ``gamma``
        (the discount, 0.9, the paper's), ``epsilon``, ``q0``.
    """

    name = "model-vi"
    keeps_arrays = True
    """The compiled plan keeps its outcome arrays between plans and writes only the pairs in
    ``changed`` again (False for a planning model rebuilt whole before each plan, as
    ``backoff-vi``'s and ``pooled-vi``'s: there is nothing to keep, and keeping the arrays
    would keep the replaced model alive)."""

    def __init__(
        self,
        n_actions: int,
        q_act: float = -1.5,
        unknown: float = -10.0,
        sweeps: int = 100,
        compiled: bool = True,
        skip_errored: bool = False,
        **kwargs: float,
    ) -> None:
        super().__init__(n_actions, **kwargs)
        self.q_act = finite(q_act, "q_act")
        self.unknown = finite(unknown, "unknown")
        self.sweeps = integer(sweeps, "sweeps", 1, 10_000)
        self.compiled = boolean(compiled, "compiled")
        self.skip_errored = boolean(skip_errored, "skip_errored")
        self.model: Model = {}
        self.q_greedy: dict[int, list[float]] = {}
        self.plan_acting = True
        """Plan after every update (False: a learner kept for its model only, planned by
        whoever reads it)."""
        self.changed: set[tuple[Any, int]] | None = None
        """The pairs whose counts changed since the last compiled plan, or None where that is
        not known (the next plan copies the whole model into its arrays). [`update`][] and
        [`set_prior`][] keep it; code that changes ``model`` in place otherwise must set it to
        None. The compiled plan copies only these pairs' outcome probabilities when nothing
        else changed ([`crmgrasp.kernels.planning.value_iteration`][])."""

    def params(self) -> dict[str, Any]:  # type: ignore[override]
        return {
            **super().params(),
            "q_act": self.q_act,
            "unknown": self.unknown,
            "sweeps": self.sweeps,
            "skip_errored": self.skip_errored,
        }

    @property
    def greedy_table(self) -> dict[int, list[float]]:
        """The greedy values (tried pairs; the acting values are ``q``)."""
        return self.q_greedy

    def set_prior(self, prior: Model, weight: float = 1.0) -> None:
        """Add ``weight`` pseudo-counts per pair of ``prior``, spread in proportion to its
        outcome counts, and plan."""
        w = positive(weight, "prior weight")
        for key, counts in prior.items():
            total = sum(counts.values())
            mine = self.model.setdefault(key, {})
            for o, c in counts.items():
                mine[o] = mine.get(o, 0.0) + w * c / total
            self._mark(*key)
        self.changed = None
        if prior:
            self._plan()

    # ----------------------------------------------------------------- acting
    def act(self, state: int, rng: np.random.Generator) -> int:
        """The best action by the acting values (untried actions at ``q_act``)."""
        if self.epsilon > 0.0 and rng.random() < self.epsilon:
            return int(rng.integers(self.n_actions))
        return greedy_choice(self.q.get(state) or [self.q_act] * self.n_actions, rng)

    def greedy(self, state: int, rng: np.random.Generator, banned: Collection[int] = ()) -> int:
        """The best tried action by the greedy values (any action where none was tried),
        outside ``banned`` where given ([`allowed_choice`][crmgrasp.agents.base.allowed_choice])."""
        tried = self.tried.get(state)
        if banned:
            acts = sorted(tried or ())
            return allowed_choice(self.q_greedy.get(state, []), acts, self.n_actions, banned, rng)
        if not tried:
            return int(rng.integers(self.n_actions)) if self.n_actions > 1 else 0
        acts = sorted(tried)
        row = self.q_greedy[state]
        return acts[greedy_choice([row[a] for a in acts], rng)]

    def update(
        self, s: int, a: int, r: float, s2: int, a2: int | None, terminal: bool, rng: np.random.Generator
    ) -> None:
        """Count the outcome, then plan."""
        self._mark(s, a)
        counts = self.model.setdefault((s, a), {})
        o = (r, s2, terminal)
        counts[o] = counts.get(o, 0.0) + 1.0
        if self.changed is not None:
            self.changed.add((s, a))
        if self.plan_acting:
            self._plan()

    # ----------------------------------------------------------------- planning
    def _plan(self) -> None:
        """Value iteration of both value functions on the current model, in place: the
        compiled sweeps (`crmgrasp.kernels._vi_jit`) or, with ``compiled=False``, the
        readable ones below; the same values bit for bit."""
        n = self.n_actions
        for s, _ in self.model:
            if s not in self.q:
                self.q[s] = [self.q_act] * n
                self.q_greedy[s] = [self.unknown] * n
        if self.compiled:
            self._sweeps_compiled()
        else:
            self._sweeps_reference()

    def _sweeps_compiled(self) -> None:
        from crmgrasp.kernels.planning import value_iteration

        value_iteration(self, TOL)

    def _sweeps_reference(self) -> None:
        """Gauss-Seidel sweeps over the pairs in the model's order (the definition)."""
        gamma = self.gamma
        pairs = [
            (self.q[s], self.q_greedy[s], a, [(c / sum(cs.values()), r, s2, t) for (r, s2, t), c in cs.items()])
            for (s, a), cs in self.model.items()
        ]
        for _ in range(self.sweeps):
            change = 0.0
            for qa, qg, a, outcomes in pairs:
                new_a = new_g = 0.0
                for p, r, s2, t in outcomes:
                    new_a += p * (r if t else r + gamma * self._v_act(s2))
                    new_g += p * (r if t else r + gamma * self._v_greedy(s2))
                change = max(change, abs(new_a - qa[a]), abs(new_g - qg[a]))
                qa[a], qg[a] = new_a, new_g
            if change < TOL:
                break

    def _v_act(self, s: int) -> float:
        row = self.q.get(s)
        return self.q_act if row is None else max(row)

    def _v_greedy(self, s: int) -> float:
        tried = self.tried.get(s)
        if not tried:
            return self.unknown
        row = self.q_greedy[s]
        return max(row[a] for a in tried)


def check_same_space(task_a: Any, task_b: Any) -> None:
    """Refuse a prior from a task whose CRMs or bins differ (its histories would mean
    other things)."""
    if task_a.actions != task_b.actions:
        raise CrmgraspError(f"prior task {task_b.name!r} has other CRMs than {task_a.name!r}")
    if task_a.discretizer != task_b.discretizer:
        raise CrmgraspError(f"prior task {task_b.name!r} has other observation bins than {task_a.name!r}")

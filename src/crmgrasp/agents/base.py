"""The learning interface shared by every learner and baseline, and its adapter to
the episode loop's [`Policy`][crmgrasp.sim.Policy].

An agent maps integer states (k-order history codes) to action indices:

* ``begin_episode()`` before each episode;
* ``act(state, rng) -> action``: the behaviour policy (may explore);
* ``update(s, a, r, s2, a2, terminal, rng)`` after each transition, where ``a2`` is
  the action already chosen in ``s2`` by ``act`` (``None`` when ``terminal``);
* ``greedy(state, rng) -> action``: the learned policy, for evaluation.

An agent whose ``skip_errored`` is true (``backoff-vi``'s parameter, and a saved policy made
from one) is also asked ``greedy(state, rng, banned)``: the best action outside ``banned``,
the CRMs that erred since the contacts last moved. An errored CRM leaves the contacts where
they were ([docs/model.md section 3][model-3]), so without sensing noise repeating it from
there errs again for certain: it costs a CRM and tells nothing new. `LearnerPolicy` keeps
that set (empty after a CRM that moved the contacts and at a reset). An agent whose
``skip_errored_learning`` is true is asked ``act(state, rng, banned)`` the same way while it
learns.

All randomness comes from the ``rng`` passed in. `LearnerPolicy` makes an
agent a [`Policy`][crmgrasp.sim.Policy] over k-order histories, so that learners act
through the same episode loop ([`crmgrasp.sim.run_episode`][]) as planners and
controllers.
"""

from __future__ import annotations

from collections.abc import Collection, Sequence
from typing import Protocol, runtime_checkable

import numpy as np

from crmgrasp._validation import CrmgraspError, generator, shown
from crmgrasp.model.hand import Error
from crmgrasp.model.history import KOrderEncoder
from crmgrasp.sim import Percept, check_policy

__all__ = ["Agent", "LearnerPolicy", "greedy_choice", "allowed_choice", "erred_here"]


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


def allowed_choice(
    row: Sequence[float], choices: Sequence[int], n_actions: int, banned: Collection[int], rng: np.random.Generator
) -> int:
    """The best of ``choices`` (actions, ``row`` their values by action) outside ``banned``,
    ties broken uniformly; where every choice is banned, uniform over the actions outside
    ``banned`` (one not yet tried may still move the contacts); where every action is
    banned, the best of ``choices`` (uniform if there are none)."""
    left = [a for a in choices if a not in banned]
    if left:
        return left[greedy_choice([row[a] for a in left], rng)]
    rest = [a for a in range(n_actions) if a not in banned]
    if rest:
        return rest[int(rng.integers(len(rest)))]
    if choices:
        return choices[greedy_choice([row[a] for a in choices], rng)]
    return int(rng.integers(n_actions))


def erred_here(banned: frozenset[int], action: int, error: Error) -> frozenset[int]:
    """The CRMs that erred since the contacts last moved, after ``action`` ended with
    ``error``: ``banned`` and ``action`` if it erred (the contacts stay), none if it moved them."""
    return banned | {action} if error is not Error.NONE else frozenset()


class LearnerPolicy:
    """An [`Agent`][] as a [`Policy`][crmgrasp.sim.Policy]: it keeps the k-order
    history ([docs/model.md section 6][model-6]) of the discretized observations, acts on its code and,
    when ``learn``, updates after every step.

    The order of the agent's draws from ``rng`` is that of SARSA's loop: the first
    action at ``begin``; after each non-terminal step the next action is chosen, then
    the update ``(s, a, r, s', a')`` is made; a terminal step updates with
    ``a' = None``. With ``learn=False`` the agent's greedy policy acts and nothing is
    updated; if the agent's ``skip_errored`` is true, it is then asked for the best action
    outside the CRMs that erred since the contacts last moved (module docstring), and so is its
    acting policy with ``learn=True`` if its ``skip_errored_learning`` is true.
    """

    def __init__(self, agent: Agent, encoder: KOrderEncoder, rng: np.random.Generator, *, learn: bool = True) -> None:
        check_policy(agent, ("begin_episode", "act", "update") if learn else ("begin_episode", "greedy"))
        if not isinstance(encoder, KOrderEncoder):
            raise CrmgraspError(f"a learner acts through a KOrderEncoder (encoder_for(task, k)), got {shown(encoder)}")
        n = getattr(agent, "n_actions", encoder.n_actions)
        if n != encoder.n_actions:
            raise CrmgraspError(f"the agent has {shown(n)} actions, the encoder {encoder.n_actions}")
        self.agent, self.encoder, self.rng, self.learn = agent, encoder, generator(rng), learn
        self._pick = agent.act if learn else agent.greedy
        self._skip = bool(getattr(agent, "skip_errored_learning" if learn else "skip_errored", False))
        self._banned: frozenset[int] = frozenset()
        self._hist: tuple[int, ...] = ()
        self._s = self._a = 0

    def begin(self, first: Percept) -> None:
        self._hist = self.encoder.start(first.obs_index)
        self._s = self.encoder.encode(self._hist)
        self._banned = frozenset()
        self.agent.begin_episode()
        self._a = self._choose(self._s)

    def _choose(self, s: int) -> int:
        if self._banned:
            return self._pick(s, self.rng, self._banned)  # type: ignore[call-arg]
        return self._pick(s, self.rng)

    def act(self) -> int:
        return self._a

    def tell(self, percept: Percept) -> None:
        self._hist = self.encoder.push(self._hist, self._a, percept.obs_index)
        s2 = self.encoder.encode(self._hist)
        if self._skip:
            self._banned = erred_here(self._banned, self._a, percept.error)
        if percept.terminated:
            if self.learn:
                self.agent.update(self._s, self._a, percept.reward, s2, None, True, self.rng)
            return
        a2 = self._choose(s2)
        if self.learn:
            self.agent.update(self._s, self._a, percept.reward, s2, a2, False, self.rng)
        self._s, self._a = s2, a2

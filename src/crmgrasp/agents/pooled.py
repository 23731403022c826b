"""Model-based learning with a pooled prior: `PooledVI` (``pooled-vi``).

[`ModelVI`][crmgrasp.agents.model_based.ModelVI] learns the k-order model of every
history separately, so a history it has seen once or never has no estimate, although
other histories that end in the same sensed bins predict its outcomes well (an
aperture error leaves the contacts where they were: the history after it senses what
the start sensed, and the CRM that grasps from there is the one that grasps from the
start). `PooledVI` adds the missing link, a two-level (back-off) model:

* **own counts** ``n(h, a, o)`` of each outcome ``o = (r, o', terminal)`` after CRM
  ``a`` in history ``h``, as in ``ModelVI``;
* **pooled counts** ``m(b, a, o)`` of the same outcomes over every history whose current
  observation has the sensed bins ``b`` (the observation without its error flag,
  [`Discretizer.decode`][crmgrasp.model.sensing.Discretizer.decode]): ``b(h)``.

The **greedy policy** (the one evaluated and saved) plans on the posterior mean of a
Dirichlet model whose prior is the pooled estimate with weight ``beta``:

``p(o | h, a) = (n(h, a, o) + beta m(b(h), a, o) / m(b(h), a)) / (n(h, a) + beta)``,

and on the pooled estimate alone for a CRM never tried in ``h`` whose bins have data
(the outcome ``o'`` moves ``h`` to its own next history). Value iteration is
``ModelVI``'s, with the pessimistic value ``unknown`` where neither level has data.
The **acting policy** is ``ModelVI``'s on the own counts only (an untried CRM is worth
``q_act``), so every history still tries its CRMs and its own counts soon outweigh a
prior that its history makes wrong; acting on the pooled model instead stalls
(tried: greedy policies that repeat an errored CRM until the step limit).

On a mirror quotient ([`SymmetricAgent`][crmgrasp.agents.symmetric.SymmetricAgent])
the learner asks the wrapper to learn each CRM at a start history that is its own mirror
image under the mirrored CRM too (``mirror_start``): the start distribution of a
symmetric task is symmetric, so both CRMs have mirrored outcome distributions there.

The learner needs to know how its states are built: [`HistoryFrame`][], which
[`crmgrasp.agents.training.build_agent`][] binds to it.
"""

from __future__ import annotations

from collections.abc import Collection
from typing import Any

import numpy as np

from crmgrasp._collector import collector_paused
from crmgrasp._validation import CrmgraspError, finite
from crmgrasp.agents.model_based import Model, ModelVI, Outcome
from crmgrasp.agents.symmetric import SymmetricAgent, mirror_observation_map
from crmgrasp.model.hand import Error
from crmgrasp.model.history import KOrderEncoder
from crmgrasp.tasks import Task

__all__ = ["HistoryFrame", "PooledVI"]

Key = tuple[int, ...]


class HistoryFrame:
    """What a learner may know about its k-order states beyond their codes, and the
    episode's horizon and largest CRM cost for learners that plan over a finite horizon
    ([`crmgrasp.agents.peers`][]).

    Parameters
    ----------
    task
        The task (its bins name the pooling key).
    encoder
        The k-order encoder of the learner's states.
    symmetric
        The mirror-quotient wrapper when the learner runs inside one: states are then its
        representatives, and an outcome's observation is read in its state's frame.
    """

    def __init__(self, task: Task, encoder: KOrderEncoder, symmetric: SymmetricAgent | None = None) -> None:
        self.task, self.encoder, self.discretizer, self.symmetric = task, encoder, task.discretizer, symmetric
        self.horizon = task.max_steps
        """CRMs per episode at most (the task's step limit)."""
        self.max_cost = max(1.0 + task.error_cost, abs(task.grasp_reward))
        """The largest cost of one CRM (reward units): an errored CRM's ``1 + c``, or the grasping one's."""
        self._omap = mirror_observation_map(task) if symmetric is not None else []
        self._keys: dict[int, Key] = {}

    def key(self, s: int, a: int) -> Key:
        """The pooling key of CRM ``a`` in state ``s``: the sensed bins of the current
        observation (its error flag dropped), and whether ``a`` repeats the CRM that has
        just erred (which leaves the hand where it was: other histories with the same
        bins say little about it)."""
        k = self._keys.get(s)
        if k is None:
            h = self.encoder.decode(s)
            bins, error = self.discretizer.decode(h[0])
            last = h[1] if len(h) > 1 and error else -1
            k = self._keys[s] = (*bins, last)
        return (*k[:-1], int(a == k[-1]))

    def siblings(self, s: int) -> set[int]:
        """The states that differ from ``s`` only in the error flag of the current
        observation and in the last CRM (the padding too, at a start): the histories the
        pooled model predicts for as soon as ``s`` is seen (representatives on a mirror
        quotient)."""
        enc, h = self.encoder, self.encoder.decode(s)
        bins = self.discretizer.decode(h[0])[0]
        firsts = [self.discretizer.compose(bins, e) for e in range(len(Error))]
        variants: list[tuple[int, ...]]
        if enc.k == 0:
            variants = [(o,) for o in firsts]
        else:
            tail = h[2:]
            start = all(v == r - 1 for v, r in zip(tail, enc.radices[2:], strict=True))
            lasts = range(enc.n_actions + 1 if start else enc.n_actions)
            variants = [(o, a, *tail) for o in firsts for a in lasts]
        codes = {enc.encode(v) for v in variants}
        if self.symmetric is None:
            return codes
        return {min(t, self.symmetric.mirror(t)) for t in codes}

    def next_state(self, s: int, a: int, obs: int) -> int:
        """The state after CRM ``a`` in ``s`` senses ``obs`` (read in ``s``'s frame): its
        representative on a mirror quotient."""
        t = self.encoder.push_code(s, a, obs)
        if self.symmetric is None:
            return t
        return min(t, self.symmetric.mirror(t))

    def outcome_observations(self, s: int, a: int, s2: int) -> tuple[int, ...]:
        """The observation that CRM ``a`` in ``s`` sensed when it led to state ``s2``, in
        ``s``'s frame. On a mirror quotient ``s2`` is a representative and may be the
        mirror image of the history in ``s``'s frame; both readings are returned where the
        codes cannot tell them apart (a CRM that is its own mirror image after a history
        that is too)."""
        obs = self.encoder.decode(s2)[0]
        if self.symmetric is None:
            return (obs,)
        enc, h, other = self.encoder, self.encoder.decode(s), self._omap[obs]
        plain = enc.encode(enc.push(h, a, obs))
        if plain != s2:
            return (other,)
        flipped = enc.encode(enc.push(h, a, other))
        if flipped != plain and self.symmetric.mirror(flipped) == s2:
            return (obs, other)
        return (obs,)


class PooledVI(ModelVI):
    """``ModelVI`` whose greedy policy plans on a model with a pooled prior (see the
    module docstring).

    Parameters
    ----------
    n_actions
        Number of actions.
    beta
        Weight of the pooled prior in pseudo-counts (0.5 by default: one own outcome
        outweighs it twice over).
    **kwargs
        ``ModelVI``'s parameters (``q_act``, ``unknown``, ``sweeps``, ``gamma``, ...).
    """

    name = "pooled-vi"
    mirror_start = True
    """Learn each CRM at a self-mirror start history under its mirror CRM too."""

    def __init__(self, n_actions: int, beta: float = 0.5, **kwargs: Any) -> None:
        super().__init__(n_actions, **kwargs)
        self.beta = finite(beta, "beta")
        if self.beta < 0.0:
            raise CrmgraspError(f"beta must be >= 0, got {self.beta}")
        sweeps = max(self.sweeps, 1000)  # the greedy model is solved from its initial values
        self.judge = ModelVI(n_actions, self.q_act, self.unknown, sweeps, self.compiled, gamma=self.gamma)
        self.judge.keeps_arrays = False  # rebuilt whole before each plan
        self.frame: HistoryFrame | None = None
        self.pool: dict[tuple[Key, int], dict[Outcome, float]] = {}
        self._known: set[int] = set()
        self._solved = True
        self._untried: dict[tuple[Key, int, int], dict[Outcome, float]] = {}  # per solve, see _entry

    def params(self) -> dict[str, Any]:
        return {**super().params(), "beta": self.beta}

    def bind(self, frame: HistoryFrame) -> None:
        """Give the learner its state structure (before the first update)."""
        self.frame = frame

    @property
    def greedy_table(self) -> dict[int, list[float]]:
        """The greedy values, on the model with the pooled prior."""
        return self.greedy_model().q_greedy

    def greedy_model(self) -> ModelVI:
        """The greedy policy's model with the pooled prior, solved: its ``model``, values
        ``q_greedy`` and choices ``tried``."""
        self._solve()
        return self.judge

    @property
    def greedy_tried(self) -> dict[int, set[int]]:
        """The actions the greedy policy may choose: tried in the state or by its bins."""
        self._solve()
        return self.judge.tried

    def greedy(self, state: int, rng: np.random.Generator, banned: Collection[int] = ()) -> int:
        """The best action on the model with the pooled prior (any action where neither
        level has data), outside ``banned`` where given."""
        self._solve()
        return self.judge.greedy(state, rng, banned)

    def set_prior(self, prior: Model, weight: float = 1.0) -> None:
        """``ModelVI.set_prior`` on the own counts; the greedy model follows."""
        super().set_prior(prior, weight)
        for s, _ in prior:
            self._learn_state(s)
        self._solved = False

    def update(
        self, s: int, a: int, r: float, s2: int, a2: int | None, terminal: bool, rng: np.random.Generator
    ) -> None:
        """Count the outcome at both levels and plan the acting policy (the greedy one is
        planned when next asked for)."""
        frame = self.frame
        if frame is None:
            raise CrmgraspError("pooled-vi needs its state structure: build it with crmgrasp.agents.build_agent")
        super().update(s, a, r, s2, a2, terminal, rng)
        seen = frame.outcome_observations(s, a, s2)
        pooled = self.pool.setdefault((frame.key(s, a), a), {})
        for obs in seen:
            o = (r, obs, terminal)
            pooled[o] = pooled.get(o, 0.0) + 1.0 / len(seen)
        for t in (s,) if terminal else (s, s2):
            self._learn_state(t)
        self._solved = False

    def _learn_state(self, t: int) -> None:
        """Add a seen state and its siblings (``HistoryFrame.siblings``) to the greedy model."""
        if t not in self._known:
            assert self.frame is not None
            self._known |= self.frame.siblings(t) | {t}

    def _solve(self) -> None:
        """Build the greedy model afresh (pairs in sorted order, values from their initial
        ones) and solve it: the greedy policy after an episode depends on the data alone,
        not on when it was last asked for."""
        if self._solved:
            return
        with collector_paused():
            judge, n = self.judge, self.n_actions
            judge.model, judge.tried = {}, {}
            judge.q = {h: [judge.q_act] * n for h in sorted(self._known)}
            judge.q_greedy = {h: [judge.unknown] * n for h in judge.q}
            self._untried = {}
            for h in judge.q:
                for b in range(n):
                    entry = self._entry(h, b)
                    if entry is not None:
                        judge.model[(h, b)] = entry
                        judge._mark(h, b)
            judge._plan()
        self._solved = True

    def _entry(self, h: int, b: int) -> dict[Outcome, float] | None:
        """``n(h, b, .) + beta m(b(h), b, .) / m(b(h), b)``, the pooled estimate alone
        where ``h`` never tried ``b`` (shared, ``_pooled_entry``), or None where neither level
        has data."""
        frame = self.frame
        assert frame is not None  # bound before the first update
        own = self.model.get((h, b))
        pooled = self.pool.get((frame.key(h, b), b))
        if not pooled or (own and self.beta == 0.0):
            return dict(own) if own else None
        if not own:
            return self._pooled_entry(h, b, pooled)  # shared: the greedy model only reads it
        return self._add_pooled(dict(own), h, b, pooled, self.beta)

    def _add_pooled(
        self, entry: dict[Outcome, float], h: int, b: int, pooled: dict[Outcome, float], share: float
    ) -> dict[Outcome, float]:
        """``entry`` with ``share m(., b) / m(b)`` added, routed from state ``h`` (in place)."""
        frame = self.frame
        assert frame is not None
        weight = share / sum(pooled.values())
        for (r, obs, t), c in pooled.items():
            o = (r, frame.next_state(h, b, obs), t)
            entry[o] = entry.get(o, 0.0) + weight * c
        return entry

    def _pooled_entry(self, h: int, b: int, pooled: dict[Outcome, float]) -> dict[Outcome, float]:
        """The pooled estimate of CRM ``b`` routed from state ``h``, which never tried it, made
        once per solve for every state with the same pooling key and the same next states
        (the same [`KOrderEncoder.kept`][crmgrasp.model.history.KOrderEncoder.kept]; at k = 1,
        every state). Shared, not to be changed: the greedy model's pairs hold it as it is and
        only read it."""
        frame = self.frame
        assert frame is not None
        key = (frame.key(h, b), b, frame.encoder.kept(h))
        entry = self._untried.get(key)
        if entry is None:
            entry = self._untried[key] = self._add_pooled({}, h, b, pooled, 1.0)
        return entry

"""Model-based learning over long histories, backed off to k = 1: `BackoffVI` (``backoff-vi``).

A learner on k = 1 histories ([`PooledVI`][crmgrasp.agents.pooled.PooledVI]) plans as if
``(o_t, a_{t-1})`` were a state. It is not: which worlds lie behind it depends on the
policy that led there, so a model learned under the acting policy misleads the greedy one,
and on object families such learners stall 30-60% above the belief-space optimum however
long they train. The outcome of a CRM given the *whole* history since the start,

``p(o' | h, a) = sum_x b_h(x) p(o' | x, a)``  (``b_h`` the belief over hidden states ``x``),

does not depend on the policy ([docs/model.md section 6][model-6]): planning on a model of
whole histories is planning in belief space. Whole histories are many and each is seen
rarely, so the model has two levels:

* **long** counts ``n(h, a, o)`` of each outcome ``o = (r, h', terminal)`` after CRM ``a``
  in the learner's k-order history ``h`` (a whole history when ``k`` is at least the
  episode's length; beyond ``k`` CRMs, its last ``k``). Shorter histories are met more
  often, so their counts fill sooner, at the price of planning as if two worlds behind the
  same last ``k`` CRMs were alike; ``--preset families`` uses ``k = 2``, measured against
  ``k = 6`` on the families in ``docs/results.md``;
* **short**: a ``PooledVI`` learner on the k = 1 suffix ``h_1 = (o_t, a_{t-1})`` of every
  history, taught every transition; its greedy model (own counts and the bins-pooled
  prior) gives ``p_1(o | h_1, a)``.

The **planning model** is a finite MDP with a node for every long history with data and
one for every short state:

``p(o | h, a) = (n(h, a, o) + beta p_1(o | h_1, a)) / (n(h, a) + beta)``,

``p_1`` alone for a CRM never tried in ``h``. An outcome leads to the long node of the next
history if that history has data, else to the short node of its suffix: the short values
stand in for the subtree not yet explored. Short nodes keep the short model. It is solved
by [`ModelVI`][crmgrasp.agents.model_based.ModelVI]'s value iteration (compiled), which
gives acting values (an untried pair is worth ``q_act``) and greedy values (tried pairs
only).

**Acting** follows the acting values of a model planned at the first step of episode ``e``
when ``e <= plan_every`` or ``e`` is a multiple of ``plan_every`` (a plan solves the whole
model); a history without a node acts from its suffix's short node. The acting model is a
posterior draw (``sample``, posterior sampling as in PSRL): each long pair's outcome
probabilities drawn from ``Dirichlet(n(h, a, .) + beta p_1(. | h_1, a))``, so a CRM that
the short level rates low is still tried where a history's own few outcomes leave room
(``docs/results.md`` has the measured difference). Acting on the plan puts the data where the planned policy
goes. **The greedy policy** (evaluated, saved)
plans on all data so far, solved afresh when asked after new data, so a checkpoint never
changes what follows. A saved policy lists the long nodes' choices and, for every other
history, the short nodes' (its ``backoff`` table, [`crmgrasp.agents.policy`][]).

On a mirror quotient ([`SymmetricAgent`][crmgrasp.agents.symmetric.SymmetricAgent]) the
long histories are representatives, and the short level learns on its own quotient; a
value is the same at a history and at its mirror image, so an outcome may lead to either.
"""

from __future__ import annotations

import math
from collections.abc import Collection, Mapping
from itertools import chain
from typing import Any

import numpy as np

from crmgrasp._collector import collector_paused
from crmgrasp._validation import CrmgraspError, boolean, integer, non_negative, positive
from crmgrasp.agents.backoff_middle import SuffixPool
from crmgrasp.agents.base import allowed_choice, greedy_choice
from crmgrasp.agents.model_based import ModelVI, Outcome
from crmgrasp.agents.pooled import HistoryFrame, PooledVI
from crmgrasp.agents.symmetric import SymmetricAgent, mirror_observation_map
from crmgrasp.agents.tabular import TabularAgent
from crmgrasp.model.history import KOrderEncoder

__all__ = ["BackoffVI"]

_LOG_1E100 = math.log(1e100)

Node = tuple[str, int]
"""A planning node: ``("L", long history code)`` or ``("S", short state code)``."""

Pair = tuple[Node, int, dict[Any, float]]
"""A planning model's pair: its node, its CRM and its entry (outcome -> pseudo-count)."""


class BackoffVI(TabularAgent):
    """Planning on whole histories with a k = 1 back-off (see the module docstring).

    Parameters
    ----------
    n_actions
        Number of actions.
    beta
        Weight of the short level's estimate in a long history's model, in pseudo-counts
        (1 by default: one own outcome weighs as much).
    plan_every
        Acting re-plans before every episode up to this one, then every ``plan_every``-th.
    q_act, unknown, sweeps, compiled
        [`ModelVI`][crmgrasp.agents.model_based.ModelVI]'s (untried pairs' acting value,
        greedy value of a node with nothing tried, most sweeps, compiled sweeps).
    gamma
        Discount (0.9, the paper's).
    sample
        Act on a posterior draw of the long level (True, the default) rather than on its
        mean: each long pair's outcome probabilities are drawn from the Dirichlet whose
        parameters are the blended counts ``n(h, a, o) + beta p_1(o | h_1, a)``.
    mean_after
        With ``sample``, act on the mean from episode ``mean_after + 1`` on (0, the default:
        draw to the end). The late episodes then follow the policy the greedy one will be,
        so the counts of a two-CRM history come from the worlds that policy meets there.
    middle
        Back a long history's model off to its k = 2 suffix first (False, the default: to the
        k = 1 level directly): the counts of every long history with the same last two CRMs and
        observations, pooled, with ``beta`` pseudo-counts of the short level's estimate, stand
        in for the short level in the long history's blend.
    explore
        Pseudo-counts of an immediate grasp added to the draw of a CRM never tried in a
        long history (0: none). The short level may rate such a CRM a sure error from other
        histories with the same suffix; this keeps a chance that the draw tries it where its
        own history may differ.
    explore_tried
        Pseudo-counts of an immediate grasp added to the draw of a CRM a long history has
        tried (0: none, the default). A draw gives no chance to an outcome the counts never
        saw, so a CRM whose first tries all erred is never drawn to grasp and is not tried
        again, however often it grasps elsewhere; these pseudo-counts keep that chance, and
        their weight falls as the CRM's own tries grow (a Dirichlet prior). Acting only: the
        greedy policy plans on the counts.
    skip_errored
        The greedy policy (evaluated, saved, run) never repeats a CRM that erred since the
        contacts last moved (False by default): such a CRM errs again for certain without
        sensing noise, as an errored CRM leaves the contacts where they were. The values are
        learned as before; the rule only chooses, after an error, the best CRM not yet known
        to err there ([`LearnerPolicy`][crmgrasp.agents.base.LearnerPolicy]). A history the
        learner's window cannot tell apart otherwise (after two errors, say, with k = 2) then
        no longer loops on the same failing CRMs.
    skip_errored_learning
        The acting policy skips them too, while it learns (False by default): after an error
        it takes the best acting value among the CRMs not known to err there. The episodes it
        learns from then go where the greedy policy with ``skip_errored`` goes, instead of
        spending CRMs (and counts) on repeats that err for certain. Measured in
        ``docs/results.md``: it narrows the U handles' spread over seeds and costs on the other
        families, so no preset sets it.
    decay
        Forgetting of the long level, in ``(0, 1]`` (1, the default: none). A count made in
        episode ``e`` weighs ``decay ** (E - e)`` when the model is planned in episode ``E``,
        so the long model follows the recent acting policies. Which worlds lie behind a
        history shorter than the episode depends on the policy that led there; old counts
        describe the policies of early training. With ``decay`` = 0.999 the counts of about
        the last 1,000 episodes weigh most.
    """

    name = "backoff-vi"

    def __init__(
        self,
        n_actions: int,
        beta: float = 1.0,
        plan_every: int = 25,
        q_act: float = -1.5,
        unknown: float = -10.0,
        sweeps: int = 1000,
        compiled: bool = True,
        gamma: float = 0.9,
        sample: bool = True,
        explore: float = 0.0,
        middle: bool = False,
        explore_tried: float = 0.0,
        skip_errored: bool = False,
        decay: float = 1.0,
        mean_after: int = 0,
        skip_errored_learning: bool = False,
    ) -> None:
        super().__init__(n_actions, gamma=gamma)
        self.decay = positive(decay, "decay")
        if self.decay > 1.0:
            raise CrmgraspError(f"decay must be in (0, 1], got {self.decay}")
        self.explore = non_negative(explore, "explore")
        self.explore_tried = non_negative(explore_tried, "explore_tried")
        self.beta = non_negative(beta, "beta")
        self.plan_every = integer(plan_every, "plan_every", 1, 1_000_000)
        self.middle = boolean(middle, "middle")
        self.skip_errored = boolean(skip_errored, "skip_errored")
        self.skip_errored_learning = boolean(skip_errored_learning, "skip_errored_learning")
        self.judge = ModelVI(n_actions, q_act, unknown, sweeps, compiled, gamma=gamma)
        self.judge.keeps_arrays = False  # rebuilt whole before each plan
        self.short = PooledVI(n_actions, q_act=q_act, unknown=unknown, compiled=compiled, gamma=gamma)
        self.short.plan_acting = False  # only its greedy model is read
        self.counts: dict[tuple[int, int], dict[Outcome, float]] = {}
        self.episodes = 0
        self._base = 0  # the episode whose counts are stored with weight 1 (decay < 1)
        self._unit = self._scale = 1.0  # weight of a new count; factor that turns stored counts into weights
        self.sample = boolean(sample, "sample")
        self.mean_after = integer(mean_after, "mean_after", 0, 1_000_000_000)
        self._replan = False
        self._act: dict[Any, list[float]] = {}
        self._solved = True
        self._frame: HistoryFrame | None = None
        self._short_sym: SymmetricAgent | None = None
        self._short_frame: HistoryFrame | None = None
        self._suffix: dict[int, int] = {}
        # functions of the history codes alone, remembered (emptied when the learner is bound)
        self._short_of: dict[int, tuple[Node, bool]] = {}
        self._next: dict[tuple[int, int, int], int] = {}
        self._seen: dict[tuple[int, int, int], tuple[int, ...]] = {}
        self._outcomes: dict[tuple[int, int, bool], list[tuple[float, int, bool, float, int]]] = {}
        self._untried: dict[tuple[int, int], dict[Any, float]] = {}  # per plan, see _untried_entry
        self._routed: dict[tuple[int, int], list[tuple[Any, float, int]]] = {}  # per plan, see _short_routed
        self._pool = SuffixPool()
        self._amap: list[int] = []
        self._omap: list[int] = []

    def params(self) -> dict[str, Any]:  # type: ignore[override]
        j = self.judge
        return {
            "beta": self.beta,
            "plan_every": self.plan_every,
            "q_act": j.q_act,
            "unknown": j.unknown,
            "sweeps": j.sweeps,
            "gamma": self.gamma,
            "sample": self.sample,
            "mean_after": self.mean_after,
            "explore": self.explore,
            "explore_tried": self.explore_tried,
            "middle": self.middle,
            "skip_errored": self.skip_errored,
            "decay": self.decay,
            "skip_errored_learning": self.skip_errored_learning,
        }

    def bind(self, frame: HistoryFrame) -> None:
        """Give the learner its long histories' structure and build the short level (on
        its own mirror quotient where the long level has one)."""
        enc = frame.encoder
        if enc.k < 2:
            raise CrmgraspError(f"backoff-vi needs long histories, k >= 2 (--preset families uses 2), got k = {enc.k}")
        task = frame.task
        short_enc = KOrderEncoder(enc.n_obs, enc.n_actions, 1)
        self._frame = frame
        self._suffix, self._short_of, self._next, self._seen = {}, {}, {}, {}
        if frame.symmetric is not None:
            self._short_sym = SymmetricAgent(self.short, task, short_enc)
            self._amap = list(task.symmetry.actions)  # type: ignore[union-attr]
            self._omap = mirror_observation_map(task)
        self._short_frame = HistoryFrame(task, short_enc, self._short_sym)
        self.short.bind(self._short_frame)

    # ----------------------------------------------------------------- levels
    def suffix(self, s: int) -> int:
        """The k = 1 code of history ``s``'s suffix ``(o_t, a_{t-1})``."""
        v = self._suffix.get(s)
        if v is None:
            frame, short = self._bound()
            h = frame.encoder.decode(s)
            v = self._suffix[s] = short.encoder.encode(h[:2])
        return v

    def _bound(self) -> tuple[HistoryFrame, HistoryFrame]:
        if self._frame is None or self._short_frame is None:
            raise CrmgraspError("backoff-vi needs its state structure: build it with crmgrasp.agents.build_agent")
        return self._frame, self._short_frame

    def _short_node(self, s1: int) -> tuple[Node, bool]:
        """The short node of k = 1 code ``s1`` and whether it is ``s1``'s mirror image."""
        c, flip = (s1, False) if self._short_sym is None else self._short_sym.representative(s1)
        return ("S", c), flip

    def _node(self, s: int, nodes: Mapping[Any, Any]) -> tuple[Node | None, bool]:
        """The node history ``s`` acts from among ``nodes`` (its own, else its suffix's)."""
        if ("L", s) in nodes:
            return ("L", s), False
        node, flip = self._suffix_short(s)
        return (node, flip) if node in nodes else (None, False)

    # ----------------------------------------------------------------- the loop
    def begin_episode(self) -> None:
        """Count the episode; a planning episode re-plans the acting values at its first step."""
        self.episodes += 1
        e = self.episodes
        self._replan = e <= self.plan_every or e % self.plan_every == 0
        if self.decay < 1.0:
            if (e - self._base) * -math.log(self.decay) > _LOG_1E100:  # decay ** (base - e) > 1e100
                scale = self.decay ** (e - self._base)  # store the counts at today's weights, far from overflow
                self.counts = {key: {o: c * scale for o, c in row.items()} for key, row in self.counts.items()}
                self._base = e
            self._unit = self.decay ** (self._base - e)

    def act(self, state: int, rng: np.random.Generator, banned: Collection[int] = ()) -> int:
        """The best action by the planned acting values (uniform where there is no node), outside
        ``banned`` where given ([`allowed_choice`][crmgrasp.agents.base.allowed_choice] over every
        action); at a planning episode's first step, plan them first (on a posterior draw with
        ``sample``, up to episode ``mean_after`` where it is set)."""
        if self._replan:
            self._replan = False
            if self.sample and (not self.mean_after or self.episodes <= self.mean_after):
                self._solved = False
                judge = self._planned(rng)
                self._solved = False
            else:
                judge = self._planned()
            self._act = {node: list(row) for node, row in judge.q.items()}
        node, flip = self._node(state, self._act)
        if banned:
            if flip:
                banned = {self._amap[b] for b in banned}
            row = self._act[node] if node is not None else [0.0] * self.n_actions
            a = allowed_choice(row, range(self.n_actions), self.n_actions, banned, rng)
        elif node is None:
            return int(rng.integers(self.n_actions))
        else:
            a = greedy_choice(self._act[node], rng)
        return self._amap[a] if flip else a

    def greedy(self, state: int, rng: np.random.Generator, banned: Collection[int] = ()) -> int:
        """The best tried action on the model of all data (uniform where none was tried),
        outside ``banned`` where given ([`allowed_choice`][crmgrasp.agents.base.allowed_choice])."""
        judge = self._planned()
        node, flip = self._node(state, judge.tried)
        if node is None:
            if banned:
                return allowed_choice([], [], self.n_actions, banned, rng)
            return int(rng.integers(self.n_actions))
        if banned and flip:
            banned = {self._amap[b] for b in banned}
        a = judge.greedy(node, rng, banned)  # type: ignore[arg-type]
        return self._amap[a] if flip else a

    def update(
        self, s: int, a: int, r: float, s2: int, a2: int | None, terminal: bool, rng: np.random.Generator
    ) -> None:
        """Count the outcome at the long level and teach the short level its suffix."""
        self._mark(s, a)
        counts = self.counts.setdefault((s, a), {})
        o = (r, s2, terminal)
        counts[o] = counts.get(o, 0.0) + self._unit
        (self._short_sym or self.short).update(self.suffix(s), a, r, self.suffix(s2), a2, terminal, rng)
        self._solved = False

    # ----------------------------------------------------------------- planning
    def _planned(self, rng: np.random.Generator | None = None) -> ModelVI:
        """The planning model of all data so far, solved (built afresh after new data)."""
        if self._solved:
            return self.judge
        with collector_paused():
            return self._rebuilt(rng)

    def _rebuilt(self, rng: np.random.Generator | None) -> ModelVI:
        """Build the planning model afresh and solve it (``rng``: the posterior draw's)."""
        short = self.short.greedy_model()
        judge, n = self.judge, self.n_actions
        judge.model, judge.tried = {}, {}
        self._scale = self.decay ** (self.episodes - self._base) if self.decay < 1.0 else 1.0
        longs = sorted({s for s, _ in self.counts})
        nodes: list[Node] = [("S", s1) for s1 in short.q] + [("L", s) for s in longs]
        judge.q = {node: [judge.q_act] * n for node in nodes}  # type: ignore[misc]
        judge.q_greedy = {node: [judge.unknown] * n for node in nodes}  # type: ignore[misc]
        self._outcomes, self._untried, self._routed = {}, {}, {}
        if self.middle:
            self._pool.pool(self.counts, self._scale, self._bound()[0])
        shorts = [
            (("S", s1), b, {(r, ("S", t2), t): c for (r, t2, t), c in entry.items()})
            for (s1, b), entry in short.model.items()
        ]
        entries = self._long_entries(longs, rng)
        if rng is not None and entries:
            self._draw(entries, rng)
        model, marked = judge.model, judge.tried
        for node, b, entry in chain(shorts, entries):  # one pass over up to millions of pairs
            model[(node, b)] = entry  # type: ignore[index]
            acts = marked.get(node)  # type: ignore[call-overload]
            if acts is None:
                marked[node] = {b}  # type: ignore[index]
            else:
                acts.add(b)
        judge._plan()
        self._solved = True
        return judge

    def _long_entries(self, longs: list[int], rng: np.random.Generator | None) -> list[Pair]:
        """The long histories' pairs with data and their entries, in order (history, then
        CRM); a CRM a history never tried holds its group's shared entry, copied only where a
        drawn plan (``rng``) adds the ``explore`` bonus to it."""
        known = set(longs)
        entries: list[Pair] = []
        kept = self._bound()[0].encoder.kept
        for s in longs:
            node, group = ("L", s), kept(s)
            for b in range(self.n_actions):
                tried = (s, b) in self.counts
                if tried or self.middle:
                    entry = self._long_entry(s, b, known, group)
                else:
                    entry = self._untried_entry(s, b, known, group)
                if not entry:
                    continue
                bonus = (self.explore_tried if tried else self.explore) if rng is not None else 0.0
                if bonus:  # a grasp stays possible in the draw
                    grasp: Any = (self._bound()[0].task.grasp_reward, node, True)
                    entry = dict(entry)
                    entry[grasp] = entry.get(grasp, 0.0) + bonus
                entries.append((node, b, entry))
        return entries

    @staticmethod
    def _draw(entries: list[Pair], rng: np.random.Generator) -> None:
        """Replace each entry (in the list; the entry itself, which may be shared, stays as it
        is) by one with its pseudo-counts ``c`` drawn, ``Gamma(c, 1)`` (plus 1e-300, so that no
        outcome is drawn impossible): normalised, the draws of one entry are a ``Dirichlet(c)``
        draw. One call to ``rng.gamma`` over all entries, in order, draws the numbers successive
        scalar calls would."""
        shapes = [c for _, _, entry in entries for c in entry.values()]
        draws = iter((rng.gamma(np.array(shapes, dtype=np.float64)) + 1e-300).tolist())
        for i, (node, b, entry) in enumerate(entries):
            entries[i] = (node, b, dict(zip(entry, draws)))  # zip stops at the entry's end, before a draw

    def _route(self, s2: int, known: set[int]) -> Node:
        """The node an outcome history leads to: its own if it has data, else its suffix's."""
        return ("L", s2) if s2 in known else self._suffix_short(s2)[0]

    def _suffix_short(self, s: int) -> tuple[Node, bool]:
        """The short node of history ``s``'s suffix and whether it is the suffix's mirror
        image, remembered (a function of the code alone)."""
        v = self._short_of.get(s)
        if v is None:
            v = self._short_of[s] = self._short_node(self.suffix(s))
        return v

    def _next_state(self, s: int, b: int, obs: int) -> int:
        """``frame.next_state(s, b, obs)``, remembered (a function of the codes alone)."""
        key = (s, b, obs)
        t = self._next.get(key)
        if t is None:
            t = self._next[key] = self._bound()[0].next_state(s, b, obs)
        return t

    def _short_seen(self, s1: int, b1: int, t2: int) -> tuple[int, ...]:
        """``outcome_observations(s1, b1, t2)``, remembered (a function of the codes
        alone)."""
        key = (s1, b1, t2)
        obs = self._seen.get(key)
        if obs is None:
            obs = self._seen[key] = self._bound()[1].outcome_observations(s1, b1, t2)
        return obs

    def _long_entry(self, s: int, b: int, known: set[int], group: int | None = None) -> dict[Any, float]:
        """``n(h, b, .) + beta p_1(. | h_1, b)`` with outcomes routed to nodes (``p_1``
        alone where ``h`` never tried ``b``, the values of `_untried_entry`; empty where neither
        level has data), a new dict; ``group``: ``s``'s
        [`KOrderEncoder.kept`][crmgrasp.model.history.KOrderEncoder.kept] value where the
        caller has it. A plan takes it for the pairs a history tried, and for all with the
        middle level."""
        own = self.counts.get((s, b))
        entry: dict[Any, float] = {}
        for (r, s2, t), c in (own or {}).items():
            o = (r, self._route(s2, known), t)
            entry[o] = entry.get(o, 0.0) + c * self._scale
        if own and self.beta == 0.0:
            return entry
        weight = self.beta if own else 1.0
        mid = self._pool.outcomes(s, b, self.beta, self._short_in_frame) if self.middle else None
        if mid:
            for (r, obs, t), p in mid.items():
                o = (r, self._route(self._next_state(s, b, obs), known), t)
                entry[o] = entry.get(o, 0.0) + weight * p
            return entry
        return self._add_short(entry, s, b, known, weight, group)

    def _add_short(
        self, entry: dict[Any, float], s: int, b: int, known: set[int], weight: float, group: int | None = None
    ) -> dict[Any, float]:
        """``entry`` with ``weight p_1(. | h_1, b)`` added, routed from history ``s`` (in place)."""
        for o, p, n_seen in self._short_routed(s, b, known, group):
            entry[o] = entry.get(o, 0.0) + weight * p / n_seen
        return entry

    def _short_routed(self, s: int, b: int, known: set[int], group: int | None) -> list[tuple[Any, float, int]]:
        """The terms of ``p_1(. | h_1, b)`` routed from history ``s``: ``(outcome, p, n)`` per
        observation of ``_short_in_frame``, its outcome ``(r, node, terminal)``. Made once per
        plan for all the histories that share ``s``'s newest ``k - 1`` CRMs (``group``): they
        have the same suffix ``h_1`` and the same next histories
        ([`KOrderEncoder.kept`][crmgrasp.model.history.KOrderEncoder.kept])."""
        key = (self._bound()[0].encoder.kept(s) if group is None else group, b)
        terms = self._routed.get(key)
        if terms is None:
            terms = self._routed[key] = [
                ((r, self._route(self._next_state(s, b, obs), known), t), p, n_seen)
                for r, obs, t, p, n_seen in self._short_in_frame(s, b)
            ]
        return terms

    def _untried_entry(self, s: int, b: int, known: set[int], group: int | None = None) -> dict[Any, float]:
        """``p_1(. | h_1, b)`` routed from history ``s``, which never tried ``b``, made once
        per plan for all the histories that share ``s``'s newest ``k - 1`` CRMs
        (``_short_routed``), so the same entry, summed in the same order. Shared, not to be
        changed: [`_rebuilt`][] copies it where it adds to it, [`_draw`][] makes new entries."""
        key = (self._bound()[0].encoder.kept(s) if group is None else group, b)
        entry = self._untried.get(key)
        if entry is None:
            entry = self._untried[key] = self._add_short({}, s, b, known, 1.0, key[0])
        return entry

    def _short_in_frame(self, s: int, b: int) -> list[tuple[float, int, bool, float, int]]:
        """The short level's outcomes of CRM ``b`` after history ``s``, read in ``s``'s frame:
        ``(r, observation, terminal, p, n)`` for each of the ``n`` observations (in ``s``'s
        frame) that can have led to an outcome of probability ``p`` under ``p_1(. | h_1, b)``
        (cached per plan; empty where the suffix never tried ``b``)."""
        (_, s1), flip = self._suffix_short(s)
        out = self._outcomes.get((s1, b, flip))
        if out is None:
            b1 = self._amap[b] if flip else b
            pooled = self.short.greedy_model().model.get((s1, b1)) or {}
            total = sum(pooled.values())
            out = []
            for (r, t2, t), c in pooled.items():
                seen = self._short_seen(s1, b1, t2)
                out.extend((r, self._omap[obs] if flip else obs, t, c / total, len(seen)) for obs in seen)
            self._outcomes[(s1, b, flip)] = out
        return out

    # ----------------------------------------------------------------- policy tables
    @property
    def greedy_table(self) -> dict[int, list[float]]:
        """The greedy values of the long histories with data."""
        judge = self._planned()
        return {node[1]: row for node, row in judge.q_greedy.items() if node[0] == "L"}  # type: ignore[index]

    @property
    def greedy_tried(self) -> dict[int, set[int]]:
        """The actions the greedy policy chooses among in each long history with data."""
        judge = self._planned()
        return {node[1]: acts for node, acts in judge.tried.items() if node[0] == "L"}  # type: ignore[index]

    def backoff_tables(self) -> tuple[int, dict[int, list[float]], dict[int, set[int]]]:
        """The back-off level of a saved policy: its order (1), and the greedy values and
        choices of the short states, both mirror images listed on a quotient."""
        judge = self._planned()
        table = {node[1]: judge.q_greedy[node] for node in judge.tried if node[0] == "S"}  # type: ignore[index]
        tried = {node[1]: acts for node, acts in judge.tried.items() if node[0] == "S"}  # type: ignore[index]
        if self._short_sym is not None:
            table, tried = self._short_sym.mirrored_table(table), self._short_sym.mirrored_sets(tried)
        return 1, table, tried

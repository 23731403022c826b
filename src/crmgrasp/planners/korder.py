"""The best policy that sees only the last k actions and observations, searched on sampled worlds.

A learner on the k-order MDP can at best find the best *k-order policy*: a table from
k-order histories ``(o_t, a_{t-1}, o_{t-1}, ..., a_{t-k})`` (docs/model.md section 6) to
CRMs. The belief-space optimum (:func:`~crmgrasp.planners.references.belief_optimum`)
may need more memory than that. :func:`korder_search` finds a good k-order policy on a
set of sampled starts (or worlds) with the same noise-free dynamics and cost as the
belief optimum, so the two compare directly:

1. *Start*: the belief-optimal policy projected onto k-order histories: it runs on every
   sample start, and each history takes the action the belief policy chose there most
   often (ties: the lowest index).
2. *Improve*: coordinate descent. In turn, for each history that some start visits
   (most visited first), every other action is tried; the change is kept if it lowers
   the mean cost over the starts (only the starts whose episodes visit that history are
   re-run). Passes repeat until one changes nothing, or ``max_passes``.

The result is an achievable k-order policy, so its mean cost is an *upper* bound on the
k-order optimum over these starts (the search is local, not exhaustive) and at least the
belief optimum: when it comes near the optimum, k-order histories are enough and a
learner's remaining gap is the learner's; when it cannot, memory is the likely limit
(evidence, not proof). During the search a history no start visits acts with CRM 0; the
returned :class:`~crmgrasp.agents.policy.GreedyPolicy` gives every unvisited history the
action of the most visited history with the same current observation (a back-off to
k = 0; up to :data:`FILL_LIMIT` codes, beyond which unvisited histories draw uniformly),
so it runs, saves and evaluates like a learned policy.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Sequence
from typing import NamedTuple

from crmgrasp._validation import CrmgraspError, integer
from crmgrasp.agents.policy import GreedyPolicy
from crmgrasp.model.hand import Error
from crmgrasp.model.history import KOrderEncoder
from crmgrasp.model.sensing import Observation
from crmgrasp.planners.references import BeliefPolicy, Start, State, _Model
from crmgrasp.sim import Percept
from crmgrasp.tasks import Task

__all__ = ["korder_search", "KOrderResult"]


class KOrderResult(NamedTuple):
    """The policy found, its mean cost over the planning starts, and their belief-space optimum."""

    policy: GreedyPolicy
    mean_cost: float
    belief_optimum: float


class _Episodes:
    """Every start's noise-free episode under a policy table: cost and visited histories."""

    def __init__(self, task: Task, starts: Sequence[Start], k: int, horizon: int) -> None:
        self.model = _Model(task)
        self.enc = KOrderEncoder(task.discretizer.size, len(task.actions), k)
        self.horizon = horizon
        self.states: list[State] = [self.model.state(c) for c in starts]
        self.first = [task.discretizer.index(self.model.tasks[i].observe(cfg), Error.NONE) for i, cfg in self.states]

    def run(self, w: int, table: dict[int, int]) -> tuple[float, list[int]]:
        """Cost (CRMs, plus ``error_cost`` per errored CRM) and visited history codes of start ``w``."""
        m, enc, c_err = self.model, self.enc, self.model.task.error_cost
        state, hist = self.states[w], self.enc.start(self.first[w])
        cost, codes = 0.0, []
        for _ in range(self.horizon):
            code = enc.encode(hist)
            codes.append(code)
            a = table.get(code, 0)
            nxt, obs, grasped = m.step(state, a)
            cost += 1.0 + c_err * m.errored[(state, a)]
            if grasped:
                break
            state, hist = nxt, enc.push(hist, a, obs)
        return cost, codes


def _projected(task: Task, starts: Sequence[Start], ep: _Episodes) -> tuple[dict[int, int], float]:
    """The belief-optimal policy's most frequent action per k-order history (it runs on
    every start through its policy interface, seeing only discretized observations), and
    the belief-space optimum of the starts."""
    policy = BeliefPolicy(task, starts)
    votes: dict[int, Counter[int]] = {}
    m, enc = ep.model, ep.enc
    for w in range(len(starts)):
        state, hist = ep.states[w], enc.start(ep.first[w])
        policy.begin(_percept(ep.first[w]))
        for _ in range(ep.horizon):
            a = policy.act()
            votes.setdefault(enc.encode(hist), Counter())[a] += 1
            state, obs, grasped = m.step(state, a)
            if grasped:
                break
            policy.tell(_percept(obs))
            hist = enc.push(hist, a, obs)
    table = {code: min(v.items(), key=lambda kv: (-kv[1], kv[0]))[0] for code, v in votes.items()}
    return table, policy.optimum()


def _percept(obs: int) -> Percept:
    """A percept carrying only what the belief policy reads: the discretized observation."""
    return Percept(Observation(0.0, 0.0, 0.0), Error.NONE, obs, None)  # type: ignore[arg-type]


FILL_LIMIT = 100_000
"""Most history codes an encoder may have for :func:`_policy` to list every one (k <= 2 on
the registered tasks); beyond it only visited histories are listed."""


def _policy(task: Task, enc: KOrderEncoder, table: dict[int, int], visits: Counter[int]) -> GreedyPolicy:
    """The table as a policy over every history code, unvisited ones backed off to the most
    visited history with the same current observation (only visited ones when the encoder
    has more than :data:`FILL_LIMIT` codes: the policy file would be too large)."""
    by_obs: dict[int, int] = {}
    for code, _ in sorted(visits.items(), key=lambda kv: (-kv[1], kv[0])):
        by_obs.setdefault(enc.decode(code)[0], table.get(code, 0))
    full: dict[int, tuple[int, ...]] = {}
    for code in range(enc.size) if enc.size <= FILL_LIMIT else sorted(visits):
        if code in visits:
            full[code] = (table.get(code, 0),)
        elif (o := enc.decode(code)[0]) in by_obs:
            full[code] = (by_obs[o],)
    return GreedyPolicy(task, enc.k, full, "korder-search")


def korder_search(task: Task, starts: Sequence[Start], k: int = 1, max_passes: int = 20) -> KOrderResult:
    """A k-order policy found by coordinate descent from the projected belief-optimal
    policy (module docstring), its mean cost over ``starts`` (CRMs per episode, plus
    ``error_cost`` per errored CRM; a start not grasped within ``task.max_steps`` costs
    that many), and the starts' belief-space optimum in the same units."""
    if not starts:
        raise CrmgraspError("korder_search needs at least one start")
    k = integer(k, "history order k", 0, 10)
    passes = integer(max_passes, "max_passes", 1, 10_000)
    ep = _Episodes(task, starts, k, task.max_steps)
    table, optimum = _projected(task, starts, ep)
    runs = [ep.run(w, table) for w in range(len(starts))]
    for _ in range(passes):
        visits = _visits(runs)
        changed = False
        for code, _ in sorted(visits.items(), key=lambda kv: (-kv[1], kv[0])):
            who = [w for w, (_, codes) in enumerate(runs) if code in codes]
            old = sum(runs[w][0] for w in who)
            best_a, best, best_runs = table.get(code, 0), old, None
            for a in range(len(task.actions)):
                if a == table.get(code, 0):
                    continue
                trial = {**table, code: a}
                new_runs = [ep.run(w, trial) for w in who]
                total = sum(c for c, _ in new_runs)
                if total < best - 1e-9:
                    best_a, best, best_runs = a, total, new_runs
            if best_runs is not None:
                table[code] = best_a
                for w, r in zip(who, best_runs, strict=True):
                    runs[w] = r
                changed = True
        if not changed:
            break
    policy = _policy(task, ep.enc, table, _visits(runs))
    return KOrderResult(policy, sum(c for c, _ in runs) / len(starts), optimum)


def _visits(runs: list[tuple[float, list[int]]]) -> Counter[int]:
    """In how many episodes each history code occurs."""
    out: Counter[int] = Counter()
    for _, codes in runs:
        out.update(set(codes))
    return out

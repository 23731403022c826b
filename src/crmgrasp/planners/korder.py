"""The best policy that sees only the last k actions and observations, searched on sampled worlds.

Two uses of one search: a *planner* (it starts from the belief-optimal policy, which
needs the hidden states) and a *learner from episodes* (it starts blank and sees only
what episodes return).

A learner on the k-order MDP can at best find the best *k-order policy*: a table from
k-order histories ``(o_t, a_{t-1}, o_{t-1}, ..., a_{t-k})`` ([docs/model.md section 6][model-6]) to
CRMs. The belief-space optimum ([`belief_optimum`][crmgrasp.planners.references.belief_optimum])
may need more memory than that. [`korder_search`][] finds a good k-order policy on a
set of sampled starts (or worlds) with the same noise-free dynamics and cost as the
belief optimum, so the two compare directly:

1. *Start* (``init``): ``"belief"``, the belief-optimal policy projected onto k-order
   histories: it runs on every sample start, and each history takes the action the
   belief policy chose there most often (ties: the lowest index); or ``"blank"``: every
   history takes CRM 0.
2. *Improve*: coordinate descent. In turn, for each history that some start visits
   (most visited first), every other action is tried; the change is kept if it lowers
   the mean cost over the starts (only the starts whose episodes visit that history are
   re-run). Passes repeat until one changes nothing, or ``max_passes``.

With ``init="blank"`` the search is a **learner from episodes** (policy search with
fixed scenarios, as in PEGASUS, Ng and Jordan 2000): all it uses of a world is the cost
of an episode of a given policy from it (CRMs, errors flagged in the observations, the
grasp ending the episode), which a simulator reset to that world returns; the hidden
states only memoise the noise-free steps (a step from the same state with the same CRM
is the same), so re-running an episode costs no new simulation. Its budget is the
number of episodes run ([`KOrderResult.episodes`][]), about 10**5 to 10**6 for 10**3
to 10**4 worlds: a simulator's learner, not a robot's.

The result is an achievable k-order policy, so its mean cost is an *upper* bound on the
k-order optimum over these starts (the search is local, not exhaustive) and at least the
belief optimum: when it comes near the optimum, k-order histories are enough and a
learner's remaining gap is the learner's; when it cannot, memory is the likely limit
(evidence, not proof). A history no start visits acts like the most visited history
with the same current observation (a back-off to k = 0), both during the search (the
back-off of the pass's start, CRM 0 where no visited history has that observation; a
history a kept change makes visited joins the table with that action) and in the
returned [`GreedyPolicy`][crmgrasp.agents.policy.GreedyPolicy] (where it is left unlisted, and
draws uniformly, if no visited history has its observation or the encoder has more than
[`FILL_LIMIT`][] codes), so the policy runs, saves and evaluates like a learned one,
and on the starts searched it does what the search measured.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Sequence
from typing import Any, NamedTuple

import numpy as np

from crmgrasp._validation import CrmgraspError, integer
from crmgrasp.agents.policy import GreedyPolicy
from crmgrasp.model.hand import Error
from crmgrasp.model.history import KOrderEncoder
from crmgrasp.planners.references import BeliefPolicy
from crmgrasp.planners.sampled import SampledModel, Start, State, checked_starts
from crmgrasp.sim import OneStep, Percept, SimState, run_episode, step_reward
from crmgrasp.tasks import Task, checked_task

__all__ = ["korder_search", "KOrderResult", "INITS"]


class KOrderResult(NamedTuple):
    """The policy found, its mean cost over the planning starts, their belief-space
    optimum (None with ``init="blank"``: not computed) and the episodes the search ran
    (every re-run of a start counts)."""

    policy: GreedyPolicy
    mean_cost: float
    belief_optimum: float | None
    episodes: int


class _Episodes:
    """Every start's noise-free episode under a policy table: cost and visited histories."""

    def __init__(self, task: Task, starts: Sequence[Start], k: int, horizon: int) -> None:
        self.model = SampledModel(task)
        self.enc = KOrderEncoder(task.discretizer.size, len(task.actions), k)
        self.horizon = horizon
        self.states: list[State] = [self.model.state(c) for c in starts]
        self.first = [self.model.observation(s) for s in self.states]
        self.count = 0
        self.policy = _TablePolicy(self.enc, task.error_cost)
        self.steps = _MemoSteps(self)
        self.unused = np.random.default_rng(0)  # what the loop hands the memoised steps, which draw nothing

    def run(self, w: int, table: dict[int, int], backoff: dict[int, int]) -> tuple[float, list[int]]:
        """Cost (CRMs, plus ``error_cost`` per errored CRM) and visited history codes of
        start ``w`` ([`_TablePolicy`][] through the one episode loop, on the memoised steps)."""
        self.count += 1
        self.policy.table, self.policy.backoff = table, backoff
        run_episode(self.model.task, self.policy, self.unused, start=self.states[w], kernel=self.steps)  # type: ignore[arg-type]
        return self.policy.cost, self.policy.codes


class _TablePolicy:
    """A [`Policy`][crmgrasp.sim.Policy] that acts as a k-order table says: a history not in
    ``table`` acts as ``backoff`` says for its current observation (CRM 0 if it says
    nothing). It keeps the episode's cost (CRMs, plus ``error_cost`` per errored CRM) and
    the history codes it acted on."""

    def __init__(self, enc: KOrderEncoder, error_cost: float) -> None:
        self.enc, self.error_cost = enc, error_cost
        self.table: dict[int, int] = {}
        self.backoff: dict[int, int] = {}
        self.cost = 0.0
        self.codes: list[int] = []
        self._hist: tuple[int, ...] = ()
        self._a = 0

    def begin(self, first: Percept) -> None:
        self.cost, self.codes, self._hist = 0.0, [], self.enc.start(first.obs_index)

    def act(self) -> int:
        code = self.enc.encode(self._hist)
        self.codes.append(code)
        a = self.table.get(code)
        self._a = self.backoff.get(self._hist[0], 0) if a is None else a
        return self._a

    def tell(self, percept: Percept) -> None:
        self.cost += 1.0 + self.error_cost * (percept.error is not Error.NONE)
        self._hist = self.enc.push(self._hist, self._a, percept.obs_index)


def _projected(task: Task, starts: Sequence[Start], ep: _Episodes) -> tuple[dict[int, int], float]:
    """The belief-optimal policy's most frequent action per k-order history (it runs on
    every start through the one episode loop, seeing only discretized observations), and
    the belief-space optimum of the starts."""
    voter = _Voter(BeliefPolicy(task, starts), ep.enc)
    for state in ep.states:
        run_episode(task, voter, ep.unused, start=state, kernel=ep.steps)  # type: ignore[arg-type]
    table = {code: min(v.items(), key=lambda kv: (-kv[1], kv[0]))[0] for code, v in voter.votes.items()}
    return table, voter.policy.optimum()


class _Voter:
    """A [`Policy`][crmgrasp.sim.Policy] that acts as ``policy`` and counts, per k-order
    history, the actions it takes there."""

    def __init__(self, policy: BeliefPolicy, enc: KOrderEncoder) -> None:
        self.policy, self.enc = policy, enc
        self.votes: dict[int, Counter[int]] = {}
        self._hist: tuple[int, ...] = ()
        self._a = 0

    def begin(self, first: Percept) -> None:
        self.policy.begin(first)
        self._hist = self.enc.start(first.obs_index)

    def act(self) -> int:
        self._a = self.policy.act()
        self.votes.setdefault(self.enc.encode(self._hist), Counter())[self._a] += 1
        return self._a

    def tell(self, percept: Percept) -> None:
        self.policy.tell(percept)
        self._hist = self.enc.push(self._hist, self._a, percept.obs_index)


class _MemoSteps:
    """The search's memoised noise-free steps ([`_Episodes`][]' model) as a
    [`Stepper`][crmgrasp.sim.Stepper] of the one episode loop, from given hidden states: a
    step's result carries the discretized observation, the error flag, the reward, the
    episode's end (a grasp, or ``max_steps`` CRMs) and ``min_friction`` 0 at a grasp
    (``inf`` elsewhere); what the policies read, without the sensed values the model does
    not keep."""

    def __init__(self, ep: _Episodes) -> None:
        self.model, self.horizon, self.task = ep.model, ep.horizon, ep.model.task
        self.first = dict(zip(ep.states, ep.first, strict=True))

    def sample_start(self, rng: np.random.Generator) -> Any:
        raise CrmgraspError("the search's episodes start from its given starts")

    def use(self, instance: Task) -> None:
        raise CrmgraspError("the search's episodes start from its given starts")

    def begin(self, config: Any, rng: np.random.Generator) -> OneStep:
        return OneStep(SimState(config, config, 0), (), Error.NONE, self.first[config], math.inf)

    def step_one(self, state: SimState, action: Any, rng: np.random.Generator) -> OneStep:
        nxt, obs, grasped = self.model.step(state.config, action)  # type: ignore[arg-type]
        error = self.model.error(state.config, action)  # type: ignore[arg-type]
        steps = state.steps + 1
        done = SimState(nxt, nxt, steps)  # type: ignore[arg-type]
        truncated = steps >= self.horizon and not grasped
        reward = step_reward(self.task, grasped, error)
        return OneStep(done, (), error, obs, 0.0 if grasped else math.inf, reward, grasped, truncated)


FILL_LIMIT = 100_000
"""Most history codes an encoder may have for [`_policy`][] to list every one (k <= 2 on
the registered tasks); beyond it only visited histories are listed."""


def _backoff(enc: KOrderEncoder, table: dict[int, int], visits: Counter[int]) -> dict[int, int]:
    """Per current observation, the action of the most visited history that has it (ties:
    the lowest code): what a history no start visits does."""
    by_obs: dict[int, int] = {}
    for code, _ in sorted(visits.items(), key=lambda kv: (-kv[1], kv[0])):
        by_obs.setdefault(enc.decode(code)[0], table.get(code, 0))
    return by_obs


def _policy(task: Task, enc: KOrderEncoder, table: dict[int, int], visits: Counter[int], name: str) -> GreedyPolicy:
    """The table as a policy over every history code, unvisited ones backed off
    ([`_backoff`][]; only visited ones when the encoder has more than
    [`FILL_LIMIT`][] codes: the policy file would be too large)."""
    by_obs = _backoff(enc, table, visits)
    full: dict[int, tuple[int, ...]] = {}
    for code in range(enc.size) if enc.size <= FILL_LIMIT else sorted(visits):
        if code in visits:
            full[code] = (table.get(code, 0),)
        elif (o := enc.decode(code)[0]) in by_obs:
            full[code] = (by_obs[o],)
    return GreedyPolicy(task, enc.k, full, name)


INITS = ("belief", "blank")
"""Where [`korder_search`][] starts: the projected belief-optimal policy (a planner),
or CRM 0 everywhere (a learner from episodes)."""


def korder_search(
    task: Task, starts: Sequence[Start], k: int = 1, max_passes: int = 20, init: str = "belief"
) -> KOrderResult:
    """A k-order policy found by coordinate descent from ``init`` (module docstring), its
    mean cost over ``starts`` (CRMs per episode, plus ``error_cost`` per errored CRM; a
    start not grasped within ``task.max_steps`` costs that many), the starts'
    belief-space optimum in the same units (``init="belief"`` only) and the episodes run."""
    checked_task(task, "korder_search")
    checked_starts(starts, "korder_search")
    k = integer(k, "history order k", 0, 10)
    passes = integer(max_passes, "max_passes", 1, 10_000)
    if init not in INITS:
        raise CrmgraspError(f"unknown init {init!r}: choose one of {', '.join(INITS)}")
    ep = _Episodes(task, starts, k, task.max_steps)
    table, optimum = _projected(task, starts, ep) if init == "belief" else ({}, None)
    runs = [ep.run(w, table, {}) for w in range(len(starts))]
    _adopt(ep.enc, table, runs, {})
    for _ in range(passes):
        if not _descend(task, ep, table, runs):
            break
    policy = _policy(task, ep.enc, table, _visits(runs), "korder-search" if init == "belief" else "policy-search")
    return KOrderResult(policy, sum(c for c, _ in runs) / len(starts), optimum, ep.count)


Run = tuple[float, list[int]]


def _descend(task: Task, ep: _Episodes, table: dict[int, int], runs: list[Run]) -> bool:
    """One pass of coordinate descent over the visited histories, most visited first
    (module docstring); ``table`` and ``runs`` change in place. During the pass an
    unvisited history acts as the back-off of the pass's start says (the returned
    policy's rule), and joins ``table`` with that action once a kept change visits it.
    Whether anything changed."""
    visits = _visits(runs)
    backoff = _backoff(ep.enc, table, visits)
    changed = False
    for code, _ in sorted(visits.items(), key=lambda kv: (-kv[1], kv[0])):
        who = [w for w, (_, codes) in enumerate(runs) if code in codes]
        kept = table[code]
        best_a, best, best_runs = kept, sum(runs[w][0] for w in who), None
        for a in range(len(task.actions)):
            if a == kept:
                continue
            table[code] = a  # tried in place (no copy of the table per candidate), restored below
            new_runs = [ep.run(w, table, backoff) for w in who]
            total = sum(c for c, _ in new_runs)
            if total < best - 1e-9:
                best_a, best, best_runs = a, total, new_runs
        table[code] = kept
        if best_runs is not None:
            table[code] = best_a
            for w, r in zip(who, best_runs, strict=True):
                runs[w] = r
            _adopt(ep.enc, table, best_runs, backoff)
            changed = True
    return changed


def _adopt(enc: KOrderEncoder, table: dict[int, int], runs: list[Run], backoff: dict[int, int]) -> None:
    """Give every history the ``runs`` visit that ``table`` lacks the action it took there
    (the back-off's, [`_Episodes.run`][])."""
    for _, codes in runs:
        for code in codes:
            if code not in table:
                table[code] = backoff.get(enc.decode(code)[0], 0)


def _visits(runs: list[Run]) -> Counter[int]:
    """In how many episodes each history code occurs."""
    out: Counter[int] = Counter()
    for _, codes in runs:
        out.update(set(codes))
    return out

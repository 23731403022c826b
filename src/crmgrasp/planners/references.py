"""Reference values a learner is measured against, computed exactly on sampled starts.

Both treat a finite set of sampled start configurations as the possible hidden
states (on a family task, sampled worlds: each an object and a start on it), with
noise-free (deterministic) dynamics, and count CRMs per episode as
the learners do (success ends an episode; ``task.max_steps`` truncates it).

* [`clairvoyant_steps`][]: an agent that sees the true configuration needs the
  fewest CRMs that reach a grasp, found by breadth-first search over CRM
  sequences. Its mean over the starts is a bound no policy can beat.
* [`belief_optimum`][]: the best any policy can do knowing the task model but
  seeing only the discretized observations: the belief is the set of starts
  consistent with the history so far (each start's configuration after that
  history is determined), and

  ``V(B, h) = min_a [ 1 + sum_o (|B_{a,o}| / |B|) V(B_{a,o}, h - 1) ]``, ``V(., 0) = 0``,

  where ``B_{a,o}`` are the starts of ``B`` not yet grasped after ``a`` that
  observe ``o``. Solved exactly by depth-first search with memoisation and a
  branch-and-bound cut (every start still in play costs at least its clairvoyant
  number of CRMs). The gap between the two is the price of perceptual aliasing.

Both searches run over the starts' cached model ([`crmgrasp.planners.sampled`][]), which
expands a state by every CRM at once, through the kernel of its object
([`crmgrasp.kernels.base.Kernel.successors`][]: compiled where a kernel exists on the
default ``backend="auto"``, the readable rules with ``backend="reference"``). Every kernel
gives the readable rules' results bit for bit, so every value here is the same on either
backend (the tests compare them); only the time differs (`benchmarks/bench_references.py`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from crmgrasp._collector import collector_paused
from crmgrasp._validation import CrmgraspError, integer, seed_value
from crmgrasp.model.contacts import Config, Grip
from crmgrasp.model.hand import Error
from crmgrasp.planners.sampled import SampledModel, Start, State, checked_starts
from crmgrasp.sim import Percept, run_episode
from crmgrasp.tasks import Task, World
from crmgrasp.tasks.core import MAX_STEPS, checked_task

__all__ = [
    "clairvoyant_steps",
    "clairvoyant_bound",
    "belief_optimum",
    "block_optima",
    "ungraspable_fraction",
    "graspable_starts",
    "graspable_warning",
    "sample_starts",
    "BeliefPolicy",
    "FALLBACKS",
    "MAX_STARTS",
]

MAX_STARTS = 1_000_000
"""The most starts [`sample_starts`][] draws at once (the command line's bound too)."""


def _horizon(task: Task, horizon: int | None) -> int:
    """The CRMs a search looks ahead: ``task.max_steps`` when ``horizon`` is None, else
    ``horizon`` checked (an integer in ``[1, MAX_STEPS]``, one-line error otherwise)."""
    return task.max_steps if horizon is None else integer(horizon, "horizon", 1, MAX_STEPS)


def _model(task: object, starts: object, backend: str, who: str) -> tuple[SampledModel, Sequence[Start]]:
    """The sampled model of ``task`` and the checked ``starts`` of the call ``who``."""
    return SampledModel(checked_task(task, who), backend), checked_starts(starts, who)


def sample_starts(task: Task, n: int, seed: int) -> list[Config | Grip] | list[World]:
    """``n`` starts from the task's sampler, seeded (worlds, for a family task; ``n`` at
    most [`MAX_STARTS`][])."""
    checked_task(task, "sample_starts")
    integer(n, "number of starts", 1, MAX_STARTS)
    rng = np.random.default_rng(seed_value(seed))
    if task.family is not None:
        return [task.sample_world(rng) for _ in range(n)]
    return [task.sample_start(rng) for _ in range(n)]


def clairvoyant_steps(task: Task, config: Start, horizon: int | None = None, backend: str = "auto") -> int:
    """Fewest CRMs from ``config`` (or a world) to a grasp (``horizon``, default
    ``task.max_steps``, if none is reachable within it)."""
    model = SampledModel(checked_task(task, "clairvoyant_steps"), backend)
    return model.clairvoyant(model.state(config), _horizon(task, horizon))


def clairvoyant_bound(task: Task, starts: Sequence[Start], horizon: int | None = None, backend: str = "auto") -> float:
    """Mean of [`clairvoyant_steps`][] over ``starts``."""
    model, starts = _model(task, starts, backend, "clairvoyant_bound")
    h = _horizon(task, horizon)
    return float(np.mean([model.clairvoyant(model.state(c), h) for c in starts]))


def graspable_starts(
    task: Task, starts: Sequence[Start], horizon: int | None = None, backend: str = "auto"
) -> np.ndarray:
    """Per start, whether some sequence of at most ``horizon`` (default ``task.max_steps``)
    CRMs reaches a grasp from it knowing the true configuration (a boolean array)."""
    model, starts = _model(task, starts, backend, "graspable_starts")
    h = _horizon(task, horizon)
    return np.array([model.depth(model.state(c), h) is not None for c in starts], dtype=bool)


def ungraspable_fraction(
    task: Task, starts: Sequence[Start], horizon: int | None = None, backend: str = "auto"
) -> float:
    """Share of ``starts`` from which no sequence of at most ``horizon`` (default
    ``task.max_steps``) CRMs reaches a grasp, even knowing the true configuration
    (the share of [`graspable_starts`][] that are not)."""
    checked_starts(starts, "ungraspable_fraction")
    return int((~graspable_starts(task, starts, horizon, backend)).sum()) / len(starts)


def graspable_warning(task: Task, n: int = 50, seed: int = 0, backend: str = "auto") -> str | None:
    """A warning when a quick check finds the task ungraspable: no sequence of at most
    ``max_steps`` CRMs grasps any of ``n`` sampled starts, even knowing the object (a
    learner cannot succeed there); ``None`` when some start can be grasped. Costs
    milliseconds on the registered tasks (about 50 ms on polygon families), stepping on
    ``backend``'s kernel."""
    if ungraspable_fraction(task, sample_starts(task, n, seed), backend=backend) < 1.0:
        return None
    return (
        f"task {task.name!r}: none of {n} sampled starts can be grasped within {task.max_steps} CRMs by any CRM "
        "sequence (is the object wider than the hand's aperture, or are the CRMs too few?); learning cannot succeed"
    )


def _first_groups(model: SampledModel, starts: Sequence[Start]) -> dict[int, tuple[State, ...]]:
    """The starts' hidden states grouped by their first observation."""
    groups: dict[int, tuple[State, ...]] = {}
    for c in starts:
        st = model.state(c)
        k = model.observation(st)
        groups[k] = (*groups.get(k, ()), st)
    return groups


def belief_optimum(task: Task, starts: Sequence[Start], horizon: int | None = None, backend: str = "auto") -> float:
    """Exact optimal expected CRMs per episode over ``starts`` from observations only
    (with ``task.error_cost`` c > 0: the expected cost, CRMs plus c per errored CRM)."""
    model, starts = _model(task, starts, backend, "belief_optimum")
    h = _horizon(task, horizon)
    memo: dict[tuple[tuple[State, ...], int], float] = {}
    with collector_paused():  # the memo is large and acyclic
        total = sum(len(g) * _value(model, g, h, memo) for g in _first_groups(model, starts).values())
    return total / len(starts)


def block_optima(
    task: Task, starts: Sequence[Start], blocks: int, horizon: int | None = None, backend: str = "auto"
) -> list[float]:
    """[`belief_optimum`][] over each of ``blocks`` disjoint runs of ``starts`` (in order,
    equally long: ``blocks`` must divide their number).

    On a family, whose worlds vary continuously, the optimum over ``n`` sampled worlds is
    optimistic: once a history is left with one of them it acts as if it knew that world.
    Its expectation is at most the family's own optimum and rises toward it as ``n`` grows
    (over a union of disjoint sets the optimum is at least the sets' size-weighted mean), so
    the blocks' mean against the optimum over all ``starts`` shows how far the sample size
    still moves it."""
    checked_task(task, "block_optima")
    n = len(checked_starts(starts, "block_optima"))
    if isinstance(blocks, bool) or not isinstance(blocks, int) or blocks < 1 or n % blocks:
        raise CrmgraspError(f"blocks must be a whole number that divides the {n} starts, got {blocks!r}")
    size = n // blocks
    return [belief_optimum(task, starts[i : i + size], horizon, backend) for i in range(0, n, size)]


def _value(model: SampledModel, belief: tuple[State, ...], h: int, memo: dict, acts: dict | None = None) -> float:
    """``V(B, h)``: expected further cost (CRMs, plus ``task.error_cost`` per errored
    CRM), mean over the starts in ``belief``; the minimising action goes to
    ``acts[(belief, h)]`` when ``acts`` is given."""
    if h == 0 or not belief:
        return 0.0
    key = (belief, h)
    if key in memo and (acts is None or key in acts):
        return memo[key]
    n = len(belief)
    c_err = model.task.error_cost
    best = float(h) * (1.0 + c_err)  # doing anything for h steps costs at most this
    best_action = 0
    options = []
    succs = [model.successors(c) for c in belief]
    errs = [model.errors(c) for c in belief] if c_err else []  # without an error cost they cost nothing
    for a in range(len(model.task.actions)):
        children: dict[int, list[State]] = {}
        for succ in succs:
            nxt, index, grasped = succ[a]
            if not grasped:
                children.setdefault(index, []).append(nxt)
        errors = sum(e[a] is not Error.NONE for e in errs)
        kids = [tuple(v) for v in children.values()]
        now = 1.0 + c_err * errors / n
        bound = now + sum(len(k) * _lower(model, k, h - 1) for k in kids) / n
        options.append((bound, now, a, kids))
    for bound, now, a, kids in sorted(options, key=lambda o: o[0]):
        if bound >= best:
            break
        cost = now
        for kid in sorted(kids, key=len, reverse=True):
            cost += len(kid) * _value(model, kid, h - 1, memo) / n
            if cost >= best:
                break
        if cost < best:
            best, best_action = cost, a
    memo[key] = best
    if acts is not None:
        acts[key] = best_action
    return best


def _lower(model: SampledModel, belief: tuple[State, ...], h: int) -> float:
    """Admissible bound on ``V(belief, h)``: the mean clairvoyant CRMs (full
    information cannot do worse), capped by the horizon."""
    if h == 0:
        return 0.0
    return model.clairvoyant_total(belief, h) / len(belief)


FALLBACKS = ("restart", "nearest")
"""What [`BeliefPolicy`][] does when no sample start explains the history (``fallback``)."""


class BeliefPolicy:
    """The belief-space optimal policy over a set of sample starts, executable on
    fresh starts in the simulator.

    The belief is the tuple of sample starts' configurations consistent with the
    history (noise-free dynamics). Each step takes the minimising action of
    ``V(B, h)``. A fresh start may produce an observation no sample start in the belief
    produced (the belief empties). With ``fallback="restart"`` (the default) the belief then
    restarts from the sample starts whose first observation equals the current one, with
    the steps left. With ``fallback="nearest"`` every sample start follows the CRMs taken
    and counts the observations it would have given otherwise (a start whose own episode
    grasps where the true one does not drops out), and the belief is always the starts
    with the fewest such mismatches: the consistent ones while any is left (the same
    belief as the default), then those that explain all but one observation, and so on
    (the most likely starts if each observation were misread with a small probability).
    """

    def __init__(self, task: Task, starts: Sequence[Start], fallback: str = "restart", backend: str = "auto") -> None:
        self._model, starts = _model(task, starts, backend, "BeliefPolicy")
        if fallback not in FALLBACKS:
            raise CrmgraspError(f"unknown fallback {fallback!r}: choose one of {', '.join(FALLBACKS)}")
        self.task, self.fallback, self.backend = task, fallback, backend
        self._memo: dict = {}
        self._acts: dict = {}
        self._belief: tuple[State, ...] = ()
        self._left, self._a = task.max_steps, 0
        self._groups = _first_groups(self._model, starts)
        self._track: list[tuple[State, int]] = []  # with "nearest": each start's state now and its mismatches

    def optimum(self) -> float:
        """The belief-space optimum over the policy's starts ([`belief_optimum`][]'s
        value, from the policy's own memo)."""
        h = self.task.max_steps
        groups = self._groups.values()
        with collector_paused():
            total = sum(len(g) * _value(self._model, g, h, self._memo) for g in groups)
        return total / sum(len(g) for g in groups)

    def _action(self, belief: tuple[State, ...], h: int) -> int:
        key = (belief, h)
        if key not in self._acts:
            with collector_paused():
                _value(self._model, belief, h, self._memo, self._acts)
        return self._acts[key]

    # -- the Policy interface (crmgrasp.sim.run_episode)
    def begin(self, first: Percept) -> None:
        """Belief: the sample starts whose first observation is this one."""
        self._belief = self._groups.get(first.obs_index, ())
        self._left = self.task.max_steps
        if self.fallback == "nearest":  # the starts with this first observation, if any
            self._track = [(st, int(o != first.obs_index)) for o, g in self._groups.items() for st in g]
            self._belief = self._nearest()

    def act(self) -> int:
        """The optimal action for the belief and the CRMs left (0 on an empty belief)."""
        self._a = self._action(self._belief, self._left) if self._belief else 0
        return self._a

    def tell(self, percept: Percept, action: int | None = None) -> None:
        """Keep the belief's configurations that the action leads to this observation
        without a grasp (if none is left: the ``fallback``, see the class docstring). ``action`` is
        the CRM (its index) that was taken when it was not this policy's choice, as when
        another policy acts for a while (``benchmarks/handover.py``); by default, the
        action this policy chose."""
        if action is not None:
            self._a = integer(action, "action", 0, len(self.task.actions) - 1)
        if percept.terminated:
            return
        if self.fallback == "nearest":  # the consistent starts while any is left, in the same order
            track = []
            for c, miss in self._track:
                c2, o2, g2 = self._model.step(c, self._a)
                if not g2:
                    track.append((c2, miss + (o2 != percept.obs_index)))
            self._track = track
            self._belief = self._nearest()
        else:
            nxt = []
            for c in self._belief:
                c2, o2, g2 = self._model.step(c, self._a)
                if not g2 and o2 == percept.obs_index:
                    nxt.append(c2)
            self._belief = tuple(nxt) or self._groups.get(percept.obs_index, ())
        self._left -= 1

    def _nearest(self) -> tuple[State, ...]:
        """The tracked starts' states with the fewest mismatches (none if every start dropped out)."""
        if not self._track:
            return ()
        least = min(miss for _, miss in self._track)
        return tuple(c for c, miss in self._track if miss == least)

    def run(self, config: Start, rng: np.random.Generator | None = None) -> tuple[int, bool]:
        """Execute the policy from ``config`` or a world ([`crmgrasp.sim.run_episode`][]; ``rng``
        is drawn from only if the task has sensing noise); return (CRMs, success)."""
        ep = run_episode(self.task, self, rng if rng is not None else np.random.default_rng(0), start=config)
        return ep.steps, ep.success

"""Reference values a learner is measured against, computed exactly on sampled starts.

Both treat a finite set of sampled start configurations as the possible hidden
states, with noise-free (deterministic) dynamics, and count CRMs per episode as
the learners do (success ends an episode; ``task.max_steps`` truncates it).

* :func:`clairvoyant_steps`: an agent that sees the true configuration needs the
  fewest CRMs that reach a grasp, found by breadth-first search over CRM
  sequences. Its mean over the starts is a bound no policy can beat.
* :func:`belief_optimum`: the best any policy can do knowing the task model but
  seeing only the discretized observations: the belief is the set of starts
  consistent with the history so far (each start's configuration after that
  history is determined), and

  ``V(B, h) = min_a [ 1 + sum_o (|B_{a,o}| / |B|) V(B_{a,o}, h - 1) ]``, ``V(., 0) = 0``,

  where ``B_{a,o}`` are the starts of ``B`` not yet grasped after ``a`` that
  observe ``o``. Solved exactly by depth-first search with memoisation and a
  branch-and-bound cut (every start still in play costs at least its clairvoyant
  number of CRMs). The gap between the two is the price of perceptual aliasing.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Sequence

import numpy as np

from crmgrasp._validation import CrmgraspError
from crmgrasp.model.contacts import Config
from crmgrasp.model.hand import Error, execute_crm
from crmgrasp.model.sensing import observe
from crmgrasp.sim import Percept, run_episode
from crmgrasp.tasks import Task

__all__ = [
    "clairvoyant_steps",
    "clairvoyant_bound",
    "belief_optimum",
    "ungraspable_fraction",
    "sample_starts",
    "BeliefPolicy",
]

Step = tuple[Config, int, bool]  # next configuration, observation index, grasped


class _Model:
    """Cached deterministic transitions of a task (noise ignored)."""

    def __init__(self, task: Task) -> None:
        self.task = task
        self._step: dict[tuple[Config, int], Step] = {}
        self._clair: dict[tuple[Config, int], int | None] = {}

    def step(self, config: Config, action: int) -> Step:
        key = (config, action)
        hit = self._step.get(key)
        if hit is None:
            t = self.task
            out = execute_crm(t.obj, t.hand, config, t.actions[action], config)
            index = t.discretizer.index(observe(out.config), out.error)
            hit = self._step[key] = (out.config, index, t.is_success(out.config))
        return hit

    def clairvoyant(self, config: Config, horizon: int) -> int:
        """Fewest CRMs to a grasp within ``horizon`` (``horizon`` if none is found)."""
        depth = self.depth(config, horizon)
        return horizon if depth is None else depth

    def depth(self, config: Config, horizon: int) -> int | None:
        """Fewest CRMs to a grasp within ``horizon``; ``None`` if no sequence grasps."""
        key = (config, horizon)
        if key not in self._clair:
            self._clair[key] = self._bfs(config, horizon)
        return self._clair[key]

    def _bfs(self, start: Config, horizon: int) -> int | None:
        seen = {start}
        frontier = deque([(start, 0)])
        while frontier:
            cfg, depth = frontier.popleft()
            if depth == horizon:
                continue
            for a in range(len(self.task.actions)):
                nxt, _, grasped = self.step(cfg, a)
                if grasped:
                    return depth + 1
                if nxt not in seen:
                    seen.add(nxt)
                    frontier.append((nxt, depth + 1))
        return None


def sample_starts(task: Task, n: int, seed: int) -> list[Config]:
    """``n`` starts from the task's sampler, seeded."""
    if isinstance(n, bool) or not isinstance(n, int) or n < 1:
        raise CrmgraspError(f"number of starts must be an integer >= 1, got {n!r}")
    rng = np.random.default_rng(seed)
    return [task.sample_start(rng) for _ in range(n)]


def clairvoyant_steps(task: Task, config: Config, horizon: int | None = None) -> int:
    """Fewest CRMs from ``config`` to a grasp (``horizon``, default ``task.max_steps``,
    if none is reachable within it)."""
    return _Model(task).clairvoyant(config, horizon or task.max_steps)


def clairvoyant_bound(task: Task, starts: Sequence[Config], horizon: int | None = None) -> float:
    """Mean of :func:`clairvoyant_steps` over ``starts``."""
    model = _Model(task)
    h = horizon or task.max_steps
    return float(np.mean([model.clairvoyant(c, h) for c in starts]))


def ungraspable_fraction(task: Task, starts: Sequence[Config], horizon: int | None = None) -> float:
    """Share of ``starts`` from which no sequence of at most ``horizon`` (default
    ``task.max_steps``) CRMs reaches a grasp, even knowing the true configuration."""
    if not starts:
        raise CrmgraspError("ungraspable_fraction needs at least one start")
    model = _Model(task)
    h = horizon or task.max_steps
    return sum(model.depth(c, h) is None for c in starts) / len(starts)


def belief_optimum(task: Task, starts: Sequence[Config], horizon: int | None = None) -> float:
    """Exact optimal expected CRMs per episode over ``starts`` from observations only."""
    if not starts:
        raise CrmgraspError("belief_optimum needs at least one start")
    model = _Model(task)
    h = horizon or task.max_steps
    groups: dict[int, list[Config]] = {}
    for c in starts:
        groups.setdefault(task.discretizer.index(observe(c), Error.NONE), []).append(c)
    memo: dict[tuple[tuple[Config, ...], int], float] = {}
    total = sum(len(g) * _value(model, tuple(g), h, memo) for g in groups.values())
    return total / len(starts)


def _value(model: _Model, belief: tuple[Config, ...], h: int, memo: dict, acts: dict | None = None) -> float:
    """``V(B, h)``: expected further CRMs, mean over the starts in ``belief``; the
    minimising action goes to ``acts[(belief, h)]`` when ``acts`` is given."""
    if h == 0 or not belief:
        return 0.0
    key = (belief, h)
    if key in memo and (acts is None or key in acts):
        return memo[key]
    n = len(belief)
    best = float(h)  # doing anything for h steps costs at most h
    best_action = 0
    options = []
    for a in range(len(model.task.actions)):
        children: dict[int, list[Config]] = {}
        for c in belief:
            nxt, index, grasped = model.step(c, a)
            if not grasped:
                children.setdefault(index, []).append(nxt)
        kids = [tuple(v) for v in children.values()]
        bound = 1.0 + sum(len(k) * _lower(model, k, h - 1) for k in kids) / n
        options.append((bound, a, kids))
    for bound, a, kids in sorted(options, key=lambda o: o[0]):
        if bound >= best:
            break
        cost = 1.0
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


def _lower(model: _Model, belief: tuple[Config, ...], h: int) -> float:
    """Admissible bound on ``V(belief, h)``: the mean clairvoyant CRMs (full
    information cannot do worse), capped by the horizon."""
    if h == 0:
        return 0.0
    return float(np.mean([model.clairvoyant(c, h) for c in belief]))


class BeliefPolicy:
    """The belief-space optimal policy over a set of sample starts, executable on
    fresh starts in the simulator.

    The belief is the tuple of sample starts' configurations consistent with the
    history (noise-free dynamics). Each step takes the minimising action of
    ``V(B, h)``. When a fresh start produces an observation no sample start in the
    belief produced (the belief empties), the belief restarts from the sample
    starts whose first observation equals the current one, with the steps left.
    """

    def __init__(self, task: Task, starts: Sequence[Config]) -> None:
        if not starts:
            raise CrmgraspError("BeliefPolicy needs at least one start")
        self.task = task
        self._model = _Model(task)
        self._memo: dict = {}
        self._acts: dict = {}
        self._belief: tuple[Config, ...] = ()
        self._left, self._a = task.max_steps, 0
        self._groups: dict[int, tuple[Config, ...]] = {}
        for c in starts:
            k = task.discretizer.index(observe(c), Error.NONE)
            self._groups[k] = (*self._groups.get(k, ()), c)

    def _action(self, belief: tuple[Config, ...], h: int) -> int:
        key = (belief, h)
        if key not in self._acts:
            _value(self._model, belief, h, self._memo, self._acts)
        return self._acts[key]

    # -- the Policy interface (crmgrasp.sim.run_episode)
    def begin(self, first: Percept) -> None:
        """Belief: the sample starts whose first observation is this one."""
        self._belief = self._groups.get(first.obs_index, ())
        self._left = self.task.max_steps

    def act(self) -> int:
        """The optimal action for the belief and the CRMs left (0 on an empty belief)."""
        self._a = self._action(self._belief, self._left) if self._belief else 0
        return self._a

    def tell(self, percept: Percept) -> None:
        """Keep the belief's configurations that the action leads to this observation
        without a grasp (restart from the sample starts if none is left)."""
        if percept.terminated:
            return
        nxt = []
        for c in self._belief:
            c2, o2, g2 = self._model.step(c, self._a)
            if not g2 and o2 == percept.obs_index:
                nxt.append(c2)
        self._belief = tuple(nxt) or self._groups.get(percept.obs_index, ())
        self._left -= 1

    def run(self, config: Config, rng: np.random.Generator | None = None) -> tuple[int, bool]:
        """Execute the policy from ``config`` (:func:`crmgrasp.sim.run_episode`; ``rng``
        is drawn from only if the task has sensing noise); return (CRMs, success)."""
        ep = run_episode(self.task, self, rng if rng is not None else np.random.default_rng(0), start=config)
        return ep.steps, ep.success

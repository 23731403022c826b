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

from ._validation import CrmgraspError
from .contacts import Config
from .hand import execute_crm
from .quality import min_friction
from .sensing import Error, observe
from .tasks import Task

__all__ = ["clairvoyant_steps", "clairvoyant_bound", "belief_optimum", "sample_starts"]

Step = tuple[Config, int, bool]  # next configuration, observation index, grasped


class _Model:
    """Cached deterministic transitions of a task (noise ignored)."""

    def __init__(self, task: Task) -> None:
        self.task = task
        self._step: dict[tuple[Config, int], Step] = {}
        self._clair: dict[tuple[Config, int], int] = {}

    def step(self, config: Config, action: int) -> Step:
        key = (config, action)
        hit = self._step.get(key)
        if hit is None:
            t = self.task
            out = execute_crm(t.obj, t.hand, config, t.actions[action], config)
            index = t.discretizer.index(observe(out.config), out.error)
            hit = self._step[key] = (out.config, index, min_friction(out.config) <= t.mu_goal)
        return hit

    def clairvoyant(self, config: Config, horizon: int) -> int:
        """Fewest CRMs to a grasp within ``horizon`` (``horizon`` if none is found)."""
        key = (config, horizon)
        if key not in self._clair:
            self._clair[key] = self._bfs(config, horizon)
        return self._clair[key]

    def _bfs(self, start: Config, horizon: int) -> int:
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
        return horizon


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


def _value(model: _Model, belief: tuple[Config, ...], h: int, memo: dict) -> float:
    """``V(B, h)``: expected further CRMs, mean over the starts in ``belief``."""
    if h == 0 or not belief:
        return 0.0
    key = (belief, h)
    if key in memo:
        return memo[key]
    n = len(belief)
    best = float(h)  # doing anything for h steps costs at most h
    options = []
    for a in range(len(model.task.actions)):
        children: dict[int, list[Config]] = {}
        for c in belief:
            nxt, index, grasped = model.step(c, a)
            if not grasped:
                children.setdefault(index, []).append(nxt)
        kids = [tuple(v) for v in children.values()]
        bound = 1.0 + sum(len(k) * _lower(model, k, h - 1) for k in kids) / n
        options.append((bound, kids))
    for bound, kids in sorted(options, key=lambda o: o[0]):
        if bound >= best:
            break
        cost = 1.0
        for kid in sorted(kids, key=len, reverse=True):
            cost += len(kid) * _value(model, kid, h - 1, memo) / n
            if cost >= best:
                break
        best = min(best, cost)
    memo[key] = best
    return best


def _lower(model: _Model, belief: tuple[Config, ...], h: int) -> float:
    """Admissible bound on ``V(belief, h)``: the mean clairvoyant CRMs (full
    information cannot do worse), capped by the horizon."""
    if h == 0:
        return 0.0
    return float(np.mean([model.clairvoyant(c, h) for c in belief]))

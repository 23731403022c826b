"""The hidden states of sampled starts and their noise-free transitions, cached.

[`SampledModel`][] numbers every place (an object and a configuration on it) that the
starts reach, once, so that a belief is a tuple of integers, and expands a state by every
CRM at once through its object's kernel. The references ([`crmgrasp.planners.references`][]:
the clairvoyant bound, the belief-space optimum and its policy), the realizable planner and
the k-order policy search all search over it.
"""

from __future__ import annotations

import dataclasses
from collections import deque
from collections.abc import Sequence

from crmgrasp._validation import CrmgraspError, shown
from crmgrasp.kernels import BACKENDS, Kernel, compiled_rules, kernel_for
from crmgrasp.model.contacts import Config, Grip
from crmgrasp.model.hand import Error
from crmgrasp.model.sensing import SensorNoise
from crmgrasp.tasks import Task, World

__all__ = ["SampledModel", "checked_starts", "expansion_kernel", "Start", "Place", "State", "Step", "SAME"]

Start = Config | Grip | World
"""A start: a configuration of the task's object, or a world (an object and a configuration)."""
Place = tuple[int, Config | Grip]
"""A world's object (an index into ``SampledModel.tasks``) and a configuration on it."""
State = int
"""A hidden state: its index in ``SampledModel.places`` (each place gets one, once)."""
Step = tuple[State, int, bool]
"""A transition: the next state, its observation index and whether it grasped."""


def checked_starts(starts: object, who: str) -> Sequence[Start]:
    """``starts`` if it is a non-empty sequence (a list or tuple of starts: each is checked
    where [`SampledModel.state`][] numbers it); one-line error otherwise, naming ``who``."""
    if isinstance(starts, (str, bytes)) or not isinstance(starts, Sequence) or not starts:
        raise CrmgraspError(f"{who} needs a non-empty list of starts (from sample_starts), got {shown(starts)}")
    return starts


class SampledModel:
    """Cached deterministic transitions of a task (noise ignored) over hidden states, each
    a place ``(object, configuration)`` numbered once (``places[state]``): object 0 is the
    task's own; each [`World`][crmgrasp.tasks.World] adds its object. A belief is then a
    tuple of numbers, cheap to compare and to look up.

    A state's successors under every CRM come from one call of its object's kernel
    ([`crmgrasp.kernels.kernel_for`][] on ``backend``: compiled where a kernel exists, the
    readable rules on ``"reference"``; the same values bit for bit, as the tests hold every
    kernel to the readable rules); a single step not yet expanded applies the task's rules."""

    def __init__(self, task: Task, backend: str = "auto") -> None:
        if backend not in BACKENDS:
            raise CrmgraspError(f"unknown backend {backend!r}; choose one of {', '.join(BACKENDS)}")
        self.task = task = compiled_rules(task)
        self.backend = backend
        self.tasks: list[Task] = [task]
        self._kernels: list[Kernel | None] = [None if task.family is not None else expansion_kernel(task, backend)]
        self._ids: dict[int, int] = {}
        self.places: list[Place] = []
        self._number: dict[Place, State] = {}
        self._succ: list[tuple[Step, ...] | None] = []
        self._succ_err: list[tuple[Error, ...] | None] = []
        self._keys: list[tuple[int, tuple[int, ...]] | None] = []
        self._step: dict[tuple[State, int], Step] = {}
        self._err: dict[tuple[State, int], Error] = {}
        self._clair: dict[State, tuple[int | None, int]] = {}  # state -> (depth found, horizon searched)

    def _state(self, place: Place) -> State:
        """The number of ``place`` (a new one the first time)."""
        s = self._number.get(place)
        if s is None:
            s = self._number[place] = len(self.places)
            self.places.append(place)
            self._succ.append(None)
            self._succ_err.append(None)
            self._keys.append(None)
        return s

    def state(self, start: Start) -> State:
        """The hidden state of a start (a configuration of the task, or a world)."""
        if isinstance(start, World):
            i = self._ids.get(id(start.task))
            if i is None:
                if start.task.actions != self.task.actions:
                    raise CrmgraspError(
                        f"a world of {start.task.name!r} has other CRMs than task {self.task.name!r}: "
                        "draw the worlds from the task itself"
                    )
                i = self._ids[id(start.task)] = len(self.tasks)
                self.tasks.append(compiled_rules(start.task))
                self._kernels.append(expansion_kernel(start.task, self.backend))
            return self._state((i, start.config))
        if self.task.family is not None:
            raise CrmgraspError(f"task {self.task.name!r} draws an object per episode: give worlds, not configurations")
        return self._state((0, self.task.check_config(start, "start")))

    def observation(self, state: State) -> int:
        """The bin index of the state's own observation (no error): what an episode
        starting there senses first."""
        i, config = self.places[state]
        return self.task.discretizer.index(self.tasks[i].observe(config), Error.NONE)

    def successors(self, state: State) -> tuple[Step, ...]:
        """``step(state, a)`` for every CRM ``a``, in order, from one call of the object's
        kernel ([`crmgrasp.kernels.base.Kernel.successors`][]), cached."""
        hit = self._succ[state]
        if hit is None:
            i, config = self.places[state]
            grasped, number = self.tasks[i].grasped, self._state
            nexts = self._kernels[i].successors(config)  # type: ignore[union-attr]
            hit = self._succ[state] = tuple((number((i, c)), index, grasped(mu)) for c, index, _, mu in nexts)
            self._succ_err[state] = tuple(s.error for s in nexts)
        return hit

    def step(self, state: State, action: int) -> Step:
        succ = self._succ[state]
        if succ is not None:
            return succ[action]
        key = (state, action)
        hit = self._step.get(key)
        if hit is None:
            i, config = self.places[state]
            t = self.tasks[i]
            out = t.execute(config, t.actions[action], config)
            index = t.discretizer.index(t.observe(out.config), out.error)
            hit = self._step[key] = (self._state((i, out.config)), index, t.is_success(out.config))
            self._err[key] = out.error
        return hit

    def error(self, state: State, action: int) -> Error:
        """The error flag of ``step(state, action)`` (after that step)."""
        errs = self._succ_err[state]
        return errs[action] if errs is not None else self._err[(state, action)]

    def errors(self, state: State) -> tuple[Error, ...]:
        """The error flags of every CRM from ``state`` (after [`successors`][])."""
        return self._succ_err[state]  # type: ignore[return-value]

    def clairvoyant(self, state: State, horizon: int) -> int:
        """Fewest CRMs to a grasp within ``horizon`` (``horizon`` if none is found)."""
        depth = self.depth(state, horizon)
        return horizon if depth is None else depth

    def clairvoyant_total(self, states: Sequence[State], horizon: int) -> int:
        """The sum of [`clairvoyant`][] over ``states``: each read straight from the memo
        where a search already answers ``horizon`` (as [`depth`][] reads it), the search
        otherwise (the branch-and-bound's bound, asked for every belief it meets)."""
        known, total = self._clair, 0
        for c in states:
            found, searched = known.get(c, (None, 0))
            if found is not None and found <= horizon:
                total += found
            elif found is None and horizon <= searched:
                total += horizon
            else:
                total += self.clairvoyant(c, horizon)
        return total

    def depth(self, state: State, horizon: int) -> int | None:
        """Fewest CRMs to a grasp within ``horizon``; ``None`` if no sequence grasps.
        One search answers every horizon up to its own: a depth ``d`` found holds for
        every horizon from ``d`` on (none below it); none found within ``H`` holds for
        every horizon up to ``H``."""
        known = self._clair.get(state)
        if known is not None:
            found, searched = known
            if found is not None:
                return found if found <= horizon else None
            if horizon <= searched:
                return None
        found = self._bfs(state, horizon)
        self._clair[state] = (found, horizon)
        return found

    def _bfs(self, start: State, horizon: int) -> int | None:
        """Breadth-first search over CRM sequences. Configurations are visited once up
        to [`SAME`][]: one reached again within rounding (a slide and its reverse)
        is the same place, and searching it again cannot find a shorter sequence."""
        seen = {self.key(start)}
        frontier = deque([(start, 0)])
        while frontier:
            cfg, depth = frontier.popleft()
            if depth == horizon:
                continue
            for nxt, _, grasped in self.successors(cfg):
                if grasped:
                    return depth + 1
                k = self.key(nxt)
                if k not in seen:
                    seen.add(k)
                    frontier.append((nxt, depth + 1))
        return None

    def key(self, state: State) -> tuple[int, tuple[int, ...]]:
        """Where the state is, for the clairvoyant search: its object and its numbers rounded
        to [`SAME`][] (remembered)."""
        k = self._keys[state]
        if k is None:
            i, c = self.places[state]
            k = self._keys[state] = (i, tuple([round(v / SAME) for v in self.tasks[i].model.numbers(c)]))
        return k


def expansion_kernel(task: Task, backend: str) -> Kernel:
    """The kernel that expands ``task``'s states: its path on ``backend`` without sensing
    noise (the references' dynamics are noise-free; a reading equal to the configuration is
    the same on every path), deciding grasps only (``friction="decided"``)."""
    if task.noise.active:
        task = dataclasses.replace(task, noise=SensorNoise())
    return kernel_for(task, backend, "decided")


SAME = 1e-9
"""Metres (and unit-normal components) within which two configurations count as one
place in the clairvoyant search."""

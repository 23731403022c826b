"""Pure episode dynamics of a task, and the one episode loop.

``begin``/``reset`` and ``step`` on an immutable state are the reference definition
of an episode: the environments, training, evaluation, planners and controllers
step through them, or through a kernel of [`crmgrasp.kernels`][] that is tested
equal to them bit for bit. [`run_episode`][] is the one loop that lets a
[`Policy`][] (a learner, a planner or a controller) act in an episode, and
[`run_batch`][] its batched form: many rows of episodes stepped together (lockstep
training, the deep peer's evaluation).

Sensing: each configuration is read once. The observation ``o_t`` is computed from
that reading, and the CRM executed at time ``t`` builds its goal line from the same
reading ([docs/model.md section 4][model-4]). With the task's noise off, readings are exact and draw
nothing from the generator.

Draw order: ``reset`` draws the start (the task's sampler) then one reading;
``step`` draws one reading of the configuration after the CRM.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator, Sequence
from typing import Any, NamedTuple, Protocol, overload

import numpy as np
from numpy.typing import NDArray

from crmgrasp._validation import CrmgraspError, generator, shown
from crmgrasp.model.contacts import Config, Grip
from crmgrasp.model.hand import CRM, Error
from crmgrasp.tasks import Task, World, checked_task

__all__ = [
    "OneStep",
    "Stepper",
    "TaskSteps",
    "FamilyStepper",
    "Episode",
    "Transition",
    "SimState",
    "Percept",
    "Policy",
    "begin",
    "reset",
    "step",
    "episode_end",
    "run_episode",
    "BatchPolicy",
    "Rows",
    "RowPolicies",
    "StepperRows",
    "run_batch",
]


class SimState(NamedTuple):
    """True configuration, its sensed reading, and CRMs executed so far."""

    config: Config | Grip
    sensed: Config | Grip
    steps: int


class Percept(NamedTuple):
    """What a policy may use after a reset or a CRM: the sensed observation (the contact
    model's values, in its ``observation_names`` order), the error flag, the discretized
    observation, the sensed contact frames (what the next CRM's goal line is built from),
    and the reward and episode end of the step."""

    observation: tuple[float, ...]
    error: Error
    obs_index: int
    sensed: Config | Grip
    reward: float = 0.0
    terminated: bool = False
    truncated: bool = False


class OneStep(NamedTuple):
    """The state after a reset or a CRM and what is sensed there: the result type of
    `begin`, [`step`][] and every kernel's single step (the one step type;
    [`Percept`][] is what a policy may see of it, and a kernel's
    [`BatchStep`][crmgrasp.kernels.base.BatchStep] its batched form). ``observation`` is the
    contact model's observation of the reading (its ``observation_names``, in order);
    ``error`` is [`Error`][crmgrasp.model.hand.Error] (an ``int``); ``min_friction`` is the
    configuration's least friction (from a kernel made with ``friction="decided"``, a friction
    that decides the grasp as it does: [`crmgrasp.kernels.kernel_for`][])."""

    state: SimState
    observation: tuple[float, ...]
    error: Error
    obs_index: int
    min_friction: float
    reward: float = 0.0
    terminated: bool = False
    truncated: bool = False

    @property
    def percept(self) -> Percept:
        """What a policy perceives of this step."""
        return Percept(
            self.observation,
            self.error,
            self.obs_index,
            self.state.sensed,
            self.reward,
            self.terminated,
            self.truncated,
        )


def begin(task: Task, config: Any, rng: np.random.Generator) -> OneStep:
    """Start an episode at ``config``: one reading, its observation and discretized index
    (error none, reward 0), and the min friction of ``config``."""
    sensed = task.read(config, rng)
    obs = task.observe(sensed)
    index = task.discretizer.index(obs, Error.NONE)
    return OneStep(SimState(config, sensed, 0), obs, Error.NONE, index, task.quality(config))


def reset(task: Task, rng: np.random.Generator) -> OneStep:
    """Draw a start (the task's scalar sampler), then `begin`."""
    return begin(task, task.sample_start(rng), rng)


def checked_state(state: object) -> SimState:
    """``state`` if it is a [`SimState`][] (what `begin` and `step` return); a one-line error
    otherwise."""
    if type(state) is not SimState:
        raise CrmgraspError(f"a step needs the SimState of the episode's last step, got {shown(state)}")
    return state


def step(task: Task, state: SimState, action: Any, rng: np.random.Generator) -> OneStep:
    """Execute ``task.actions[action]`` (or the CRM ``action`` itself, within the
    hand's reach) from ``state``: the CRM from the state's reading, then one reading of
    the configuration it leads to.

    ``terminated`` when the true configuration is a grasp (``min_friction <=
    mu_goal``); ``truncated`` when ``max_steps`` CRMs have been executed without.
    """
    out = task.execute(checked_state(state).config, task.crm(action), state.sensed)
    sensed = task.read(out.config, rng)
    obs = task.observe(sensed)
    mu = task.quality(out.config)
    steps = state.steps + 1
    terminated, truncated = episode_end(task, mu, steps)
    return OneStep(
        SimState(out.config, sensed, steps),
        obs,
        out.error,
        task.discretizer.index(obs, out.error),
        mu,
        step_reward(task, terminated, out.error),
        terminated,
        truncated,
    )


@overload
def episode_end(task: Task, mu: float, steps: int) -> tuple[bool, bool]: ...


@overload
def episode_end(
    task: Task, mu: NDArray[np.float64], steps: NDArray[np.int64]
) -> tuple[NDArray[np.bool_], NDArray[np.bool_]]: ...


def episode_end(task: Task, mu: Any, steps: Any) -> tuple[Any, Any]:
    """``(terminated, truncated)`` after a CRM: terminated when the true configuration is
    a grasp (`Task.grasped`), truncated when ``steps >= max_steps`` CRMs have been
    executed without one. Works on numbers or, elementwise, on arrays."""
    terminated = task.grasped(mu)
    return terminated, (steps >= task.max_steps) > terminated  # a > b on booleans: a and not b


STEP_REWARD = -1.0
"""The reward of every CRM that does not end in a grasp."""


def step_reward(task: Task, terminated: Any, error: Any = 0) -> Any:
    """The reward of a CRM: ``task.grasp_reward`` for the one that reaches a grasp
    (``-1`` in the paper's reading, ``0`` in the "-1 in every non-goal state" reading),
    [`STEP_REWARD`][] for every other, less ``task.error_cost`` for one that ends in an
    error (aperture or palm; the cost of a failed attempt, 0 in the paper); elementwise
    on arrays of ``terminated`` and ``error`` codes."""
    if isinstance(terminated, np.ndarray):
        base = np.where(terminated, task.grasp_reward, STEP_REWARD)
        return base - task.error_cost * (np.asarray(error) != 0) if task.error_cost else base
    reward = task.grasp_reward if terminated else STEP_REWARD
    return reward - task.error_cost if error and task.error_cost else reward


class Policy(Protocol):
    """The one agent interface of [`run_episode`][]: learners (through
    `crmgrasp.agents.LearnerPolicy`), planners and controllers.

    ``begin`` receives the first percept of an episode, ``act`` returns an action
    index of the task or a [`CRM`][crmgrasp.model.hand.CRM], and ``tell`` the percept
    that action produced (a learner learns there).
    """

    def begin(self, first: Percept) -> None: ...

    def act(self) -> int | CRM: ...

    def tell(self, percept: Percept) -> None: ...


class Stepper(Protocol):
    """What [`run_episode`][] steps through: a kernel of [`crmgrasp.kernels`][] (its
    ``sample_start``, ``begin`` and ``step_one`` equal `Task.sample_start`,
    `begin` and [`step`][] bit for bit)."""

    def sample_start(self, rng: np.random.Generator) -> Config | Grip: ...

    def begin(self, config: Config | Grip, rng: np.random.Generator) -> OneStep: ...

    def step_one(self, state: SimState, action: int | CRM, rng: np.random.Generator) -> OneStep: ...

    def use(self, instance: Task) -> None:
        """Step ``instance`` (a task on one object of this task's family) from now on;
        a one-line error on a task with one object."""
        ...


class TaskSteps:
    """The reference [`Stepper`][] of one task: `Task.sample_start`,
    `begin` and [`step`][]."""

    def __init__(self, task: Task) -> None:
        self.task = task

    def sample_start(self, rng: np.random.Generator) -> Config | Grip:
        return self.task.sample_start(rng)

    def begin(self, config: Config | Grip, rng: np.random.Generator) -> OneStep:
        return begin(self.task, config, rng)

    def step_one(self, state: SimState, action: int | CRM, rng: np.random.Generator) -> OneStep:
        return step(self.task, state, action, rng)

    def use(self, instance: Task) -> None:
        raise CrmgraspError(f"task {self.task.name!r} has one object: a World start needs a family task")


class FamilyStepper:
    """A [`Stepper`][] for a task with an object family: `sample_start` draws
    the episode's object (`Task.instance`), then a start on it; `begin` and
    `step_one` step that object's task through ``make(instance)`` (the reference
    [`TaskSteps`][], or a kernel). [`use`][] puts a given world's object in place
    (an episode from a fixed [`World`][crmgrasp.tasks.World])."""

    def __init__(self, task: Task, make: Callable[[Task], Stepper] = TaskSteps) -> None:
        self.task, self._make = task, make
        self.instance: Task
        self.current: Stepper
        self.use(task.with_object(task.obj))

    def use(self, instance: Task) -> None:
        """Step ``instance`` (a task on one object) from now on."""
        self.instance, self.current = instance, self._make(instance)

    def sample_start(self, rng: np.random.Generator) -> Config | Grip:
        """Draw the episode's object, then a start on it."""
        self.use(self.task.instance(rng))
        return self.current.sample_start(rng)

    def begin(self, config: Config | Grip, rng: np.random.Generator) -> OneStep:
        return self.current.begin(config, rng)

    def step_one(self, state: SimState, action: int | CRM, rng: np.random.Generator) -> OneStep:
        return self.current.step_one(state, action, rng)


class Transition(NamedTuple):
    """One step of a traced episode: the step before it, the action taken, its result."""

    before: OneStep
    action: int | CRM
    after: OneStep


class Episode(NamedTuple):
    """CRMs executed, success, and (when asked for) every transition. ``success``: the
    last step's ``min_friction`` is a grasp (`Task.grasped`). On the kinematic model that
    is the episode's ``terminated``; a stepper whose episodes end on what a hand senses
    (a simulated hand, [`crmgrasp.hardware.runner.HandSteps`][]) may report the true
    ``min_friction`` there, and then a sensed grasp that is not a true one is no success."""

    steps: int
    success: bool
    trace: tuple[Transition, ...] = ()


_HAS: set[tuple[type, tuple[str, ...]]] = set()
"""The classes seen to define the methods asked for: each is checked once, not per episode."""


def check_policy(policy: object, methods: tuple[str, ...]) -> None:
    """A one-line error unless ``policy`` has every method of ``methods`` (a [`Policy`][]'s
    ``begin``, ``act`` and ``tell``; a learner's own). A class that defines them all is
    remembered, so that an episode's check is one set lookup."""
    key = (type(policy), methods)
    if key in _HAS:
        return
    missing = [m for m in methods if not callable(getattr(policy, m, None))]
    if missing:
        raise CrmgraspError(f"a policy needs the methods {', '.join(methods)}; {shown(policy)} has no {missing[0]}")
    if all(callable(getattr(type(policy), m, None)) for m in methods):
        _HAS.add(key)


def run_episode(
    task: Task,
    policy: Policy,
    rng: np.random.Generator,
    *,
    start: Config | Grip | World | None = None,
    trace: bool = False,
    kernel: Stepper | None = None,
) -> Episode:
    """Run ``policy`` for one episode of ``task``: from a start drawn from ``rng`` (the
    task's scalar sampler, after the object for a family task) or from ``start`` (a
    [`World`][crmgrasp.tasks.World] for a family task), one step per action until the
    episode ends; starts and readings draw from ``rng``. Steps are `begin`
    and [`step`][] (of the episode's object), or the same steps of ``kernel``
    (faster, the same results)."""
    checked_task(task, "run_episode")
    check_policy(policy, ("begin", "act", "tell"))
    generator(rng)
    if kernel is None:
        kernel = FamilyStepper(task) if task.family is not None else TaskSteps(task)
    if isinstance(start, World):
        kernel.use(start.task)
        config = start.config
    else:
        config = kernel.sample_start(rng) if start is None else start
    now, advance = kernel.begin(config, rng), kernel.step_one
    if now.terminated or now.truncated:  # a stepper that senses its start (a hand) may end here
        return Episode(now.state.steps, bool(task.grasped(now.min_friction)))
    policy.begin(now.percept)
    steps: list[Transition] = []
    while True:
        action = policy.act()
        nxt = advance(now.state, action, rng)
        if trace:
            steps.append(Transition(now, action, nxt))
        policy.tell(nxt.percept)
        if nxt.terminated or nxt.truncated:
            return Episode(nxt.state.steps, bool(task.grasped(nxt.min_friction)), tuple(steps))
        now = nxt


class BatchPolicy(Protocol):
    """The agent interface of [`run_batch`][]: a [`Policy`][] over rows of episodes.
    ``begin`` and ``tell`` receive one row's percepts, ``act`` the actions of the live
    ``rows`` (in their order), so that a policy can decide for all of them in one call."""

    def begin(self, row: int, first: Percept) -> None: ...

    def act(self, rows: list[int]) -> Sequence[int | CRM]: ...

    def tell(self, row: int, percept: Percept) -> None: ...


class Rows(Protocol):
    """What [`run_batch`][] steps: rows of episodes, each with its own state."""

    def begin(self, row: int) -> Percept:
        """Start the row's next episode; its first percept."""
        ...

    def step(self, rows: list[int], actions: Sequence[int | CRM]) -> Iterable[Percept]:
        """One CRM in each of ``rows`` (``actions`` in their order); the percepts, in the
        rows' order (an iterator may build each when it is asked for: the loop tells each
        before it asks for the next)."""
        ...

    def episode(self, row: int) -> Episode:
        """The row's current episode: CRMs executed and success (trace empty)."""
        ...


class RowPolicies:
    """One [`Policy`][] per row as a [`BatchPolicy`][] (each told its row's percepts)."""

    def __init__(self, policies: Sequence[Policy]) -> None:
        self.policies = policies

    def begin(self, row: int, first: Percept) -> None:
        self.policies[row].begin(first)

    def act(self, rows: list[int]) -> list[int | CRM]:
        p = self.policies
        return [p[r].act() for r in rows]

    def tell(self, row: int, percept: Percept) -> None:
        self.policies[row].tell(percept)


class StepperRows:
    """[`Rows`][] of one episode each from given starts (a configuration of ``task``, or a
    [`World`][crmgrasp.tasks.World] of a family task: its object and configuration), each
    row stepped through its own [`Stepper`][] (``make`` of its task: the reference
    [`TaskSteps`][] unless given); readings draw from ``rng`` in row order. A row begun
    again starts from its start again."""

    def __init__(
        self,
        task: Task,
        starts: Sequence[Config | Grip | World],
        rng: np.random.Generator,
        make: Callable[[Task], Stepper] = TaskSteps,
    ) -> None:
        self.rng = rng
        self.tasks = [s.task if isinstance(s, World) else task for s in starts]
        self.configs = [s.config if isinstance(s, World) else s for s in starts]
        made: dict[int, Stepper] = {}  # one stepper per object
        for t in self.tasks:
            if id(t) not in made:
                made[id(t)] = make(t)
        self.steppers = [made[id(t)] for t in self.tasks]
        self.now: dict[int, OneStep] = {}

    def begin(self, row: int) -> Percept:
        self.now[row] = now = self.steppers[row].begin(self.configs[row], self.rng)
        return now.percept

    def step(self, rows: list[int], actions: Sequence[int | CRM]) -> Iterator[Percept]:
        """Each row's step, when its percept is asked for."""
        for r, a in zip(rows, actions, strict=True):
            self.now[r] = now = self.steppers[r].step_one(self.now[r].state, a, self.rng)
            yield now.percept

    def episode(self, row: int) -> Episode:
        now = self.now[row]
        return Episode(now.state.steps, bool(self.tasks[row].grasped(now.min_friction)))


def run_batch(rows: Rows, policy: BatchPolicy, n: int, more: Callable[[int, Episode | None], bool]) -> None:
    """The batched form of [`run_episode`][]: rows ``0 .. n-1`` of episodes in lockstep.

    Row ``r`` begins an episode whenever ``more(r, last)`` is true (``last``: the row's
    episode that just ended, ``None`` before its first; the caller records it there).
    Each step, every live row's action comes from one ``policy.act`` call, every row's
    CRM from one ``rows.step`` call, and then, row by row, the policy is told the percept
    (``rows.step`` may yield them one at a time: a percept is dropped once told, which
    keeps the garbage collector's young generation small) and an ended episode is handed
    to ``more``. Per row, the calls come in [`run_episode`][]'s order."""
    live: list[int] = []
    for r in range(n):
        if more(r, None):
            policy.begin(r, rows.begin(r))
            live.append(r)
    while live:
        still = []
        for r, p in zip(live, rows.step(live, policy.act(live)), strict=True):
            policy.tell(r, p)
            if p.terminated or p.truncated:
                if not more(r, rows.episode(r)):
                    continue
                policy.begin(r, rows.begin(r))
            still.append(r)
        live = still

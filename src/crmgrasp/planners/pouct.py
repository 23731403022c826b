"""pomdp_py's POUCT as an online peer: Monte Carlo tree search over the task's own simulator.

[`POUCTPolicy`][] is a [`Policy`][crmgrasp.sim.Policy] of the one episode loop. At each step it
plans with ``pomdp_py.POUCT`` (Silver and Veness 2010; extra ``crmgrasp[pomdp]``) from a
particle belief over hidden worlds, then acts. The generative model behind the tree is the
task's own step ([`crmgrasp.sim.step`][]: the CRM, one reading, its discretized observation,
the reward; a grasp is absorbing with reward 0 after it), so the planner knows the model and
the start distribution, as the belief-space optimum does, and spends no task episode: it
belongs beside the optimum, not among the learners.

Belief: ``particles`` worlds drawn from the task's start distribution (the object too, on a
family task) and kept when their first discretized observation is the one sensed; after each
CRM every particle is stepped with it and kept if its observation equals the sensed one
(rejection: exact for a noise-free task). Emptied, it is refilled by drawing worlds and
replaying the episode's CRMs, up to ``refill_tries`` draws; then the last particles are kept.

[`ModelPOUCTPolicy`][] plans with POUCT on an explicit POMDP of the task instead (the sampled
POMDP that ``crmgrasp pomdp`` builds and exports, or that file read back by
[`read_cassandra`][crmgrasp.planners.pomdp.read_cassandra]): its states are the model's cells, its
transitions and observations drawn from the model's ``T`` and ``Z``, its belief the model's exact
Bayes belief, kept in the real simulator as the PBVI agent keeps it
([`BeliefTracker`][crmgrasp.planners.pomdp_task.BeliefTracker]). POUCT then plans on the model
a user exports, the same model PBVI solves.

Randomness: every draw comes from the policy's ``numpy.random.Generator``: the particles,
the model's steps, the belief samples at the root of each simulation (the belief is a
``pomdp_py.GenerativeDistribution`` drawing from it) and the random rollouts. pomdp_py's own
``random`` is never used, so one seed gives one run.
"""

from __future__ import annotations

from dataclasses import dataclass
from types import ModuleType
from typing import Any

import numpy as np

from crmgrasp._validation import CrmgraspError, integer, require_extra
from crmgrasp.planners.pomdp import POMDP
from crmgrasp.planners.pomdp_task import BeliefTracker, TaskPOMDP
from crmgrasp.sim import Percept, SimState, begin, step
from crmgrasp.tasks import Task

__all__ = ["POUCTPolicy", "ModelPOUCTPolicy", "POUCTSettings", "require_pomdp_py"]


def require_pomdp_py() -> ModuleType:
    """Import and return ``pomdp_py``, or raise a one-line error naming the extra."""
    return require_extra("pomdp", "the POUCT peer", "pomdp_py")[0]  # type: ignore[no-any-return]


@dataclass(frozen=True)
class POUCTSettings:
    """POUCT's budget per decision and the belief's size."""

    num_sims: int = 1000
    """Simulations per decision."""
    particles: int = 1000
    """Worlds in the belief."""
    exploration_const: float = 1.0
    """UCB1's exploration constant (rewards are -1 per CRM)."""
    refill_tries: int = 20000
    """Worlds drawn at most to refill an emptied belief."""

    def __post_init__(self) -> None:
        for name in ("num_sims", "particles", "refill_tries"):
            integer(getattr(self, name), name, 1, 10_000_000)
        if not (self.exploration_const >= 0.0):
            raise CrmgraspError(f"exploration_const must be >= 0, got {self.exploration_const!r}")


class _World:
    """A hidden world: the task on its object, the simulator state, and its last discretized
    observation (``-1``: grasped, absorbing)."""

    __slots__ = ("obs", "state", "task")

    def __init__(self, task: Task, state: SimState, obs: int) -> None:
        self.task, self.state, self.obs = task, state, obs

    def __hash__(self) -> int:
        return id(self)


def _rollout(pomdp_py: ModuleType, actions: list[Any], rng: np.random.Generator) -> Any:
    """POUCT's action set and rollout policy: every CRM, uniform rollouts through ``rng``."""

    class Actions(pomdp_py.RolloutPolicy):  # type: ignore[misc,name-defined]
        def get_all_actions(self, state: Any = None, history: Any = None) -> list[Any]:
            return actions

        def rollout(self, state: Any, history: Any = None) -> Any:
            return actions[int(rng.integers(len(actions)))]

    return Actions()


def _plan(pomdp_py: ModuleType, settings: POUCTSettings, depth: int, belief: Any, models: list[Any]) -> int:
    """One POUCT decision: the CRM index planned from ``belief`` over ``depth`` CRMs at most."""
    transition, observe, reward, actions = models
    planner = pomdp_py.POUCT(
        max_depth=depth,
        num_sims=settings.num_sims,
        discount_factor=1.0,
        exploration_const=settings.exploration_const,
        rollout_policy=actions,
    )
    return int(planner.plan(pomdp_py.Agent(belief, actions, transition, observe, reward)).name)


def _models(pomdp_py: ModuleType, task: Task, rng: np.random.Generator) -> tuple[Any, ...]:
    """The transition, observation, reward and policy models over [`_World`][] states."""
    n = len(task.actions)
    actions = [pomdp_py.SimpleAction(str(i)) for i in range(n)]
    grasped = pomdp_py.SimpleObservation(-1)

    class State(pomdp_py.State):  # type: ignore[misc,name-defined]
        def __init__(self, world: _World) -> None:
            self.world = world

        def __hash__(self) -> int:
            return id(self)

        def __eq__(self, other: object) -> bool:
            return self is other

    class Transition(pomdp_py.TransitionModel):  # type: ignore[misc,name-defined]
        def sample(self, state: Any, action: Any) -> Any:
            w = state.world
            if w.obs < 0:
                return state
            out = step(w.task, w.state, int(action.name), rng)
            return State(_World(w.task, out.state, -1 if out.terminated else out.obs_index))

    class Observe(pomdp_py.ObservationModel):  # type: ignore[misc,name-defined]
        def sample(self, next_state: Any, action: Any) -> Any:
            obs = next_state.world.obs
            return grasped if obs < 0 else pomdp_py.SimpleObservation(obs)

    class Reward(pomdp_py.RewardModel):  # type: ignore[misc,name-defined]
        def sample(self, state: Any, action: Any, next_state: Any) -> float:
            if state.world.obs < 0:
                return 0.0
            return float(task.grasp_reward if next_state.world.obs < 0 else -1.0)

    class Belief(pomdp_py.GenerativeDistribution):  # type: ignore[misc,name-defined]
        """The particle belief, sampled uniformly through the policy's generator."""

        def __init__(self, states: list[Any]) -> None:
            self.states = states

        def random(self) -> Any:
            return self.states[int(rng.integers(len(self.states)))]

    return State, Belief, Transition(), Observe(), Reward(), _rollout(pomdp_py, actions, rng)


class POUCTPolicy:
    """pomdp_py's POUCT over the task's simulator, acting through the one episode loop
    (see the module docstring).

    Parameters
    ----------
    task
        The task (its model is POUCT's generative model and its start distribution the
        prior).
    rng
        Source of the particles, the model's draws, the belief samples and the rollouts.
    settings
        Simulations per decision and belief size.
    """

    def __init__(self, task: Task, rng: np.random.Generator, settings: POUCTSettings | None = None) -> None:
        self.pomdp_py = require_pomdp_py()
        self.task, self.rng = task, rng
        self.settings = POUCTSettings() if settings is None else settings
        self._state_cls, self._belief_cls, *self._models = _models(self.pomdp_py, task, rng)
        self._worlds: list[_World] = []
        self._taken: list[int] = []
        self._taken_obs: list[tuple[int, int]] = []
        self._first = -1
        self.refills = 0
        """Times the belief emptied and was refilled, over this policy's life."""

    # -- belief ------------------------------------------------------------------------
    def _draw(self) -> _World:
        world = self.task.sample_world(self.rng)
        first = begin(world.task, world.config, self.rng)
        return _World(world.task, first.state, first.obs_index)

    def _replay(self, w: _World) -> _World | None:
        """``w`` after the episode's CRMs, or None where an observation differs."""
        for a, obs in self._taken_obs:
            out = step(w.task, w.state, a, self.rng)
            if out.obs_index != obs:
                return None
            w = _World(w.task, out.state, out.obs_index)
        return w

    def _refill(self) -> list[_World]:
        self.refills += 1
        kept: list[_World] = []
        for _ in range(self.settings.refill_tries):
            w = self._draw()
            if w.obs == self._first:
                w2 = self._replay(w)
                if w2 is not None:
                    kept.append(w2)
                    if len(kept) >= self.settings.particles:
                        break
        return kept

    # -- the Policy interface ------------------------------------------------------------
    def begin(self, first: Percept) -> None:
        self._first, self._taken, self._taken_obs = first.obs_index, [], []
        drawn = (self._draw() for _ in range(self.settings.refill_tries))
        self._worlds = []
        for w in drawn:
            if w.obs == first.obs_index:
                self._worlds.append(w)
                if len(self._worlds) >= self.settings.particles:
                    break

    def act(self) -> int:
        if not self._worlds:
            return int(self.rng.integers(len(self.task.actions)))  # no world explains what was sensed
        belief = self._belief_cls([self._state_cls(w) for w in self._worlds])
        action = _plan(self.pomdp_py, self.settings, self.task.max_steps - len(self._taken), belief, self._models)
        self._taken.append(action)
        return action

    def tell(self, percept: Percept) -> None:
        a = self._taken[-1]
        self._taken_obs.append((a, percept.obs_index))
        if percept.terminated or percept.truncated:
            return
        kept = []
        for w in self._worlds:
            out = step(w.task, w.state, a, self.rng)
            if out.obs_index == percept.obs_index and not out.terminated:
                kept.append(_World(w.task, out.state, out.obs_index))
        self._worlds = kept or self._refill()


def _draw(cumulative: np.ndarray, rng: np.random.Generator) -> int:
    """An index drawn with the probabilities whose running sums are ``cumulative`` (one uniform)."""
    return min(int(np.searchsorted(cumulative, rng.random() * cumulative[-1], side="right")), len(cumulative) - 1)


def _sparse_rows(t: Any) -> list[tuple[np.ndarray, np.ndarray]]:
    """Per state of a CSR transition matrix: its successors and the running sums of their
    probabilities (what [`_draw`][] takes; zero entries are never drawn either way)."""
    ptr = t.indptr
    return [(t.indices[ptr[s] : ptr[s + 1]], np.cumsum(t.data[ptr[s] : ptr[s + 1]])) for s in range(t.shape[0])]


def _model_models(pomdp_py: ModuleType, m: POMDP, grasp_reward: float, rng: np.random.Generator) -> tuple[Any, ...]:
    """The transition, observation, reward and policy models of POUCT over an explicit POMDP's
    states (cell indices): ``s' ~ T[a](s, .)``, ``o ~ Z[a, s', .]``; a goal state is absorbing,
    observed as ``-1``, and reached with the task's grasp reward (-1 per CRM otherwise)."""
    n = m.n_actions
    actions = [pomdp_py.SimpleAction(str(i)) for i in range(n)]
    grasped = pomdp_py.SimpleObservation(-1)
    rows = [_sparse_rows(t.tocsr()) for t in m.T]
    seen = np.cumsum(m.Z, axis=2)
    goal = m.goal

    class State(pomdp_py.State):  # type: ignore[misc,name-defined]
        def __init__(self, s: int) -> None:
            self.s = s

        def __hash__(self) -> int:
            return self.s

        def __eq__(self, other: object) -> bool:
            return isinstance(other, State) and other.s == self.s

    class Transition(pomdp_py.TransitionModel):  # type: ignore[misc,name-defined]
        def sample(self, state: Any, action: Any) -> Any:
            successors, cumulative = rows[int(action.name)][state.s]
            if goal[state.s] or not len(cumulative) or cumulative[-1] <= 0:
                return state
            return State(int(successors[_draw(cumulative, rng)]))

    class Observe(pomdp_py.ObservationModel):  # type: ignore[misc,name-defined]
        def sample(self, next_state: Any, action: Any) -> Any:
            s2 = next_state.s
            return grasped if goal[s2] else pomdp_py.SimpleObservation(_draw(seen[int(action.name), s2], rng))

    class Reward(pomdp_py.RewardModel):  # type: ignore[misc,name-defined]
        def sample(self, state: Any, action: Any, next_state: Any) -> float:
            return 0.0 if goal[state.s] else float(grasp_reward if goal[next_state.s] else -1.0)

    class Belief(pomdp_py.GenerativeDistribution):  # type: ignore[misc,name-defined]
        """The model's exact belief (a vector over its states), sampled through the policy's generator."""

        def __init__(self, b: np.ndarray) -> None:
            self.cumulative = np.cumsum(b)

        def random(self) -> Any:
            return State(_draw(self.cumulative, rng))

    return Belief, Transition(), Observe(), Reward(), _rollout(pomdp_py, actions, rng)


class ModelPOUCTPolicy(BeliefTracker):
    """pomdp_py's POUCT on an explicit POMDP of the task, acting in the simulator on the model's
    exact belief (see the module docstring).

    Parameters
    ----------
    tp
        The sampled POMDP ([`build_task_pomdp`][crmgrasp.planners.pomdp_task.build_task_pomdp]);
        ``tp.model`` may be replaced by the same model read back from its Cassandra file.
    rng
        Source of the belief samples, the model's draws and the rollouts.
    settings
        Simulations per decision (``particles`` and ``refill_tries`` are not used: the belief is exact).
    """

    def __init__(self, tp: TaskPOMDP, rng: np.random.Generator, settings: POUCTSettings | None = None) -> None:
        super().__init__(tp)
        self.pomdp_py = require_pomdp_py()
        self.rng, self.settings = rng, POUCTSettings() if settings is None else settings
        self._belief_cls, *self._models = _model_models(self.pomdp_py, tp.model, tp.task.grasp_reward, rng)

    def act(self) -> int:
        """POUCT's CRM from the current belief, over the CRMs left."""
        self._a = _plan(self.pomdp_py, self.settings, self._left, self._belief_cls(self._b), self._models)
        return self._a

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
from crmgrasp.sim import Percept, SimState, begin, step
from crmgrasp.tasks import Task

__all__ = ["POUCTPolicy", "POUCTSettings", "require_pomdp_py"]


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

    class Actions(pomdp_py.RolloutPolicy):  # type: ignore[misc,name-defined]
        def get_all_actions(self, state: Any = None, history: Any = None) -> list[Any]:
            return actions

        def rollout(self, state: Any, history: Any = None) -> Any:
            return actions[int(rng.integers(n))]

    class Belief(pomdp_py.GenerativeDistribution):  # type: ignore[misc,name-defined]
        """The particle belief, sampled uniformly through the policy's generator."""

        def __init__(self, states: list[Any]) -> None:
            self.states = states

        def random(self) -> Any:
            return self.states[int(rng.integers(len(self.states)))]

    return State, Belief, Transition(), Observe(), Reward(), Actions()


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
        pp, s = self.pomdp_py, self.settings
        if not self._worlds:
            return int(self.rng.integers(len(self.task.actions)))  # no world explains what was sensed
        transition, observe, reward, actions = self._models
        belief = self._belief_cls([self._state_cls(w) for w in self._worlds])
        agent = pp.Agent(belief, actions, transition, observe, reward)
        planner = pp.POUCT(
            max_depth=self.task.max_steps - len(self._taken),
            num_sims=s.num_sims,
            discount_factor=1.0,
            exploration_const=s.exploration_const,
            rollout_policy=actions,
        )
        action = int(planner.plan(agent).name)
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

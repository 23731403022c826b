"""The MuJoCo stand-in as the episode loop's stepper: learning and evaluation on the physics hand.

[`MujocoSteps`][] is a [`Stepper`][crmgrasp.sim.Stepper] (the interface of the kinematic
kernels), so training ([`crmgrasp.agents.training.train_trials`][]), evaluation, the
Gymnasium environments of [`crmgrasp.hardware.mujoco.env`][] and ``crmgrasp learn --hand
mujoco`` step MuJoCo CRMs through the one episode loop ([`crmgrasp.sim.run_episode`][]).

An episode:

1. ``sample_start`` draws a world from the task (its object, for a family task, then a start
   on it), exactly as on the kinematic model;
2. ``begin`` builds the MuJoCo scene with that object free on the table and places the
   fingertips at the start ([`mujoco_hand`][crmgrasp.hardware.mujoco.spatial.mujoco_hand]:
   the planar or the spatial hand by the task's contact model), then senses;
3. each step executes one CRM as a real motion and senses once
   ([`HandSteps`][crmgrasp.hardware.runner.HandSteps]).

What the learner gets is what the robot has: the observation and error flag of the
*sensed* contacts, and an episode that ends when the sensed configuration is a grasp
(reward ``task.grasp_reward``) or after ``task.max_steps`` CRMs. What is scored is the
truth: each step's ``min_friction`` is that of MuJoCo's own contacts (``inf`` with a
fingertip free), so an episode is a success only if the true configuration is a grasp.

A CRM after which the physics cannot be trusted
([`PhysicsError`][crmgrasp.hardware.mujoco.hand.PhysicsError]: unstable, deep
penetration, object off the table), or after which a fingertip senses no contact, ends
the episode as an error outcome: ``truncated``, the reward of a failed CRM (``-1 -
task.error_cost``), the observation before it (nothing new was sensed), and no success.
A start whose placement faults or loses contact ends at once (0 CRMs, no success).
Each is counted in [`MujocoSteps.faults`][] by kind ([`FAULT_KINDS`][]).
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Callable
from typing import Any

import numpy as np

from crmgrasp.hardware.mujoco import hardware_task, require_mujoco
from crmgrasp.hardware.mujoco.hand import FAULTS, PhysicsError
from crmgrasp.hardware.mujoco.model import PhysicsParams, checked_params
from crmgrasp.hardware.runner import HandSteps
from crmgrasp.model.contacts import Config, Grip
from crmgrasp.model.hand import Error
from crmgrasp.model.spatial import Contacts3D
from crmgrasp.sim import STEP_REWARD, OneStep, SimState
from crmgrasp.tasks import Task

__all__ = ["MujocoSteps", "FAULT_KINDS"]

LOST = "contact lost"
FAULT_KINDS = (*FAULTS, LOST)
"""What ends a MuJoCo episode early: the [`PhysicsError`][crmgrasp.hardware.mujoco.hand.PhysicsError]
kinds, and a fingertip that senses no contact."""


class MujocoSteps(HandSteps):
    """Steps episodes of ``task`` on the MuJoCo stand-in (see the module docstring).

    Parameters
    ----------
    task
        The task as learned: its CRMs, bins, rewards and ``max_steps``. The hand runs it
        as [`hardware_task`][crmgrasp.hardware.mujoco.hardware_task] does (fingertip palm
        tolerance ``palm_tolerance_deg``).
    params
        The stand-in's physical and controller parameters (default:
        [`PhysicsParams`][crmgrasp.hardware.mujoco.model.PhysicsParams]`()`).
    palm_tolerance_deg
        Angle by which a sensed surface may face the palm side before a palm error, degrees.
    """

    @staticmethod
    def require() -> None:
        """A one-line error naming the extra if MuJoCo is not installed."""
        require_mujoco()

    def __init__(self, task: Task, params: PhysicsParams | None = None, palm_tolerance_deg: float = 10.0) -> None:
        self.require()
        super().__init__(hardware_task(task, palm_tolerance_deg))
        self.params = checked_params(params)
        self.palm_tolerance_deg = palm_tolerance_deg
        self.instance = self.task if task.family is None else self.task.with_object(task.obj)
        self.faults: Counter[str] = Counter()
        """Episodes ended early, by kind ([`FAULT_KINDS`][]), over this stepper's life."""
        self.episodes = 0
        """Episodes begun."""
        self.fault: str | None = None
        """What ended the last step early ([`FAULT_KINDS`][]), or ``None``."""
        self._last: OneStep

    # -- the world -------------------------------------------------------------------
    def sample_start(self, rng: np.random.Generator) -> Any:
        """Draw the episode's world: the object (a family task), then a start on it."""
        world = self.task.sample_world(rng)
        self.instance = world.task
        return world.config

    def use(self, instance: Task) -> None:
        """Run episodes on ``instance`` (a task on one object of this task's family)."""
        self.instance = hardware_task(instance, self.palm_tolerance_deg)

    # -- truth -------------------------------------------------------------------
    def score(self, reading: Config | Grip | Contacts3D, sensed: float) -> float:
        """The true ``min_friction``, from MuJoCo's contacts (``inf`` with a fingertip free),
        in place of the sensed one."""
        true = self.hand.true_config()  # type: ignore[attr-defined]
        return math.inf if true is None else float(self.task.quality(true))

    # -- steps ---------------------------------------------------------------------
    def begin(self, config: Any, rng: np.random.Generator) -> OneStep:
        """Build the scene with the episode's object, place the fingertips at ``config``
        and sense."""
        from crmgrasp.hardware.mujoco.spatial import mujoco_hand

        self.episodes += 1
        self.raws, self.clock, self.lost, self.fault = [], [], None, None
        start = SimState(config, config, 0)
        try:
            self.hand = mujoco_hand(self.instance, config, rng, self.params)
        except PhysicsError as fault:
            return self._ended(start, fault.kind, Error.NONE, start=True)
        now, kind = self._guarded(lambda: self._sense(0, Error.NONE))
        if kind is not None or self.lost is not None:
            return self._ended(start, kind or LOST, Error.NONE, start=True)
        self._last = self.first = now
        return now

    def step_one(self, state: SimState, action: Any, rng: np.random.Generator) -> OneStep:
        """Execute the CRM on the hand and sense; a physics fault or a lost contact ends
        the episode as an error outcome."""
        self.fault = None
        crm = self.task.crm(action)
        error, kind = self._guarded(lambda: self.hand.execute(crm))
        if kind is not None:
            return self._ended(state, kind, Error.NONE)
        now, kind = self._guarded(lambda: self._sense(state.steps + 1, error))
        if kind is not None:
            return self._ended(state, kind, error)
        if self.lost is not None:
            return self._ended(state, LOST, error)
        self._last = now
        return now

    def _guarded(self, call: Callable[[], Any]) -> tuple[Any, str | None]:
        """``(call(), None)``, or ``(None, kind)`` of the [`PhysicsError`][crmgrasp.hardware.mujoco.hand.PhysicsError]
        it raised. An arithmetic or value error on the way (a diverged state read by the
        sensors) is a physics fault if the state says so, else a bug, raised as it is."""
        try:
            return call(), None
        except PhysicsError as fault:
            return None, fault.kind
        except (ArithmeticError, ValueError, np.linalg.LinAlgError):
            try:
                self.hand.check_physics()  # type: ignore[attr-defined]
            except PhysicsError as fault:
                return None, fault.kind
            raise

    def _ended(self, state: SimState, kind: str, error: Error, start: bool = False) -> OneStep:
        """The step that ends an episode early: counted; the observation before it; the
        reward of a failed CRM; truncated, no success."""
        self.faults[kind] += 1
        self.fault = kind
        steps = state.steps if start else state.steps + 1
        if start:
            obs, index = (math.nan,) * len(self.task.model.observation_names), 0
        else:
            obs, index = self._last.observation, self._last.obs_index
        reward = STEP_REWARD - self.task.error_cost
        return OneStep(SimState(state.config, state.sensed, steps), obs, error, index, math.inf, reward, False, True)

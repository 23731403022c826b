"""Gymnasium environments whose steps are CRMs of the MuJoCo stand-in hand.

Registered (extra ``crmgrasp[mujoco]``) as the ids of
[`crmgrasp.envs.single.MUJOCO_ENVS`][]: ``crmgrasp/PaperBoxMujoco-v0``,
``crmgrasp/BoxFamilyMujoco-v0``, ``crmgrasp/Cup3DMujoco-v0`` and
``crmgrasp/Box3DMujoco-v0``. Without the extra, ``gymnasium.make`` answers with a one-line
error naming it.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from crmgrasp._validation import CrmgraspError
from crmgrasp.envs.single import check_reset_options, observation_space, space_observation, world_config
from crmgrasp.hardware.mujoco.model import PhysicsParams
from crmgrasp.hardware.mujoco.steps import MujocoSteps
from crmgrasp.sim import OneStep, SimState
from crmgrasp.tasks import Task, make_task

__all__ = ["MujocoCRMEnv", "MAX_START_TRIES"]

MAX_START_TRIES = 100
"""Worlds a reset draws at most before it gives up: a world whose placement faults, loses
contact or is sensed as a grasp at once is redrawn (and counted in ``faults``)."""


class MujocoCRMEnv(gym.Env[dict[str, Any], np.int64]):
    """A two-fingertip MuJoCo hand grasping an unseen object on a table by CRMs.

    ## Description
    As [`CRMGraspEnv`][crmgrasp.envs.single.CRMGraspEnv], but each step is one CRM executed
    as a real motion on the MuJoCo stand-in
    ([`MujocoSteps`][crmgrasp.hardware.mujoco.steps.MujocoSteps]: the planar hand for a
    planar task, the spatial one for a spatial task), with its sensor model (bias, drift,
    white noise, tare, averaging). Each reset draws a world from the task (the object, for
    a family task, and a start) and places the object free on the table.

    ## Action Space
    ``Discrete(len(task.actions))``: action ``i`` executes ``task.actions[i]``.

    ## Observation Space
    The contact model's observations of the *sensed* contacts and the error flag, as in
    [`CRMGraspEnv`][crmgrasp.envs.single.CRMGraspEnv] (``rho``, ``m_a``, ``m_b``, ``error``).

    ## Rewards
    -1 per CRM; ``task.grasp_reward`` for the CRM after which the sensed contacts are a
    grasp; ``-1 - task.error_cost`` for a CRM that errs or faults.

    ## Episode End
    ``terminated`` when the *sensed* configuration is a grasp (all the robot can check);
    ``truncated`` after ``task.max_steps`` CRMs, or at once after a physics fault or a lost
    contact (``info["fault"]`` names it). ``info["success"]``: the *true* configuration,
    from MuJoCo's contacts, is a grasp (``info["min_friction"]``: its least friction).

    ## Arguments
    ``task``: a [`Task`][crmgrasp.tasks.Task] or a registered task name; ``params``: the
    stand-in's [`PhysicsParams`][crmgrasp.hardware.mujoco.model.PhysicsParams];
    ``palm_tolerance_deg``: the fingertips' palm tolerance, degrees.

    ## Version History
    * v0: initial version.
    """

    metadata = {"render_modes": []}  # noqa: RUF012 - Gymnasium's convention

    def __init__(
        self, task: Task | str = "paper-box", params: PhysicsParams | None = None, palm_tolerance_deg: float = 10.0
    ) -> None:
        self.task = make_task(task) if isinstance(task, str) else task
        if not isinstance(self.task, Task):
            raise CrmgraspError(f"task must be a Task or a registered name, got {task!r}")
        self.steps = MujocoSteps(self.task, params, palm_tolerance_deg)
        self.action_space = spaces.Discrete(len(self.task.actions))
        self.observation_space = observation_space(self.task.model)
        bounds = self.task.model.observation_bounds()
        self._clip = [(name, *bounds[name]) for name in self.task.model.observation_names]
        self._state: SimState | None = None

    def _emit(self, res: OneStep) -> tuple[dict[str, Any], dict[str, Any]]:
        self._state = res.state
        info = {
            "obs_index": res.obs_index,
            "min_friction": res.min_friction,
            "success": bool(self.task.grasped(res.min_friction)),
            "steps": res.state.steps,
            "fault": self.steps.fault,
        }
        return space_observation(self._clip, res), info

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[dict[str, Any], dict[str, Any]]:
        """Start an episode in a world drawn from the task, or at ``options={"config":
        Config}`` (``{"world": World}`` on a family task)."""
        super().reset(seed=seed)
        check_reset_options(options)
        rng = self.np_random
        for _ in range(MAX_START_TRIES):
            if options and "world" in options:
                config = world_config(self.task, options["world"])
                self.steps.use(options["world"].task)
            elif options and "config" in options:
                config = self.steps.instance.check_config(options["config"], "options['config']")
            else:
                config = self.steps.sample_start(rng)
            res = self.steps.begin(config, rng)
            if not (res.terminated or res.truncated):
                return self._emit(res)
            if options and ("world" in options or "config" in options):
                break
        raise CrmgraspError(f"no usable start on the MuJoCo hand ({dict(self.steps.faults) or 'sensed as a grasp'})")

    def step(self, action: Any) -> tuple[dict[str, Any], float, bool, bool, dict[str, Any]]:
        """Execute the CRM ``task.actions[action]`` on the MuJoCo hand and sense."""
        if self._state is None:
            raise CrmgraspError("call reset() before step()")
        n = len(self.task.actions)
        if not isinstance(action, (int, np.integer)) or not 0 <= int(action) < n:
            raise CrmgraspError(f"action must be an integer in [0, {n}), got {action!r}")
        res = self.steps.step_one(self._state, int(action), self.np_random)
        obs, info = self._emit(res)
        if res.terminated or res.truncated:
            self._state = None
        return obs, float(res.reward), bool(res.terminated), bool(res.truncated), info

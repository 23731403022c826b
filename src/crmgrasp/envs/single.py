"""Gymnasium environments: ``CRMGraspEnv`` for any task, and the k-order history wrapper.

``crmgrasp/PaperBox-v0`` is registered with `gymnasium.register` when
``crmgrasp`` is imported.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from crmgrasp._validation import CrmgraspError, boolean, optional_seed, shown
from crmgrasp.kernels import Kernel, kernel_for
from crmgrasp.model.contact_model import ContactModel
from crmgrasp.model.contacts import Config
from crmgrasp.model.hand import Error
from crmgrasp.model.history import KOrderEncoder
from crmgrasp.sim import OneStep, SimState
from crmgrasp.tasks import Task, World, as_task

__all__ = [
    "CRMGraspEnv",
    "KOrderHistory",
    "ENV_ID",
    "FAMILY_ENVS",
    "SPATIAL_ENVS",
    "CONTINUOUS_ENVS",
    "observation_space",
    "space_observation",
    "MUJOCO_ENVS",
    "RESET_OPTIONS",
    "check_reset_options",
    "world_config",
]

ENV_ID = "crmgrasp/PaperBox-v0"
_empty = np.empty
_FIRST_BLOCK, _MAX_BLOCK = 16, 1024


RESET_OPTIONS = ("config", "world")
"""The keys ``reset(options=...)`` takes: a start configuration or, on a family task, a world."""


def check_reset_options(options: Any) -> None:
    """A one-line error unless ``options`` is ``None`` or a dict of at most one of
    [`RESET_OPTIONS`][]."""
    if options is None:
        return
    if not isinstance(options, dict):
        raise CrmgraspError(f"reset options must be a dict, got {shown(options)}")
    unknown = sorted(map(str, set(options) - set(RESET_OPTIONS)))
    if unknown:
        raise CrmgraspError(f"unknown reset option(s) {', '.join(unknown)}; known: {', '.join(RESET_OPTIONS)}")
    if len(options) > 1:
        raise CrmgraspError("reset takes options['config'] or options['world'], not both")


def world_config(task: Task, world: Any) -> Any:
    """The start configuration of ``world`` given as ``options['world']`` to an environment of the
    family task ``task``, checked: a [`World`][crmgrasp.tasks.World] on one object whose CRMs,
    hand and bins are the task's (they make the environment's spaces), its configuration on
    that object (one-line errors)."""
    if task.family is None:
        raise CrmgraspError("options['world'] needs a family task; use options['config']")
    if not isinstance(world, World) or not isinstance(world.task, Task) or world.task.family is not None:
        raise CrmgraspError(f"options['world'] must be a World(task on one object, config), got {world!r}")
    t = world.task
    if t.actions != task.actions or t.hand != task.hand or t.discretizer != task.discretizer:
        raise CrmgraspError(
            f"options['world'] is a world of task {t.name!r}, whose CRMs, hand or bins are not task "
            f"{task.name!r}'s: draw it from the environment's task"
        )
    return t.check_config(world.config, "options['world'].config")


def observation_space(model: ContactModel) -> spaces.Dict:
    """One environment's observation space: each of the contact model's observations in
    its bounds (``rho`` in ``[0, 4]``, the moments within twice the aperture, metres), and
    the error flag."""
    boxes: dict[str, spaces.Space[Any]] = {
        name: spaces.Box(low, high, shape=(1,), dtype=np.float64)
        for name, (low, high) in model.observation_bounds().items()
    }
    return spaces.Dict({**boxes, "error": spaces.Discrete(len(Error))})


def space_observation(clip: list[tuple[str, float, float]], res: OneStep) -> dict[str, Any]:
    """A step's observation as an [`observation_space`][crmgrasp.envs.single.observation_space]
    value: each ``(name, low, high)`` of ``clip`` (the model's order) clipped into its box,
    and the error flag."""
    obs: dict[str, Any] = {}
    for (name, low, high), v in zip(clip, res.observation):
        if not (low <= v <= high):
            v = low if v < low else high
        box = _empty(1)  # cheaper than np.array([v])
        box[0] = v
        obs[name] = box
    obs["error"] = int(res.error)
    return obs


class CRMGraspEnv(gym.Env[dict[str, Any], np.int64]):
    """A two-contact hand grasping an unseen planar object by CRMs (Platt).

    ## Description
    The hand starts touching the object (the task's start sampler) and may only
    execute the task's CRMs. After each CRM it senses force-derived quantities and
    an error flag. The goal is a grasp in as few CRMs as possible.

    ## Action Space
    ``Discrete(len(task.actions))``: action ``i`` executes ``task.actions[i]``. For
    paper-box: 0 = C1 (a,b,0), 1 = C2 (b,a,0), 2 = C3 (a,a,+0.08), 3 = C4 (b,b,-0.08).

    ## Observation Space
    A ``Dict``, computed from the sensed contacts ([docs/model.md section 4][model-4]):

    | key | meaning | min | max |
    | --- | --- | --- | --- |
    | ``rho`` | squared frictionless force residual ``|n_a + n_b|^2`` | 0 | 4 |
    | ``m_a`` | frictionless moment about contact a, m | -2A | 2A |
    | ``m_b`` | frictionless moment about contact b, m | -2A | 2A |
    | ``error`` | error of the last CRM: 0 none, 1 aperture, 2 palm | 0 | 2 |

    (A is the hand aperture; sensed values are clipped into the box.) ``info``
    carries ``obs_index`` (the task's discretized observation, 24 values for
    paper-box), ``config`` (the true configuration), ``min_friction`` (its least
    friction; not with ``exact_friction=False``) and ``steps``.

    ## Rewards
    -1 per CRM.

    ## Starting State
    Drawn by the task's sampler from ``self.np_random`` (paper-box: a random corner,
    one contact uniform on each side meeting there, a fair coin for the labels,
    resampled until feasible and not a grasp).

    ## Episode End
    ``terminated`` when the true configuration is a grasp (``min_friction <=
    mu_goal``, 0.05 for paper-box); ``truncated`` after ``task.max_steps`` CRMs (10).

    ## Arguments
    ``task``: a [`Task`][crmgrasp.tasks.Task] or a registered task name;
    ``render_mode``: ``None`` or ``"rgb_array"``; ``backend``: ``"auto"``,
    ``"numba"`` or ``"reference"`` ([`crmgrasp.kernels.kernel_for`][]; every
    backend gives the same episodes); ``exact_friction``: true (the default) to report each
    configuration's least friction in ``info``; false to have the step only decide whether
    the configuration is a grasp (the same observations, rewards and episode ends), which
    on a tripod stops the least friction's search as soon as that is decided
    (``kernel_for(..., friction="decided")``), and ``info`` then has no ``min_friction``.

    ## Version History
    * v0: initial version (docs/model.md).
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 2}  # noqa: RUF012 - Gymnasium's convention

    def __init__(
        self,
        task: Task | str = "paper-box",
        render_mode: str | None = None,
        backend: str = "auto",
        exact_friction: bool = True,
    ) -> None:
        self.task = as_task(task, "CRMGraspEnv")
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise CrmgraspError(f"render_mode must be None or 'rgb_array', got {render_mode!r}")
        self.render_mode = render_mode
        self.exact_friction = boolean(exact_friction, "exact_friction")
        self.kernel: Kernel = kernel_for(self.task, backend, "exact" if exact_friction else "decided")
        self.action_space = spaces.Discrete(len(self.task.actions))
        self._n_actions = len(self.task.actions)
        self.observation_space = observation_space(self.task.model)
        self._clip = [(name, *self.kernel.bounds[name]) for name in self.task.model.observation_names]
        self._state: SimState | None = None
        self._last: tuple[SimState, Any] | None = None
        self._starts: list[tuple[float, ...]] = []
        self._next, self._block = 0, _FIRST_BLOCK

    def _emit(self, res: OneStep) -> tuple[dict[str, Any], dict[str, Any]]:
        """The observation (clipped into the space) and ``info`` of a kernel's result."""
        self._state = res.state
        obs = space_observation(self._clip, res)
        info = {
            "obs_index": res.obs_index,
            "config": res.state.config,
            "min_friction": res.min_friction,
            "steps": res.state.steps,
        }
        if not self.exact_friction:  # then only a friction that decides the grasp
            del info["min_friction"]
        return obs, info

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[dict[str, Any], dict[str, Any]]:
        """Start an episode. ``options={"config": Config}`` starts from a given
        configuration; on a family task, ``options={"world": World}`` from a given
        object and configuration (a family draws the object of each episode)."""
        super().reset(seed=optional_seed(seed))
        self._last = None
        check_reset_options(options)
        if options and "world" in options:
            cfg = self._use_world(options["world"])
        elif options and "config" in options:
            cfg = self.scene_task.check_config(options["config"], "options['config']")
        elif self.task.family is not None:
            cfg = self.kernel.sample_start(self.np_random)
        else:
            if seed is not None:
                self._starts, self._next, self._block = [], 0, _FIRST_BLOCK
            cfg = self._next_start()
        return self._emit(self.kernel.begin(cfg, self.np_random))

    def step(self, action: Any) -> tuple[dict[str, Any], float, bool, bool, dict[str, Any]]:
        """Execute the CRM ``task.actions[action]`` ([`crmgrasp.kernels.Kernel.step_one`][],
        the kernel's form of [`crmgrasp.sim.step`][])."""
        if self._state is None:
            raise CrmgraspError("call reset() before step()")
        if type(action) is not int or not 0 <= action < self._n_actions:
            action = self.task.action_index(action)
        self._last = (self._state, action)
        res = self.kernel.step_one(self._state, action, self.np_random)
        obs, info = self._emit(res)
        return obs, res.reward, res.terminated, res.truncated, info

    def crm_of(self, action: Any) -> Any:
        """The CRM of a stepped action (an index into the task's CRMs)."""
        return self.task.actions[action]

    @property
    def scene_task(self) -> Task:
        """The task on this episode's object (the task itself without a family)."""
        return self.kernel.instance

    def _use_world(self, world: Any) -> Config:
        cfg = world_config(self.task, world)
        self.kernel.use(world.task)
        return cfg

    def _next_start(self) -> Config:
        """The next start, from blocks drawn by the kernel's vectorised sampler: 16 after
        each seeding, doubling up to 1,024 (starts are i.i.d., so drawing them in
        blocks changes cost, not distribution; a seeded reset stays cheap)."""
        if self._next >= len(self._starts):
            self._starts, self._next = self.kernel.sample_starts(self.np_random, self._block).tolist(), 0
            self._block = min(2 * self._block, _MAX_BLOCK)
        row = self._starts[self._next]
        self._next += 1
        return self.kernel.trusted(self.kernel.config_of(row))  # a row of the kernel's own starts

    def render(self) -> np.ndarray | None:  # type: ignore[override]
        """An RGB image of the scene (``render_mode="rgb_array"``), else ``None``."""
        if self.render_mode != "rgb_array" or self._state is None:
            return None
        from matplotlib.backends.backend_agg import FigureCanvasAgg

        from crmgrasp.plotting import scene_figure

        n = self._state.steps
        title = f"{self.task.name}: after {n} CRM{'' if n == 1 else 's'}"
        t = self.scene_task
        if self._last is None:
            fig = scene_figure(t.obj, t.hand, self._state.config, None, title)
        else:
            prev, action = self._last
            outcome = t.execute(prev.config, self.crm_of(action), prev.sensed)
            fig = scene_figure(t.obj, t.hand, prev.config, outcome, f"{title} ({outcome.error.name.lower()})")
        canvas = FigureCanvasAgg(fig)
        canvas.draw()
        return np.asarray(canvas.buffer_rgba())[:, :, :3].copy()


class KOrderHistory(gym.Wrapper[int, np.int64, dict[str, Any], np.int64], gym.utils.RecordConstructorArgs):
    """Replace the observation by the k-order history state of [docs/model.md section 6][model-6].

    The observation becomes ``Discrete(encoder.size)``: the integer code of
    ``(o_t, a_{t-1}, o_{t-1}, ..., a_{t-k})`` over the task's discretized
    observations (``info["obs_index"]``), padded at the episode start. ``k = 0``
    is the current discretized observation alone. It records ``k``, so that a spec of the
    wrapped environment recreates it (Gymnasium's ``check_env`` and ``env.spec.make``).
    """

    def __init__(self, env: gym.Env, k: int = 2) -> None:
        if not isinstance(env, gym.Env) or not isinstance(getattr(env.unwrapped, "task", None), Task):
            raise CrmgraspError(f"KOrderHistory wraps a crmgrasp environment, got {shown(env)}")
        gym.utils.RecordConstructorArgs.__init__(self, k=k)
        gym.Wrapper.__init__(self, env)
        task = env.unwrapped.task  # type: ignore[attr-defined]
        self.encoder = KOrderEncoder(task.discretizer.size, len(task.actions), k)
        self.observation_space = spaces.Discrete(self.encoder.size)  # type: ignore[assignment]
        self._history: tuple[int, ...] = ()

    def reset(self, **kwargs: Any) -> tuple[int, dict[str, Any]]:  # type: ignore[override]
        _, info = self.env.reset(**kwargs)
        self._history = self.encoder.start(info["obs_index"])
        info["history"] = self._history
        return self.encoder.encode(self._history), info

    def step(self, action: Any) -> tuple[int, float, bool, bool, dict[str, Any]]:  # type: ignore[override]
        _, reward, terminated, truncated, info = self.env.step(action)
        self._history = self.encoder.push(self._history, int(action), info["obs_index"])
        info["history"] = self._history
        return self.encoder.encode(self._history), float(reward), terminated, truncated, info


SPATIAL_ENVS = {
    "crmgrasp/Box3D-v0": "box-3d",
    "crmgrasp/Cup3D-v0": "cup-3d",
    "crmgrasp/OpenCup3D-v0": "open-cup-3d",
    "crmgrasp/Box3D3F-v0": "box-3d-3f",
    "crmgrasp/Cup3D3F-v0": "cup-3d-3f",
}
"""Registered spatial environments (docs/model-3d.md): id -> task name (each episode draws its solid)."""

FAMILY_ENVS = {
    "crmgrasp/BoxFamily-v0": "box-family",
    "crmgrasp/CupFamily-v0": "cup-family",
    "crmgrasp/PolygonFamily-v0": "polygon-family",
    "crmgrasp/UHandle-v0": "u-handle",
    "crmgrasp/LShape-v0": "l-shape",
    "crmgrasp/Mixed-v0": "mixed",
    "crmgrasp/Triangles-v0": "triangles",
    "crmgrasp/Triangles3F-v0": "triangles-3f",
    "crmgrasp/OddPolygons-v0": "odd-polygons",
    "crmgrasp/OddPolygons3F-v0": "odd-polygons-3f",
    "crmgrasp/BoxFamily3F-v0": "box-family-3f",
    "crmgrasp/CupFamily3F-v0": "cup-family-3f",
}
"""Registered family environments: id -> task name (each episode draws its object; the
``3F`` ones with a three-finger hand)."""


CONTINUOUS_ENVS = {
    "crmgrasp/PaperBoxContinuous-v0": "paper-box",
    "crmgrasp/BoxFamilyContinuous-v0": "box-family",
    "crmgrasp/UHandleContinuous-v0": "u-handle",
    "crmgrasp/NotchOrBoxContinuous-v0": "notch-or-box",
    "crmgrasp/Cup3DContinuous-v0": "cup-3d",
}
"""Registered environments with the continuous action space
([`ContinuousCRMEnv`][crmgrasp.envs.continuous.ContinuousCRMEnv]): id -> task name."""


MUJOCO_ENVS = {
    "crmgrasp/PaperBoxMujoco-v0": "paper-box",
    "crmgrasp/BoxFamilyMujoco-v0": "box-family",
    "crmgrasp/Cup3DMujoco-v0": "cup-3d",
    "crmgrasp/Box3DMujoco-v0": "box-3d",
}
"""Registered environments whose steps are CRMs of the MuJoCo stand-in hand
(`crmgrasp.hardware.mujoco.env.MujocoCRMEnv`, extra ``crmgrasp[mujoco]``): id -> task name."""


def register() -> None:
    """Register ``crmgrasp/PaperBox-v0``, the [`FAMILY_ENVS`][], the [`SPATIAL_ENVS`][], the
    [`CONTINUOUS_ENVS`][] and the [`MUJOCO_ENVS`][] (idempotent). Every registered task cuts episodes at 10 CRMs (its
    ``max_steps``: the env cuts them there itself)."""
    kinds = (
        ({ENV_ID: "paper-box", **FAMILY_ENVS, **SPATIAL_ENVS}, "single:CRMGraspEnv", "vector:vector_env"),
        (CONTINUOUS_ENVS, "continuous:ContinuousCRMEnv", "vector:continuous_vector_env"),
    )
    for table, entry, vector in kinds:
        for env_id, task in table.items():
            if env_id not in gym.registry:
                gym.register(
                    id=env_id,
                    entry_point=f"crmgrasp.envs.{entry}",
                    vector_entry_point=f"crmgrasp.envs.{vector}",
                    kwargs={"task": task},
                    max_episode_steps=10,
                )
    for env_id, task in MUJOCO_ENVS.items():  # the entry point is imported by gymnasium.make only
        if env_id not in gym.registry:
            gym.register(
                id=env_id,
                entry_point="crmgrasp.hardware.mujoco.env:MujocoCRMEnv",
                kwargs={"task": task},
                max_episode_steps=10,
            )


register()

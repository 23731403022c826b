"""Deep-RL peer: sb3-contrib's RecurrentPPO (an LSTM policy) on the continuous observation.

Needs the optional extra ``crmgrasp[deep]`` (torch, stable-baselines3, sb3-contrib);
this module imports them only when training or evaluating, and raises a one-line
`CrmgraspError` naming the extra when they are missing.

The policy sees what the tabular learners see before discretisation, as a float
vector: each of the contact model's observation quantities scaled by its bound
(``[rho / 4, m_a / (2A), m_b / (2A)]`` for two contacts, ``A`` the hand aperture, values
clipped as in [`CRMGraspEnv`][crmgrasp.envs.single.CRMGraspEnv]), then the error flag one-hot; the LSTM
carries the history that the k-order state spells out for the tabular learners.
Training runs ``n_envs`` environments in a ``DummyVecEnv`` with one torch thread
(deterministic for a seed on a given machine). The learning curve is the CRMs
of every finished training episode in completion order; greedy (deterministic)
checkpoints after each rollout use the same fixed starts as the tabular learners'
checkpoints ([`checkpoint_generators`][crmgrasp.agents.training.checkpoint_generators]).
"""

from __future__ import annotations

import hashlib
import importlib
import io
import json
import math
import os
import time
import zipfile
from collections.abc import Sequence
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from crmgrasp._validation import CrmgraspError, boolean, float_array, require_extra, shown
from crmgrasp.agents.training import checkpoint_generators, checkpoints_to_within
from crmgrasp.model.contacts import Config, Grip
from crmgrasp.model.hand import Error
from crmgrasp.sim import Percept, StepperRows, run_batch
from crmgrasp.tasks import Task, World, checked_task

__all__ = [
    "ContinuousObservation",
    "RecurrentPPOConfig",
    "DeepRun",
    "deep_available",
    "train_recurrent_ppo",
    "evaluate_recurrent",
    "RecurrentPolicy",
    "features",
    "bounds_of",
    "crm_of_action",
    "ALGORITHM_MODULES",
    "DeepAlgorithm",
    "DEEP_AGENTS",
    "make_model",
    "env_maker",
]

N_ERRORS = len(Error)


def features(values: Sequence[float], error: int, bounds: Sequence[tuple[float, float]]) -> np.ndarray:
    """The policy's input vector (float32, length ``len(bounds) + len(Error)``): each
    observation value clipped into its ``(low, high)`` and divided by ``max(-low, high)``
    (``rho / 4`` and ``m / (2A)`` for two contacts), then the error flag one-hot."""
    try:
        n = len(bounds)
        v = np.zeros(n + N_ERRORS, dtype=np.float32)
        for i, (x, (lo, hi)) in enumerate(zip(values, bounds, strict=True)):
            v[i] = min(max(x, lo), hi) / max(-lo, hi)
        if not 0 <= error < N_ERRORS:
            raise IndexError
        v[n + int(error)] = 1.0
    except (TypeError, ValueError, IndexError, OverflowError):  # the happy path pays no test
        raise CrmgraspError(
            f"features need one number per bound (low, high) and an error code in [0, {N_ERRORS}), "
            f"got {shown(values)}, {shown(error)}, {shown(bounds)}"
        ) from None
    return v


def bounds_of(task: Task) -> tuple[tuple[float, float], ...]:
    """The ``(low, high)`` of each of the task's observation quantities, in order (the
    model's [`observation_bounds`][crmgrasp.model.contact_model.ContactModel.observation_bounds])."""
    return tuple(checked_task(task, "bounds_of").model.observation_bounds().values())


class ContinuousObservation(gym.ObservationWrapper, gym.utils.RecordConstructorArgs):
    """Flattens [`CRMGraspEnv`][crmgrasp.envs.single.CRMGraspEnv]'s ``Dict`` observation into [`features`][]."""

    def __init__(self, env: gym.Env) -> None:
        gym.utils.RecordConstructorArgs.__init__(self)
        gym.ObservationWrapper.__init__(self, env)
        task = env.unwrapped.task  # type: ignore[attr-defined]
        self.names, self.bounds = task.model.observation_names, bounds_of(task)
        self.observation_space = spaces.Box(-1.0, 1.0, (len(self.names) + N_ERRORS,), np.float32)

    def observation(self, observation: dict[str, Any]) -> np.ndarray:
        o = observation
        return features([float(o[n][0]) for n in self.names], int(o["error"]), self.bounds)


@dataclass(frozen=True)
class RecurrentPPOConfig:
    """RecurrentPPO settings (small networks: the observation has 6 numbers)."""

    total_steps: int = 60_000
    """Environment steps (CRMs) of training."""
    n_envs: int = 8
    n_steps: int = 64
    """Steps per environment per rollout (a rollout is ``n_envs * n_steps`` CRMs)."""
    n_epochs: int = 4
    learning_rate: float = 1e-3
    gamma: float = 0.9
    """The paper's discount."""
    ent_coef: float = 0.01
    lstm_hidden: int = 32
    hidden: int = 32
    checkpoint_episodes: int = 100
    """Fixed starts of each greedy checkpoint (0: no checkpoints)."""
    continuous: bool = False
    """Act in the task's continuous action space (a contact pair and a real offset, through
    [`FlatCRMAction`][crmgrasp.envs.continuous.FlatCRMAction]) instead of its CRMs."""

    def __post_init__(self) -> None:
        boolean(self.continuous, "RecurrentPPO continuous")
        for f in fields(self):
            if f.name == "continuous":
                continue
            v, low = getattr(self, f.name), 0 if f.name == "checkpoint_episodes" else 1e-300
            integral = f.type in ("int", int)
            if isinstance(v, bool) or not isinstance(v, int if integral else (int, float)) or not v >= low:
                need = "an integer" if integral else "a number"
                raise CrmgraspError(f"RecurrentPPO {f.name} must be {need} {'>= 0' if low == 0 else '> 0'}, got {v!r}")
        if self.gamma > 1:
            raise CrmgraspError(f"RecurrentPPO gamma must be <= 1, got {self.gamma}")


@dataclass
class DeepRun:
    """A trained RecurrentPPO model, its curve, checkpoints and wall time."""

    model: Any
    episode_steps: np.ndarray
    """CRMs of every finished training episode, in completion order."""
    checkpoints: np.ndarray
    """Training episodes completed at each greedy checkpoint."""
    checkpoint_steps: np.ndarray
    """Greedy mean CRMs on the fixed checkpoint starts."""
    seconds: float

    def greedy_episodes_to_within(self, reference: float, factor: float = 1.05) -> int | None:
        """First checkpoint (in training episodes) from which the greedy policy stays within ``factor``."""
        return checkpoints_to_within(self.checkpoints, self.checkpoint_steps, reference, factor)


ALGORITHM_MODULES = {"RecurrentPPO": "sb3_contrib", "PPO": "stable_baselines3", "SAC": "stable_baselines3"}
"""The stable-baselines3 algorithms a deep policy file may hold, and the module of each."""


@dataclass(frozen=True)
class DeepAlgorithm:
    """A deep learner of ``crmgrasp learn``: its stable-baselines3 class and policy network,
    and whether it can act in a task's discrete CRMs."""

    algorithm: str
    policy: str
    discrete: bool
    description: str


DEEP_AGENTS: dict[str, DeepAlgorithm] = {
    "recurrent-ppo": DeepAlgorithm("RecurrentPPO", "MlpLstmPolicy", True, "RecurrentPPO, an LSTM over the episode"),
    "ppo": DeepAlgorithm("PPO", "MlpPolicy", True, "PPO, an MLP on the current observation"),
    "sac": DeepAlgorithm("SAC", "MlpPolicy", False, "SAC, an MLP on the current observation, continuous actions"),
}
"""Deep learner name -> algorithm (each in [`ALGORITHM_MODULES`][crmgrasp.agents.deep.ALGORITHM_MODULES])."""

DEEP_FORMAT = "crmgrasp-deep-policy"
_META = "crmgrasp.json"  # our member of the model's zip archive
MAX_MODEL_BYTES = 256 * 2**20
"""Largest deep policy file read (256 MiB)."""


def _member(name: str) -> zipfile.ZipInfo:
    """A compressed zip member dated 1980-01-01 (the earliest date zip stores)."""
    info = zipfile.ZipInfo(name, date_time=(1980, 1, 1, 0, 0, 0))
    info.compress_type = zipfile.ZIP_DEFLATED
    return info


def _model_digest(archive: zipfile.ZipFile) -> str:
    """SHA-256 over the names and contents of the model's members (ours excluded)."""
    h = hashlib.sha256()
    for name in sorted(n for n in archive.namelist() if n != _META):
        h.update(name.encode() + b"\0" + archive.read(name) + b"\0")
    return h.hexdigest()


class RecurrentPolicy:
    """A trained deep model (RecurrentPPO, or PPO and SAC from ``crmgrasp learn``) with the
    task it was trained on.

    Saved as the model's own zip archive (stable-baselines3 format) with one more
    member, ``crmgrasp.json``: format, version, the task (task-file schema) and a
    SHA-256 of the model's members, so the file loads by path alone and an edited or
    truncated file is refused. Loading runs stable-baselines3's loader, which unpickles
    parts of the archive: load deep policies only from sources you trust.
    """

    def __init__(self, model: Any, task: Task) -> None:
        self.model = model
        self.task = task
        self.continuous = isinstance(model.action_space, spaces.Box)
        """Whether the model acts in the continuous action space (it was trained so)."""

    def predict(
        self, observations: Sequence[Any], actions: Sequence[int] = (), rng: np.random.Generator | None = None
    ) -> Any:
        """The deterministic action after an episode's history (observations: the model's
        values then the error flag, one more than ``actions``; the LSTM reads the
        observations from the episode's start; ``actions`` are checked, ``rng`` unused): an
        index into the task's CRMs, or a CRM of its continuous action space."""
        from crmgrasp.agents.policy import observation_indices

        if self.continuous:  # the actions taken are CRMs of the task's continuous action space
            for a in actions:
                self.task.model.check_crm(a)
            actions = [0] * len(actions)
        observation_indices(self.task, [tuple(o) for o in observations], actions)  # checks
        state, action, bounds = None, None, bounds_of(self.task)
        for i, o in enumerate(observations):
            f = features([float(v) for v in o[:-1]], int(o[-1]), bounds)
            action, state = self.model.predict(
                f[None], state=state, episode_start=np.array([i == 0]), deterministic=True
            )
        return crm_of_action(self.task, np.asarray(action).ravel())

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write the model and its task atomically to ``path`` (a .zip)."""
        from crmgrasp._io import atomic_write_bytes

        return atomic_write_bytes(path, self.to_bytes())

    def to_bytes(self) -> bytes:
        """The policy file's bytes: the model's archive with ``crmgrasp.json`` added."""
        from crmgrasp._io import dumps_json
        from crmgrasp.tasks import task_to_dict

        buf = io.BytesIO()
        self.model.save(buf)
        out = io.BytesIO()
        with zipfile.ZipFile(io.BytesIO(buf.getvalue())) as src, zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as dst:
            digest = _model_digest(src)
            for name in src.namelist():  # fixed dates: the same model gives the same file, byte for byte
                dst.writestr(_member(name), src.read(name))
            meta = {
                "format": DEEP_FORMAT,
                "version": 1,
                "algorithm": type(self.model).__name__,
                "task": self.task.name,
                "task_spec": task_to_dict(self.task),
                "model_sha256": digest,
            }
            dst.writestr(_member(_META), dumps_json(meta))
        return out.getvalue()

    @classmethod
    def load(cls, path: str | os.PathLike[str], task: Task | None = None) -> RecurrentPolicy:
        """Read a saved deep policy (one-line errors for a damaged file or another task)."""
        from crmgrasp._io import read_bounded
        from crmgrasp.agents.policy_file import first_difference, policy_task
        from crmgrasp.tasks import task_to_dict

        where = f"policy file {str(path)!r}"
        data = read_bounded(path, MAX_MODEL_BYTES, "policy file")
        try:
            with zipfile.ZipFile(io.BytesIO(data)) as archive:
                meta = json.loads(archive.read(_META))
                digest = _model_digest(archive)
        except KeyError:
            raise CrmgraspError(f"{where} is a zip archive but not a crmgrasp deep policy") from None
        except (zipfile.BadZipFile, ValueError, OSError, RecursionError) as exc:
            raise CrmgraspError(f"{where} is damaged ({exc})") from None
        if not isinstance(meta, dict) or meta.get("format") != DEEP_FORMAT or meta.get("version") != 1:
            raise CrmgraspError(f"{where} is not a crmgrasp deep policy (version 1)")
        if meta.get("model_sha256") != digest:
            raise CrmgraspError(f"{where}: the checksum does not match: the file was edited or damaged")
        own = policy_task(meta, where)
        if task is not None:
            diff = first_difference(task_to_dict(own), task_to_dict(task))
            if diff is not None:
                raise CrmgraspError(f"{where} was made for another task than {task.name!r} (it differs in {diff})")
        algorithm = meta.get("algorithm")
        if algorithm not in ALGORITHM_MODULES:
            known = ", ".join(ALGORITHM_MODULES)
            raise CrmgraspError(f"{where} names an unknown algorithm {algorithm!r}; known: {known}")
        _modules()
        try:
            model = getattr(importlib.import_module(ALGORITHM_MODULES[algorithm]), algorithm).load(
                io.BytesIO(data), device="cpu"
            )
        except Exception as exc:  # stable-baselines3's own errors, in one line
            raise CrmgraspError(f"{where}: the model does not load ({type(exc).__name__}: {exc})") from None
        return cls(model, task or own)


def crm_of_action(task: Task, action: Any) -> Any:
    """The task's CRM that a model's action names: ``task.actions[a]`` for an integer, the
    CRM of a flat continuous action ([`crmgrasp.envs.continuous.flat_action`][]) for a vector."""
    u = float_array(action, "a model's action").ravel()
    if u.size == 1:
        a = float(u[0])
        if not (math.isfinite(a) and a == int(a)):
            raise CrmgraspError(f"a model's discrete action must be an integer, got {a!r}")
        return int(a)
    from crmgrasp.envs.continuous import flat_action

    ranges = task.crm_ranges
    pair, r = flat_action(ranges, np.clip(u, -1.0, 1.0))  # the Gaussian policy's mean may leave the box
    return task.model.range_crm(ranges[pair], r.tolist())


def _modules() -> tuple[Any, Any, Any, Any]:
    modules = ("torch", "sb3_contrib", "stable_baselines3.common.vec_env", "stable_baselines3.common.callbacks")
    return require_extra("deep", "the deep-RL peer", *modules)  # type: ignore[return-value]


def deep_available() -> bool:
    """True if torch, stable-baselines3 and sb3-contrib import."""
    try:
        _modules()
    except CrmgraspError:
        return False
    return True


def evaluate_recurrent(
    model: Any, task: Task, starts: Sequence[Config | Grip | World], rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray]:
    """Run the deterministic LSTM policy from every start (a configuration, or a world of
    a family task: its object and configuration), all episodes batched
    ([`crmgrasp.sim.run_batch`][], each episode stepped by [`crmgrasp.sim.step`][]).

    Returns CRMs per episode and success flags. ``rng`` drives sensing noise (if the task has any).
    """
    n = len(starts)
    rows = StepperRows(task, starts, rng)
    run_batch(rows, _ModelRows(model, rows.tasks, bounds_of(task)), n, lambda row, last: last is None)
    episodes = [rows.episode(r) for r in range(n)]
    return np.array([e.steps for e in episodes], dtype=np.int64), np.array([e.success for e in episodes], dtype=bool)


class _ModelRows:
    """A deep model as a [`BatchPolicy`][crmgrasp.sim.BatchPolicy] over one episode per row:
    each step, one deterministic ``predict`` over every row's latest observation (rows
    whose episode ended keep their last one, so the batch, and with it the model's
    floats, stays the same size), the LSTM state carried between calls."""

    def __init__(self, model: Any, tasks: Sequence[Task], bounds: Any) -> None:
        self.model, self.tasks, self.bounds = model, tasks, bounds
        self.obs: np.ndarray | None = None
        self.first = np.ones(len(tasks), dtype=bool)
        self.lstm: Any = None

    def begin(self, row: int, first: Percept) -> None:
        self.tell(row, first)

    def act(self, rows: list[int]) -> list[Any]:
        actions, self.lstm = self.model.predict(self.obs, state=self.lstm, episode_start=self.first, deterministic=True)
        self.first[:] = False
        return [crm_of_action(self.tasks[r], actions[r]) for r in rows]

    def tell(self, row: int, percept: Percept) -> None:
        f = features(percept.observation, int(percept.error), self.bounds)
        if self.obs is None:
            self.obs = np.zeros((len(self.tasks), len(f)), dtype=f.dtype)
        self.obs[row] = f


def train_recurrent_ppo(
    task: Task, seed: int, config: RecurrentPPOConfig = RecurrentPPOConfig(), *, backend: str = "auto"
) -> DeepRun:
    """Train RecurrentPPO on ``task`` from ``seed`` (environments on the kernel ``backend``);
    return the model, curve and checkpoints."""
    torch, _, vec, callbacks = _modules()
    c = config
    starts_rng, _ = checkpoint_generators(seed)
    ckpt_starts = [task.sample_world(starts_rng) for _ in range(c.checkpoint_episodes)]  # the starts' stream
    lengths: list[int] = []
    ckpts: list[tuple[int, float]] = []

    class Track(callbacks.BaseCallback):  # type: ignore[misc, name-defined]
        def _on_step(self) -> bool:
            for done, info in zip(self.locals["dones"], self.locals["infos"]):
                if done:
                    lengths.append(int(info["steps"]))
            return True

        def _on_rollout_end(self) -> None:
            if ckpt_starts:
                rng = checkpoint_generators(seed)[1]  # the same noise stream at every checkpoint
                ckpts.append((len(lengths), float(evaluate_recurrent(self.model, task, ckpt_starts, rng)[0].mean())))

    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        env = vec.DummyVecEnv([env_maker(task, c, backend)] * c.n_envs)
        model = make_model("recurrent-ppo", env, c, seed)
        t0 = time.perf_counter()
        model.learn(c.total_steps, callback=Track())
        seconds = time.perf_counter() - t0
    finally:
        torch.set_num_threads(threads)
    cp = np.array([e for e, _ in ckpts], dtype=np.int64)
    cv = np.array([v for _, v in ckpts], dtype=float)
    return DeepRun(model, np.array(lengths, dtype=float), cp, cv, seconds)


def make_model(name: str, env: Any, c: RecurrentPPOConfig, seed: int, budget: int = 0) -> Any:
    """The untrained stable-baselines3 model of deep learner ``name`` on ``env`` (``budget``:
    SAC's replay buffer, in transitions). Its logger writes nowhere: stable-baselines3's
    default makes a folder under the system's temporary directory for every model."""
    algo = DEEP_AGENTS[name]
    cls = getattr(importlib.import_module(ALGORITHM_MODULES[algo.algorithm]), algo.algorithm)
    common = {"learning_rate": c.learning_rate, "gamma": c.gamma, "seed": seed, "device": "cpu", "verbose": 0}
    if algo.algorithm == "SAC":
        arch = _mlp(c)
        replay = {"batch_size": 64, "learning_starts": c.n_steps, "buffer_size": budget}
        model = cls(algo.policy, env, policy_kwargs=arch, **replay, **common)
    else:
        ppo = {"n_steps": c.n_steps, "batch_size": max(1, c.n_steps * c.n_envs // 4), "n_epochs": c.n_epochs}
        recurrent = algo.algorithm == "RecurrentPPO"
        net: dict[str, Any] = {"lstm_hidden_size": c.lstm_hidden, "net_arch": [c.hidden]} if recurrent else _mlp(c)
        model = cls(algo.policy, env, ent_coef=c.ent_coef, policy_kwargs=net, **ppo, **common)
    model.set_logger(importlib.import_module("stable_baselines3.common.logger").Logger(None, []))
    return model


def _mlp(c: RecurrentPPOConfig) -> dict[str, Any]:
    """The MLP of PPO and SAC: two hidden layers of ``c.hidden`` units."""
    return {"net_arch": [c.hidden, c.hidden]}


def env_maker(task: Task, config: RecurrentPPOConfig, backend: str) -> Any:
    """A maker of one training environment: the task's CRMs, or its flat continuous actions."""
    from crmgrasp.envs.continuous import ContinuousCRMEnv, FlatCRMAction
    from crmgrasp.envs.single import CRMGraspEnv

    def make() -> gym.Env:
        if config.continuous:
            return ContinuousObservation(FlatCRMAction(ContinuousCRMEnv(task, backend=backend)))
        return ContinuousObservation(CRMGraspEnv(task, backend=backend))

    return make

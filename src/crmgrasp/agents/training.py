"""Training and evaluation loops on the pure task dynamics ([`crmgrasp.sim`][]).

Seeding: a run's seed feeds a `numpy.random.SeedSequence`; trial ``i`` gets
child ``i``, which spawns three generators: the environment's (starts and sensing),
the agent's (tie-breaking, exploration, planning) and the evaluation's. With the
environment stream separate, every learner sees the same start sequence for the
same seed (common random numbers).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numpy as np

from crmgrasp._progress import Progress
from crmgrasp._validation import CrmgraspError, boolean, finite, integer, positive, seed_value, shown
from crmgrasp.agents.backoff import BackoffVI
from crmgrasp.agents.base import Agent, LearnerPolicy
from crmgrasp.agents.baselines import FixedSequence, RandomAgent
from crmgrasp.agents.model_based import ModelVI
from crmgrasp.agents.peers import PSRL, UCBVI, EpisodicModel
from crmgrasp.agents.pooled import HistoryFrame, PooledVI
from crmgrasp.agents.refine import RefineVI
from crmgrasp.agents.symmetric import SymmetricAgent
from crmgrasp.agents.tabular import DynaQ, QLearning, Sarsa, SarsaLambda
from crmgrasp.kernels import kernel_for
from crmgrasp.model.contacts import Config, Grip
from crmgrasp.model.hand import Outcome
from crmgrasp.model.history import KOrderEncoder
from crmgrasp.sim import Stepper
from crmgrasp.sim import run_episode as sim_run_episode
from crmgrasp.tasks import Task, checked_task

__all__ = [
    "AGENTS",
    "make_agent",
    "build_agent",
    "parameter_defaults",
    "PRIOR_KEYS",
    "PRIOR_DEFAULTS",
    "takes_prior",
    "prior_settings",
    "encoder_for",
    "run_episode",
    "evaluate",
    "trial_generators",
    "TrialResult",
    "train_trials",
    "episodes_to_within",
    "checkpoints_to_within",
    "checkpoint_generators",
    "DEFAULT_CHECKPOINTS",
    "RolloutStep",
    "rollout",
]

AGENTS: dict[str, Callable[..., Agent]] = {
    "sarsa": Sarsa,
    "q": QLearning,
    "sarsa-lambda": SarsaLambda,
    "dyna-q": DynaQ,
    "model-vi": ModelVI,
    "pooled-vi": PooledVI,
    "backoff-vi": BackoffVI,
    "refine-vi": RefineVI,
    "psrl": PSRL,
    "ucbvi": UCBVI,
    "random": RandomAgent,
    "fixed": FixedSequence,
}
"""Agent name -> constructor ``(n_actions, **params)``."""


def make_agent(name: str, n_actions: int, **params: object) -> Agent:
    """Build a registered agent; unknown names or parameters give a one-line error."""
    try:
        cls = AGENTS[name]
    except (KeyError, TypeError):
        raise CrmgraspError(f"unknown agent {shown(name)}; known agents: {', '.join(AGENTS)}") from None
    accepted = agent_parameters(name)
    for key in params:
        if key not in accepted:
            takes = f"it takes {', '.join(accepted)}" if accepted else "it takes none"
            raise CrmgraspError(f"agent {name!r} has no parameter {key!r}; {takes}")
    return cls(n_actions, **params)


def agent_parameters(name: str) -> tuple[str, ...]:
    """The keyword parameters the registered agent ``name`` accepts (its constructor's and,
    through ``**kwargs``, its base classes')."""
    import inspect

    out: list[str] = []
    for klass in getattr(AGENTS[name], "__mro__", ()):
        init = klass.__dict__.get("__init__")
        if init is None:
            continue
        sig = inspect.signature(init).parameters.values()
        out += [p.name for p in sig if p.kind is p.POSITIONAL_OR_KEYWORD and p.name not in ("self", "n_actions")]
        out += [p.name for p in sig if p.kind is p.KEYWORD_ONLY]
        if not any(p.kind is p.VAR_KEYWORD for p in sig):
            break
    return tuple(dict.fromkeys(out))


def parameter_defaults(param: str) -> dict[str, object]:
    """The default of keyword parameter ``param`` of every registered agent that takes it
    (agent name -> default), read from the constructors; the prior's keys
    ([`PRIOR_KEYS`][]) are the model-based agents' ([`takes_prior`][]), with
    [`PRIOR_DEFAULTS`][]."""
    import inspect

    if param in PRIOR_DEFAULTS:
        return {name: PRIOR_DEFAULTS[param] for name in AGENTS if takes_prior(name)}
    out: dict[str, object] = {}
    for name, made in AGENTS.items():
        if param not in agent_parameters(name):
            continue
        for klass in getattr(made, "__mro__", ()):
            init = klass.__dict__.get("__init__")
            p = None if init is None else inspect.signature(init).parameters.get(param)
            if p is not None and p.default is not p.empty:
                out[name] = p.default
                break
    return out


def build_agent(task: Task, encoder: KOrderEncoder, name: str, params: dict[str, object] | None = None) -> Agent:
    """[`make_agent`][], wrapped in a `SymmetricAgent`
    when ``params`` has ``symmetric=True`` (the task must declare a symmetry).

    A learner that needs to know how its states are built (``pooled-vi``, the peers
    ``psrl`` and ``ucbvi``) or its task's offsets (``refine-vi``) is given its
    [`HistoryFrame`][crmgrasp.agents.pooled.HistoryFrame].

    ``prior_task`` (a task name, file or factory with the same CRMs and bins, e.g. an
    object family) gives a model-based agent (``model-vi``, ``pooled-vi``) a prior: the model one agent with the
    same settings learns there in ``prior_episodes`` episodes (seed ``prior_seed``), added
    as ``prior_weight`` pseudo-counts per pair (defaults: [`PRIOR_DEFAULTS`][])
    (`set_prior`). The prior is computed once
    per setting and reused by every trial."""
    if params is not None and not isinstance(params, dict):
        raise CrmgraspError(f"agent parameters must be a dict of name -> value, got {shown(params)}")
    p = dict(params or {})
    symmetric = boolean(p.pop("symmetric", False), "symmetric")
    prior = {key: p.pop(key) for key in PRIOR_KEYS if key in p}
    agent = make_agent(name, len(task.actions), **p)
    if prior and not isinstance(agent, ModelVI):
        known = ", ".join(n for n in AGENTS if takes_prior(n))
        raise CrmgraspError(f"prior_task needs a model-based agent ({known}), not {name!r}")
    wrapped = SymmetricAgent(agent, task, encoder) if symmetric else None  # type: ignore[arg-type]
    if isinstance(agent, (PooledVI, BackoffVI, EpisodicModel, RefineVI)):
        agent.bind(HistoryFrame(task, encoder, wrapped))
    if prior and isinstance(agent, ModelVI):
        model, weight = _prior(task, encoder.k, name, p, symmetric, prior)
        agent.set_prior(model, weight)
    return agent if wrapped is None else wrapped  # type: ignore[return-value]


PRIOR_KEYS = ("prior_task", "prior_episodes", "prior_weight", "prior_seed")
"""The parameters of [`build_agent`][] that give a model-based agent a prior."""


def takes_prior(name: str) -> bool:
    """Whether the registered agent ``name`` can start from a prior model (``model-vi``,
    ``pooled-vi``: the agents that keep outcome counts)."""
    made = AGENTS.get(name)
    return isinstance(made, type) and issubclass(made, ModelVI)


def prior_settings(params: dict[str, object]) -> dict[str, object] | None:
    """The prior a run's ``params`` ask for, every setting filled in from
    [`PRIOR_DEFAULTS`][] (``task``, ``episodes``, ``weight``, ``seed``), or None: what a
    run records and reports, so that its prior episodes are counted with its own."""
    if params.get("prior_task") is None:
        return None
    return {key.removeprefix("prior_"): params.get(key, PRIOR_DEFAULTS[key]) for key in PRIOR_KEYS}


PRIOR_DEFAULTS: dict[str, object] = {"prior_task": None, "prior_episodes": 500, "prior_weight": 1.0, "prior_seed": 0}
"""The prior's settings when not given (``prior_task`` None: no prior)."""

_PRIORS: dict[tuple, Any] = {}


def _prior(
    task: Task, k: int, name: str, params: dict[str, object], symmetric: bool, prior: dict[str, Any]
) -> tuple[Any, float]:
    """The prior model (cached) and its weight."""
    from crmgrasp.agents.model_based import check_same_space
    from crmgrasp.tasks import resolve_task

    spec = prior.get("prior_task")
    if not isinstance(spec, str):
        raise CrmgraspError(f"prior_task must be a task name, file or factory, got {spec!r}")
    episodes = integer(prior.get("prior_episodes", PRIOR_DEFAULTS["prior_episodes"]), "prior_episodes", 1, 1_000_000)
    seed = seed_value(prior.get("prior_seed", PRIOR_DEFAULTS["prior_seed"]), "prior_seed")
    weight = float(prior.get("prior_weight", PRIOR_DEFAULTS["prior_weight"]))  # type: ignore[arg-type]  # checked by set_prior
    key = (spec, k, name, tuple(sorted(params.items())), symmetric, episodes, seed)
    if key not in _PRIORS:
        source = resolve_task(spec)
        check_same_space(task, source)
        res = train_trials(
            source,
            name,
            trials=1,
            episodes=episodes,
            seed=seed,
            k=k,
            eval_episodes=0,
            params={**params, "symmetric": symmetric},
        )
        agent: Any = res.agents[0]
        _PRIORS[key] = getattr(agent, "inner", agent).model
    return _PRIORS[key], weight


def encoder_for(task: Task, k: int) -> KOrderEncoder:
    """The k-order encoder of a task's discretized observations and actions."""
    task = checked_task(task, "encoder_for")
    return KOrderEncoder(task.discretizer.size, len(task.actions), k)


def run_episode(
    task: Task,
    agent: Agent,
    encoder: KOrderEncoder,
    env_rng: np.random.Generator,
    agent_rng: np.random.Generator,
    *,
    learn: bool = True,
    kernel: Stepper | None = None,
) -> tuple[int, bool]:
    """One episode of ``agent`` ([`crmgrasp.sim.run_episode`][] with a
    [`LearnerPolicy`][crmgrasp.agents.base.LearnerPolicy], stepping through ``kernel`` if
    given); returns (CRMs executed, success). ``learn=False`` acts greedily and does
    not update."""
    ep = sim_run_episode(task, LearnerPolicy(agent, encoder, agent_rng, learn=learn), env_rng, kernel=kernel)
    return ep.steps, ep.success


def evaluate(
    task: Task,
    agent: Agent,
    encoder: KOrderEncoder,
    episodes: int,
    rng: np.random.Generator,
    agent_rng: np.random.Generator | None = None,
    *,
    kernel: Stepper | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Greedy evaluation: CRMs per episode and success flags over ``episodes`` fresh
    starts. Starts (and sensing) draw from ``rng``, tie-breaking from ``agent_rng``
    (default: ``rng`` too); separate streams give every policy the same starts."""
    episodes = integer(episodes, "episodes", 0, MAX_EPISODE_RECORDS)
    agent_rng = rng if agent_rng is None else agent_rng
    steps = np.empty(episodes, dtype=np.int64)
    success = np.empty(episodes, dtype=bool)
    for i in range(episodes):
        steps[i], success[i] = run_episode(task, agent, encoder, rng, agent_rng, learn=False, kernel=kernel)
    return steps, success


DEFAULT_CHECKPOINTS = (5, 10, 15, 20, 30, 40, 50, 60, 80, 100, 150, 200, 300, 500, 1000, 1500, 2000)
"""Training episodes after which [`train_trials`][] evaluates the greedy policy."""

_CHECKPOINT_KEY = 2**31  # spawn key of the checkpoint streams; trial streams use 0 .. trials-1


def checkpoint_generators(seed: int) -> tuple[np.random.Generator, np.random.Generator]:
    """Fresh (starts, tie-breaking) generators for a checkpoint evaluation: identical
    at every checkpoint, for every trial and every learner of a run with this seed."""
    return tuple(  # type: ignore[return-value]
        np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(_CHECKPOINT_KEY, i))) for i in range(2)
    )


def trial_generators(seed: int, trials: int, first: int = 0) -> list[tuple[np.random.Generator, ...]]:
    """``(env, agent, eval)`` generators of trials ``first .. first + trials - 1``, from
    one seed: trial ``t`` draws from child ``t`` of ``SeedSequence(seed)`` whatever the
    other trials, so trials can run in any grouping, order or process. A seed outside
    ``[0, 2**63 - 1]`` or not an integer is a one-line error."""
    seed = seed_value(seed)
    children = [np.random.SeedSequence(seed, spawn_key=(t,)) for t in range(first, first + trials)]
    return [tuple(np.random.default_rng(s) for s in child.spawn(3)) for child in children]


@dataclass
class TrialResult:
    """Learning curves ``(trials, episodes)``, greedy evaluation, greedy checkpoints
    ``(trials, len(checkpoints))``, and the trained agents."""

    steps: np.ndarray
    success: np.ndarray
    greedy_steps: np.ndarray
    greedy_success: np.ndarray
    agents: list[Agent]
    checkpoints: np.ndarray
    checkpoint_steps: np.ndarray
    faults: dict[str, int] = field(default_factory=dict)
    """Episodes a hand's stepper ended early, by kind (none on the kinematic model)."""

    @property
    def curve(self) -> np.ndarray:
        """Mean CRMs per episode over trials."""
        return self.steps.mean(axis=0)

    @property
    def sem(self) -> np.ndarray:
        """Standard error of the mean over trials (0 for a single trial)."""
        n = self.steps.shape[0]
        return self.steps.std(axis=0, ddof=1) / np.sqrt(n) if n > 1 else np.zeros(self.steps.shape[1])


PROGRESS_EVERY = 100
"""Training episodes between two calls of ``progress.advance``."""

MAX_EPISODE_RECORDS = 200_000_000
"""Most episodes (training and evaluation, all trials) whose results one run keeps in
memory (9 bytes each: about 1.8 GB)."""


def check_budget(trials: int, episodes: int, eval_episodes: int) -> None:
    """One-line errors for a bad training budget, before any work or allocation."""
    for name, v, low in (("trials", trials, 1), ("episodes", episodes, 1), ("eval_episodes", eval_episodes, 0)):
        integer(v, name, low, MAX_EPISODE_RECORDS)
    total = trials * (episodes + eval_episodes)
    if total > MAX_EPISODE_RECORDS:
        raise CrmgraspError(
            f"trials x (episodes + eval_episodes) = {total:,} episodes exceed the {MAX_EPISODE_RECORDS:,} "
            "whose results one run keeps in memory; split the run"
        )


def _episode_counts(checkpoints: object) -> tuple[int, ...]:
    """``checkpoints`` (any iterable of Python or NumPy integers) as ints in
    ``[0, MAX_EPISODE_RECORDS]``; a one-line error otherwise."""
    if isinstance(checkpoints, (str, bytes)) or not isinstance(checkpoints, Iterable):
        raise CrmgraspError(f"checkpoints must be episode counts, got {shown(checkpoints)}")
    marks = tuple(checkpoints)
    return tuple(
        integer(int(c) if isinstance(c, np.integer) else c, "a checkpoint", 0, MAX_EPISODE_RECORDS) for c in marks
    )


def train_trials(
    task: Task,
    agent: str,
    *,
    trials: int,
    episodes: int,
    seed: int,
    k: int = 2,
    eval_episodes: int = 1000,
    params: dict[str, object] | None = None,
    checkpoints: tuple[int, ...] = (),
    checkpoint_episodes: int = 100,
    backend: str = "auto",
    first_trial: int = 0,
    progress: Progress | None = None,
    stepper: Callable[[Task], Stepper] | None = None,
) -> TrialResult:
    """Train ``trials`` independent agents for ``episodes`` each, then evaluate each
    greedily on ``eval_episodes`` fresh episodes.

    The trials are numbers ``first_trial ..`` of the run ([`trial_generators`][]), so
    a run split into groups of trials gives the results of one call. ``progress``
    advances by the training episodes done.

    After each training episode listed in ``checkpoints`` the greedy policy is also
    evaluated on ``checkpoint_episodes`` episodes whose starts are the same at every
    checkpoint ([`checkpoint_generators`][]): a learning curve of the policy itself,
    free of exploration and of start-to-start noise. Episodes step through the task's
    kernel on ``backend`` ([`crmgrasp.kernels.kernel_for`][]; every backend gives
    the same results), or through ``stepper(task)`` if given (another hand:
    `crmgrasp.hardware.mujoco.steps.MujocoSteps`); the result's ``faults`` are the
    episodes that such a stepper ended early, by kind (its ``faults``), training and
    evaluation together."""
    check_budget(trials, episodes, eval_episodes)
    checked_task(task, "train_trials")
    marks = _episode_counts(checkpoints)
    integer(checkpoint_episodes, "checkpoint_episodes", 0, MAX_EPISODE_RECORDS)
    encoder = encoder_for(task, k)
    kernel = kernel_for(task, backend) if stepper is None else stepper(task)
    every = PROGRESS_EVERY if stepper is None else 1  # a hand's episode takes a noticeable time
    steps = np.empty((trials, episodes), dtype=np.int64)
    success = np.empty((trials, episodes), dtype=bool)
    gsteps = np.empty((trials, eval_episodes), dtype=np.int64)
    gsucc = np.empty((trials, eval_episodes), dtype=bool)
    ckpts = np.array(sorted({c for c in marks if 1 <= c <= episodes}), dtype=np.int64)
    if len(ckpts) and checkpoint_episodes < 1:
        raise CrmgraspError(f"checkpoint_episodes must be at least 1 with checkpoints {ckpts.tolist()}, got 0")
    csteps = np.empty((trials, len(ckpts)))
    agents = []
    for t, (env_rng, agent_rng, eval_rng) in enumerate(trial_generators(seed, trials, first_trial)):
        ag = build_agent(task, encoder, agent, params)
        j = 0
        for e in range(episodes):
            steps[t, e], success[t, e] = run_episode(task, ag, encoder, env_rng, agent_rng, kernel=kernel)
            if progress is not None and e % every == every - 1:
                progress.advance(every)
            if j < len(ckpts) and ckpts[j] == e + 1:
                starts_rng, ties_rng = checkpoint_generators(seed)
                ck = evaluate(task, ag, encoder, checkpoint_episodes, starts_rng, ties_rng, kernel=kernel)
                csteps[t, j] = ck[0].mean()
                j += 1
        gsteps[t], gsucc[t] = evaluate(task, ag, encoder, eval_episodes, eval_rng, kernel=kernel)
        agents.append(ag)
        if progress is not None:
            progress.advance(episodes % every)
    faults = dict(sorted(getattr(kernel, "faults", {}).items()))
    return TrialResult(steps, success, gsteps, gsucc, agents, ckpts, csteps, faults)


def checkpoints_to_within(
    checkpoints: np.ndarray, values: np.ndarray, reference: float, factor: float = 1.05
) -> int | None:
    """First checkpoint from which every later checkpoint's value is at or below
    ``factor * reference``; ``None`` if the last one is above.

    Examples
    --------
    >>> checkpoints_to_within(np.array([10, 20, 50, 100]), np.array([3.0, 1.0, 1.2, 1.0]), 1.0, 1.05)
    100
    """
    ok = np.asarray(values) <= factor * reference + 1e-12
    if len(ok) == 0 or not ok[-1]:
        return None
    bad = np.flatnonzero(~ok)
    return int(checkpoints[0 if len(bad) == 0 else bad[-1] + 1])


def as_curve(curve: object) -> np.ndarray:
    """``curve`` as a 1-D float array of finite numbers (one-line error otherwise)."""
    try:
        out = np.asarray(curve, dtype=np.float64)
    except (TypeError, ValueError, OverflowError):
        out = np.empty((0, 0))
    if out.ndim != 1 or not np.all(np.isfinite(out)):
        raise CrmgraspError(f"a learning curve must be a 1-D sequence of finite numbers, got {shown(curve)}")
    return out


def episodes_to_within(curve: np.ndarray, reference: float, factor: float = 1.05, window: int = 10) -> int | None:
    """First episode (1-based) after which the ``window``-episode moving average of
    ``curve`` stays at or below ``factor * reference``; ``None`` if it never does.

    The moving average at episode ``e`` covers episodes ``e - window + 1 .. e``.

    Examples
    --------
    >>> episodes_to_within(np.array([5.0] * 20 + [1.0] * 30), 1.0, window=10)
    30
    """
    curve = as_curve(curve)
    reference, factor = finite(reference, "reference"), positive(factor, "factor")
    window = integer(window, "window", 1, MAX_EPISODE_RECORDS)
    if len(curve) < window:
        return None
    ma = np.convolve(curve, np.ones(window) / window, mode="valid")  # ma[j] ends at episode j + window
    ok = ma <= factor * reference + 1e-12
    if not ok[-1]:
        return None
    bad = np.flatnonzero(~ok)
    first = 0 if len(bad) == 0 else bad[-1] + 1
    return int(first + window)


class RolloutStep(NamedTuple):
    """One CRM of a rollout: the configuration and observation before it, the action,
    its outcome, and the observation after it."""

    config: Config | Grip
    observation: tuple[float, ...]
    action: int
    outcome: Outcome
    next_observation: tuple[float, ...]
    obs_index: int
    min_friction: float


def rollout(
    task: Task, agent: Agent, encoder: KOrderEncoder, start: Config | Grip, rng: np.random.Generator
) -> tuple[list[RolloutStep], bool]:
    """Run the agent's greedy policy from ``start``; returns the steps and success."""
    ep = sim_run_episode(task, LearnerPolicy(agent, encoder, rng, learn=False), rng, start=start, trace=True)
    steps = []
    for tr in ep.trace:
        a, before, after = tr.action, tr.before, tr.after
        assert isinstance(a, int)  # a learner acts by index
        path = task.execute(before.state.config, task.actions[a], before.state.sensed)
        steps.append(
            RolloutStep(
                before.state.config, before.observation, a, path, after.observation, after.obs_index, after.min_friction
            )
        )
    return steps, ep.success

"""Learning on the physics hand (``crmgrasp reproduce physics-learning``).

Per task (``paper-box``, ``box-family``, ``cup-3d``) and seed, ``pooled-vi`` (k = 1, the
mirror quotient where the task declares one) learns three ways:

* **transferred**: ``kinematic_episodes`` episodes on the kinematic model, no MuJoCo
  episode;
* **scratch**: ``mujoco_episodes`` episodes on the MuJoCo stand-in, nothing else
  ([`MujocoSteps`][crmgrasp.hardware.mujoco.steps.MujocoSteps]: the object free on the
  table, the stand-in's sensors; episodes end on the *sensed* grasp);
* **fine-tuned**: the transferred agent, then ``mujoco_episodes`` episodes on MuJoCo
  (the same agent keeps learning: its counts from the kinematic model and from MuJoCo
  together).

Each greedy policy then runs ``eval_episodes`` episodes on MuJoCo from worlds drawn by
one generator per (task, seed), the same for the three ways. Success is the *true*
least friction, from MuJoCo's contacts at the end of the episode, at or below
``mu_goal``. Episodes that MuJoCo ended early (physics faults, lost contacts) are
counted. Files: ``data.csv`` (one row per task, seed and way), ``curves.csv`` (CRMs
and true success per MuJoCo training episode, mean over seeds), ``summary.json``,
``physics_learning.png`` and, with the extra ``crmgrasp[mcap]``, ``<task>.mcap``: the
first seed's scratch policy on one MuJoCo world, recorded in Foxglove's schemas
([`crmgrasp.hardware.records`][]).
"""

from __future__ import annotations

import statistics
import time
from collections import Counter
from dataclasses import asdict, dataclass
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np

from crmgrasp._io import save_figure, write_csv, write_json
from crmgrasp._progress import Progress
from crmgrasp._validation import CrmgraspError
from crmgrasp.agents.policy import GreedyPolicy
from crmgrasp.agents.training import build_agent, encoder_for, run_episode
from crmgrasp.experiments.configs import CheckedConfig, checked_config
from crmgrasp.experiments.parallel import run_parallel
from crmgrasp.experiments.stats import bootstrap_ci
from crmgrasp.hardware.mujoco.steps import MujocoSteps
from crmgrasp.kernels import kernel_for
from crmgrasp.tasks import Task, make_task

__all__ = [
    "PhysicsLearningConfig",
    "physics_learning",
    "train_episodes",
    "score_on_mujoco",
    "record_mujoco_episode",
    "WAYS",
]

WAYS = ("transferred", "scratch", "fine-tuned")
"""How each policy learned: on the kinematic model only, on MuJoCo only, on both in turn."""


@dataclass(frozen=True)
class PhysicsLearningConfig(CheckedConfig):
    """Parameters of the physics-learning experiment."""

    tasks: tuple[str, ...] = ("paper-box", "box-family", "cup-3d")
    mujoco_episodes: tuple[int, ...] = (100, 100, 200)
    """MuJoCo training episodes per task (scratch and fine-tuned), in the order of ``tasks``."""
    kinematic_episodes: int = 1000
    """Kinematic-model episodes of the transferred and fine-tuned policies."""
    eval_episodes: int = 100
    """MuJoCo episodes that score each greedy policy."""
    seeds: int = 5
    seed: int = 0
    """Seeds ``seed .. seed + seeds - 1``."""
    agent: str = "pooled-vi"

    @classmethod
    def quick(cls, seed: int = 0) -> PhysicsLearningConfig:
        """A smoke-sized run: one seed, 5 MuJoCo and 100 kinematic episodes, 3 scoring episodes."""
        return cls(mujoco_episodes=(5, 5, 5), kinematic_episodes=100, eval_episodes=3, seeds=1, seed=seed)


def _params(task: Task) -> dict[str, object]:
    return {"symmetric": True} if task.symmetry is not None else {}


def train_episodes(
    task: Task, agent: Any, encoder: Any, episodes: int, kernel: Any, rngs: Any
) -> tuple[list[int], list[bool], list[float]]:
    """``episodes`` learning episodes of ``agent`` through ``kernel`` (a kinematic kernel
    or [`MujocoSteps`][crmgrasp.hardware.mujoco.steps.MujocoSteps]), the environment
    drawing from ``rngs[0]`` and the agent from ``rngs[1]``; the CRMs, success and wall
    time (s) of each."""
    steps, success, seconds = [], [], []
    for _ in range(episodes):
        t0 = time.perf_counter()
        n, ok = run_episode(task, agent, encoder, rngs[0], rngs[1], kernel=kernel)
        seconds.append(time.perf_counter() - t0)
        steps.append(n)
        success.append(ok)
    return steps, success, seconds


def score_on_mujoco(task: Task, agent: Any, encoder: Any, episodes: int, seed: int) -> dict[str, Any]:
    """The greedy policy of ``agent`` on ``episodes`` MuJoCo worlds drawn from one
    generator of ``seed`` (the same worlds for every policy scored with this seed, so the first
    of a longer run are a shorter run's): mean CRMs, true success rate, each episode's true
    success and CRMs in order (``outcomes``, ``episode_crms``) and the episodes MuJoCo ended
    early, by kind."""
    steps = MujocoSteps(task)
    env, ties = (np.random.default_rng(s) for s in np.random.SeedSequence(seed, spawn_key=(2**31,)).spawn(2))
    crms, success = [], []
    for _ in range(episodes):
        n, ok = run_episode(task, agent, encoder, env, ties, learn=False, kernel=steps)
        crms.append(n)
        success.append(ok)
    out = {"crms": float(np.mean(crms)), "success": float(np.mean(success)), "faults": dict(steps.faults)}
    return out | {"outcomes": [bool(ok) for ok in success], "episode_crms": [int(n) for n in crms]}


def record_mujoco_episode(policy: GreedyPolicy, seed: int, path: Path) -> Path | None:
    """Run ``policy`` on one MuJoCo world of its task (drawn from ``seed``) through the
    [`PolicyRunner`][crmgrasp.hardware.runner.PolicyRunner] and record it to the MCAP file
    ``path`` ([`crmgrasp.hardware.records`][]); ``None`` without the extra ``crmgrasp[mcap]``."""
    from crmgrasp.hardware.mujoco import hardware_task
    from crmgrasp.hardware.mujoco.spatial import mujoco_hand
    from crmgrasp.hardware.records import require_mcap
    from crmgrasp.hardware.runner import PolicyRunner

    try:
        require_mcap()
    except CrmgraspError:
        return None
    rng = np.random.default_rng(seed)
    world = policy.task.sample_world(rng)
    task = hardware_task(world.task)
    hand = mujoco_hand(task, world.config, rng)
    PolicyRunner(policy, hardware_task(policy.task)).run(hand, rng, log=path)
    return path


def _unit(c: PhysicsLearningConfig, name: str, episodes: int, seed: int, out_dir: Path) -> dict[str, Any]:
    """The three ways on one task and seed (the first seed's scratch policy recorded to
    ``<task>.mcap`` in ``out_dir``)."""
    task = make_task(name)
    encoder = encoder_for(task, 1)
    kin_rngs = [np.random.default_rng(s) for s in np.random.SeedSequence(seed, spawn_key=(0,)).spawn(2)]
    out: dict[str, Any] = {}
    t0 = time.perf_counter()
    kin = build_agent(task, encoder, c.agent, _params(task))
    train_episodes(task, kin, encoder, c.kinematic_episodes, kernel_for(task), kin_rngs)
    kin_seconds = time.perf_counter() - t0
    out["transferred"] = score_on_mujoco(task, kin, encoder, c.eval_episodes, seed)
    out["transferred"].update(mujoco=0, kinematic=c.kinematic_episodes, seconds=kin_seconds)
    for way, agent in (("scratch", build_agent(task, encoder, c.agent, _params(task))), ("fine-tuned", kin)):
        steps = MujocoSteps(task)
        rngs = [np.random.default_rng(s) for s in np.random.SeedSequence(seed, spawn_key=(1,)).spawn(2)]
        t0 = time.perf_counter()
        crms, success, seconds = train_episodes(task, agent, encoder, episodes, steps, rngs)
        elapsed = time.perf_counter() - t0 + (kin_seconds if way == "fine-tuned" else 0.0)
        kinematic = c.kinematic_episodes if way == "fine-tuned" else 0
        out[way] = score_on_mujoco(task, agent, encoder, c.eval_episodes, seed)
        out[way].update(mujoco=episodes, kinematic=kinematic, seconds=elapsed, curve=crms, curve_success=success)
        out[way].update(episode_seconds=seconds, train_faults=dict(steps.faults))
        if way == "scratch" and seed == c.seed:
            record_mujoco_episode(GreedyPolicy.from_agent(task, 1, agent), seed, out_dir / f"{name}.mcap")  # type: ignore[arg-type]
    return out


def physics_learning(
    out_dir: str | Path, config: PhysicsLearningConfig | None = None, progress: Progress | None = None, jobs: int = 1
) -> dict[str, Any]:
    """Run the experiment (see the module docstring); write its files to ``out_dir``;
    return the summary. ``jobs`` worker processes run (task, seed) units at once."""
    c = PhysicsLearningConfig() if config is None else checked_config(config, PhysicsLearningConfig)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    episodes = dict(zip(c.tasks, c.mujoco_episodes, strict=True))
    seeds = range(c.seed, c.seed + c.seeds)
    calls = [((name, s), partial(_unit, c, name, episodes[name], s, out)) for name in c.tasks for s in seeds]
    stage = progress.stage("physics learning: (task, seed) units", len(calls), "units") if progress else None
    results: dict[tuple[str, int], dict[str, Any]] = {}
    for key, res in run_parallel(calls, jobs):
        results[key] = res
        if stage:
            stage.advance(1)
    if stage:
        stage.end()
    rows = [
        [name, s, way, r["kinematic"], r["mujoco"], round(r["success"], 4), round(r["crms"], 4), round(r["seconds"], 2)]
        for (name, s), unit in sorted(results.items())
        for way, r in unit.items()
    ]
    write_csv(
        out / "data.csv",
        ["task", "seed", "way", "kinematic_episodes", "mujoco_episodes", "success", "crms", "seconds"],
        rows,
    )
    summary = {"config": asdict(c), "tasks": {name: _task_summary(c, name, results) for name in c.tasks}}
    times = [t for unit in results.values() for way in WAYS[1:] for t in unit[way]["episode_seconds"]]
    summary["mujoco_episode_seconds"] = {
        "median": round(statistics.median(times), 4) if times else None,
        "max": round(max(times), 4) if times else None,
    }
    _curves(out, c, results)
    write_json(out / "summary.json", summary)
    return summary


def _task_summary(c: PhysicsLearningConfig, name: str, results: dict) -> dict[str, Any]:
    units = [results[(name, s)] for s in range(c.seed, c.seed + c.seeds)]
    seed0 = c.seed
    per: dict[str, Any] = {}
    for way in WAYS:
        success = np.array([u[way]["success"] for u in units])
        crms = np.array([u[way]["crms"] for u in units])
        faults = sum((Counter(u[way]["faults"]) + Counter(u[way].get("train_faults", {})) for u in units), Counter())
        per[way] = {
            "success": round(float(success.mean()), 4),
            "success_ci95": [round(v, 4) for v in bootstrap_ci(success, seed0)] if len(units) >= 5 else None,
            "seeds_at_95pct": int((success >= 0.95).sum()),
            "seeds_at_90pct": int((success >= 0.90).sum()),
            "crms": round(float(crms.mean()), 3),
            "kinematic_episodes": units[0][way]["kinematic"],
            "mujoco_episodes": units[0][way]["mujoco"],
            "seconds": round(float(np.mean([u[way]["seconds"] for u in units])), 2),
            "faults": dict(sorted(faults.items())),
        }
    diff = np.array([u["fine-tuned"]["success"] - u["transferred"]["success"] for u in units])
    per["fine_tuned_minus_transferred_success"] = round(float(diff.mean()), 4)
    crm_diff = np.array([u["fine-tuned"]["crms"] - u["transferred"]["crms"] for u in units])
    per["fine_tuned_minus_transferred_crms"] = round(float(crm_diff.mean()), 3)
    per["seeds"] = len(units)
    return per


def _curves(out: Path, c: PhysicsLearningConfig, results: dict) -> None:
    """``curves.csv`` and the figure: CRMs per MuJoCo training episode (10-episode moving
    mean over seeds), scratch and fine-tuned, with the transferred policy's greedy CRMs."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(c.tasks), figsize=(4.2 * len(c.tasks), 3.4), squeeze=False)
    rows = []
    for ax, name in zip(axes[0], c.tasks, strict=True):
        units = [results[(name, s)] for s in range(c.seed, c.seed + c.seeds)]
        for way, colour in (("scratch", "tab:blue"), ("fine-tuned", "tab:green")):
            curve = np.mean([u[way]["curve"] for u in units], axis=0)
            succ = np.mean([u[way]["curve_success"] for u in units], axis=0)
            rows += [[name, way, e + 1, float(m), float(s)] for e, (m, s) in enumerate(zip(curve, succ))]
            w = min(10, len(curve))
            ax.plot(np.arange(w, len(curve) + 1), np.convolve(curve, np.ones(w) / w, "valid"), color=colour, label=way)
        transferred = np.mean([u["transferred"]["crms"] for u in units])
        ax.axhline(transferred, color="tab:orange", ls="--", label="transferred (greedy on MuJoCo)")
        ax.set_title(f"{name} on MuJoCo, {len(units)} seeds")
        ax.set_xlabel("MuJoCo training episode")
        ax.set_ylabel("CRMs per episode (10-episode mean)")
        ax.legend(fontsize=7)
    seeds = f"seeds {c.seed}-{c.seed + c.seeds - 1}" if c.seeds > 1 else f"seed {c.seed}"
    fig.suptitle(
        f"pooled-vi training episodes on the MuJoCo stand-in ({seeds}; exploration included): from scratch, "
        f"and fine-tuned after {c.kinematic_episodes:,} kinematic episodes"
    )
    fig.tight_layout()
    save_figure(fig, out / "physics_learning.png", dpi=110)
    write_csv(out / "curves.csv", ["task", "way", "episode", "mean_crms", "true_success_rate"], rows)

"""Spatial CRM policies on the MuJoCo stand-in in 3-D (extra ``crmgrasp[mujoco]``).

[`spatial_mujoco`][]: for each spatial task (``cup-3d``, ``box-3d``), the policy of
``model-vi`` (k = 1) is trained in the kinematic model (or loaded), then
runs from ``trials`` worlds drawn from the task (a solid of the family and a surface start
on it) on the MuJoCo hand ([`MujocoHand3D`][crmgrasp.hardware.mujoco.spatial.MujocoHand3D]) and,
from the same worlds, on the kinematic hand, both through the one
[`PolicyRunner`][crmgrasp.hardware.runner.PolicyRunner]. A run stops when the *sensed*
configuration is a grasp; it counts as a success when the true contacts (MuJoCo's contact
list) have ``min_friction_3d <= mu_goal``. Also recorded: the wall time of every CRM, the
accuracy of 3-D intrinsic contact sensing against MuJoCo's contacts, and, from
``random_crms`` more worlds, how often one random CRM has the kinematic model's error flag.
"""

from __future__ import annotations

import math
import statistics
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from crmgrasp._io import save_figure, write_csv, write_json
from crmgrasp._progress import Progress
from crmgrasp.experiments._policy import learned_policy
from crmgrasp.experiments.configs import CheckedConfig, checked_config
from crmgrasp.experiments.learning import LearnerSpec
from crmgrasp.experiments.mujoco import SensingErrors, animate
from crmgrasp.hardware.mujoco import hardware_task
from crmgrasp.hardware.mujoco.model import PhysicsParams
from crmgrasp.hardware.mujoco.spatial import MujocoHand3D
from crmgrasp.hardware.runner import KinematicHand, PolicyRunner, log_columns
from crmgrasp.model.mesh import TriangleMesh
from crmgrasp.model.solids import Cylinder
from crmgrasp.tasks import Task, make_task

__all__ = ["SpatialMujocoConfig", "spatial_mujoco"]

COLUMNS = [
    "task",
    "trial",
    "object",
    "actions",
    "crms_mujoco",
    "crms_kinematic",
    "stopped",
    "grasped_kinematic",
    "success",
    "true_min_friction",
]


@dataclass(frozen=True)
class SpatialMujocoConfig(CheckedConfig):
    """Parameters of the spatial MuJoCo transfer."""

    tasks: tuple[str, ...] = ("cup-3d", "box-3d")
    trials: int = 20
    """Worlds run on the MuJoCo hand per task."""
    seed: int = 0
    train_trials: int = 2
    train_episodes: int = 3000
    """Training of ``model-vi`` (k = 1) per task; the trial with the best greedy score is used."""
    policies: tuple[str, ...] = ()
    """Saved policy files, one per task in order, instead of training (empty: train)."""
    palm_tolerance_deg: float = 10.0
    """The fingertip palm tolerance ([`hardware_task`][crmgrasp.hardware.mujoco.hardware_task])."""
    random_crms: int = 60
    """Worlds per task where one random CRM runs on both hands, to compare error flags."""
    animate: bool = True
    """Render the first task's trial 0 to ``spatial_mujoco.gif`` (needs headless OpenGL)."""

    @classmethod
    def quick(cls, seed: int = 0) -> SpatialMujocoConfig:
        """A smoke-sized run: 4 worlds per task, 300 training episodes."""
        return cls(trials=4, seed=seed, train_trials=1, train_episodes=300, random_crms=4, animate=False)


def _kind(task: Task) -> str:
    obj = task.obj
    if isinstance(obj, Cylinder):
        upright = abs(obj.axis[2]) > 0.99
        return f"{'upright' if upright else 'lying'} cylinder r {obj.radius:.3f} h {obj.height:.3f}"
    if isinstance(obj, TriangleMesh):
        lo, hi = obj.corner_array.min(axis=0), obj.corner_array.max(axis=0)
        return f"mesh of {len(obj.faces)} triangles, {hi[2] - lo[2]:.3f} m tall"
    corners = obj.vertices  # type: ignore[attr-defined]
    lo, hi = corners.min(axis=0), corners.max(axis=0)
    return f"box, {hi[2] - lo[2]:.3f} m tall"


def _transfer(
    base: Task, policy: Any, c: SpatialMujocoConfig, out: Path, errors: SensingErrors
) -> tuple[list[list[Any]], list[float], Any]:
    """Run ``c.trials`` worlds of task ``base`` on both hands; rows, CRM seconds, first world."""
    name = base.name
    rng = np.random.default_rng(c.seed)
    action = log_columns(base).index("action")
    names = [n.split()[0] for n in base.action_names()]
    rows, seconds, first = [], [], None
    for trial in range(c.trials):
        world = base.sample_world(rng)
        first = first or world
        task = hardware_task(world.task, c.palm_tolerance_deg)
        hand = MujocoHand3D(task, world.config, rng)  # type: ignore[arg-type]
        errors.add(hand.sense(), hand.true_config())
        run = PolicyRunner(policy, task).run(hand, rng, log=out / "logs" / f"{name}-trial{trial:02d}.csv")
        true = hand.true_config()
        errors.add(hand.sense(), true)
        mu = task.quality(true) if true is not None else math.inf
        kin = PolicyRunner(policy, task).run(KinematicHand(task, world.config, rng), rng)
        seconds += hand.crm_seconds
        actions = " ".join(names[r[action]] for r in run.rows if r[action] != "")
        rows.append(
            [name, trial, _kind(task), actions, run.crms, kin.crms, run.stopped, kin.grasped, task.grasped(mu), mu]
        )
    return rows, seconds, first


def _same_errors(base: Task, c: SpatialMujocoConfig, errors: SensingErrors) -> tuple[dict[str, int], list[float]]:
    """One random CRM from each of ``c.random_crms`` worlds on both hands: the counts of
    (kinematic error flag -> MuJoCo error flag); and the CRMs' wall times."""
    rng = np.random.default_rng(c.seed + 1)
    flags: dict[str, int] = {}
    seconds: list[float] = []
    for _ in range(c.random_crms):
        world = base.sample_world(rng)
        task = hardware_task(world.task, c.palm_tolerance_deg)
        hand = MujocoHand3D(task, world.config, rng)  # type: ignore[arg-type]
        crm = task.actions[int(rng.integers(len(task.actions)))]
        got, kin = hand.execute(crm), task.execute(world.config, crm, world.config).error
        key = f"{kin.name.lower()} -> {got.name.lower()}"
        flags[key] = flags.get(key, 0) + 1
        errors.add(hand.sense(), hand.true_config())
        seconds += hand.crm_seconds
    return dict(sorted(flags.items())), seconds


def _figure(rows: list[list[Any]], c: SpatialMujocoConfig, mu_goal: dict[str, float], path: Path) -> None:
    from matplotlib.figure import Figure

    fig = Figure(figsize=(10, 4), layout="constrained")
    left, right = fig.subplots(1, 2)
    for k, name in enumerate(c.tasks):
        mine = [r for r in rows if r[0] == name]
        x = np.arange(len(mine)) + 0.2 * k
        left.plot(x, [r[4] for r in mine], "o", ms=5, label=f"{name}: MuJoCo")
        left.plot(x, [r[5] for r in mine], "x", ms=5, label=f"{name}: kinematic")
        mu = [min(r[9], 10.0) for r in mine]
        right.semilogy(x, np.maximum(mu, 1e-4), "o", ms=5, label=name)
        right.axhline(mu_goal[name], color="k", ls="--", lw=1)
    left.set_xlabel("world")
    left.set_ylabel("CRMs per world (stops at a sensed grasp or 10)")
    left.legend(fontsize=7)
    right.set_xlabel("world")
    right.set_ylabel("true min friction at the end (no contact: at 10)")
    right.legend(fontsize=7)
    fig.suptitle(f"Spatial policies on the MuJoCo stand-in, {c.trials} worlds per task, seed {c.seed}", fontsize=9)
    save_figure(fig, path)


def _task_summary(c: SpatialMujocoConfig, mine: list[list[Any]], seconds: list[float], flags: dict[str, int]) -> dict:
    """One task's summary: successes on MuJoCo and on the kinematic hand, CRMs on both, the true
    least friction and the CRMs' wall time (``mine``: its rows of ``data.csv``), and how often a
    random CRM raised the same error flag on MuJoCo as on the kinematic hand (``flags``)."""
    same = sum(n for k, n in flags.items() if k.split(" -> ")[0] == k.split(" -> ")[1])
    return {
        "trials": c.trials,
        "successes": int(sum(r[8] for r in mine)),
        "kinematic_successes": int(sum(r[7] for r in mine)),
        "mean_crms_mujoco": round(statistics.fmean(r[4] for r in mine), 3),
        "mean_crms_kinematic": round(statistics.fmean(r[5] for r in mine), 3),
        "median_true_min_friction": round(float(np.median([r[9] for r in mine])), 4),
        "median_crm_seconds": round(float(np.median(seconds)), 4) if seconds else None,
        "max_crm_seconds": round(float(np.max(seconds)), 4) if seconds else None,
        "random_crms_same_error_as_kinematic": f"{same} of {c.random_crms}",
        "random_crm_flags_kinematic_to_mujoco": flags,
    }


def spatial_mujoco(
    out_dir: str | Path,
    config: SpatialMujocoConfig = SpatialMujocoConfig(),
    *,
    backend: str = "auto",
    progress: Progress | None = None,
) -> dict[str, Any]:
    """Train (or load) each task's policy, run it on the MuJoCo and kinematic hands; write
    ``data.csv``, ``spatial_mujoco.png``, per-trial step logs, ``summary.json``; return the summary."""
    config = checked_config(config, SpatialMujocoConfig)
    c = config
    if c.policies and len(c.policies) != len(c.tasks):
        raise ValueError(f"give one policy file per task ({len(c.tasks)}), got {len(c.policies)}")
    out = Path(out_dir)
    stage = progress.stage("spatial-mujoco", 2 * len(c.tasks), "stages") if progress else None
    rows: list[list[Any]] = []
    summary: dict[str, Any] = {"tasks": {}}
    errors, all_seconds, mu_goal = SensingErrors(), [], {}
    for k, name in enumerate(c.tasks):
        task = make_task(name)
        policy = learned_policy(
            task,
            c.policies[k] if c.policies else None,
            c.seed,
            c.train_trials,
            c.train_episodes,
            backend,
            spec=LearnerSpec("model-vi", 1),
        )
        if stage is not None:
            stage.advance(1)
        mine, seconds, first = _transfer(task, policy, c, out, errors)
        if c.animate and k == 0 and first is not None:
            hw = hardware_task(first.task, c.palm_tolerance_deg)
            gif = out / "spatial_mujoco.gif"
            summary["animation"] = animate(hw, first.config, policy, np.random.default_rng(c.seed), gif)
        flags, more = _same_errors(task, c, errors)
        rows += mine
        all_seconds += seconds + more
        mu_goal[name] = task.mu_goal
        summary["tasks"][name] = _task_summary(c, mine, seconds, flags)
        if stage is not None:
            stage.advance(1)
    write_csv(out / "data.csv", COLUMNS, rows)
    _figure(rows, c, mu_goal, out / "spatial_mujoco.png")
    summary["contact_sensing"] = errors.summary()
    summary["crm_seconds"] = {
        "crms": len(all_seconds),
        "median": round(float(np.median(all_seconds)), 4) if all_seconds else None,
        "max": round(float(np.max(all_seconds)), 4) if all_seconds else None,
    }
    write_json(
        out / "summary.json",
        {"experiment": "spatial-mujoco", "config": asdict(c), "physics": asdict(PhysicsParams()), **summary},
    )
    if stage is not None:
        stage.end()
    return summary

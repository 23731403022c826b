"""Paper Figure 9: the learned policy run 11 times with sensing noise, in the plane of
frictionless force residual (x) and the frictionless moment about the finger contact (y).

Starts are like the paper's Robonaut trials: the "thumb" touches a long side
farther from the corner than the short side is long (0.10 to 0.18 m, so one
move toward the corner brings it within reach), the "fingers" the short side.
Sensing noise (3 degrees, 2 mm) is on, with the fingertip palm tolerance of
Figure 4 (10 degrees). Because noisy oppositions are a few degrees off, an
episode counts as a grasp when ``min_friction <= mu_goal`` = 0.15 (a fingertip
friction coefficient well below rubber's); the fraction within the noise-free
goal 0.05 is reported too. Each configuration is plotted before the first CRM,
before the second, and after the last, from the *measured* (sensed) values.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from crmgrasp._io import save_figure, write_csv, write_json
from crmgrasp.agents.training import rollout
from crmgrasp.experiments._policy import learned_policy
from crmgrasp.experiments.configs import CheckedConfig, checked_config
from crmgrasp.experiments.figure4 import noisy_execution
from crmgrasp.model.contacts import Config, two_contacts
from crmgrasp.model.geometry import Polygon
from crmgrasp.plotting import cluster_figure
from crmgrasp.tasks import Task, make_task

__all__ = ["Figure9Config", "figure_9_robonaut_trials", "thumb_far_start", "Clusters"]


@dataclass(frozen=True)
class Figure9Config(CheckedConfig):
    """Parameters of Figure 9."""

    task: str = "paper-box"
    trials: int = 11
    """Policy executions (the paper: 11 on Robonaut)."""
    seed: int = 0
    sigma_n_deg: float = 3.0
    sigma_p: float = 0.002
    palm_tolerance_deg: float = 10.0
    mu_goal: float = 0.15
    min_thumb_distance: float = 0.10
    max_thumb_distance: float = 0.18
    policy: str | None = None
    train_trials: int = 5
    train_episodes: int = 2000


def _corner_distances(obj: Polygon, cfg: Config) -> list[tuple[float, float]]:
    """(edge length, distance to the nearest vertex) of each contact."""
    out = []
    for c in cfg:
        edge = obj.edge_length(obj.edge_index(c.point))
        out.append((edge, min(math.dist(c.point, v) for v in obj.vertices)))
    return out


def thumb_far_start(task: Task, rng: np.random.Generator, lo: float, hi: float) -> tuple[Config, str]:
    """A start whose long-side contact (the thumb) is ``lo..hi`` from the corner;
    returns it and the label of the short-side contact (the fingers)."""
    assert isinstance(task.obj, Polygon)
    for _ in range(100_000):
        cfg = two_contacts(task.sample_start(rng), "Figure 9")
        (la, da), (lb, db) = _corner_distances(task.obj, cfg)
        if la != lb:
            thumb_dist = da if la > lb else db
            if lo < thumb_dist <= hi:
                return cfg, ("b" if la > lb else "a")
    raise RuntimeError("no start found")  # pragma: no cover - the range is wide


def _point(task: Task, obs: tuple[float, ...], fingers: str) -> tuple[float, float]:
    """``(rho, |moment about the fingers|)`` of an observation."""
    return (obs[0], abs(obs[task.model.moment_index(fingers)]))


class Clusters:
    """Figure 9's point groups: each run's reading before CRM 1, before CRM 2 (runs of
    two or more CRMs) and after the last CRM, in the (rho, |moment|) plane."""

    def __init__(self) -> None:
        self.groups: dict[str, list[tuple[float, float]]] = {
            "before CRM 1": [],
            "before CRM 2": [],
            "after last CRM": [],
        }

    def add(self, readings: list[tuple[float, float]]) -> None:
        """One run's readings in order: one before each CRM, then the final one."""
        self.groups["before CRM 1"].append(readings[0])
        if len(readings) > 2:
            self.groups["before CRM 2"].append(readings[1])
        self.groups["after last CRM"].append(readings[-1])

    def save(self, title: str, xlabel: str, path: Path) -> dict[str, list[float]]:
        """Write the scatter plot; return each group's centroid, keyed ``centroid <group>``."""
        arrays = {k: np.array(v) for k, v in self.groups.items()}
        fig = cluster_figure(arrays, title, xlabel, "|frictionless moment about the fingers| (m)")
        save_figure(fig, path, dpi=120)
        return {f"centroid {k}": [round(float(x), 3) for x in v.mean(axis=0)] for k, v in arrays.items() if len(v)}


def figure_9_robonaut_trials(
    out_dir: str | Path, config: Figure9Config = Figure9Config(), *, backend: str = "auto"
) -> dict[str, Any]:
    """Run the trials and plot the three clusters."""
    config = checked_config(config, Figure9Config)
    base = make_task(config.task)
    policy = learned_policy(base, config.policy, config.seed, config.train_trials, config.train_episodes, backend)
    noisy = noisy_execution(base, config.sigma_n_deg, config.sigma_p, config.palm_tolerance_deg)
    task = dataclasses.replace(noisy, mu_goal=config.mu_goal)
    rng = np.random.default_rng(config.seed)
    clusters = Clusters()
    rows, crms, successes, tight = [], [], 0, 0
    for trial in range(config.trials):
        start, fingers = thumb_far_start(base, rng, config.min_thumb_distance, config.max_thumb_distance)
        steps, ok = rollout(task, policy, policy.encoder, start, rng)
        successes += ok
        tight += base.grasped(steps[-1].min_friction)
        crms.append(len(steps))
        readings = [_point(task, st.observation, fingers) for st in steps]
        readings.append(_point(task, steps[-1].next_observation, fingers))
        clusters.add(readings)
        points = readings[:2] + readings[-1:] if len(steps) > 1 else readings
        actions = " ".join(task.action_names()[s.action].split()[0] for s in steps)
        rows.append([trial, fingers, actions, len(steps), bool(ok), steps[-1].min_friction, *np.ravel(points[:3])])
    out = Path(out_dir)
    write_csv(
        out / "data.csv",
        [
            "trial",
            "fingers",
            "crms",
            "n_crms",
            "success",
            "final_min_friction",
            "rho_0",
            "m_0",
            "rho_1",
            "m_1",
            "rho_2",
            "m_2",
        ],
        rows,
    )
    centroids = clusters.save(
        f"Learned policy, {config.trials} noisy trials (paper Fig. 9)",
        "frictionless force residual rho",
        out / "figure9.png",
    )
    summary = {
        "trials": config.trials,
        "successes": successes,
        "within_mu_0.05": tight,
        "mean_crms": float(np.mean(crms)),
        **centroids,
    }
    write_json(out / "config.json", {"experiment": "figure9", "config": asdict(config), "summary": summary})
    return summary

"""Paper Figure 4: grasp quality of 30 opposition CRMs under sensing noise.

Setting (paper Sec. II-B): the "fingers" touch a long side of the box and the
"thumb" is moved by the opposition CRM ``(thumb, fingers, 0)``. Starts are
paper-box corner starts whose long-side contact is at most ``max_corner_distance``
from the corner, so a single opposition can reach an antipodal grasp without a
palm collision (the palm clears the short side when that distance is below the
palm depth, 0.12 m). The goal line is computed from noisy sensed contacts; the
reported ``min_friction`` is that of the *true* final configuration.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from crmgrasp._io import save_figure, write_csv, write_json
from crmgrasp._validation import CrmgraspError
from crmgrasp.experiments.configs import CheckedConfig, checked_config
from crmgrasp.model.contacts import Config, two_contacts
from crmgrasp.model.geometry import Polygon
from crmgrasp.model.hand import CRM, Error
from crmgrasp.model.quality import min_friction
from crmgrasp.model.sensing import SensorNoise
from crmgrasp.plotting import friction_histogram
from crmgrasp.tasks import Task, make_task

__all__ = ["Figure4Config", "figure_4_opposition_quality", "long_side_start"]


@dataclass(frozen=True)
class Figure4Config(CheckedConfig):
    """Parameters of the Figure 4 experiment."""

    task: str = "paper-box"
    """Registered task name (its object must be a polygon)."""
    trials: int = 30
    """Number of opposition grasps (the paper: 30)."""
    seed: int = 0
    """Seed of the run's numpy Generator."""
    sigma_n_deg: float = 3.0
    """Sensing noise on normals, degrees (standard deviation)."""
    sigma_p: float = 0.002
    """Sensing noise on positions, metres (standard deviation per axis)."""
    max_corner_distance: float = 0.10
    """Largest distance of the fingers' contact from the corner, metres."""
    min_corner_distance: float = 0.01
    """Smallest distance of the fingers' contact from the corner, metres: five
    standard deviations of the position noise, so the fingers are on the long side
    (nearer, a noisy goal line can slide off the side past the corner)."""
    palm_tolerance_deg: float = 10.0
    """Angle a contact surface may face the palm side (``Hand.palm_normal_tol`` =
    sin of it). the default 1e-9 would turn nearly every noisy opposition into a palm
    error, because a misaligned landing tilts one normal toward the palm by a hair."""


def noisy_execution(task: Task, sigma_n_deg: float, sigma_p: float, palm_tolerance_deg: float) -> Task:
    """``task`` with sensing noise (degrees, metres) and a fingertip palm tolerance
    (``Hand.palm_normal_tol = sin(palm_tolerance_deg)``): how the noisy experiments
    (Figures 4 and 9) execute CRMs."""
    hand = dataclasses.replace(task.hand, palm_normal_tol=math.sin(math.radians(palm_tolerance_deg)))
    return dataclasses.replace(task, hand=hand, noise=SensorNoise(math.radians(sigma_n_deg), sigma_p))


def _long_side_contact(task: Task, cfg: Config) -> str | None:
    """Label of the contact on the longer of the two touched edges (None if equal)."""
    obj = task.obj
    if not isinstance(obj, Polygon):
        raise CrmgraspError(f"figure 4 needs a polygonal object, got {type(obj).__name__}")
    la, lb = (obj.edge_length(obj.edge_index(c.point)) for c in cfg)
    if la == lb:
        return None
    return "a" if la > lb else "b"


def long_side_start(
    task: Task, rng: np.random.Generator, max_corner_distance: float, min_corner_distance: float = 0.0
) -> tuple[Config, str]:
    """A task start whose long-side contact lies ``min_corner_distance`` to
    ``max_corner_distance`` from the nearest vertex; returns the configuration and
    that contact's label."""
    for _ in range(10_000):
        cfg = two_contacts(task.sample_start(rng), "Figure 4")
        lab = _long_side_contact(task, cfg)
        if lab is None:
            continue
        c = cfg[lab]
        dist = min(math.hypot(c.x - vx, c.y - vy) for vx, vy in task.obj.vertices)  # type: ignore[attr-defined]
        if min_corner_distance <= dist <= max_corner_distance:
            return cfg, lab
    raise CrmgraspError("no long-side start found within max_corner_distance")


def figure_4_opposition_quality(out_dir: str | Path, config: Figure4Config = Figure4Config()) -> dict[str, Any]:
    """Run the experiment; write ``data.csv``, ``figure4.png`` and ``config.json`` to
    ``out_dir``; return a summary dict."""
    config = checked_config(config, Figure4Config)
    if config.trials < 1:
        raise CrmgraspError(f"trials must be >= 1, got {config.trials}")
    task = make_task(config.task)
    noisy = noisy_execution(task, config.sigma_n_deg, config.sigma_p, config.palm_tolerance_deg)
    rng = np.random.default_rng(config.seed)
    rows, values, failures = [], [], 0
    for trial in range(config.trials):
        start, fingers = long_side_start(task, rng, config.max_corner_distance, config.min_corner_distance)
        thumb = "b" if fingers == "a" else "a"
        crm = CRM(thumb, fingers, 0.0)
        outcome = noisy.hand.execute(task.obj, start, crm, noise=noisy.noise, rng=rng)
        mu = min_friction(outcome.config) if outcome.error == Error.NONE else math.inf
        failures += outcome.error != Error.NONE
        values.append(mu)
        rows.append(
            [
                trial,
                *(v for c in start for v in c.point),
                str(crm),
                outcome.error.name.lower(),
                *(v for c in outcome.config for v in c.point),
                mu,
            ]
        )
    out = Path(out_dir)
    header = [
        "trial",
        "start_ax",
        "start_ay",
        "start_bx",
        "start_by",
        "crm",
        "error",
        "final_ax",
        "final_ay",
        "final_bx",
        "final_by",
        "min_friction",
    ]
    write_csv(out / "data.csv", header, rows)
    fig = friction_histogram(values, failures, "Opposition CRM on the box under sensing noise (paper Fig. 4)")
    save_figure(fig, out / "figure4.png", dpi=120)
    finite = [v for v in values if math.isfinite(v)]
    summary: dict[str, Any] = {
        "trials": config.trials,
        "failures": failures,
        "median_min_friction": float(np.median(finite)) if finite else math.nan,
        "max_min_friction": float(max(finite)) if finite else math.nan,
        "fraction_below_0.1": sum(v < 0.1 for v in values) / len(values),
    }
    write_json(out / "config.json", {"experiment": "figure4", "config": asdict(config), "summary": summary})
    return summary

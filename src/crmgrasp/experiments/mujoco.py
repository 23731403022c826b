"""The paper's hardware experiments on the MuJoCo stand-in (extra ``crmgrasp[mujoco]``).

* [`figure_9_mujoco`][]: the policy learned in the kinematic simulator runs
  11 times on the MuJoCo hand from starts like the paper's Robonaut trials; the
  same starts also run on the kinematic hand (sensing noise of Figure 9) through
  the same [`PolicyRunner`][crmgrasp.hardware.runner.PolicyRunner], so the CRM counts compare
  one to one. Points are plotted from the *sensed* readings, as in Figure 9;
  success and the final ``min_friction`` come from MuJoCo's true contacts.
* [`figure_4_mujoco`][]: 30 opposition CRMs on the MuJoCo hand, histogram of
  the true final ``min_friction``; and the accuracy of intrinsic contact
  sensing against MuJoCo's contact list over every reading taken, plus
  ``extra_starts`` random task starts (two readings each: after the grasp is
  established and after one random CRM); the error flag of that random CRM is
  compared with the kinematic model's from the same start.
"""

from __future__ import annotations

import dataclasses
import math
import statistics
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from crmgrasp._io import save_figure, write_csv, write_json
from crmgrasp._validation import CrmgraspError
from crmgrasp.experiments._policy import learned_policy
from crmgrasp.experiments.configs import CheckedConfig, checked_config
from crmgrasp.experiments.figure4 import long_side_start, noisy_execution
from crmgrasp.experiments.figure9 import Clusters, Figure9Config, thumb_far_start
from crmgrasp.hardware.contact_sensing import NoContact
from crmgrasp.hardware.mujoco import hardware_task
from crmgrasp.hardware.mujoco.hand import MujocoHand
from crmgrasp.hardware.mujoco.model import PhysicsParams
from crmgrasp.hardware.runner import KinematicHand, PolicyRunner, log_columns
from crmgrasp.model.contacts import Config, Grip, two_contacts
from crmgrasp.model.hand import CRM, Error, execute_crm
from crmgrasp.model.quality import min_friction
from crmgrasp.model.spatial import Contacts3D
from crmgrasp.plotting import friction_histogram
from crmgrasp.tasks import Task, make_task

__all__ = ["MujocoFigure9Config", "MujocoFigure4Config", "figure_9_mujoco", "figure_4_mujoco", "SensingErrors"]


@dataclass(frozen=True)
class MujocoFigure9Config(Figure9Config):
    """Figure 9 on the MuJoCo stand-in; the fields of [`Figure9Config`][crmgrasp.experiments.Figure9Config]
    keep their meaning, ``sigma_n_deg`` and ``sigma_p`` being the sensing noise of the kinematic
    comparison runs (the MuJoCo hand has its own sensors,
    [`PhysicsParams`][crmgrasp.hardware.mujoco.model.PhysicsParams])."""

    animate: bool = True
    """Also render trial 0 to ``figure9_mujoco.gif`` (needs headless OpenGL)."""


@dataclass(frozen=True)
class MujocoFigure4Config(CheckedConfig):
    """Parameters of Figure 4 on the MuJoCo stand-in (see [`Figure4Config`][crmgrasp.experiments.Figure4Config])."""

    task: str = "paper-box"
    trials: int = 30
    seed: int = 0
    max_corner_distance: float = 0.10
    min_corner_distance: float = 0.01
    palm_tolerance_deg: float = 10.0
    extra_starts: int = 100
    """Random task starts sensed only for the contact-sensing accuracy."""


class SensingErrors:
    """Position (m) and normal (degrees) errors of sensed versus true contacts."""

    def __init__(self) -> None:
        self.position: list[float] = []
        self.normal: list[float] = []

    def add(self, sensed: Config | Grip | Contacts3D | NoContact, true: Config | Grip | Contacts3D | None) -> None:
        """Record every contact of one reading (skipped if either side has no contact)."""
        if isinstance(sensed, NoContact) or true is None:
            return
        for s, t in zip(sensed, true):
            (sp, sn), (tp, tn) = _point_normal(s), _point_normal(t)
            self.position.append(math.dist(sp, tp))
            dot = max(-1.0, min(1.0, sum(u * v for u, v in zip(sn, tn))))
            self.normal.append(math.degrees(math.acos(dot)))

    def summary(self) -> dict[str, Any]:
        """Count, median and 90th percentile of both errors."""
        if not self.position:
            return {"contacts": 0}
        pos, ang = np.array(self.position) * 1e3, np.array(self.normal)
        return {
            "contacts": len(pos),
            "median_position_error_mm": round(float(np.median(pos)), 4),
            "p90_position_error_mm": round(float(np.percentile(pos, 90)), 4),
            "median_normal_error_deg": round(float(np.median(ang)), 4),
            "p90_normal_error_deg": round(float(np.percentile(ang, 90)), 4),
        }


def _point_normal(c: Any) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """A planar or spatial contact's position and normal."""
    return (tuple(c.point), tuple(c.normal)) if hasattr(c, "point") else (tuple(c.x), tuple(c.n))


def _points(task: Task, rows: list[list[Any]], fingers: str) -> list[tuple[float, float]]:
    """(rho, |moment about the fingers|) of each logged reading (the runner's log columns)."""
    cols, names = log_columns(task), task.model.observation_names
    at_rho, at_moment = cols.index(names[0]), cols.index(names[task.model.moment_index(fingers)])
    return [(float(r[at_rho]), abs(float(r[at_moment]))) for r in rows]


def animate(task: Task, start: Any, policy: Any, rng: np.random.Generator, path: Path) -> str:
    """Render one MuJoCo episode (planar or spatial task) to a GIF; returns a note of what happened."""
    from crmgrasp.hardware.mujoco.render import Recorder, save_gif
    from crmgrasp.hardware.mujoco.spatial import mujoco_hand

    hand = mujoco_hand(task, start, rng)
    try:
        rec = Recorder(hand, every=8).attach()
    except CrmgraspError as exc:
        return f"no animation: {exc}"
    PolicyRunner(policy, task).run(hand, rng)
    rec.close()
    save_gif(rec.frames, path, fps=12)
    return f"{len(rec.frames)} frames"


FIGURE9_COLUMNS = [
    "trial",
    "fingers",
    "actions",
    "crms_mujoco",
    "crms_kinematic",
    "stopped",
    "success",
    "true_min_friction",
    "rho_0",
    "m_0",
    "rho_1",
    "m_1",
    "rho_last",
    "m_last",
]
"""The columns of Fig. 9 on MuJoCo's ``data.csv``: per trial its CRMs on MuJoCo and on the
kinematic hand from the same start, whether and how it stopped, the true least friction, and
the sensed points (``rho``, ``|m|``) of its first, second and last logged reading."""


def figure_9_mujoco(
    out_dir: str | Path, config: MujocoFigure9Config = MujocoFigure9Config(), *, backend: str = "auto"
) -> dict[str, Any]:
    """Run the kinematic policy on the MuJoCo hand; write CSV, PNG, per-trial logs and config."""
    config = checked_config(config, MujocoFigure9Config)
    c = config
    base = make_task(c.task)
    policy = learned_policy(base, c.policy, c.seed, c.train_trials, c.train_episodes, backend)
    task = hardware_task(base, c.palm_tolerance_deg, c.mu_goal)
    kin_task = dataclasses.replace(
        noisy_execution(base, c.sigma_n_deg, c.sigma_p, c.palm_tolerance_deg), mu_goal=c.mu_goal
    )
    runner, kin_runner = PolicyRunner(policy, task), PolicyRunner(policy, kin_task)
    rng = np.random.default_rng(c.seed)
    out = Path(out_dir)
    names, action = [n.split()[0] for n in task.action_names()], log_columns(task).index("action")
    clusters = Clusters()
    rows, errors, seconds, starts = [], SensingErrors(), [], []
    for trial in range(c.trials):
        start, fingers = thumb_far_start(base, rng, c.min_thumb_distance, c.max_thumb_distance)
        starts.append(start)
        hand = MujocoHand(task, start, rng)
        errors.add(hand.sense(), hand.true_config())
        run = runner.run(hand, rng, log=out / "logs" / f"trial{trial:02d}.csv")
        true = hand.true_config()
        mu = min_friction(true) if true is not None else math.inf
        kin = kin_runner.run(KinematicHand(kin_task, start, rng), rng)
        pts = _points(task, run.rows, fingers) or [(math.nan, math.nan)]
        clusters.add(pts)
        pts = (pts + pts[-1:])[:2] + pts[-1:]
        seconds += hand.crm_seconds
        actions = " ".join(names[r[action]] for r in run.rows if r[action] != "")
        rows.append([trial, fingers, actions, run.crms, kin.crms, run.stopped, task.grasped(mu), mu, *np.ravel(pts)])
    write_csv(out / "data.csv", FIGURE9_COLUMNS, rows)
    centroids = clusters.save(
        f"Kinematic policy on the MuJoCo hand, {c.trials} trials (paper Fig. 9)",
        "frictionless force residual rho (sensed)",
        out / "figure9_mujoco.png",
    )
    extra = {}
    if c.animate:
        extra["animation"] = animate(task, starts[0], policy, np.random.default_rng(c.seed), out / "figure9_mujoco.gif")
    more = [r[3] - r[4] for r in rows]
    summary = {
        "trials": c.trials,
        "successes": int(sum(r[6] for r in rows)),
        "mean_crms_mujoco": round(statistics.fmean(r[3] for r in rows), 3),
        "mean_crms_kinematic": round(statistics.fmean(r[4] for r in rows), 3),
        "max_extra_crms": max(more),
        "median_true_min_friction": round(float(np.median([r[7] for r in rows])), 4),
        "median_crm_seconds": round(float(np.median(seconds)), 4) if seconds else None,
        "max_crm_seconds": round(float(np.max(seconds)), 4) if seconds else None,
        **centroids,
        "contact_sensing": errors.summary(),
        **extra,
    }
    write_json(
        out / "config.json",
        {"experiment": "figure9-mujoco", "config": asdict(c), "physics": asdict(PhysicsParams()), "summary": summary},
    )
    return summary


def _random_crms_agreeing(
    task: Task, rng: np.random.Generator, n: int, errors: SensingErrors, seconds: list[float]
) -> int:
    """Of ``n`` random CRMs from random task starts on the MuJoCo hand, how many end with the
    kinematic model's error flag; the contacts sensed before and after each go to ``errors``,
    the CRMs' wall times (s) to ``seconds``."""
    agree = 0
    for _ in range(n):
        start = two_contacts(task.sample_start(rng), "the MuJoCo stand-in")
        hand = MujocoHand(task, start, rng)
        errors.add(hand.sense(), hand.true_config())
        crm = task.actions[int(rng.integers(len(task.actions)))]
        agree += hand.execute(crm) == execute_crm(task.obj, task.hand, start, crm).error
        errors.add(hand.sense(), hand.true_config())
        seconds.extend(hand.crm_seconds)
    return agree


def figure_4_mujoco(out_dir: str | Path, config: MujocoFigure4Config = MujocoFigure4Config()) -> dict[str, Any]:
    """Opposition CRMs on the MuJoCo hand and the contact-sensing accuracy; write CSV, PNG, config."""
    config = checked_config(config, MujocoFigure4Config)
    c = config
    task = hardware_task(make_task(c.task), c.palm_tolerance_deg)
    rng = np.random.default_rng(c.seed)
    rows, values, failures, errors, seconds = [], [], 0, SensingErrors(), []
    for trial in range(c.trials):
        start, fingers = long_side_start(task, rng, c.max_corner_distance, c.min_corner_distance)
        hand = MujocoHand(task, start, rng)
        errors.add(hand.sense(), hand.true_config())
        crm = CRM("b" if fingers == "a" else "a", fingers, 0.0)
        error = hand.execute(crm)
        seconds += hand.crm_seconds
        true = hand.true_config()
        errors.add(hand.sense(), true)
        mu = min_friction(true) if error == Error.NONE and true is not None else math.inf
        failures += not math.isfinite(mu)
        values.append(mu)
        x, y, yaw = hand.object_pose()
        rows.append([trial, *start.a.point, *start.b.point, str(crm), error.name.lower(), mu, x, y, yaw])
    agree = _random_crms_agreeing(task, rng, c.extra_starts, errors, seconds)
    out = Path(out_dir)
    write_csv(
        out / "data.csv",
        [
            "trial",
            "start_ax",
            "start_ay",
            "start_bx",
            "start_by",
            "crm",
            "error",
            "true_min_friction",
            "object_x",
            "object_y",
            "object_yaw",
        ],
        rows,
    )
    fig = friction_histogram(values, failures, "Opposition CRM on the MuJoCo hand (paper Fig. 4)")
    save_figure(fig, out / "figure4_mujoco.png", dpi=120)
    finite = [v for v in values if math.isfinite(v)]
    summary: dict[str, Any] = {
        "trials": c.trials,
        "failures": failures,
        "median_min_friction": round(float(np.median(finite)), 4) if finite else math.nan,
        "max_min_friction": round(float(max(finite)), 4) if finite else math.nan,
        "fraction_below_0.1": sum(v < 0.1 for v in values) / len(values),
        "median_crm_seconds": round(float(np.median(seconds)), 4),
        "max_crm_seconds": round(float(np.max(seconds)), 4),
        "contact_sensing": errors.summary(),
        "random_crms_same_error_as_kinematic": f"{agree} of {c.extra_starts}",
    }
    write_json(
        out / "config.json",
        {"experiment": "figure4-mujoco", "config": asdict(c), "physics": asdict(PhysicsParams()), "summary": summary},
    )
    return summary

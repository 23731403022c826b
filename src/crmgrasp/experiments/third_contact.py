"""A third contact: two fingers against three on the same objects and goals.

The paper expects its approach to extend "to more than two contacts with little
modification". For each pair of twin tasks (``triangles``/``triangles-3f``,
``odd-polygons``/``odd-polygons-3f``: the same family, the same CRM kinds, two or three
fingers; ``box-family``/``box-family-3f`` and ``cup-family``/``cup-family-3f``: the same
family, each hand with its own CRMs and starts; docs/families.md; and in space
``cup-3d``/``cup-3d-3f``, cups on a table, two fingers against a tripod, docs/model-3d.md)
and each goal ``mu_goal`` (0.15 and 0.05), on the same number of sampled starts: the share
of starts from which some sequence of at most ``max_steps`` CRMs grasps (the clairvoyant
search, knowing the object), and where some do, the clairvoyant bound and the belief-space
optimum (observations only), in CRMs per episode, and a learner preset (``families`` by
default: ``backoff-vi``, k = 2) learned from episodes and run from the same starts: its CRMs
per episode, success share and the least friction its final grasps need (the median), and
the first trial's policy transferred to the MuJoCo stand-in (the hand's fingertips on the
object free on the table; success: the true least friction from MuJoCo's contacts at or
below the goal). Writes ``third_contact.csv``, ``third_contact.png`` and ``summary.json``.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from crmgrasp._io import save_figure, write_csv, write_json
from crmgrasp._progress import Progress
from crmgrasp._validation import CrmgraspError
from crmgrasp.agents.presets import PRESETS
from crmgrasp.experiments.configs import CheckedConfig, checked_config
from crmgrasp.kernels import compiled_rules
from crmgrasp.planners.references import belief_optimum, clairvoyant_bound, sample_starts, ungraspable_fraction
from crmgrasp.tasks import make_task

__all__ = ["ThirdContactConfig", "third_contact"]

COLUMNS = (
    "family",
    "mu_goal",
    "fingers",
    "task",
    "starts",
    "graspable_share",
    "clairvoyant_bound",
    "belief_optimum",
    "learned_crms",
    "learned_success",
    "final_friction",
    "mujoco_success",
)


@dataclass(frozen=True)
class ThirdContactConfig(CheckedConfig):
    """Twin tasks (two fingers, three), goals, sampled starts per task and goal, the
    learner's trials and episodes per trial, MuJoCo worlds for the first trial's policy (0:
    none; none either without the extra ``crmgrasp[mujoco]``), seed, and the learner: a
    preset of ``crmgrasp learn --preset`` ([`crmgrasp.agents.presets.PRESETS`][])."""

    pairs: tuple[tuple[str, str], ...] = (
        ("triangles", "triangles-3f"),
        ("odd-polygons", "odd-polygons-3f"),
        ("box-family", "box-family-3f"),
        ("cup-family", "cup-family-3f"),
        ("cup-3d", "cup-3d-3f"),
    )
    mu_goals: tuple[float, ...] = (0.15, 0.05)
    starts: int = 100
    trials: int = 3
    episodes: int = 3000
    mujoco_worlds: int = 20
    seed: int = 0
    preset: str = "families"

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.preset not in PRESETS:
            raise CrmgraspError(f"unknown learner preset {self.preset!r}; known presets: {', '.join(PRESETS)}")

    @classmethod
    def quick(cls, seed: int = 0) -> ThirdContactConfig:
        """Triangles at 0.15 on 20 starts, 1 trial x 200 episodes, 4 MuJoCo worlds: a smoke run."""
        return cls(
            pairs=(("triangles", "triangles-3f"),),
            mu_goals=(0.15,),
            starts=20,
            trials=1,
            episodes=200,
            mujoco_worlds=4,
            seed=seed,
        )


def _row(name: str, mu: float, cfg: ThirdContactConfig) -> dict[str, Any]:
    """The references of task ``name`` at goal ``mu`` on ``cfg.starts`` sampled starts, and
    where some start can be grasped, the learner's greedy policies on those starts."""
    task = compiled_rules(dataclasses.replace(make_task(name), mu_goal=mu))  # three contacts: least friction compiled
    starts = sample_starts(task, cfg.starts, cfg.seed)
    share = 1.0 - ungraspable_fraction(task, starts)
    found = share > 0.0
    return {
        "mu_goal": mu,
        "fingers": task.model.n_contacts,
        "task": name,
        "starts": cfg.starts,
        "graspable_share": share,
        "clairvoyant_bound": clairvoyant_bound(task, starts) if found else None,
        "belief_optimum": belief_optimum(task, starts) if found else None,
        **(
            _learned(task, starts, cfg)
            if found
            else {"learned_crms": None, "learned_success": None, "final_friction": None, "mujoco_success": None}
        ),
    }


def _learned(task: Any, starts: Any, cfg: ThirdContactConfig) -> dict[str, Any]:
    """The preset ``cfg.preset``, ``cfg.trials`` x ``cfg.episodes`` task episodes, its greedy
    policies run from ``starts``: the median over trials of the mean CRMs per episode, the
    success share, and the median least friction of the final grasps."""
    from crmgrasp.experiments._episodes import greedy_records, train_preset

    agents, k = train_preset(task, cfg.preset, cfg.trials, cfg.episodes, cfg.seed)
    records = greedy_records(task, agents, starts, cfg.seed, k=k)
    finals = [task.quality(r.final) for trial in records for r in trial if r.success]
    return {
        "learned_crms": float(np.median([np.mean([len(r.actions) for r in trial]) for trial in records])),
        "learned_success": float(np.mean([r.success for trial in records for r in trial])),
        "final_friction": float(np.median(finals)) if finals else None,
        "mujoco_success": _on_mujoco(task, agents[0], k, cfg),
    }


def _on_mujoco(task: Any, agent: Any, k: int, cfg: ThirdContactConfig) -> float | None:
    """The share of ``cfg.mujoco_worlds`` MuJoCo worlds (drawn from ``cfg.seed``) that the first
    trial's greedy policy (k-order histories, ``k``) grasps, judged by the true least friction
    from MuJoCo's contacts ([`crmgrasp.experiments.physics_learning.score_on_mujoco`][]);
    ``None`` without worlds or without the extra."""
    from crmgrasp.hardware.mujoco import mujoco_available

    if cfg.mujoco_worlds == 0 or not mujoco_available():
        return None
    from crmgrasp.agents.training import encoder_for
    from crmgrasp.experiments.physics_learning import score_on_mujoco

    return float(score_on_mujoco(task, agent, encoder_for(task, k), cfg.mujoco_worlds, cfg.seed)["success"])


def third_contact(
    out_dir: str | Path, cfg: ThirdContactConfig = ThirdContactConfig(), progress: Progress | None = None
) -> dict[str, Any]:
    """Compute the table, draw it, write it; return the summary (``rows``: one per task and
    goal; ``budget``)."""
    cfg = checked_config(cfg, ThirdContactConfig)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    units = [(pair, mu, name) for pair in cfg.pairs for mu in cfg.mu_goals for name in pair]
    stage = progress.stage("third contact: references", len(units), "tasks") if progress else None
    rows = []
    for (two, _), mu, name in units:
        rows.append({"family": two, **_row(name, mu, cfg)})
        if stage is not None:
            stage.advance(1)
    if stage is not None:
        stage.end()
    write_csv(out / "third_contact.csv", list(COLUMNS), [[r[c] for c in COLUMNS] for r in rows])
    save_figure(_figure(rows, cfg), out / "third_contact.png")
    budget = (
        f"{cfg.starts} sampled starts per task and goal, seed {cfg.seed}; learner preset {cfg.preset}, "
        f"{cfg.trials} trials x {cfg.episodes} task episodes per task and goal, greedy on those starts; "
        f"the first trial's policy on {cfg.mujoco_worlds} MuJoCo worlds"
    )
    summary = {"budget": budget, "rows": rows}
    write_json(out / "summary.json", summary)
    return summary


def _figure(rows: list[dict[str, Any]], cfg: ThirdContactConfig) -> Any:
    """Left: the graspable share, two fingers against three, per family and goal. Right:
    the three-finger clairvoyant bound, belief-space optimum and learned greedy policy."""
    from matplotlib.figure import Figure

    groups = [(r["family"], r["mu_goal"]) for r in rows if r["fingers"] == 2]
    by = {(r["family"], r["mu_goal"], r["fingers"]): r for r in rows}
    x = np.arange(len(groups))
    labels = [f"{fam}\nmu_goal {mu:g}" for fam, mu in groups]
    fig = Figure(figsize=(max(10.0, 1.8 * len(groups)), 7.2), layout="constrained")
    left, right = fig.subplots(2, 1)
    for k, (fingers, color) in enumerate(((2, "tab:gray"), (3, "tab:blue"))):
        share = [100 * by[(f, m, fingers)]["graspable_share"] for f, m in groups]
        bars = left.bar(x + (k - 1) * 0.27, share, 0.27, color=color, label=f"{fingers} fingers: graspable")
        left.bar_label(bars, fmt="%.0f%%", fontsize=7)
    if any(by[(f, m, 3)]["mujoco_success"] is not None for f, m in groups):
        grasped = [100 * (by[(f, m, 3)]["mujoco_success"] or 0.0) for f, m in groups]
        label = f"3 fingers, {cfg.preset} preset on MuJoCo ({cfg.mujoco_worlds} worlds): grasped"
        bars = left.bar(x + 0.27, grasped, 0.27, color="tab:purple", label=label)
        left.bar_label(bars, fmt="%.0f%%", fontsize=7)
    left.set_xticks(x, labels, fontsize=8)
    left.set_ylim(0, 130)
    left.set_yticks(range(0, 101, 20))
    left.set_ylabel("share of starts\nor worlds (%)")
    left.set_title("what a third contact makes graspable", fontsize=10)
    left.legend(fontsize=8, loc="upper right", ncols=3)
    parts = (
        ("clairvoyant_bound", "tab:green", "clairvoyant bound"),
        ("belief_optimum", "tab:blue", "belief-space optimum"),
        ("learned_crms", "tab:orange", f"{cfg.preset} preset, median of {cfg.trials} x {cfg.episodes} episodes"),
    )
    for k, (key, color, name) in enumerate(parts):
        values = [by[(f, m, 3)][key] or 0.0 for f, m in groups]
        bars = right.bar(x + (k - 1) * 0.27, values, 0.27, color=color, label=name)
        right.bar_label(bars, fmt="%.2f", fontsize=7)
    right.set_xticks(x, labels, fontsize=8)
    right.set_ylabel("CRMs per episode,\nthree fingers")
    right.set_title("how many CRMs the grasp takes", fontsize=10)
    top = max([r[key] or 0.0 for r in rows for key, _, _ in parts if r["fingers"] == 3] + [1.0])
    right.set_ylim(0, 1.3 * top)
    right.legend(fontsize=8, loc="upper right", ncols=3)
    fig.suptitle(f"two fingers against three ({cfg.starts} sampled starts per bar, seed {cfg.seed})", fontsize=10)
    return fig

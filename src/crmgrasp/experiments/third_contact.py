"""A third contact: two fingers against three on the same objects and goals.

The paper expects its approach to extend "to more than two contacts with little
modification". For each pair of twin tasks (``triangles``/``triangles-3f``,
``odd-polygons``/``odd-polygons-3f``: the same family, the same CRM kinds, two or three
fingers; docs/families.md) and each goal ``mu_goal`` (0.15 and 0.05), on the same number
of sampled starts: the share of starts from which some sequence of at most ``max_steps``
CRMs grasps (the clairvoyant search, knowing the object), and where some do, the
clairvoyant bound and the belief-space optimum (observations only), in CRMs per episode.
Writes ``third_contact.csv``, ``third_contact.png`` and ``summary.json``.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from crmgrasp._io import save_figure, write_csv, write_json
from crmgrasp._progress import Progress
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
)


@dataclass(frozen=True)
class ThirdContactConfig:
    """Twin tasks (two fingers, three), goals, sampled starts per task and goal, seed."""

    pairs: tuple[tuple[str, str], ...] = (("triangles", "triangles-3f"), ("odd-polygons", "odd-polygons-3f"))
    mu_goals: tuple[float, ...] = (0.15, 0.05)
    starts: int = 100
    seed: int = 0

    @classmethod
    def quick(cls, seed: int = 0) -> ThirdContactConfig:
        """Triangles at 0.15 on 20 starts: a smoke run."""
        return cls(pairs=(("triangles", "triangles-3f"),), mu_goals=(0.15,), starts=20, seed=seed)


def _row(name: str, mu: float, cfg: ThirdContactConfig) -> dict[str, Any]:
    """The references of task ``name`` at goal ``mu`` on ``cfg.starts`` sampled starts."""
    task = dataclasses.replace(make_task(name), mu_goal=mu)
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
    }


def third_contact(
    out_dir: str | Path, cfg: ThirdContactConfig = ThirdContactConfig(), progress: Progress | None = None
) -> dict[str, Any]:
    """Compute the table, draw it, write it; return the summary (``rows``: one per task and
    goal; ``budget``)."""
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
    summary = {"budget": f"{cfg.starts} sampled starts per task and goal, seed {cfg.seed}", "rows": rows}
    write_json(out / "summary.json", summary)
    return summary


def _figure(rows: list[dict[str, Any]], cfg: ThirdContactConfig) -> Any:
    """Left: the graspable share, two fingers against three, per family and goal. Right:
    the three-finger clairvoyant bound and belief-space optimum."""
    from matplotlib.figure import Figure

    groups = [(r["family"], r["mu_goal"]) for r in rows if r["fingers"] == 2]
    by = {(r["family"], r["mu_goal"], r["fingers"]): r for r in rows}
    x = np.arange(len(groups))
    labels = [f"{fam}\nmu_goal {mu:g}" for fam, mu in groups]
    fig = Figure(figsize=(10, 4.2), layout="constrained")
    left, right = fig.subplots(1, 2)
    for k, (fingers, color) in enumerate(((2, "tab:gray"), (3, "tab:blue"))):
        share = [100 * by[(f, m, fingers)]["graspable_share"] for f, m in groups]
        bars = left.bar(x + (k - 0.5) * 0.38, share, 0.38, color=color, label=f"{fingers} fingers")
        left.bar_label(bars, fmt="%.0f%%", fontsize=8)
    left.set_xticks(x, labels, fontsize=8)
    left.set_ylim(0, 130)
    left.set_yticks(range(0, 101, 20))
    left.set_ylabel("starts some CRM sequence grasps (%)")
    left.set_title("what a third contact makes graspable", fontsize=10)
    left.legend(fontsize=8, loc="upper center", ncols=2)
    for k, (key, color, name) in enumerate(
        (
            ("clairvoyant_bound", "tab:green", "clairvoyant bound"),
            ("belief_optimum", "tab:blue", "belief-space optimum"),
        )
    ):
        values = [by[(f, m, 3)][key] or 0.0 for f, m in groups]
        bars = right.bar(x + (k - 0.5) * 0.38, values, 0.38, color=color, label=name)
        right.bar_label(bars, fmt="%.2f", fontsize=8)
    right.set_xticks(x, labels, fontsize=8)
    right.set_ylabel("CRMs per episode, three fingers")
    right.set_title("how many CRMs the grasp takes", fontsize=10)
    right.set_ylim(0, 1.25 * max([r["belief_optimum"] or 0.0 for r in rows] + [1.0]))
    right.legend(fontsize=8, loc="upper center", ncols=2)
    fig.suptitle(f"two fingers against three ({cfg.starts} sampled starts per bar, seed {cfg.seed})", fontsize=10)
    return fig

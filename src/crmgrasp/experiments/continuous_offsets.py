"""What the hand-picked CRMs cost: the best policy over grids of offsets, and what a learner gets.

The paper's action space is ``C x C x [-r_max, r_max]``; its experiments use four CRMs picked
by hand. Per task, on the same sampled starts (worlds on a family task), this computes the
belief-space optimum and the clairvoyant bound with the task's own CRMs and with every
contact pair on grids of ``n`` offsets per coordinate over ``[-r_max, r_max]``
([`crmgrasp.tasks.offsets.offset_grid`][]). Odd grids nest (5 in 9 in 17 in 33, each holding
``r = 0``), so their optimum can only fall as the grid refines; even grids leave out
``r = 0``, the offset that opposes a contact straight across. Then model-vi (k = 1) learns
from episodes on the task's CRMs and on one grid, and refine-vi
([`crmgrasp.agents.refine.RefineVI`][]: it chooses its offsets, refining a coarse grid
around the best offset of each history) on a fine dyadic grid, all with the same budget;
each greedy policy runs from the same sampled starts as the references.

Writes ``continuous_offsets.csv``, ``continuous_offsets.png`` and ``summary.json``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from crmgrasp._io import save_figure, write_csv, write_json
from crmgrasp._progress import Progress
from crmgrasp.experiments.configs import CheckedConfig, checked_config
from crmgrasp.planners.references import belief_optimum, clairvoyant_bound, sample_starts
from crmgrasp.tasks import Task, make_task
from crmgrasp.tasks.offsets import offset_grid

__all__ = ["ContinuousOffsetsConfig", "continuous_offsets"]

COLUMNS = ("task", "crms", "grid", "offsets_per_pair", "actions", "starts", "clairvoyant_bound", "belief_optimum")
LEARNED = (
    "task",
    "learner",
    "crms",
    "actions",
    "offsets_per_pair",
    "crms_tried",
    "trials",
    "episodes",
    "greedy_mean",
    "greedy_low",
    "greedy_high",
    "success",
)


@dataclass(frozen=True)
class ContinuousOffsetsConfig(CheckedConfig):
    """Tasks; grids (offsets per coordinate: ``grids`` in the plane, ``spatial_grids`` in
    space, where a pair gets ``n**2``); sampled starts per task (the references' and the
    learned policies' evaluation); model-vi's grid (per coordinate, planar and spatial);
    refine-vi's fine grid and the level it starts from (``2**level + 1`` offsets per
    coordinate: five in the plane, three in space); trials and training episodes per trial;
    seed."""

    tasks: tuple[str, ...] = ("paper-box", "box-family", "u-handle", "notch-or-box", "cup-3d")
    grids: tuple[int, ...] = (4, 5, 9, 17, 33)
    spatial_grids: tuple[int, ...] = (2, 3, 5, 7)
    starts: int = 100
    learn_grid: int = 9
    learn_spatial_grid: int = 3
    refine_grid: int = 33
    refine_spatial_grid: int = 9
    refine_start_level: int = 2
    refine_spatial_start_level: int = 1
    trials: int = 5
    episodes: int = 2000
    seed: int = 0

    @classmethod
    def quick(cls, seed: int = 0) -> ContinuousOffsetsConfig:
        """paper-box and u-handle, grids 4, 5 and 9, 30 starts, 2 trials x 200 episodes."""
        return cls(
            tasks=("paper-box", "u-handle"),
            grids=(4, 5, 9),
            starts=30,
            trials=2,
            episodes=200,
            seed=seed,
        )


def _grids(task: Task, cfg: ContinuousOffsetsConfig) -> tuple[int, ...]:
    return cfg.grids if task.model.offset_dim == 1 else cfg.spatial_grids


def _references(task: Task, label: str, n: int | None, cfg: ContinuousOffsetsConfig) -> dict[str, Any]:
    """The two references of ``task`` on ``cfg.starts`` starts (the same worlds for every
    grid: drawing them does not depend on the CRMs)."""
    starts = sample_starts(task, cfg.starts, cfg.seed)
    t0 = time.perf_counter()
    row = {
        "crms": label,
        "grid": n,
        "offsets_per_pair": None if n is None else n**task.model.offset_dim,
        "actions": len(task.actions),
        "starts": cfg.starts,
        "clairvoyant_bound": clairvoyant_bound(task, starts),
        "belief_optimum": belief_optimum(task, starts),
    }
    row["seconds"] = round(time.perf_counter() - t0, 2)
    return row


def _learned(
    task: Task, n: int | None, cfg: ContinuousOffsetsConfig, learner: str = "model-vi", **params: object
) -> dict[str, Any]:
    """``learner`` (k = 1, on the mirror quotient where the task declares a symmetry; model-vi
    by default) trained on ``task`` (its own CRMs for ``n`` None, else a grid of ``n`` offsets
    per coordinate), its greedy policy run on the references' sampled starts: CRMs per
    episode per trial, their mean and a bootstrap 95% interval over trials (none below 5),
    the success rate, and the distinct CRMs tried in any history (mean over trials). The
    same starts as the optimum, so the two compare without sampling noise."""
    from crmgrasp.experiments._episodes import greedy_records, train_model_vi
    from crmgrasp.experiments.stats import bootstrap_ci

    agents = train_model_vi(task, cfg.trials, cfg.episodes, cfg.seed, learner, **params)
    records = greedy_records(task, agents, sample_starts(task, cfg.starts, cfg.seed), cfg.seed)
    per_trial = np.array([np.mean([len(r.actions) for r in trial]) for trial in records])
    low, high = (None if np.isnan(v) else float(v) for v in bootstrap_ci(per_trial, seed=cfg.seed))
    tried = [len(set().union(*agent.tried.values())) for agent in agents]  # type: ignore[attr-defined]
    return {
        "learner": learner,
        "crms": "hand-picked" if n is None else f"grid {n}",
        "actions": len(task.actions),
        "offsets_per_pair": None if n is None else n**task.model.offset_dim,
        "crms_tried": float(np.mean(tried)),
        "trials": cfg.trials,
        "episodes": cfg.episodes,
        "per_trial": [float(v) for v in per_trial],
        "greedy_mean": float(per_trial.mean()),
        "greedy_low": low,
        "greedy_high": high,
        "success": float(np.mean([r.success for trial in records for r in trial])),
    }


def _learners(task: Task, cfg: ContinuousOffsetsConfig) -> list[tuple[Task, int | None, str, dict[str, object]]]:
    """What learns on ``task``: model-vi on its own CRMs and on a grid, refine-vi on a fine
    grid from its coarse start (task, offsets per coordinate or None, learner, parameters)."""
    spatial = task.model.offset_dim > 1
    n = cfg.learn_spatial_grid if spatial else cfg.learn_grid
    fine = cfg.refine_spatial_grid if spatial else cfg.refine_grid
    start = cfg.refine_spatial_start_level if spatial else cfg.refine_start_level
    return [
        (task, None, "model-vi", {}),
        (offset_grid(task, n), n, "model-vi", {}),
        (offset_grid(task, fine), fine, "refine-vi", {"start_level": start}),
    ]


def continuous_offsets(
    out_dir: str | Path, cfg: ContinuousOffsetsConfig = ContinuousOffsetsConfig(), progress: Progress | None = None
) -> dict[str, Any]:
    """Compute the tables, draw them, write them; return the summary (``rows``: references
    per task and CRM set; ``learned``: model-vi per task on its CRMs and on a grid, refine-vi
    on a fine grid;
    ``budget``)."""
    cfg = checked_config(cfg, ContinuousOffsetsConfig)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    tasks = [make_task(name) for name in cfg.tasks]
    units = sum(len(_grids(t, cfg)) + 4 for t in tasks)
    stage = progress.stage("continuous offsets", units, "units") if progress else None
    rows: list[dict[str, Any]] = []
    learned: list[dict[str, Any]] = []
    for task in tasks:
        sets = [(task, "hand-picked", None)] + [(offset_grid(task, n), f"grid {n}", n) for n in _grids(task, cfg)]
        for t, label, n in sets:
            rows.append({"task": task.name, **_references(t, label, n, cfg)})
            if stage is not None:
                stage.advance(1)
        for t, n, learner, params in _learners(task, cfg):
            learned.append({"task": task.name, **_learned(t, n, cfg, learner, **params)})
            if stage is not None:
                stage.advance(1)
    if stage is not None:
        stage.end()
    write_csv(out / "continuous_offsets.csv", list(COLUMNS), [[r[c] for c in COLUMNS] for r in rows])
    write_csv(out / "continuous_offsets_learned.csv", list(LEARNED), [[r[c] for c in LEARNED] for r in learned])
    save_figure(_figure(rows, learned, cfg), out / "continuous_offsets.png")
    budget = (
        f"{cfg.starts} sampled starts per task, seed {cfg.seed}, for the references and the greedy policies; "
        f"model-vi k=1 (mirror quotient where declared), {cfg.trials} trials x {cfg.episodes} task episodes "
        "per CRM set; "
        f"refine-vi the same on grids {cfg.refine_grid} (planar, from {2**cfg.refine_start_level + 1}) and "
        f"{cfg.refine_spatial_grid} x {cfg.refine_spatial_grid} (spatial, from "
        f"{2**cfg.refine_spatial_start_level + 1} x {2**cfg.refine_spatial_start_level + 1})"
    )
    summary = {"budget": budget, "rows": rows, "learned": learned}
    write_json(out / "summary.json", summary)
    return summary


def _panel(ax: Any, name: str, mine: list[dict[str, Any]], mine_learned: list[dict[str, Any]]) -> None:
    """One task's panel of [`_figure`][] on ``ax``: its optima per grid (``mine``) and its
    learners' greedy means (``mine_learned``)."""
    hand = next(r for r in mine if r["grid"] is None)["belief_optimum"]
    top = max([1.6 * hand] + [1.1 * r["greedy_mean"] for r in mine_learned])
    ax.axhline(hand, color="tab:gray", lw=1, label="optimum, hand-picked CRMs")
    grids = [r for r in mine if r["grid"] is not None]
    odd = [r for r in grids if r["grid"] % 2]
    ax.plot(
        [r["offsets_per_pair"] for r in odd],
        [r["belief_optimum"] for r in odd],
        "o-",
        color="tab:blue",
        label="optimum, odd grid (holds r = 0)",
    )
    for r in (r for r in grids if not r["grid"] % 2):
        y = min(r["belief_optimum"], 0.97 * top)
        ax.plot([r["offsets_per_pair"]], [y], "x", color="tab:red", label="optimum, even grid")
        if r["belief_optimum"] > top:
            ax.annotate(
                f"{r['belief_optimum']:.3g}",
                (r["offsets_per_pair"], y),
                fontsize=6,
                color="tab:red",
                xytext=(3, -9),
                textcoords="offset points",
            )
    for r in mine_learned:
        at = r["offsets_per_pair"] or 1
        refined = r["learner"] == "refine-vi"
        label = "model-vi, hand-picked CRMs" if at == 1 else "model-vi, on a grid"
        ax.plot(
            [at],
            [r["greedy_mean"]],
            "P" if refined else "*",
            ms=9 if refined else 11,
            color="tab:green" if refined else "tab:gray" if at == 1 else "tab:blue",
            label="refine-vi, offsets chosen on its finest grid" if refined else label,
        )
    ticks = [1, *sorted({r["offsets_per_pair"] for r in [*grids, *mine_learned] if r["offsets_per_pair"]})]
    ax.set_xscale("log", base=2)
    ax.set_xticks(ticks, ["hand", *map(str, ticks[1:])], fontsize=7)
    ax.minorticks_off()
    ax.set_ylim(0.85 * min(r["belief_optimum"] for r in mine), top)
    ax.set_title(name, fontsize=9)
    ax.set_xlabel("offsets per contact pair", fontsize=8)
    ax.tick_params(labelsize=7)


def _figure(rows: list[dict[str, Any]], learned: list[dict[str, Any]], cfg: ContinuousOffsetsConfig) -> Any:
    """One panel per task: the belief-space optimum against offsets per pair (odd grids, which
    hold ``r = 0``, joined; even grids as crosses, drawn at the top edge with their value when
    beyond it), the hand-picked CRMs' optimum as a line, model-vi's greedy mean on each CRM
    set as stars (the hand-picked set's at the left, "hand") and refine-vi's as a plus at its
    finest grid."""
    from matplotlib.figure import Figure

    names = list(dict.fromkeys(r["task"] for r in rows))
    fig = Figure(figsize=(max(6.0, 2.9 * len(names)), 4.2), layout="constrained")
    axes = np.atleast_1d(fig.subplots(1, len(names)))
    for ax, name in zip(axes, names, strict=True):
        _panel(ax, name, [r for r in rows if r["task"] == name], [r for r in learned if r["task"] == name])
    axes[0].set_ylabel("CRMs per episode")
    handles, labels = axes[0].get_legend_handles_labels()
    unique = dict(zip(labels, handles, strict=True))
    fig.legend(unique.values(), unique.keys(), loc="outside lower center", ncols=3, fontsize=7)
    fig.suptitle(
        f"the price of hand-picked CRMs: {cfg.starts} sampled starts per point, the same for every point;\n"
        f"model-vi and refine-vi k=1: {cfg.trials} trials x {cfg.episodes} task episodes, greedy on those starts",
        fontsize=9,
    )
    return fig

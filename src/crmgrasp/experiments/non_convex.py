"""A non-convex object: the learned strategy on U handles, drawn like Figure 8.

``u-handle`` draws U-shaped handles (outer width, height and bar thickness from
ranges, any pose). A learner (``model-vi``, k = 1, mirror quotient) trains on the
family; its greedy policy runs on held-out handles beside the belief-space optimum of
those worlds. A grasp is *inside the handle* when a contact lies on one of the three
edges that face the opening (edges 3, 4 and 5 of the U: the inner sides of the bars
and the bottom of the slot); ``inside_share`` is the share of the policy's grasps with
a contact there. Writes ``non_convex.png`` (three rollouts of the policy, one per row,
each CRM a panel), ``non_convex.gif`` (the first rollout animated), ``rollouts.csv``
and ``summary.json``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from crmgrasp._io import atomic_path, save_figure, write_csv, write_json
from crmgrasp._progress import Progress
from crmgrasp.agents.base import Agent
from crmgrasp.agents.training import encoder_for, rollout
from crmgrasp.experiments._episodes import MODEL_VI_LABEL, greedy_records, train_model_vi
from crmgrasp.experiments.configs import CheckedConfig, checked_config
from crmgrasp.model.contacts import Config
from crmgrasp.model.geometry import Polygon
from crmgrasp.planners.references import belief_optimum, clairvoyant_bound, sample_starts
from crmgrasp.plotting import rollout_animation, rollout_panels
from crmgrasp.tasks import World, make_task

__all__ = ["NonConvexConfig", "non_convex", "INNER_EDGES", "inside"]

INNER_EDGES = (3, 4, 5)
"""The U's edges that face its opening (vertex order of
[`UHandleFamily`][crmgrasp.model.families.UHandleFamily], kept by the pose)."""


def inside(obj: Polygon, config: Config) -> bool:
    """Whether a contact of ``config`` lies on an inner edge of the U ``obj``."""
    return any(obj.edge_index((c.x, c.y)) in INNER_EDGES for c in config)


@dataclass(frozen=True)
class NonConvexConfig(CheckedConfig):
    """Task, learner budget, held-out worlds, seed."""

    task: str = "u-handle"
    trials: int = 3
    episodes: int = 600
    heldout: int = 400
    seed: int = 0

    @classmethod
    def quick(cls, seed: int = 0) -> NonConvexConfig:
        """A small budget for smoke runs."""
        return cls(trials=2, episodes=150, heldout=100, seed=seed)


def non_convex(
    out_dir: str | Path, cfg: NonConvexConfig = NonConvexConfig(), progress: Progress | None = None
) -> dict[str, Any]:
    """Train, evaluate, draw; return the summary (``learner_mean_crms``,
    ``belief_optimum``, ``clairvoyant_bound``, ``success_rate``, ``inside_share``,
    ``gap_to_optimum``)."""
    cfg = checked_config(cfg, NonConvexConfig)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    task = make_task(cfg.task)
    stage = progress.stage(f"non-convex: {task.name}", 3, "stages") if progress else None
    agents = train_model_vi(task, cfg.trials, cfg.episodes, cfg.seed)
    if stage is not None:
        stage.advance(1)
    worlds: list[World] = sample_starts(task, cfg.heldout, cfg.seed + 1)  # type: ignore[assignment]
    per_agent = greedy_records(task, agents, worlds, cfg.seed)
    records = [r for rs in per_agent for r in rs]
    best = min(range(len(agents)), key=lambda t: np.mean([len(r.actions) for r in per_agent[t]]))
    grasps = [(w, r.final) for w, r in zip(worlds, per_agent[best], strict=True) if r.success]
    summary: dict[str, Any] = {
        "task": task.name,
        "learner": MODEL_VI_LABEL,
        "budget": f"{cfg.trials} trials x {cfg.episodes} episodes; {cfg.heldout} held-out worlds; seed {cfg.seed}",
        "learner_mean_crms": float(np.mean([len(r.actions) for r in records])),
        "success_rate": float(np.mean([r.success for r in records])),
        "belief_optimum": belief_optimum(task, worlds),
        "clairvoyant_bound": clairvoyant_bound(task, worlds),
        "inside_share": float(np.mean([inside(w.task.obj, c) for w, c in grasps])) if grasps else 0.0,  # type: ignore[arg-type]
    }
    summary["gap_to_optimum"] = summary["learner_mean_crms"] / summary["belief_optimum"] - 1.0
    if stage is not None:
        stage.advance(1)
    _draw(out, task, agents[best], worlds, cfg.seed)
    write_json(out / "summary.json", summary)
    if stage is not None:
        stage.advance(1)
        stage.end()
    return summary


def _draw(out: Path, task: Any, agent: Agent, worlds: Sequence[World], seed: int) -> None:
    """Three rollouts of ``agent`` on one held-out handle (the first world's): starts on
    it whose policy grasps in one, two and three or four CRMs (fewer rows if 300 starts
    give none), as panels and, the longest, as a GIF."""
    encoder = encoder_for(task, 1)
    handle = worlds[0].task
    rng = np.random.default_rng(seed)
    chosen: dict[int, list[Any]] = {}
    for _ in range(300):
        steps, ok = rollout(handle, agent, encoder, handle.sample_start(rng), np.random.default_rng(seed))
        n = min(len(steps), 3)
        if ok and len(steps) <= 4 and n not in chosen:
            chosen[n] = steps
        if len(chosen) == 3:
            break
    names = task.action_names()
    rows_csv = [
        [n, i + 1, names[st.action], st.outcome.error.name.lower(), round(st.min_friction, 6)]
        for n, steps in sorted(chosen.items())
        for i, st in enumerate(steps)
    ]
    write_csv(out / "rollouts.csv", ["row", "crm", "action", "error", "min_friction_after"], rows_csv)
    if not chosen:
        return
    rows = [(f"grasped in {len(st)} CRM{'s' if len(st) > 1 else ''}", st) for _, st in sorted(chosen.items())]
    save_figure(rollout_panels(handle.obj, task.hand, rows, names), out / "non_convex.png")
    longest = rows[-1][1]
    with atomic_path(out / "non_convex.gif") as tmp:
        rollout_animation(handle.obj, task.hand, longest, names, tmp, label=f"{task.name}, a held-out handle")

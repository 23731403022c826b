"""A k-order policy planned on sampled worlds, measured on held-out ones (``crmgrasp plan``).

[`plan_korder`][] runs [`korder_search`][crmgrasp.planners.korder.korder_search] (from the
belief-optimal policy, or blank: a learner from episodes) on ``worlds`` sampled starts
(a family task: worlds, an object and a start each), then evaluates the policy it
returns through the learners' own greedy evaluation
([`greedy_records`][crmgrasp.experiments._episodes.greedy_records]) on ``heldout`` other worlds,
against the belief-space optimum and the clairvoyant bound of those worlds. The policy is
a [`GreedyPolicy`][crmgrasp.agents.policy.GreedyPolicy] (``policy.json``): ``evaluate``, ``run``
and the environments take it like a learned one.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import numpy as np

from crmgrasp._io import write_json
from crmgrasp._progress import Progress
from crmgrasp._validation import integer
from crmgrasp.agents.policy import GreedyPolicy
from crmgrasp.experiments._episodes import greedy_records
from crmgrasp.planners.korder import korder_search
from crmgrasp.planners.references import belief_optimum, clairvoyant_bound, sample_starts
from crmgrasp.tasks import Task

__all__ = ["plan_korder"]


def plan_korder(
    task: Task,
    *,
    worlds: int = 1000,
    k: int = 1,
    heldout: int = 400,
    seed: int = 0,
    init: str = "belief",
    out_dir: str | Path | None = None,
    progress: Progress | None = None,
) -> tuple[GreedyPolicy, dict[str, Any]]:
    """Search on ``worlds`` starts (seed ``seed``) from ``init`` (``"belief"``: plan;
    ``"blank"``: learn from episodes), evaluate on ``heldout`` (seed ``seed + 1``); return
    the policy and the summary (also written to ``out_dir`` with ``policy.json``;
    ``planned_belief_optimum`` is None with ``init="blank"``)."""
    integer(worlds, "worlds", 1, 1_000_000)
    integer(heldout, "heldout", 1, 1_000_000)
    stage = progress.stage(f"plan {task.name}", 3, "stages") if progress else None
    t0 = time.perf_counter()
    policy, value, planned_opt, episodes = korder_search(task, sample_starts(task, worlds, seed), k, init=init)
    if stage is not None:
        stage.advance(1)
    held = sample_starts(task, heldout, seed + 1)
    (records,) = greedy_records(task, [policy], held, seed, k=k)
    mean = float(np.mean([len(r.actions) for r in records]))
    if stage is not None:
        stage.advance(1)
    opt = belief_optimum(task, held)
    summary: dict[str, Any] = {
        "task": task.name,
        "k": k,
        "init": init,
        "worlds": worlds,
        "episodes": episodes,
        "heldout": heldout,
        "seed": seed,
        "planned_mean_cost": value,
        "planned_belief_optimum": planned_opt,
        "heldout_mean_crms": mean,
        "heldout_success_rate": float(np.mean([r.success for r in records])),
        "belief_optimum": opt,
        "clairvoyant_bound": clairvoyant_bound(task, held),
        "gap_to_optimum": mean / opt - 1.0,
        "seconds": round(time.perf_counter() - t0, 3),
    }
    if stage is not None:
        stage.end()
    if out_dir is not None:
        policy.save(Path(out_dir) / "policy.json")
        write_json(Path(out_dir) / "summary.json", summary)
    return policy, summary

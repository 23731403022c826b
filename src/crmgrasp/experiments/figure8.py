"""Paper Figure 8: the grasp strategies the learned policy executes.

Three starts on paper-box (noise off), drawn CRM by CRM:

* two aliased mirror starts near a corner (both moments below 0.10: the same
  observation), contact a on the short side in one and on the long side in the
  other. The policy opposes one contact; where that fails with an aperture error
  it opposes the other (the on-failure switch);
* a start whose long-side contact is 0.14 from the corner: opposing it directly
  would hit the palm, so the policy first moves it toward the corner (C3 or C4),
  then opposes it with the other contact.

Writes ``figure8.png`` (one row per start), ``figure8.gif`` (the far start,
animated), ``rollouts.csv`` and ``config.json``.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from crmgrasp._io import atomic_path, save_figure, write_csv, write_json
from crmgrasp.agents.training import rollout
from crmgrasp.experiments._policy import learned_policy
from crmgrasp.experiments.configs import CheckedConfig, checked_config
from crmgrasp.plotting import rollout_animation, rollout_panels
from crmgrasp.tasks import make_task

__all__ = ["Figure8Config", "figure_8_strategies", "FIGURE8_STARTS"]

FIGURE8_STARTS: dict[str, tuple[tuple[float, float], tuple[float, float]]] = {
    "near corner, a on the short side": ((-0.15, -0.02), (-0.10, -0.05)),
    "near corner, a on the long side (mirror)": ((0.10, -0.05), (0.15, -0.02)),
    "long-side contact 0.14 from the corner": ((-0.15, -0.02), (-0.01, -0.05)),
}
"""Start label -> points for contacts a and b (projected onto the box)."""


@dataclass(frozen=True)
class Figure8Config(CheckedConfig):
    """Parameters of Figure 8."""

    task: str = "paper-box"
    seed: int = 0
    policy: str | None = None
    """Policy file to execute; None trains the paper's SARSA first."""
    train_trials: int = 5
    """Trials of SARSA when training (the best trial's policy is used)."""
    train_episodes: int = 2000


def figure_8_strategies(
    out_dir: str | Path, config: Figure8Config = Figure8Config(), *, backend: str = "auto"
) -> dict[str, Any]:
    """Execute the learned policy from the three starts and draw them."""
    config = checked_config(config, Figure8Config)
    task = make_task(config.task)
    policy = learned_policy(task, config.policy, config.seed, config.train_trials, config.train_episodes, backend)
    rng = np.random.default_rng(config.seed)
    names = task.action_names()
    rows, csv_rows, summary = [], [], {}
    for label, (pa, pb) in FIGURE8_STARTS.items():
        start = task.hand.contact(task.obj, pa, pb)
        steps, _ = rollout(task, policy, policy.encoder, start, rng)
        rows.append((label, steps))
        summary[label] = " ".join(f"{names[s.action].split()[0]}:{s.outcome.error.name.lower()}" for s in steps)
        for i, s in enumerate(steps):
            csv_rows.append(
                [
                    label,
                    i + 1,
                    names[s.action],
                    s.outcome.error.name.lower(),
                    *(v for c in s.config for v in c.point),
                    *(v for c in s.outcome.config for v in c.point),
                    s.min_friction,
                ]
            )
    out = Path(out_dir)
    write_csv(
        out / "rollouts.csv",
        [
            "start",
            "step",
            "crm",
            "error",
            "ax",
            "ay",
            "bx",
            "by",
            "new_ax",
            "new_ay",
            "new_bx",
            "new_by",
            "min_friction",
        ],
        csv_rows,
    )
    save_figure(rollout_panels(task.obj, task.hand, rows, names), out / "figure8.png", dpi=100)
    with atomic_path(out / "figure8.gif") as tmp:
        rollout_animation(task.obj, task.hand, rows[-1][1], names, tmp, label=f"start: {rows[-1][0]}")
    write_json(out / "config.json", {"experiment": "figure8", "config": asdict(config), "summary": summary})
    return summary

"""model-vi on a grid of offsets with the continuous-offsets target's budget of 5,000 episodes.

``crmgrasp reproduce continuous-offsets`` learns from 2,000 episodes per trial. This script
reruns its learner (model-vi, k = 1, mirror quotient where declared, 5 trials) with the
issue's budget, 5,000 task episodes per trial, on the U handle (grid of 9 offsets per pair)
and cup-3d (3 x 3 per pair), and runs each greedy policy from the optimum's own 100 starts.

Prints one JSON object: per task, CRMs per episode per trial, their median, the grid's
belief-space optimum on those starts and the median's gap to it. Usage:
``python benchmarks/offset_learning.py [EPISODES]`` (default 5000; about 8 minutes on 2 cores).
"""

from __future__ import annotations

import json
import sys
from typing import Any

import numpy as np

from crmgrasp.experiments.continuous_offsets import ContinuousOffsetsConfig, _learned
from crmgrasp.planners.references import belief_optimum, sample_starts
from crmgrasp.tasks import make_task
from crmgrasp.tasks.offsets import offset_grid

GRIDS = {"u-handle": 9, "cup-3d": 3}


def main(episodes: int = 5000, trials: int = 5, starts: int = 100) -> dict[str, Any]:
    cfg = ContinuousOffsetsConfig(trials=trials, episodes=episodes, starts=starts)
    out: dict[str, Any] = {"episodes": episodes, "trials": trials, "starts": starts}
    for name, n in GRIDS.items():
        task = offset_grid(make_task(name), n)
        optimum = belief_optimum(task, sample_starts(task, starts, cfg.seed))
        row = _learned(task, task.name, cfg)
        median = float(np.median(row["per_trial"]))
        out[task.name] = {
            "per_trial": row["per_trial"],
            "median": median,
            "optimum": optimum,
            "gap": round(median / optimum - 1.0, 4),
        }
    return out


if __name__ == "__main__":
    print(json.dumps(main(*[int(a) for a in sys.argv[1:2]]), indent=2))

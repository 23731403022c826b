"""Family tasks on the fast path: SARSA on ``box-family`` against ``paper-box``.

A family task draws a new object each episode and builds that object's compiled kernel
(:class:`crmgrasp.kernels.family.FamilyKernel`); this measures what that costs. Both
runs: the paper's SARSA (k = 2), 20 trials x 2,000 episodes, 1,000 evaluation episodes
per trial, ``--jobs 2`` (the issue's target: box-family under 30 s on 2 cores).

Each is timed ``REPEATS`` times, alternating, and the least time of each is kept (this
machine's timings vary by tens of percent between runs; the least is the one least
disturbed). Prints one JSON object: the seconds of each, every run's seconds, and
``family_over_paper_box`` (the ratio of the least times, the peer measured in the same run).

Usage: ``python benchmarks/bench_family.py [JOBS] [REPEATS]`` (defaults 2 and 3).
"""

from __future__ import annotations

import json
import sys
import time

from crmgrasp.experiments.learning import LearnerSpec, learn
from crmgrasp.tasks import make_task


def _seconds(task_name: str, jobs: int) -> float:
    t0 = time.perf_counter()
    learn(
        make_task(task_name), LearnerSpec("sarsa", 2), trials=20, episodes=2000, seed=0, eval_episodes=1000, jobs=jobs
    )
    return time.perf_counter() - t0


def main(jobs: int = 2, repeats: int = 3) -> dict:
    _seconds("paper-box", 1)  # compile and warm caches first
    runs = [(_seconds("paper-box", jobs), _seconds("box-family", jobs)) for _ in range(repeats)]
    paper, family = min(r[0] for r in runs), min(r[1] for r in runs)
    return {
        "jobs": jobs,
        "paper_box_seconds": round(paper, 2),
        "box_family_seconds": round(family, 2),
        "runs": [[round(p, 2), round(f, 2)] for p, f in runs],
        "family_over_paper_box": round(family / paper, 2),
    }


if __name__ == "__main__":
    print(json.dumps(main(*(int(a) for a in sys.argv[1:3])), indent=2))

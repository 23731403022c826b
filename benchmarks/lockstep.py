"""Lockstep against sequential training: the numbers behind README "lockstep".

Times the paper's SARSA (training only, no evaluation) sequentially
(``train_trials``) and in lockstep (``train_trials_lockstep``, one batched
simulator call per step for all trials mid-episode) at two sizes, 1,000 trials x
100 episodes and 20 trials x 2,000 episodes, and checks that both give the same
curves. Minimum of 3 runs each; prints one JSON object (seconds). Lockstep runs on
the compiled kernel (``backend="numba"``).

Usage: ``python benchmarks/lockstep.py``.
"""

import json
import time

import numpy as np

from crmgrasp import paper_box
from crmgrasp.agents.lockstep import train_trials_lockstep
from crmgrasp.agents.training import train_trials


def _best(fn, runs: int = 3) -> tuple[float, object]:
    best, out = float("inf"), None
    for _ in range(runs):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return round(best, 2), out


def main() -> dict:
    task = paper_box()
    res: dict = {"backend": "numba"}
    for trials, episodes in ((1000, 100), (20, 2000)):
        kw = {"trials": trials, "episodes": episodes, "seed": 0, "eval_episodes": 0}
        seq_s, seq = _best(lambda kw=kw: train_trials(task, "sarsa", **kw))
        lock_s, lock = _best(lambda kw=kw: train_trials_lockstep(task, "sarsa", **kw, backend="numba"))
        assert np.array_equal(seq.steps, lock.steps)  # type: ignore[attr-defined]
        res[f"{trials}x{episodes}"] = {"sequential_s": seq_s, "lockstep_s": lock_s}
    print(json.dumps(res, indent=2))
    return res


if __name__ == "__main__":
    main()

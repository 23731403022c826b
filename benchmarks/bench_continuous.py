"""The continuous-action environment step against the discrete one, in one process.

Per task, steps ``ContinuousCRMEnv`` (a contact pair and a real offset per CRM) and
``CRMGraspEnv`` (an index into the task's CRMs) on the same kernel (backend ``auto``) with
random actions drawn before the clock starts, resets timed apart, and reports microseconds
per step and their ratio. The target (issue: the paper's full action space): continuous
step at most 1.2x the discrete one. Rounds alternate the two environments and the median
round is reported.

Prints one JSON object. Usage: ``python benchmarks/bench_continuous.py [STEPS] [ROUNDS]``
(default 4000 steps, 5 rounds).
"""

from __future__ import annotations

import json
import statistics
import sys
import time
from typing import Any

import numpy as np

from crmgrasp.envs import ContinuousCRMEnv, CRMGraspEnv

TASKS = ("paper-box", "u-handle", "cup-3d")


def _seconds_per_step(env: Any, actions: list[Any]) -> float:
    env.reset(seed=0)
    stepping = 0.0
    for a in actions:
        t0 = time.perf_counter()
        _, _, terminated, truncated, _ = env.step(a)
        stepping += time.perf_counter() - t0
        if terminated or truncated:
            env.reset()
    return stepping / len(actions)


def _actions(env: ContinuousCRMEnv, steps: int) -> tuple[list[int], list[dict[str, Any]]]:
    rng = np.random.default_rng(0)
    discrete = rng.integers(len(env.task.actions), size=steps).tolist()
    pairs = rng.integers(len(env.ranges), size=steps).tolist()
    low, high = env.action_space["r"].low, env.action_space["r"].high  # type: ignore[index]
    offsets = rng.uniform(low, high, size=(steps, len(low)))
    return discrete, [{"pair": p, "r": r} for p, r in zip(pairs, offsets, strict=True)]


def main(steps: int = 4000, rounds: int = 5) -> dict[str, Any]:
    out: dict[str, Any] = {"steps": steps, "rounds": rounds}
    for name in TASKS:
        cont, disc = ContinuousCRMEnv(name), CRMGraspEnv(name)
        discrete, continuous = _actions(cont, steps)
        _seconds_per_step(cont, continuous[:50])  # compile and warm caches first
        _seconds_per_step(disc, discrete[:50])
        d_times, c_times = [], []
        for _ in range(rounds):
            d_times.append(_seconds_per_step(disc, discrete))
            c_times.append(_seconds_per_step(cont, continuous))
        d, c = statistics.median(d_times), statistics.median(c_times)
        out[name] = {
            "discrete_us": round(d * 1e6, 2),
            "continuous_us": round(c * 1e6, 2),
            "continuous_over_discrete": round(c / d, 3),
        }
    return out


if __name__ == "__main__":
    args = [int(a) for a in sys.argv[1:3]]
    print(json.dumps(main(*args), indent=2))

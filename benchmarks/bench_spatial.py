"""The spatial environments' step time against CartPole, measured in one process.

For ``CartPole-v1`` and each of ``crmgrasp/Box3D-v0``, ``crmgrasp/Cup3D-v0`` and
``crmgrasp/OpenCup3D-v0`` (a triangle mesh) on the compiled spatial kernel (``--reference``
adds the readable reference rules; on the open cups, whose readable rules take milliseconds
per CRM, with a twentieth of the steps): random
actions through ``gymnasium.make``, ``steps`` of them in each of ``rounds`` rounds, the
environments alternating round by round (this machine's speed drifts by tens of percent within
a minute), the least round kept per environment. Two times per environment: one ``env.step`` alone, and
``env.step`` plus the resets it triggers, per step (a spatial reset draws a new solid,
builds its kernel and draws a start, so it weighs more than CartPole's).

Prints one JSON object with microseconds and the ratios to CartPole (the issue's target:
a 3-D step at most 2x a CartPole step).

Usage: ``python benchmarks/bench_spatial.py [STEPS] [ROUNDS] [--reference]``.
"""

from __future__ import annotations

import json
import sys
import time
from typing import Any

import gymnasium as gym
import numpy as np

import crmgrasp  # noqa: F401  (registers the environments)

ENVS = ("crmgrasp/Box3D-v0", "crmgrasp/Cup3D-v0", "crmgrasp/OpenCup3D-v0")
SLOW_REFERENCE = ("crmgrasp/OpenCup3D-v0",)
"""Environments whose readable rules are timed on a twentieth of the steps (a mesh's
inside test and first entry loop over its triangles in Python)."""


class _Timer:
    """One environment and its fixed random actions; `round` times one pass over them."""

    def __init__(self, env_id: str, steps: int, **kwargs: Any) -> None:
        self.env = gym.make(env_id, **kwargs)
        self.env.reset(seed=0)
        self.actions = np.random.default_rng(0).integers(self.env.action_space.n, size=steps).tolist()
        self.best = (float("inf"), float("inf"))

    def round(self) -> None:
        """Microseconds per ``env.step`` alone and per step with the resets it triggers; the
        round with the least total is kept."""
        env, clock = self.env, time.perf_counter
        in_step = in_reset = 0.0
        for a in self.actions:
            t0 = clock()
            _, _, term, trunc, _ = env.step(a)
            t1 = clock()
            in_step += t1 - t0
            if term or trunc:
                env.reset()
                in_reset += clock() - t1
        n = len(self.actions)
        if (in_step + in_reset) / n * 1e6 < self.best[1]:
            self.best = (in_step / n * 1e6, (in_step + in_reset) / n * 1e6)


def main(steps: int = 20_000, rounds: int = 5, reference: bool = False) -> dict[str, Any]:
    runs = [("", {})] + ([("_reference", {"backend": "reference"})] if reference else [])
    timers = {"cartpole": _Timer("CartPole-v1", steps)}
    for env_id in ENVS:
        for suffix, kw in runs:
            n = max(1, steps // 20) if suffix and env_id in SLOW_REFERENCE else steps
            timers[env_id.split("/")[1].split("-")[0].lower() + suffix] = _Timer(env_id, n, **kw)
    for _ in range(rounds):  # the environments alternate round by round: each sees the same machine
        for timer in timers.values():
            timer.round()
    cart = timers.pop("cartpole").best
    out: dict[str, Any] = {"steps": steps, "rounds": rounds, "cartpole_us": [round(v, 2) for v in cart]}
    for name, timer in timers.items():
        step, with_resets = timer.best
        out[f"{name}_step_us"] = round(step, 2)
        out[f"{name}_step_over_cartpole"] = round(step / cart[0], 2)
        out[f"{name}_with_resets_over_cartpole"] = round(with_resets / cart[1], 2)
    return out


if __name__ == "__main__":
    args = [a for a in sys.argv[1:] if a != "--reference"]
    print(json.dumps(main(*(int(a) for a in args[:2]), reference="--reference" in sys.argv), indent=2))

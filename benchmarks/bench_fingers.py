"""The three-finger environment against CartPole, in one process.

Steps ``crmgrasp/Triangles3F-v0`` with random actions on the compiled kernel
(``FusedFingersKernel``, backend ``auto``: the task is noise-free) and on the readable rules (``reference``), and
``CartPole-v1`` as the peer. Two numbers per backend: microseconds per step counting the
resets (a new triangle and a start each episode), and per step alone (the episode's
CRMs, resets timed apart). The issue's target: a step at most 1.5x CartPole's.

Prints one JSON object. Usage: ``python benchmarks/bench_fingers.py [STEPS]`` (default 3000).
"""

from __future__ import annotations

import json
import sys
import time

import gymnasium as gym
import numpy as np

import crmgrasp.envs  # noqa: F401  (registers the environments)


def _rates(env_id: str, steps: int, **kwargs: object) -> tuple[float, float]:
    """Seconds per step with resets, and per step without them."""
    env = gym.make(env_id, **kwargs)
    env.reset(seed=0)
    rng = np.random.default_rng(0)
    n_actions = int(env.action_space.n)  # type: ignore[attr-defined]
    stepping = resetting = 0.0
    for _ in range(steps):
        t0 = time.perf_counter()
        _, _, terminated, truncated, _ = env.step(int(rng.integers(n_actions)))
        t1 = time.perf_counter()
        stepping += t1 - t0
        if terminated or truncated:
            env.reset()
            resetting += time.perf_counter() - t1
    return (stepping + resetting) / steps, stepping / steps


def main(steps: int = 3000) -> dict:
    _rates("crmgrasp/Triangles3F-v0", 50)  # compile and warm caches first
    cart, _ = _rates("CartPole-v1", 10 * steps)
    out: dict[str, object] = {"steps": steps, "cartpole_us": round(cart * 1e6, 2)}
    for backend in ("auto", "reference"):
        with_resets, alone = _rates("crmgrasp/Triangles3F-v0", steps, backend=backend)
        out[backend] = {
            "us_per_step_with_resets": round(with_resets * 1e6, 1),
            "us_per_step_alone": round(alone * 1e6, 1),
            "over_cartpole_with_resets": round(with_resets / cart, 2),
            "over_cartpole_alone": round(alone / cart, 2),
        }
    return out


if __name__ == "__main__":
    print(json.dumps(main(int(sys.argv[1]) if len(sys.argv) > 1 else 3000), indent=2))

"""Speed benchmarks against Gymnasium's CartPole, measured in one process.

Each workload is timed in alternating rounds and the minimum over rounds is kept;
ratios compare minimum times measured in the same run:

* ``step_ratio_vs_cartpole``: one paper-box ``env.step`` through ``gymnasium.make``
  over one ``CartPole-v1`` step (random actions, reset at episode end; episodes of
  paper-box under random actions last about 4 CRMs, CartPole's about 22 steps,
  so resets weigh more on ours);
* ``batch_ratio_vs_cartpole_vec``: paper-box env-steps per second with 1,024
  batched envs over Gymnasium's numpy-vectorised CartPole with 1,024;
* ``sarsa_fig7_seconds``: 20 trials x 2,000 episodes of the paper's SARSA
  (training only), minimum over rounds;
* ``reproduce_quick_seconds``: ``crmgrasp reproduce --quick`` in a subprocess;
* ``batch_peak_mb``: peak traced memory of 100 steps of the 1,024-env vector env;
* ``import_over_gymnasium_seconds``: a fresh interpreter's ``import crmgrasp`` less its
  ``import gymnasium`` (the least of 7 alternating subprocess runs each).

Run ``crmgrasp bench`` (an installed package, or a source checkout), ``python
benchmarks/bench_env.py`` or ``python benchmarks/run.py``; ``--smoke`` for tiny sizes.
"""

from __future__ import annotations

import json
import platform
import subprocess
import sys
import tempfile
import time
import tracemalloc
from collections.abc import Callable
from typing import Any

import gymnasium as gym
import numpy as np

from crmgrasp.agents import train_trials
from crmgrasp.envs import ENV_ID
from crmgrasp.tasks import paper_box

__all__ = ["run_benchmarks"]


def _single_steps(env: gym.Env, actions: list[int]) -> Callable[[], None]:
    def run() -> None:
        step, reset = env.step, env.reset
        for a in actions:
            _, _, term, trunc, _ = step(a)
            if term or trunc:
                reset()

    return run


def _vector_steps(env: Any, actions: np.ndarray) -> Callable[[], None]:
    def run() -> None:
        for a in actions:
            env.step(a)

    return run


def _import_cost(rounds: int) -> float:
    """Seconds ``import crmgrasp`` adds to ``import gymnasium`` in a fresh interpreter
    (each the least of ``rounds`` alternating runs; the interpreter's start cancels)."""
    best = {"gymnasium": float("inf"), "crmgrasp": float("inf")}
    for _ in range(rounds):
        for module in best:
            t0 = time.perf_counter()
            subprocess.run([sys.executable, "-c", f"import {module}"], check=True)
            best[module] = min(best[module], time.perf_counter() - t0)
    return best["crmgrasp"] - best["gymnasium"]


def _timed(fn: Callable[[], None]) -> float:
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


def _step_timings(
    rng: np.random.Generator, rounds: int, steps: int, vec_steps: int, num_envs: int, seed: int
) -> tuple[dict[str, float], str]:
    """Best of ``rounds`` timings (s) of the single and vectorised paper-box and CartPole
    workloads (keys ``pb``, ``cp``, ``vpb``, ``vcp``), and the paper-box env's kernel name."""
    pb, cp = gym.make(ENV_ID), gym.make("CartPole-v1")
    pb.reset(seed=seed)
    cp.reset(seed=seed)
    pb_run = _single_steps(pb, rng.integers(4, size=steps).tolist())
    cp_run = _single_steps(cp, rng.integers(2, size=steps).tolist())
    vpb = gym.make_vec(ENV_ID, num_envs=num_envs, vectorization_mode="vector_entry_point")
    vcp = gym.make_vec("CartPole-v1", num_envs=num_envs, vectorization_mode="vector_entry_point")
    vpb.reset(seed=seed)
    vcp.reset(seed=seed)
    vpb_run = _vector_steps(vpb, rng.integers(4, size=(vec_steps, num_envs)))
    vcp_run = _vector_steps(vcp, rng.integers(2, size=(vec_steps, num_envs)))
    best = dict.fromkeys(("pb", "cp", "vpb", "vcp"), float("inf"))
    for _ in range(rounds):
        for key, fn in (("pb", pb_run), ("cp", cp_run), ("vpb", vpb_run), ("vcp", vcp_run)):
            best[key] = min(best[key], _timed(fn))
    return best, pb.unwrapped.kernel.name  # type: ignore[attr-defined]


def _batch_peak_mb(rng: np.random.Generator, num_envs: int, seed: int) -> float:
    """Peak traced memory (MiB) of 100 steps of the vectorised paper-box env."""
    tracemalloc.start()
    env = gym.make_vec(ENV_ID, num_envs=num_envs, vectorization_mode="vector_entry_point")
    env.reset(seed=seed)
    for a in rng.integers(4, size=(100, num_envs)):
        env.step(a)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return round(peak / 2**20, 2)


def _reproduce_quick_seconds() -> float:
    """Wall time (s) of ``crmgrasp reproduce --quick`` in a fresh process."""
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        subprocess.run(
            [sys.executable, "-m", "crmgrasp", "reproduce", "--quick", "--out", tmp], check=True, capture_output=True
        )
        return round(time.perf_counter() - t0, 2)


def run_benchmarks(
    *,
    rounds: int = 15,
    steps: int = 20_000,
    vec_steps: int = 200,
    num_envs: int = 1024,
    sarsa_rounds: int = 3,
    sarsa_trials: int = 20,
    sarsa_episodes: int = 2000,
    quick: bool = True,
    seed: int = 0,
    import_rounds: int = 7,
) -> dict[str, Any]:
    """Run every workload; return the results (see the module docstring)."""
    rng = np.random.default_rng(seed)
    best, kernel = _step_timings(rng, rounds, steps, vec_steps, num_envs, seed)
    task = paper_box()

    def sarsa_run() -> None:
        train_trials(task, "sarsa", trials=sarsa_trials, episodes=sarsa_episodes, seed=seed, eval_episodes=0)

    sarsa = min(_timed(sarsa_run) for _ in range(sarsa_rounds))
    result: dict[str, Any] = {
        "step_ratio_vs_cartpole": round(best["pb"] / best["cp"], 3),
        "batch_ratio_vs_cartpole_vec": round(best["vcp"] / best["vpb"], 3),
        "sarsa_fig7_seconds": round(sarsa, 3),
        "paperbox_step_us": round(best["pb"] / steps * 1e6, 3),
        "cartpole_step_us": round(best["cp"] / steps * 1e6, 3),
        "paperbox_vec_steps_per_s": round(vec_steps * num_envs / best["vpb"]),
        "cartpole_vec_steps_per_s": round(vec_steps * num_envs / best["vcp"]),
        "batch_peak_mb": _batch_peak_mb(rng, num_envs, seed),
        "import_over_gymnasium_seconds": round(_import_cost(import_rounds), 3),
        "kernel": kernel,
        "rounds": rounds,
        "num_envs": num_envs,
        "python": platform.python_version(),
        "numpy": np.__version__,
        "gymnasium": gym.__version__,
    }
    if quick:
        result["reproduce_quick_seconds"] = _reproduce_quick_seconds()
    return result


def main(argv: list[str] | None = None) -> dict[str, Any]:
    """``crmgrasp bench`` / ``python benchmarks/run.py``: print one JSON object."""
    import argparse

    ap = argparse.ArgumentParser(prog="crmgrasp bench", description=__doc__.split("\n\n")[0])
    ap.add_argument("--smoke", action="store_true", help="tiny sizes (CI): no meaningful timings")
    ap.add_argument("--rounds", type=int, default=15)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    if args.smoke:
        res = run_benchmarks(
            rounds=2,
            steps=200,
            vec_steps=3,
            num_envs=64,
            sarsa_rounds=1,
            sarsa_trials=2,
            sarsa_episodes=20,
            quick=False,
            seed=args.seed,
            import_rounds=1,
        )
    else:
        res = run_benchmarks(rounds=args.rounds, seed=args.seed)
    print(json.dumps(res, indent=2))
    return res


if __name__ == "__main__":
    main()

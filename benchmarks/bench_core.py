"""Core simulator speed against Gymnasium's CartPole-v1, measured in one process.

Workloads (alternated each round; the minimum over rounds is kept):

* ``execute_us``: one scalar ``hand.execute`` on paper-box (random corner start,
  random action of the task), microseconds per call;
* ``batch_us_per_crm``: ``execute_batch`` on N random configurations and CRMs,
  microseconds per CRM;
* ``cartpole_step_us``: one ``env.step`` of ``gymnasium.make("CartPole-v1")``
  with random actions, resetting at episode end.

Ratios below 1 mean faster than a CartPole step. Run:
``python benchmarks/bench_core.py`` (``--smoke`` for a tiny run).
"""

from __future__ import annotations

import argparse
import json
import platform
import time

import gymnasium as gym
import numpy as np

from crmgrasp.kernels import execute_batch
from crmgrasp.model.contacts import configs_to_array
from crmgrasp.tasks import paper_box


def _time_per_item(fn, items: int) -> float:
    t0 = time.perf_counter()
    fn()
    return (time.perf_counter() - t0) / items * 1e6


def main(argv: list[str] | None = None) -> dict[str, float]:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--rounds", type=int, default=15)
    ap.add_argument("--calls", type=int, default=20_000, help="scalar calls per round")
    ap.add_argument("--batch", type=int, default=100_000, help="CRMs per batch")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--smoke", action="store_true", help="tiny sizes (for CI)")
    args = ap.parse_args(argv)
    if args.smoke:
        args.rounds, args.calls, args.batch = 2, 200, 1_000

    task = paper_box()
    rng = np.random.default_rng(args.seed)
    starts = [task.sample_start(rng) for _ in range(1000)]
    actions = [task.actions[i] for i in rng.integers(len(task.actions), size=args.calls)]
    pairs = [(starts[i % len(starts)], actions[i]) for i in range(args.calls)]
    obj, hand = task.obj, task.hand

    def scalar() -> None:
        for cfg, crm in pairs:
            hand.execute(obj, cfg, crm)

    rows = configs_to_array(starts)[rng.integers(len(starts), size=args.batch)]
    c = np.array([m.ci for m in task.actions])
    f = np.array([m.fi for m in task.actions])
    r = np.array([m.r for m in task.actions])
    pick = rng.integers(len(task.actions), size=args.batch)

    def batch() -> None:
        execute_batch(obj, hand, rows, c[pick], f[pick], r[pick], backend="numba")

    env = gym.make("CartPole-v1")
    env.reset(seed=args.seed)
    env.action_space.seed(args.seed)
    cp_actions = rng.integers(2, size=args.calls).tolist()

    def cartpole() -> None:
        for a in cp_actions:
            _, _, term, trunc, _ = env.step(a)
            if term or trunc:
                env.reset()

    best = {"execute_us": np.inf, "batch_us_per_crm": np.inf, "cartpole_step_us": np.inf}
    for _ in range(args.rounds):
        best["execute_us"] = min(best["execute_us"], _time_per_item(scalar, args.calls))
        best["cartpole_step_us"] = min(best["cartpole_step_us"], _time_per_item(cartpole, args.calls))
        best["batch_us_per_crm"] = min(best["batch_us_per_crm"], _time_per_item(batch, args.batch))
    result = {
        **{k: round(v, 4) for k, v in best.items()},
        "execute_ratio_vs_cartpole_step": round(best["execute_us"] / best["cartpole_step_us"], 3),
        "batch_ratio_vs_cartpole_step": round(best["batch_us_per_crm"] / best["cartpole_step_us"], 4),
        "rounds": args.rounds,
        "batch": args.batch,
        "python": platform.python_version(),
        "numpy": np.__version__,
        "gymnasium": gym.__version__,
    }
    print(json.dumps(result, indent=2))
    return result


if __name__ == "__main__":
    main()

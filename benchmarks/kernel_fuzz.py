"""The compiled kernels against the readable rules, at scale: every registered task, step by step.

For each task (noise-free, then with sensing noise of 0.05 rad on the normals and 3 mm on the
positions) it draws worlds from the task's own start distribution and, in each, steps random
actions with the readable rules (`crmgrasp.sim.step`) and with the task's kernel as the seam
picks it (`kernel_for(task, "auto")`: fused, compiled or reference), from the same state and
the same random stream, and compares the whole step (state, observation, bins, error, least
friction, reward, end flags). Three in ten steps branch from an earlier state of the episode,
errored ones included, so the kernels' reuse of a row's last reading is checked too.

``--continuous`` draws CRMs of the continuous action space instead: a random contact pair and an
offset uniform in 70% of the hand's reach per coordinate, stepped by the kernel's ``step_one``
(with the CRM) and ``step_row`` (with its action-table row), both against the readable step.

The unit tests check the same equalities on a few hundred steps per kernel; this runs as many
as one asks. It prints one JSON line per task and noise level and exits 1 if any step differs
(the first differing steps are printed). Measured 2026-12-07 on all 21 registered tasks, noise-free
and noisy: the defaults (2,000 worlds x 12 CRMs) stepped 1,008,000 CRMs, 660,071 of them errored,
in 10 min on one core beside other runs; ``--continuous --worlds 1500 --steps 10`` 630,000 CRMs,
496,276 errored, in 9.5 min (``open-cup-3d``, a mesh without a compiled kernel, takes half of
each). No step differed.

Usage: ``python benchmarks/kernel_fuzz.py [--task NAME ...] [--worlds N] [--steps N] [--seed S]
[--continuous]``.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
import time
from typing import Any

import numpy as np

from crmgrasp.kernels import kernel_for
from crmgrasp.model.sensing import SensorNoise
from crmgrasp.sim import begin, step
from crmgrasp.tasks import make_task, task_names

NOISE = SensorNoise(sigma_n=0.05, sigma_p=0.003)


def _random_crm(inst: Any, rng: np.random.Generator) -> Any:
    """A CRM of the continuous action space: a random pair, offsets within 70% of the reach."""
    m = inst.model
    n = len(m.labels)
    r = rng.uniform(-1.0, 1.0, m.offset_dim) * 0.7 * inst.hand.reach
    return m.crm(int(rng.integers(n)), int(rng.integers(n)), float(r[0]) if m.offset_dim == 1 else tuple(r.tolist()))


def fuzz(name: str, noisy: bool, worlds: int, steps: int, seed: int, continuous: bool) -> dict[str, Any]:
    """Step ``worlds`` worlds of task ``name`` for ``steps`` CRMs each on both paths; the counts
    and the first differing steps."""
    task = make_task(name)
    if noisy:
        task = dataclasses.replace(task, noise=NOISE)
    rng = np.random.default_rng([seed, int(noisy), int(continuous)])
    t0 = time.perf_counter()
    out: dict[str, Any] = {"task": name, "noisy": noisy, "continuous": continuous, "steps": 0, "errors": 0}
    kernels: set[str] = set()
    differ: list[str] = []
    for w in range(worlds):
        inst, start = task.sample_world(rng)
        fast = kernel_for(inst, "auto")
        kernels.add(type(fast).__name__)
        s = int(rng.integers(1 << 62))
        a, b = begin(inst, start, np.random.default_rng(s)), fast.begin(start, np.random.default_rng(s))
        if a != b:
            differ.append(f"world {w}, begin: {a} != {b}")
            continue
        states = [a.state]
        for _ in range(steps):
            src = states[int(rng.integers(len(states)))] if rng.random() < 0.3 else states[-1]
            action = _random_crm(inst, rng) if continuous else int(rng.integers(len(inst.actions)))
            s = int(rng.integers(1 << 62))
            want = step(inst, src, action, np.random.default_rng(s))
            got = [fast.step_one(src, action, np.random.default_rng(s))]
            if continuous:
                got.append(fast.step_row(src, fast.crm_row(action), np.random.default_rng(s)))
            out["steps"] += 1
            out["errors"] += int(want.error != 0)
            if any(g != want for g in got):
                differ.append(f"world {w}, action {action!r}: {want} != {got}")
                break
            states.append(want.state)
    out.update(
        kernels=sorted(kernels), worlds=worlds, mismatches=len(differ), seconds=round(time.perf_counter() - t0, 1)
    )
    out["first_mismatches"] = differ[:3]
    return out


def main(argv: list[str] | None = None) -> list[dict[str, Any]]:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--task", action="append", help="task (repeatable; default: every registered task)")
    ap.add_argument("--worlds", type=int, default=2000, help="worlds per task and noise level")
    ap.add_argument("--steps", type=int, default=12, help="CRMs per world")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--continuous", action="store_true", help="CRMs of the continuous action space")
    args = ap.parse_args(argv)
    rows = []
    for name in args.task or task_names():
        for noisy in (False, True):
            row = fuzz(name, noisy, args.worlds, args.steps, args.seed, args.continuous)
            print(json.dumps(row), flush=True)
            rows.append(row)
    return rows


if __name__ == "__main__":
    sys.exit(1 if any(r["mismatches"] for r in main()) else 0)

"""The compiled kernels' first compilation: what a fresh install pays once.

Runs, in a fresh interpreter with an empty numba cache (``NUMBA_CACHE_DIR`` a new temporary
folder), a paper-box vector step and single step (the polygon kernels), then a ``Box3D-v0``
step (the spatial kernel), then what reuses those kernels on other arguments: a step of the
U-handle family (each object's edges moved into the kernel), of ``PaperBoxContinuous-v0`` and
of ``UHandleContinuous-v0`` (CRMs of the continuous action space, single and batched). It
prints the seconds each part took, compilation included, and how many argument-type
signatures the kernels' compiled functions then hold (numba compiles each function once per
signature: a function met with a read-only array in one call and a writable one in another
compiles twice; compiling gives the helpers it calls their signatures too, loading does
not); then the same again on the now-filled cache (loading, not compiling).
``ROUNDS`` fresh caches, the least kept.

To compare with a commit, run it with that commit's source first on the path, e.g.
``PYTHONPATH=/tmp/old/src python benchmarks/bench_compile.py`` after
``git worktree add /tmp/old <commit>``.

Usage: ``python benchmarks/bench_compile.py [ROUNDS]`` (default 2). Prints one JSON object.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
from typing import Any

_SNIPPET = """
import time, numpy as np, gymnasium as gym
import crmgrasp
t0 = time.perf_counter()
v = gym.make_vec("crmgrasp/PaperBox-v0", num_envs=8, vectorization_mode="vector_entry_point")
v.reset(seed=0)
v.step(np.zeros(8, dtype=np.int64))
e = gym.make("crmgrasp/PaperBox-v0")
e.reset(seed=0)
e.step(0)
t1 = time.perf_counter()
e = gym.make("crmgrasp/Box3D-v0")
e.reset(seed=0)
e.step(0)
t2 = time.perf_counter()
e = gym.make("crmgrasp/UHandle-v0")
e.reset(seed=0)
e.step(0)
for name in ("PaperBoxContinuous", "UHandleContinuous"):
    e = gym.make(f"crmgrasp/{name}-v0")
    e.action_space.seed(0)
    e.reset(seed=0)
    e.step(e.action_space.sample())
    v = gym.make_vec(f"crmgrasp/{name}-v0", num_envs=8, vectorization_mode="vector_entry_point")
    v.action_space.seed(0)
    v.reset(seed=0)
    v.step(v.action_space.sample())
t3 = time.perf_counter()
import sys
from numba.core.registry import CPUDispatcher
found = {id(f): f for name, m in list(sys.modules.items()) if name.startswith("crmgrasp.kernels._")
         for f in vars(m).values() if isinstance(f, CPUDispatcher)}
print(t1 - t0, t2 - t1, t3 - t2, sum(len(f.signatures) for f in found.values()))
"""


PARTS = ("polygon", "spatial", "others")


def _run(cache: str) -> tuple[list[float], int]:
    """Seconds per part and the signatures held, in a fresh interpreter on ``cache``."""
    env = {**os.environ, "NUMBA_CACHE_DIR": cache}
    out = subprocess.run([sys.executable, "-c", _SNIPPET], env=env, check=True, capture_output=True, text=True)
    *seconds, signatures = out.stdout.split()
    return [float(s) for s in seconds], int(signatures)


def main(rounds: int = 2) -> dict[str, Any]:
    best = {f"{part}_{kind}_s": float("inf") for kind in ("first", "cached") for part in PARTS}
    signatures: dict[str, set[int]] = {"first": set(), "cached": set()}
    for _ in range(rounds):
        with tempfile.TemporaryDirectory() as cache:
            for kind in ("first", "cached"):
                seconds, held = _run(cache)
                signatures[kind].add(held)
                for part, s in zip(PARTS, seconds, strict=True):
                    best[f"{part}_{kind}_s"] = min(best[f"{part}_{kind}_s"], s)
    out: dict[str, Any] = {k: round(v, 2) for k, v in best.items()}
    for kind, counts in signatures.items():  # compiling also gives the helpers signatures; loading does not
        out[f"signatures_{kind}"] = counts.pop() if len(counts) == 1 else sorted(counts)
    return out


if __name__ == "__main__":
    print(json.dumps(main(*(int(a) for a in sys.argv[1:2])), indent=2))

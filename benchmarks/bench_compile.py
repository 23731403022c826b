"""The compiled kernels' first compilation: what a fresh install pays once.

Runs, in a fresh interpreter with an empty numba cache (``NUMBA_CACHE_DIR`` a new temporary
folder), a paper-box vector step and single step (the polygon kernels) and then a ``Box3D-v0``
step (the spatial kernel), and prints the seconds each took, compilation included; then the
same again on the now-filled cache (loading, not compiling). ``ROUNDS`` fresh caches, the
least kept.

Usage: ``python benchmarks/bench_compile.py [ROUNDS]`` (default 2). Prints one JSON object.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile

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
print(t1 - t0, time.perf_counter() - t1)
"""


def _run(cache: str) -> tuple[float, float]:
    env = {**os.environ, "NUMBA_CACHE_DIR": cache}
    out = subprocess.run([sys.executable, "-c", _SNIPPET], env=env, check=True, capture_output=True, text=True)
    polygon, spatial = map(float, out.stdout.split())
    return polygon, spatial


def main(rounds: int = 2) -> dict[str, float]:
    best = {"polygon_first_s": float("inf"), "spatial_first_s": float("inf")}
    best.update({"polygon_cached_s": float("inf"), "spatial_cached_s": float("inf")})
    for _ in range(rounds):
        with tempfile.TemporaryDirectory() as cache:
            for kind in ("first", "cached"):
                polygon, spatial = _run(cache)
                best[f"polygon_{kind}_s"] = min(best[f"polygon_{kind}_s"], polygon)
                best[f"spatial_{kind}_s"] = min(best[f"spatial_{kind}_s"], spatial)
    return {k: round(v, 2) for k, v in best.items()}


if __name__ == "__main__":
    print(json.dumps(main(*(int(a) for a in sys.argv[1:2])), indent=2))

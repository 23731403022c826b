"""Polygon validation time against testing every pair of edges (the peer, same run).

Builds star-shaped polygons of n random vertices (simple by construction) and times
``Polygon(vertices)`` (grid broad phase) and the all-pairs simplicity check on the same
vertices; prints one JSON object (seconds and the ratio).

Usage: ``python benchmarks/polygon_validation.py [n ...]`` (default 300 1000 3000).
"""

import json
import sys
import time

import numpy as np

from crmgrasp import Polygon
from crmgrasp.model.polygon import _segments_cross


def _all_pairs(pts: list[tuple[float, float]]) -> None:
    n = len(pts)
    for i in range(n):
        p, q = pts[i], pts[(i + 1) % n]
        for j in range(i + 2, n):
            if not (i == 0 and j == n - 1) and _segments_cross(p, q, pts[j], pts[(j + 1) % n]):
                raise ValueError((i, j))


def main(sizes: list[int]) -> dict:
    out = {}
    for n in sizes:
        rng = np.random.default_rng(n)
        ang, r = np.sort(rng.uniform(0, 2 * np.pi, n)), rng.uniform(0.5, 1.0, n)
        pts = list(zip((r * np.cos(ang)).tolist(), (r * np.sin(ang)).tolist()))
        t0 = time.perf_counter()
        Polygon(pts)
        grid = time.perf_counter() - t0
        t0 = time.perf_counter()
        _all_pairs(pts)
        peer = time.perf_counter() - t0
        out[n] = {"polygon_s": round(grid, 4), "all_pairs_s": round(peer, 4), "ratio": round(grid / peer, 4)}
    print(json.dumps(out, indent=2))
    return out


if __name__ == "__main__":
    main([int(a) for a in sys.argv[1:]] or [300, 1000, 3000])

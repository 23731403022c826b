"""What the convex pieces of a non-convex mesh cost the MuJoCo stand-in: open cups as their
pieces against the same cups' outer 24-gon as one convex piece.

MuJoCo collides a mesh as its convex hull, so the stand-in gives it a mesh's convex pieces
(``TriangleMesh.pieces``; an open cup's: its bottom and one block of the wall per side). For
WORLDS worlds of ``open-cup-3d`` (seed 11) and each of two bodies, the cup as its pieces and the
cup's outer surface as one convex piece (a closed cup with the same facets), from the same start
and the same sensor seed, on worlds where the start's contacts and those after ``C1`` in the
kinematic model are all on the outer surface (where the two bodies are the same): the angle
between each fingertip's sensed normal and the start's normal
(degrees), and the outcome of the paper's opposition ``C1``: its error flag and the true least
friction of MuJoCo's contacts after it (a grasp at ``mu_goal`` or below). ``--extra ATTRS`` adds
MJCF attributes to every piece's geom (e.g. ``'solref="0.004 1"'``: stiffer contacts).

Prints one JSON object: ``C1``'s grasps in the kinematic model; per body, the sensed normal
error (median, 90th percentile, largest) and ``C1``'s grasps. Usage: ``python
benchmarks/mujoco_mesh_seams.py [--worlds 20] [--extra ATTRS]`` (about 10 s at the default on
one core; needs crmgrasp[mujoco]).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
from typing import Any

import numpy as np

import crmgrasp.hardware.mujoco.spatial as stand_in
from crmgrasp.hardware.mujoco import hardware_task
from crmgrasp.hardware.mujoco.spatial import MujocoHand3D
from crmgrasp.model.mesh import TriangleMesh
from crmgrasp.model.spatial import Config3D
from crmgrasp.tasks import make_task


def _angle(u: Any, v: Any) -> float:
    return math.degrees(math.acos(max(-1.0, min(1.0, float(np.dot(u, v))))))


def _outside(cup: TriangleMesh, x: Any, segments: int = 24) -> bool:
    """Whether the surface point ``x`` lies on the cup's outer surface (the boundary of the
    convex hull of its outer corners, to 1e-7 m)."""
    from scipy.spatial import ConvexHull

    eq = ConvexHull(cup.corner_array[: 2 * segments]).equations
    return bool(np.max(eq[:, :3] @ np.asarray(x) + eq[:, 3]) > -1e-7)


def one_hull(cup: TriangleMesh, segments: int = 24) -> TriangleMesh:
    """The cup's outer surface as one convex piece: the outer bottom and top rings (the first
    ``2 * segments`` corners of `open_cup`)."""
    return TriangleMesh(cup.vertices, cup.faces, (tuple(range(2 * segments)),))


def main(worlds: int = 20, extra: str = "") -> dict[str, Any]:
    plain = stand_in._geom
    if extra:  # MJCF attributes for every piece's geom, for this run only
        stand_in._geom = lambda name, mass, p, shape: plain(name, mass, p, f"{shape} {extra}")  # type: ignore[assignment]
    try:
        return _run(worlds, extra)
    finally:
        stand_in._geom = plain  # type: ignore[assignment]


def _run(worlds: int, extra: str) -> dict[str, Any]:
    base = make_task("open-cup-3d")
    rng = np.random.default_rng(11)
    out: dict[str, dict[str, list[float]]] = {"pieces": {"error": [], "mu": []}, "one hull": {"error": [], "mu": []}}
    w = tried = kinematic = 0
    while w < worlds:
        world, tried = base.sample_world(rng), tried + 1
        task = hardware_task(world.task)
        kin = task.execute(world.config, task.actions[0], world.config)
        if not all(_outside(task.obj, c.x) for c in (*world.config, *kin.config)):  # type: ignore[arg-type]
            continue
        w += 1
        kinematic += task.grasped(task.quality(kin.config)) and kin.error.name == "NONE"
        for body, obj in (("pieces", task.obj), ("one hull", one_hull(task.obj))):  # type: ignore[arg-type]
            t = dataclasses.replace(task, obj=obj)
            hand = MujocoHand3D(t, world.config, np.random.default_rng(w))  # type: ignore[arg-type]
            sensed = hand.sense()
            if isinstance(sensed, Config3D):
                out[body]["error"] += [_angle(k.n, s.n) for k, s in zip(world.config, sensed)]
            hand.execute(t.actions[0])
            true = hand.true_config()
            out[body]["mu"].append(t.quality(true) if true is not None else math.inf)
    goal = base.mu_goal
    return {
        "worlds": worlds,
        "worlds_drawn": tried,
        "c1_grasps_kinematic": kinematic,
        "extra": extra,
        **{
            body: {
                "sensed_normal_error_deg_median_p90_max": [
                    round(float(np.median(v["error"])), 2),
                    round(float(np.percentile(v["error"], 90)), 2),
                    round(max(v["error"]), 2),
                ],
                "c1_grasps": sum(mu <= goal for mu in v["mu"]),
            }
            for body, v in out.items()
        },
    }


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--worlds", type=int, default=20)
    ap.add_argument("--extra", default="", help="MJCF attributes added to every piece's geom")
    a = ap.parse_args()
    print(json.dumps(main(a.worlds, a.extra), indent=1))

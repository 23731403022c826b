"""Figures of the spatial model: a solid on the table, the two contacts and the palm.

Matplotlib's 3-D axes on a `Figure` (no pyplot state). A
scene shows the solid (faces shaded), the table plane, each contact with its inward
normal, the palm point, and, after a CRM, the configuration before it faded.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from matplotlib.figure import Figure
from mpl_toolkits.mplot3d.art3d import Poly3DCollection

from crmgrasp.model.solids import ConvexPolyhedron, Cylinder, Solid
from crmgrasp.model.spatial import Contacts3D, Hand3D, palm_point3d
from crmgrasp.plotting.colors import COLORS

__all__ = ["draw_solid", "draw_scene3d", "scene_figure3d", "rollout_panels3d", "rollout_animation3d"]


def _faces(poly: ConvexPolyhedron) -> list[np.ndarray]:
    """Each face's corners in order around it."""
    v = poly.vertices
    out = []
    for a0, a1, a2, b in poly.planes:
        a = np.array([a0, a1, a2])
        on = v[np.abs(v @ a - b) < 1e-9]
        if len(on) < 3:
            continue
        c = on.mean(axis=0)
        e1 = on[0] - c
        e1 /= np.linalg.norm(e1)
        e2 = np.cross(a, e1)
        out.append(on[np.argsort(np.arctan2((on - c) @ e2, (on - c) @ e1))])
    return out


def _cylinder_faces(cyl: Cylinder, n: int = 32) -> list[np.ndarray]:
    e, o = np.array(cyl.axis), np.array(cyl.origin)
    helper = np.array([1.0, 0.0, 0.0]) if abs(e[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = np.cross(e, helper)
    u /= np.linalg.norm(u)
    w = np.cross(e, u)
    ang = np.linspace(0.0, 2.0 * math.pi, n, endpoint=False)
    ring = cyl.radius * (np.cos(ang)[:, None] * u + np.sin(ang)[:, None] * w)
    bottom, top = o + ring, o + cyl.height * e + ring
    sides = [np.array([bottom[i], bottom[(i + 1) % n], top[(i + 1) % n], top[i]]) for i in range(n)]
    return [bottom, top, *sides]


def draw_solid(ax: Any, solid: Solid) -> None:
    """The solid's faces, shaded grey: one collection per face size (matplotlib pads
    ragged face lists with uninitialised values, which its projection then multiplies)."""
    if isinstance(solid, ConvexPolyhedron):
        faces = _faces(solid)
    elif isinstance(solid, Cylinder):
        faces = _cylinder_faces(solid)
    else:  # a triangle mesh
        faces = [np.array([solid.vertices[i] for i in tri]) for tri in solid.faces]
    for size in sorted({len(f) for f in faces}):
        same = [f for f in faces if len(f) == size]
        style = dict(facecolor="0.8", edgecolor="0.35", linewidths=0.4, alpha=0.35)
        ax.add_collection3d(Poly3DCollection(same, **style), autolim=False)


def _draw_config(ax: Any, hand: Hand3D, cfg: Contacts3D, scale: float, alpha: float, primed: bool) -> None:
    for lab, c in zip(hand.labels, cfg):
        x, n = np.array(c.x), np.array(c.n)
        ax.scatter(*x, color=COLORS[lab], s=40, alpha=alpha, depthshade=False)
        ax.quiver(*x, *(scale * n), color=COLORS[lab], alpha=alpha, arrow_length_ratio=0.3)
        ax.text(*(x - 0.4 * scale * n), lab + ("'" if primed else ""), color=COLORS[lab], alpha=alpha)
    palm = palm_point3d(cfg, hand)
    if palm is not None:
        pts = np.array([cfg[0].x, palm, cfg[-1].x])  # the outer contacts and the palm between them
        ax.plot(pts[:, 0], pts[:, 1], pts[:, 2], "-", color="0.4", lw=0.8, alpha=alpha)
        ax.scatter(*palm, marker="s", color="0.3", s=30, alpha=alpha, depthshade=False)


def draw_scene3d(
    ax: Any,
    solid: Solid,
    hand: Hand3D,
    config: Contacts3D,
    after: Contacts3D | None = None,
    *,
    title: str | None = None,
    table: float | None = 0.0,
) -> None:
    """The solid, the table, the contacts (faded when ``after`` is given) and ``after``.
    The view (a cube around the solid) is fixed before anything is drawn and never
    autoscaled: matplotlib's 3-D autoscaling from an empty axes can overflow."""
    c = solid.centre
    size = (
        max(2.0 * solid.radius, solid.height)
        if isinstance(solid, Cylinder)
        else float(np.ptp(np.asarray(solid.vertices), axis=0).max())
    )
    half = 0.5 * size + 0.06
    ax.set_autoscale_on(False)
    ax.set_xlim(c[0] - half, c[0] + half)
    ax.set_ylim(c[1] - half, c[1] + half)
    ax.set_zlim(max(0.0, c[2] - half) if table is not None else c[2] - half, c[2] + half)
    draw_solid(ax, solid)
    if table is not None:
        sq = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]]) * half + c[:2]
        ax.add_collection3d(
            Poly3DCollection([np.c_[sq, np.full(4, table)]], facecolor="tan", alpha=0.15), autolim=False
        )
    scale = 0.05
    _draw_config(ax, hand, config, scale, 0.35 if after is not None else 1.0, False)
    if after is not None:
        _draw_config(ax, hand, after, scale, 1.0, True)
    ax.set_box_aspect((1, 1, 1))
    ax.set_xlabel("x (m)", fontsize=7)
    ax.set_ylabel("y (m)", fontsize=7)
    ax.set_zlabel("z (m)", fontsize=7)
    ax.tick_params(labelsize=6)
    if title:
        ax.set_title(title, fontsize=9)


def scene_figure3d(
    solid: Solid, hand: Hand3D, config: Contacts3D, after: Contacts3D | None = None, title: str | None = None
) -> Figure:
    """A one-panel figure of [`draw_scene3d`][]."""
    fig = Figure(figsize=(6, 5.2), layout="constrained")
    draw_scene3d(fig.add_subplot(projection="3d"), solid, hand, config, after, title=title)
    return fig


def rollout_panels3d(hand: Hand3D, rows: Sequence[tuple[str, Solid, Sequence[Any]]]) -> Figure:
    """One row per rollout (``label``, its solid, its steps), one panel per CRM: each step
    (``config``, ``after``, ``title``) drawn by [`draw_scene3d`][] (the 3-D Figure 8)."""
    ncols = max(len(steps) for _, _, steps in rows)
    fig = Figure(figsize=(3.6 * ncols, 3.6 * len(rows)), layout="constrained")
    for r, (label, solid, steps) in enumerate(rows):
        for c, (config, after, title) in enumerate(steps):
            ax = fig.add_subplot(len(rows), ncols, r * ncols + c + 1, projection="3d")
            draw_scene3d(ax, solid, hand, config, after, title=f"{label}\n{title}" if c == 0 else title)
    return fig


def rollout_animation3d(solid: Solid, hand: Hand3D, steps: Sequence[Any], path: Any, turns: int = 8) -> None:
    """Animated GIF of one rollout: each CRM (``config``, ``after``, ``title``) shown while
    the view turns ``360 / turns`` degrees per frame, ``turns`` frames per CRM."""
    from matplotlib.animation import FuncAnimation, PillowWriter

    fig = Figure(figsize=(5, 4.6), layout="constrained")
    ax = fig.add_subplot(projection="3d")
    frames = [(i, j) for i in range(len(steps)) for j in range(turns)]

    def draw(frame: tuple[int, int]) -> list[Any]:
        i, j = frame
        ax.clear()
        config, after, title = steps[i]
        draw_scene3d(ax, solid, hand, config, after, title=f"CRM {i + 1} of {len(steps)}: {title}")
        ax.view_init(elev=25, azim=-60 + 360.0 * (i * turns + j) / (turns * max(len(steps), 1)))
        return []

    FuncAnimation(fig, draw, frames=frames, blit=False).save(str(path), writer=PillowWriter(fps=4))

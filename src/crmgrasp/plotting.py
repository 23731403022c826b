"""Figures: the hand-object scene and the experiment plots.

Built on :class:`matplotlib.figure.Figure` directly (no pyplot state), so drawing
works headless and in threads.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.patches import Circle
from matplotlib.patches import Polygon as PolygonPatch

from .contacts import LABELS, Config
from .geometry import Disc, Polygon, Shape
from .hand import Hand, Outcome

__all__ = ["draw_object", "draw_scene", "scene_figure", "friction_histogram"]

COLORS = {"a": "tab:blue", "b": "tab:orange"}


def draw_object(ax: Axes, obj: Shape) -> None:
    """Fill the object's region."""
    style = dict(facecolor="0.85", edgecolor="0.2", linewidth=1.5, zorder=1)
    if isinstance(obj, Polygon):
        ax.add_patch(PolygonPatch(np.asarray(obj.vertices), closed=True, **style))
    elif isinstance(obj, Disc):
        ax.add_patch(Circle(obj.center, obj.radius, **style))
    else:
        pts, _ = obj.boundary_batch(np.linspace(0.0, obj.perimeter, 400, endpoint=False))
        ax.add_patch(PolygonPatch(pts, closed=True, **style))


def draw_scene(
    ax: Axes,
    obj: Shape,
    hand: Hand,
    config: Config,
    outcome: Outcome | None = None,
    *,
    title: str | None = None,
) -> None:
    """Object, contacts with inward normals, palm point; with ``outcome``: the goal
    line (chord within reach solid, the rest dotted), the moving contact's path and
    the new configuration."""
    draw_object(ax, obj)
    scale = 0.15 * max(obj.bounds()[2] - obj.bounds()[0], obj.bounds()[3] - obj.bounds()[1])
    if outcome is not None and outcome.goal is not None:
        g = outcome.goal
        lo, hi = g.at(g.t_lo), g.at(g.t_hi)
        span = g.t_hi - g.t_lo
        far0, far1 = g.at(g.t_lo - 0.3 * span), g.at(g.t_hi + 0.3 * span)
        ax.plot([far0[0], far1[0]], [far0[1], far1[1]], ":", color="0.5", lw=1, zorder=2)
        ax.plot([lo[0], hi[0]], [lo[1], hi[1]], "--", color="tab:green", lw=1.2, zorder=2, label="goal line (reach)")
    if outcome is not None:
        path = np.asarray(outcome.path)
        ax.plot(path[:, 0], path[:, 1], "-", color="tab:purple", lw=1.5, marker=".", zorder=3, label="contact path")
    _draw_config(ax, hand, config, scale, alpha=0.45 if outcome is not None and outcome.error == 0 else 1.0)
    if outcome is not None and outcome.error == 0:
        _draw_config(ax, hand, outcome.config, scale, alpha=1.0, primed=True)
    ax.set_aspect("equal")
    ax.autoscale_view()
    x0, y0, x1, y1 = obj.bounds()
    pad = 0.5 * max(x1 - x0, y1 - y0)
    ax.set_xlim(min(ax.get_xlim()[0], x0 - pad * 0.4), max(ax.get_xlim()[1], x1 + pad * 0.4))
    ax.set_ylim(min(ax.get_ylim()[0], y0 - pad * 0.4), max(ax.get_ylim()[1], y1 + pad * 0.4))
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    if title:
        ax.set_title(title, fontsize=10)


def _draw_config(ax: Axes, hand: Hand, config: Config, scale: float, *, alpha: float, primed: bool = False) -> None:
    for lab, c in zip(LABELS, config):
        ax.plot(c.x, c.y, "o", color=COLORS[lab], ms=8, alpha=alpha, zorder=4)
        ax.annotate(
            "",
            xy=(c.x + 0.5 * scale * c.nx, c.y + 0.5 * scale * c.ny),
            xytext=(c.x, c.y),
            arrowprops=dict(arrowstyle="->", color=COLORS[lab], alpha=alpha),
            zorder=4,
        )
        ax.annotate(
            lab + ("'" if primed else ""),
            (c.x, c.y),
            textcoords="offset points",
            xytext=(-12 * c.nx - 4, -12 * c.ny - 4),
            color=COLORS[lab],
            alpha=alpha,
            fontsize=11,
        )
    px, py = hand.palm(config)
    if math.isfinite(px):
        ax.plot(
            [config.a.x, px, config.b.x], [config.a.y, py, config.b.y], "-", color="0.4", lw=0.8, alpha=alpha, zorder=3
        )
        ax.plot(px, py, "s", color="0.3", ms=7, alpha=alpha, zorder=4)


def scene_figure(
    obj: Shape, hand: Hand, config: Config, outcome: Outcome | None = None, title: str | None = None
) -> Figure:
    """A one-panel figure of :func:`draw_scene`."""
    fig = Figure(figsize=(6, 4.5), layout="constrained")
    ax = fig.add_subplot()
    draw_scene(ax, obj, hand, config, outcome, title=title)
    if outcome is not None:
        ax.legend(loc="upper right", fontsize=8)
    return fig


def friction_histogram(values: Sequence[float], failures: int, title: str) -> Figure:
    """Histogram of minimum friction coefficients (paper Fig. 4)."""
    fig = Figure(figsize=(5.5, 3.8), layout="constrained")
    ax = fig.add_subplot()
    vals = np.asarray([v for v in values if math.isfinite(v)])
    top = max(0.1, float(vals.max()) * 1.1) if len(vals) else 0.1
    ax.hist(vals, bins=np.linspace(0.0, top, 16), color="tab:blue", edgecolor="white")
    ax.set_xlabel("minimum friction coefficient for force closure")
    ax.set_ylabel("grasps")
    note = f"n = {len(values)}" + (f", {failures} failed (no contact / error)" if failures else "")
    ax.set_title(f"{title}\n{note}", fontsize=10)
    return fig

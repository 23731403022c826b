"""Figures: the hand-object scene and the experiment plots.

Built on :class:`matplotlib.figure.Figure` directly (no pyplot state), so drawing
works headless and in threads.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.patches import Circle
from matplotlib.patches import Polygon as PolygonPatch

from crmgrasp.model.contacts import LABELS, Config
from crmgrasp.model.geometry import Disc, Polygon, Shape
from crmgrasp.model.hand import Hand, Outcome

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
        pts = np.array([obj.boundary(s).point for s in np.linspace(0.0, obj.perimeter, 400, endpoint=False).tolist()])
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
    ax.hist(vals, bins=np.linspace(0.0, top, 16).tolist(), color="tab:blue", edgecolor="white")
    ax.set_xlabel("minimum friction coefficient for force closure")
    ax.set_ylabel("grasps")
    note = f"n = {len(values)}" + (f", {failures} failed (no contact / error)" if failures else "")
    ax.set_title(f"{title}\n{note}", fontsize=10)
    return fig


def learning_curve_figure(
    curves: dict[str, tuple[np.ndarray, np.ndarray]],
    reference: float | None,
    title: str,
    *,
    highlight: str | None = None,
    paper: tuple[float, float] | None = None,
    smooth: int = 10,
    hlines: dict[str, float] | None = None,
) -> Figure:
    """Mean CRMs per episode vs episode, one line per learner with a standard-error
    band, the task's reference optimum as a dashed line, optionally the paper's
    reported (episode, CRMs) point. Curves and bands are ``smooth``-episode moving
    averages (plotted at the window's last episode); log-scaled episode axis."""
    fig = Figure(figsize=(7.5, 4.5), layout="constrained")
    ax = fig.add_subplot()
    for name, (mean, sem) in curves.items():
        if smooth > 1 and len(mean) >= smooth:
            kernel = np.ones(smooth) / smooth
            mean = np.convolve(mean, kernel, mode="valid")
            sem = np.convolve(sem, kernel, mode="valid")
        ep = np.arange(len(curves[name][0]) - len(mean) + 1, len(curves[name][0]) + 1)
        lw = 2.2 if name == highlight else 1.2
        (line,) = ax.plot(ep, mean, lw=lw, label=name)
        ax.fill_between(ep, mean - sem, mean + sem, color=line.get_color(), alpha=0.2, lw=0)
    if reference:
        ax.axhline(reference, color="k", ls="--", lw=1, label=f"belief-space optimum {reference:g}")
        ax.axhline(1.05 * reference, color="k", ls=":", lw=0.8, label="optimum + 5%")
    for (label, value), style in zip((hlines or {}).items(), ["-.", (0, (5, 1)), (0, (1, 1)), "--"]):
        ax.axhline(value, color="0.35", ls=style, lw=1.2, label=f"{label} {value:.3g}")
    if paper:
        ax.plot(*paper, "k*", ms=12, label=f"paper: {paper[1]:g} CRMs at ~{paper[0]:g} episodes")
    ax.set_xscale("log")
    ax.set_xlabel("episode")
    ax.set_ylabel(f"CRMs per episode ({smooth}-episode mean)" if smooth > 1 else "CRMs per episode")
    ax.set_ylim(bottom=0)
    ax.set_title(title, fontsize=10)
    ax.legend(fontsize=7, loc="upper right")
    return fig


def rollout_panels(
    obj: Shape, hand: Hand, rows: Sequence[tuple[str, Sequence[Any]]], action_names: Sequence[str]
) -> Figure:
    """One row per rollout, one panel per CRM: the configuration before it, the goal
    line, the moving contact's path and the result (paper Fig. 8)."""
    ncols = max(len(steps) for _, steps in rows)
    fig = Figure(figsize=(3.6 * ncols, 3.2 * len(rows)), layout="constrained")
    axes = fig.subplots(len(rows), ncols, squeeze=False)
    for r, (label, steps) in enumerate(rows):
        for c in range(ncols):
            ax = axes[r][c]
            if c >= len(steps):
                ax.set_axis_off()
                continue
            st = steps[c]
            title = f"{label}\n" if c == 0 else "\n"
            title += f"CRM {c + 1}: {action_names[st.action]} -> {st.outcome.error.name.lower()}"
            draw_scene(ax, obj, hand, st.config, st.outcome, title=title)
            if st.outcome.error == 0 and st.min_friction == 0.0:
                ax.text(0.02, 0.04, "grasp (min friction 0)", transform=ax.transAxes, fontsize=8, color="tab:green")
    return fig


def rollout_animation(obj: Shape, hand: Hand, steps: Sequence[Any], action_names: Sequence[str], path: Any) -> None:
    """Animated GIF of one rollout: the moving contact travels each CRM's path."""
    from matplotlib.animation import FuncAnimation, PillowWriter

    frames: list[tuple[int, int]] = []
    for i, st in enumerate(steps):
        frames += [(i, j) for j in range(1, len(st.outcome.path) + 1)]
    frames.append((len(steps) - 1, -1))
    fig = Figure(figsize=(6, 4.5), layout="constrained")
    ax = fig.add_subplot()
    pts = np.array([p for st in steps for p in (*st.outcome.path, st.config.a.point, st.config.b.point)])
    x0, y0, x1, y1 = obj.bounds()
    pad = 0.25 * max(x1 - x0, y1 - y0)
    limits = (
        min(x0, pts[:, 0].min()) - pad,
        max(x1, pts[:, 0].max()) + pad,
        min(y0, pts[:, 1].min()) - pad,
        max(y1, pts[:, 1].max()) + pad,
    )

    def draw(frame: tuple[int, int]) -> list[Any]:
        i, j = frame
        st = steps[i]
        ax.clear()
        title = f"CRM {i + 1}: {action_names[st.action]}"
        if j == -1:
            done = f" -> {st.outcome.error.name.lower()} (done)"
            draw_scene(ax, obj, hand, st.config, st.outcome, title=title + done)
        else:
            partial = st.outcome._replace(
                path=st.outcome.path[:j], error=1 if j < len(st.outcome.path) else st.outcome.error
            )
            draw_scene(ax, obj, hand, st.config, partial, title=title)
            x, y = st.outcome.path[j - 1]
            ax.plot(x, y, "o", color="tab:purple", ms=10, zorder=5)
        ax.set_xlim(limits[0], limits[1])  # the same view in every frame
        ax.set_ylim(limits[2], limits[3])
        return []

    anim = FuncAnimation(fig, draw, frames=frames, blit=False)
    anim.save(str(path), writer=PillowWriter(fps=2))


def cluster_figure(groups: dict[str, np.ndarray], title: str, xlabel: str, ylabel: str) -> Figure:
    """Scatter of labelled point groups (paper Fig. 9)."""
    fig = Figure(figsize=(5.5, 4.5), layout="constrained")
    ax = fig.add_subplot()
    for (label, pts), marker in zip(groups.items(), "o^s*"):
        pts = np.asarray(pts).reshape(-1, 2)
        ax.scatter(pts[:, 0], pts[:, 1], marker=marker, s=45, label=f"{label} ({len(pts)})", alpha=0.8)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=10)
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    return fig


def checkpoint_figure(
    checkpoints: np.ndarray, curves: dict[str, tuple[np.ndarray, np.ndarray]], reference: float | None, title: str
) -> Figure:
    """Greedy-policy CRMs per episode at training checkpoints, mean and standard error."""
    fig = Figure(figsize=(7.5, 4.5), layout="constrained")
    ax = fig.add_subplot()
    for name, (mean, sem) in curves.items():
        ax.errorbar(checkpoints, mean, yerr=sem, marker="o", ms=3, lw=1.2, capsize=2, label=name)
    if reference:
        ax.axhline(reference, color="k", ls="--", lw=1, label=f"belief-space optimum {reference:g}")
        ax.axhline(1.05 * reference, color="k", ls=":", lw=0.8, label="optimum + 5%")
    ax.set_xscale("log")
    ax.set_xlabel("training episodes")
    ax.set_ylabel("greedy CRMs per episode")
    ax.set_title(title, fontsize=10)
    ax.legend(fontsize=7)
    return fig

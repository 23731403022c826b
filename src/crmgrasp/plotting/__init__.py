"""Figures: the hand-object scene and the experiment plots.

Built on `matplotlib.figure.Figure` directly (no pyplot state), so drawing
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

from crmgrasp._validation import CrmgraspError, finite, float_array, integer, shown
from crmgrasp.model.contacts import ALL_LABELS, Config, Grip, check_contacts
from crmgrasp.model.geometry import Disc, Polygon, Shape
from crmgrasp.model.hand import Hand, Outcome
from crmgrasp.plotting.colors import COLORS

__all__ = [
    "draw_object",
    "draw_scene",
    "is_planar",
    "scene_figure",
    "friction_histogram",
    "learning_curve_figure",
    "checkpoint_figure",
    "learner_color",
    "learner_colors",
    "rollout_panels",
    "rollout_animation",
    "cluster_figure",
    "scene_legend",
]


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
    config: Config | Grip,
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


def _draw_config(
    ax: Axes, hand: Hand, config: Config | Grip, scale: float, *, alpha: float, primed: bool = False
) -> None:
    for lab, c in zip(ALL_LABELS, config):
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
            xytext=(-16 * c.nx - 4, -16 * c.ny - 4),
            color=COLORS[lab],
            alpha=alpha,
            fontsize=11,
        )
    px, py = hand.palm(config)
    if math.isfinite(px):
        first, last = config[0], config[-1]
        ax.plot([first.x, px, last.x], [first.y, py, last.y], "-", color="0.4", lw=0.8, alpha=alpha, zorder=3)
        ax.plot(px, py, "s", color="0.3", ms=7, alpha=alpha, zorder=4)


def is_planar(obj: Any) -> bool:
    """Whether ``obj`` is a planar shape (drawn by [`draw_scene`][]), else a solid (drawn by
    [`crmgrasp.plotting.spatial.draw_scene3d`][])."""
    return isinstance(obj, (Polygon, Disc)) or hasattr(obj, "perimeter")


def check_scene(obj: object, hand: object, config: object, outcome: object) -> None:
    """A one-line error unless ``obj`` is a planar [`Shape`][crmgrasp.model.geometry.Shape]
    with a [`Hand`][crmgrasp.model.hand.Hand], its configuration and an ``Outcome`` or None,
    or a solid with a ``Hand3D``, its configuration and an ``Outcome3D`` or None."""
    from crmgrasp.model import spatial

    hand_kind: type
    outcome_kind: type
    check: Any
    if isinstance(obj, Shape):
        hand_kind, outcome_kind, check = Hand, Outcome, check_contacts
    elif isinstance(obj, spatial.SOLIDS):
        hand_kind, outcome_kind, check = spatial.Hand3D, spatial.Outcome3D, spatial.check_contacts3d
    else:
        raise CrmgraspError(f"a scene's object must be a Shape or a solid, got {shown(obj)}")
    if not isinstance(hand, hand_kind):
        raise CrmgraspError(f"a scene of a {type(obj).__name__} needs a {hand_kind.__name__}, got {shown(hand)}")
    check(config, "configuration", hand.contacts)
    if outcome is not None and not isinstance(outcome, outcome_kind):
        raise CrmgraspError(f"a scene's outcome must be an {outcome_kind.__name__} or None, got {shown(outcome)}")


def scene_figure(
    obj: Shape, hand: Hand, config: Config | Grip, outcome: Outcome | None = None, title: str | None = None
) -> Figure:
    """A one-panel figure of [`draw_scene`][] (of [`crmgrasp.plotting.spatial.scene_figure3d`][]
    for a solid: ``outcome`` then gives the configuration after the CRM); a scene that
    cannot be drawn is a one-line error ([`check_scene`][])."""
    check_scene(obj, hand, config, outcome)
    if not is_planar(obj):
        from crmgrasp.plotting.spatial import scene_figure3d

        after = outcome.config if outcome is not None and outcome.error == 0 else None
        return scene_figure3d(obj, hand, config, after, title)  # type: ignore[arg-type]
    fig = Figure(figsize=(6, 5.2), layout="constrained")
    ax = fig.add_subplot()
    draw_scene(ax, obj, hand, config, outcome, title=title)
    handles, labels = scene_legend(len(config))
    fig.legend(handles, labels, loc="outside lower center", ncols=2, fontsize=7, frameon=False)
    return fig


def friction_histogram(values: Sequence[float], failures: int, title: str) -> Figure:
    """Histogram of minimum friction coefficients (paper Fig. 4; ``values``: numbers, those
    not finite left out)."""
    array = float_array(values, "friction values")
    failures = integer(failures, "failures", 0, 10**12)
    if array.ndim != 1:
        raise CrmgraspError(f"friction values must be a list of numbers, got shape {array.shape}")
    fig = Figure(figsize=(5.5, 3.8), layout="constrained")
    ax = fig.add_subplot()
    vals = array[np.isfinite(array)]
    top = max(0.1, float(vals.max()) * 1.1) if len(vals) else 0.1
    ax.hist(vals, bins=np.linspace(0.0, top, 16).tolist(), color="tab:blue", edgecolor="white")
    ax.set_xlabel("minimum friction coefficient for force closure")
    ax.set_ylabel("grasps")
    note = f"n = {len(array)}" + (f", {failures} failed (no contact / error)" if failures else "")
    ax.set_title(f"{title}\n{note}", fontsize=10)
    return fig


LEARNER_COLORS = {
    "SARSA k=2 (paper)": "black",
    "Q-learning k=2": "0.45",
    "SARSA(0.9) k=2": "tab:blue",
    "Dyna-Q k=2 (20 samples)": "tab:orange",
    "Dyna-Q k=1 (VI sweeps)": "tab:green",
    "Dyna-Q k=1 (VI sweeps, mirror quotient)": "tab:red",
    "fixed sequence": "tab:brown",
    "random": "tab:pink",
    "SARSA k=0": "tab:cyan",
    "SARSA k=1": "tab:olive",
    "SARSA k=2": "black",
    "SARSA k=3": "tab:purple",
}
"""One colour per learner in every figure."""

_SPARE = ("tab:purple", "tab:cyan", "tab:olive", "tab:gray", "gold", "navy", "teal", "maroon")


def learner_color(name: str) -> str:
    """The colour of a learner: fixed for the built-in ones, else chosen from its name
    (the same in every figure and run)."""
    if name in LEARNER_COLORS:
        return LEARNER_COLORS[name]
    return _SPARE[sum(name.encode()) % len(_SPARE)]


def learner_colors(names: Sequence[str]) -> dict[str, str]:
    """One colour per learner of one figure: [`learner_color`][] where no earlier learner
    of the figure has it, else the next spare colour not yet used in the figure (two
    readings whose names hash alike are never drawn alike).

    >>> c = learner_colors(["pessimistic Q0 = -10", "near-corner starts (Fig. 8a), grasp reward 0"])
    >>> len(set(c.values()))
    2
    """
    out: dict[str, str] = {}
    for name in names:
        color = learner_color(name)
        if color in out.values() and name not in LEARNER_COLORS:
            free = [c for c in _SPARE if c not in out.values()]
            start = _SPARE.index(color) if color in _SPARE else 0
            color = min(free, key=lambda c: (_SPARE.index(c) - start) % len(_SPARE)) if free else color
        out[name] = color
    return out


def _smoothed(mean: np.ndarray, sem: np.ndarray, smooth: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Moving averages plotted at each window's last episode (1-based)."""
    n = len(mean)
    if smooth > 1 and n >= smooth:
        kernel = np.ones(smooth) / smooth
        mean, sem = np.convolve(mean, kernel, mode="valid"), np.convolve(sem, kernel, mode="valid")
    return np.arange(n - len(mean) + 1, n + 1), mean, sem


def _twins(curves: dict[str, tuple[np.ndarray, np.ndarray]]) -> dict[str, str]:
    """Curve name -> the earlier curve it equals exactly (drawn dashed, named in the legend)."""
    out: dict[str, str] = {}
    names = list(curves)
    for i, name in enumerate(names):
        for other in names[:i]:
            if other not in out and np.array_equal(curves[name][0], curves[other][0]):
                out[name] = other
                break
    return out


def _check_curves(curves: object) -> None:
    """A one-line error unless ``curves`` maps names to (mean, standard error) pairs of
    equally long 1-D arrays of numbers."""
    if not isinstance(curves, dict) or not all(isinstance(k, str) for k in curves):
        raise CrmgraspError(f"curves must be a dict of learner names to (mean, standard error), got {shown(curves)}")
    for name, pair in curves.items():
        arrays = [float_array(a, f"curve {name!r}") for a in pair] if isinstance(pair, (tuple, list)) else []
        if len(arrays) != 2 or arrays[0].ndim != 1 or arrays[0].shape != arrays[1].shape:
            raise CrmgraspError(f"curve {name!r} must be (mean, standard error): two equally long 1-D arrays")


def learning_curve_figure(
    curves: dict[str, tuple[np.ndarray, np.ndarray]],
    reference: float | None,
    title: str,
    *,
    highlight: str | None = None,
    paper: tuple[float, float] | None = None,
    smooth: int = 10,
    hlines: dict[str, float] | None = None,
    per_panel: int = 4,
    log_x: bool = False,
    ylabel: str = "CRMs per episode",
) -> Figure:
    """Mean CRMs per episode vs episode, one line per learner (its fixed colour,
    [`learner_color`][]) with a standard-error band, at most ``per_panel`` bands per
    panel (more learners: more panels, side by side, the same axes), the task's
    reference optimum dashed and the paper's (episode, CRMs) point. A curve equal to an
    earlier one is drawn dashed and named in the legend ("= SARSA ..."). Curves and bands
    are ``smooth``-episode moving averages plotted at the window's last episode; linear
    episode axis unless ``log_x``."""
    _check_curves(curves)
    if reference is not None:
        reference = finite(reference, "reference")
    twins = _twins(curves)
    banded = [n for n in curves if n not in twins]
    groups = [banded[i : i + per_panel] for i in range(0, max(len(banded), 1), per_panel)] or [[]]
    fig = Figure(figsize=(6.0 * len(groups) + 1.5, 4.6), layout="constrained")
    axes = fig.subplots(1, len(groups), squeeze=False, sharey=True)[0]
    colors = learner_colors(list(curves))
    for ax, group in zip(axes, groups):
        for name in group + [t for t in twins if twins[t] in group]:
            ep, mean, sem = _smoothed(*curves[name], smooth)
            color = colors[name]
            if name in twins:
                ax.plot(ep, mean, lw=1.4, ls=(0, (4, 3)), color=color, zorder=5, label=f"{name} (= {twins[name]})")
                continue
            lw = 2.4 if name == highlight else 1.3
            ax.plot(ep, mean, lw=lw, color=color, zorder=4 if name == highlight else 3, label=name)
            ax.fill_between(ep, mean - sem, mean + sem, color=color, alpha=0.15, lw=0)
        if reference:
            ax.axhline(reference, color="k", ls="--", lw=1, label=f"belief-space optimum {reference:g}")
            ax.axhline(1.05 * reference, color="k", ls=":", lw=0.8, label="optimum + 5%")
        for (label, value), style in zip((hlines or {}).items(), ["-.", (0, (5, 1)), (0, (1, 1)), "--"]):
            ax.axhline(value, color="0.35", ls=style, lw=1.2, label=f"{label} {value:.3g}")
        if paper:
            ax.plot(
                *paper,
                "*",
                color="gold",
                mec="k",
                ms=14,
                zorder=6,
                label=f"paper: {paper[1]:g} CRMs at ~{paper[0]:g} ep.",
            )
        if log_x:
            ax.set_xscale("log")
        ax.set_xlabel("training episode")
        ax.set_ylim(bottom=0)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper right")
    axes[0].set_ylabel(f"{ylabel} ({smooth}-episode moving average)" if smooth > 1 else ylabel)
    fig.suptitle(title, fontsize=10)
    return fig


def scene_legend(contacts: int = 2) -> tuple[list[Any], list[str]]:
    """Legend handles for the scene's marks (``contacts`` contacts, normals, palm, goal
    line, path)."""
    from matplotlib.lines import Line2D

    labels = ALL_LABELS[:contacts]
    handles = [
        *(Line2D([], [], marker="o", ls="", color=COLORS[lab], ms=7) for lab in labels),
        Line2D([], [], marker="s", ls="-", color="0.3", ms=6, lw=0.8),
        Line2D([], [], ls="--", color="tab:green"),
        Line2D([], [], ls=":", color="0.5"),
        Line2D([], [], ls="-", marker=".", color="tab:purple"),
    ]
    texts = [
        "contact a (arrow: sensed inward normal)",
        *(f"contact {lab}" for lab in labels[1:]),
        "palm point (behind the contacts)",
        "goal line within reach",
        "goal line beyond reach",
        "moving contact's path",
    ]
    return handles, texts


def _limits(obj: Shape, points: np.ndarray) -> tuple[float, float, float, float]:
    """A view holding the object and ``points`` with a margin."""
    x0, y0, x1, y1 = obj.bounds()
    pad = 0.25 * max(x1 - x0, y1 - y0)
    return (
        min(x0, points[:, 0].min()) - pad,
        max(x1, points[:, 0].max()) + pad,
        min(y0, points[:, 1].min()) - pad,
        max(y1, points[:, 1].max()) + pad,
    )


def _rollout_points(steps: Sequence[Any]) -> list[tuple[float, float]]:
    return [p for st in steps for p in (*st.outcome.path, *(c.point for c in st.config))]


def rollout_panels(
    obj: Shape, hand: Hand, rows: Sequence[tuple[str, Sequence[Any]]], action_names: Sequence[str]
) -> Figure:
    """One row per rollout, named, one panel per CRM (no empty panels): the
    configuration before it, the goal line, the moving contact's path and the result
    (paper Fig. 8). Every panel has the same scale; one legend explains the marks."""
    ncols = max(len(steps) for _, steps in rows)
    fig = Figure(figsize=(3.6 * ncols, 3.3 * len(rows) + 0.9), layout="constrained")
    subs = fig.subfigures(len(rows), 1, squeeze=False)[:, 0]
    view = _limits(obj, np.array([p for _, steps in rows for p in _rollout_points(steps)]))
    for sub, (label, steps) in zip(subs, rows):
        sub.suptitle(f"start: {label}", fontsize=10, x=0.02, ha="left")
        axes = sub.subplots(1, ncols, squeeze=False)[0]
        for c, ax in enumerate(axes):
            if c >= len(steps):
                ax.remove()
                continue
            st = steps[c]
            title = f"CRM {c + 1}: {action_names[st.action]} -> {st.outcome.error.name.lower()}"
            draw_scene(ax, obj, hand, st.config, st.outcome, title=title)
            ax.set_xlim(view[0], view[1])
            ax.set_ylim(view[2], view[3])
            if st.outcome.error == 0 and st.min_friction == 0.0:
                ax.text(0.02, 0.04, "grasp (min friction 0)", transform=ax.transAxes, fontsize=8, color="tab:green")
    handles, labels = scene_legend()
    fig.legend(handles, labels, loc="outside lower center", ncols=3, fontsize=8, frameon=False)
    return fig


def rollout_animation(
    obj: Shape, hand: Hand, steps: Sequence[Any], action_names: Sequence[str], path: Any, label: str = ""
) -> None:
    """Animated GIF of one rollout: the moving contact travels each CRM's path; every
    frame is titled with the start ``label``, the CRM and its outcome."""
    from matplotlib.animation import FuncAnimation, PillowWriter

    frames: list[tuple[int, int]] = []
    for i, st in enumerate(steps):
        frames += [(i, j) for j in range(1, len(st.outcome.path) + 1)]
    frames.append((len(steps) - 1, -1))
    fig = Figure(figsize=(6, 4.8), layout="constrained")
    ax = fig.add_subplot()
    limits = _limits(obj, np.array(_rollout_points(steps)))
    head = f"{label}\n" if label else ""

    def draw(frame: tuple[int, int]) -> list[Any]:
        i, j = frame
        st = steps[i]
        ax.clear()
        title = f"{head}CRM {i + 1} of {len(steps)}: {action_names[st.action]}"
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
        ax.errorbar(
            checkpoints, mean, yerr=sem, marker="o", ms=3, lw=1.2, capsize=2, color=learner_color(name), label=name
        )
    if reference:
        ax.axhline(reference, color="k", ls="--", lw=1, label=f"belief-space optimum {reference:g}")
        ax.axhline(1.05 * reference, color="k", ls=":", lw=0.8, label="optimum + 5%")
    ax.set_xscale("log")
    ax.set_xlabel("training episodes")
    ax.set_ylabel("greedy CRMs per episode")
    ax.set_title(title, fontsize=10)
    ax.legend(fontsize=7)
    return fig

"""The figure of one run of a policy on a hand: one panel per reading.

``crmgrasp run --figure`` draws what the robot sensed at each reading of the run it logs:
the object, the contacts with their sensed inward normals and the palm point, titled with
the CRM that followed and its error; the last panel says how the run stopped. Panels are
laid out four to a row, all at the same scale (planar) or in the same cube (spatial).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from crmgrasp.plotting import _limits, draw_scene, is_planar, scene_legend

__all__ = ["readings_figure"]

COLUMNS = 4
"""Panels per row."""


def readings_figure(obj: Any, hand: Any, panels: Sequence[tuple[Any, str]], title: str) -> Figure:
    """One panel per ``(sensed configuration, panel title)`` of ``panels``, in order, under
    ``title``; ``obj`` a planar shape or a solid, ``hand`` its hand. With no panel (no
    contact was ever sensed), one empty panel that says so."""
    n = max(1, len(panels))
    cols = min(COLUMNS, n)
    rows = math.ceil(n / cols)
    planar = is_planar(obj)
    fig = Figure(figsize=(3.6 * cols, (3.0 if planar else 3.6) * rows + 0.8), layout="constrained")
    fig.suptitle(title, fontsize=10)
    if not panels:
        ax = fig.add_subplot()
        ax.text(0.5, 0.5, "no contact sensed", ha="center", va="center", transform=ax.transAxes)
        ax.set_axis_off()
        return fig
    if not planar:
        from crmgrasp.plotting.spatial import draw_scene3d

        for i, (config, text) in enumerate(panels):
            draw_scene3d(fig.add_subplot(rows, cols, i + 1, projection="3d"), obj, hand, config, title=text)
        return fig
    palms = [p for p in (hand.palm(config) for config, _ in panels) if all(map(math.isfinite, p))]
    view = _limits(obj, np.array([c.point for config, _ in panels for c in config] + palms))
    for i, (config, text) in enumerate(panels):
        ax = fig.add_subplot(rows, cols, i + 1)
        draw_scene(ax, obj, hand, config, title=text)
        ax.set_xlim(view[0], view[1])
        ax.set_ylim(view[2], view[3])
    marks = len(panels[0][0]) + 1  # the contacts and the palm: no goal line or path is drawn here
    handles, labels = scene_legend(marks - 1)
    fig.legend(handles[:marks], labels[:marks], loc="outside lower center", ncols=3, fontsize=8, frameon=False)
    return fig

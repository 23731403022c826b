"""Planar objects: boundary, inward normals, projection, strict inside test, ray entry.

Conventions ([docs/model.md section 1][model-1])
----------------------------
* Units are metres; the plane is x-y and z points out of the plane.
* Polygon vertices are stored counter-clockwise (clockwise input is reversed).
* Every boundary point has an inward unit normal ``n``. For a CCW edge with
  direction ``e`` the inward normal is ``n = (-e_y, e_x)``.
* "Inside" means strictly inside: a point within [`EPS`][] of the boundary is
  *not* inside.
* Arclength ``s`` runs counter-clockwise from vertex 0 (polygons) or from the
  point at angle 0 (discs), in ``[0, perimeter)``.

The inside test and the first-entry rule are defined here once, on plain Python
floats ([`Polygon.contains`][], [`Polygon.ray_entry`][] and the functions of
`crmgrasp.model.polygon`; [`Disc.contains`][], [`Disc.ray_entry`][]). Batched
and compiled evaluations live in [`crmgrasp.kernels`][] and are tested equal to
these bit for bit.
"""

from __future__ import annotations

import math

import numpy as np

from crmgrasp._validation import CrmgraspError, as_numbers, as_point, finite, positive, shown
from crmgrasp.model.disc import Disc
from crmgrasp.model.polygon import MAX_VERTICES, Polygon, rigid_motion
from crmgrasp.model.shape import EPS, LINE_TOL, S_TOL, BoundaryPoint, Entry, Shape

__all__ = [
    "EPS",
    "S_TOL",
    "LINE_TOL",
    "BoundaryPoint",
    "Entry",
    "Shape",
    "Polygon",
    "Disc",
    "Rectangle",
    "regular_polygon",
]


def Rectangle(  # noqa: N802 - reads as a type
    length: float, width: float, pose: tuple[float, float, float] | None = None
) -> Polygon:
    """Axis-aligned rectangle centred at the origin, long axis along x; with ``pose``
    ``(angle, dx, dy)``, that rectangle rotated by ``angle`` (radians) about the origin,
    then translated by ``(dx, dy)`` (metres): the vertices of
    ``Rectangle(length, width).moved(*pose)``, bit for bit, built as one polygon.

    Parameters
    ----------
    length
        Extent along x in metres (> 0).
    width
        Extent along y in metres (> 0).
    pose
        ``(angle, dx, dy)``, or ``None`` for the rectangle at the origin.

    Examples
    --------
    >>> Rectangle(0.30, 0.10).vertices
    ((-0.15, -0.05), (0.15, -0.05), (0.15, 0.05), (-0.15, 0.05))
    """
    hx = positive(length, "rectangle length") / 2.0
    hy = positive(width, "rectangle width") / 2.0
    corners = [(-hx, -hy), (hx, -hy), (hx, hy), (-hx, hy)]
    if pose is None:
        return Polygon(corners, _simple=True)
    return Polygon(rigid_motion(corners, *as_numbers(pose, "rectangle pose", 3, "(angle, dx, dy)")), _simple=True)


def regular_polygon(
    n: int, circumradius: float, center: tuple[float, float] = (0.0, 0.0), rotation: float = 0.0
) -> Polygon:
    """Regular ``n``-gon with vertex ``k`` at angle ``rotation + 2 pi k / n`` (radians).

    Examples
    --------
    >>> len(regular_polygon(6, 0.1).vertices)
    6
    """
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or not 3 <= n <= MAX_VERTICES:
        raise CrmgraspError(f"a regular polygon needs an integer n in [3, {MAX_VERTICES}], got {shown(n)}")
    r = positive(circumradius, "circumradius")
    cx, cy = as_point(center, "center")
    rot = finite(rotation, "rotation")
    return Polygon(
        [
            (cx + r * math.cos(rot + 2 * math.pi * k / n), cy + r * math.sin(rot + 2 * math.pi * k / n))
            for k in range(int(n))
        ],
        _simple=True,
    )

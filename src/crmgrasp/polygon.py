"""Simple polygons, convex or not (see :mod:`crmgrasp.geometry` for the conventions)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._columns import ConvexColumns
from ._geombase import _S_TOL, EPS, Array, BoundaryPoint, Entry, _points, _ray_entry_rows
from ._scalar import contains, convex_entry, first_entry
from ._validation import CrmgraspError, as_point, finite

__all__ = ["Polygon"]


def _segments_cross(p: tuple, q: tuple, r: tuple, s: tuple) -> bool:
    """True if closed segments pq and rs share a point (collinear overlap included)."""

    def orient(a: tuple, b: tuple, c: tuple) -> float:
        return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])

    def on_seg(a: tuple, b: tuple, c: tuple) -> bool:
        return min(a[0], b[0]) <= c[0] <= max(a[0], b[0]) and min(a[1], b[1]) <= c[1] <= max(a[1], b[1])

    d1, d2, d3, d4 = orient(r, s, p), orient(r, s, q), orient(p, q, r), orient(p, q, s)
    if ((d1 > 0) != (d2 > 0)) and d1 != 0 and d2 != 0 and ((d3 > 0) != (d4 > 0)) and d3 != 0 and d4 != 0:
        return True
    return (
        (d1 == 0 and on_seg(r, s, p))
        or (d2 == 0 and on_seg(r, s, q))
        or (d3 == 0 and on_seg(p, q, r))
        or (d4 == 0 and on_seg(p, q, s))
    )


@dataclass(frozen=True, eq=False)
class Polygon:
    """A simple polygon, convex or not.

    Parameters
    ----------
    vertices
        Sequence of at least 3 ``(x, y)`` points in metres, in either orientation
        (clockwise input is reversed to counter-clockwise). The polygon must be
        simple (no self-intersection) with non-zero area and no repeated vertex.

    Examples
    --------
    >>> sq = Polygon([(0, 0), (1, 0), (1, 1), (0, 1)])
    >>> sq.contains((0.5, 0.5)), sq.contains((1.0, 0.5)), sq.contains((2.0, 0.5))
    (True, False, False)
    >>> sq.project((0.5, -0.2)).normal      # inward normal of the bottom edge
    (-0.0, 1.0)
    >>> sq.ray_entry((0.5, 2.0), (0.0, -1.0), 5.0).point   # enters through the top
    (0.5, 1.0)
    """

    vertices: tuple[tuple[float, float], ...]

    def __init__(self, vertices: ArrayLike) -> None:
        try:
            raw: list[Any] = list(vertices)  # type: ignore[call-overload, arg-type]
        except TypeError:
            raise CrmgraspError(f"polygon vertices must be a sequence of (x, y), got {vertices!r}") from None
        if len(raw) < 3:
            raise CrmgraspError(f"a polygon needs at least 3 vertices, got {len(raw)}")
        pts = [as_point(v, f"vertex {i}") for i, v in enumerate(raw)]
        area2 = sum(
            pts[i][0] * pts[(i + 1) % len(pts)][1] - pts[(i + 1) % len(pts)][0] * pts[i][1] for i in range(len(pts))
        )
        scale = max(max(abs(x), abs(y)) for x, y in pts) or 1.0
        if abs(area2) <= 1e-12 * scale * scale:
            raise CrmgraspError("polygon has zero area")
        if area2 < 0:
            pts.reverse()
        _check_simple(pts)
        object.__setattr__(self, "vertices", tuple(pts))

    def __repr__(self) -> str:
        return f"Polygon({[tuple(round(c, 6) for c in v) for v in self.vertices]})"

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Polygon) and type(other) is type(self) and other.vertices == self.vertices

    def __hash__(self) -> int:
        return hash(self.vertices)

    # ----------------------------------------------------------- derived data
    @cached_property
    def edges(self) -> tuple[tuple[float, float, float, float, float, float, float], ...]:
        """Per edge ``(ax, ay, ex, ey, L2, nx, ny)``: start, edge vector, squared
        length, inward unit normal."""
        out = []
        v = self.vertices
        for i in range(len(v)):
            (ax, ay), (bx, by) = v[i], v[(i + 1) % len(v)]
            ex, ey = bx - ax, by - ay
            length = math.sqrt(ex * ex + ey * ey)
            out.append((ax, ay, ex, ey, ex * ex + ey * ey, -ey / length, ex / length))
        return tuple(out)

    @cached_property
    def convex(self) -> bool:
        """True if every vertex turns left (CCW convex; collinear vertices allowed)."""
        e = self.edges
        return all(e[i][2] * e[(i + 1) % len(e)][3] - e[i][3] * e[(i + 1) % len(e)][2] >= 0.0 for i in range(len(e)))

    @cached_property
    def _columns(self) -> ConvexColumns:
        """Whole-column constants for the convex fast paths (:mod:`crmgrasp._columns`)."""
        return ConvexColumns(self.edges)

    @cached_property
    def _edge_arrays(self) -> Array:
        return np.array(self.edges, dtype=np.float64)  # (E, 7)

    @cached_property
    def _cumlen(self) -> tuple[float, ...]:
        acc, out = 0.0, [0.0]
        for e in self.edges:
            acc += math.sqrt(e[4])
            out.append(acc)
        return tuple(out)

    @property
    def perimeter(self) -> float:
        """Total boundary length in metres."""
        return self._cumlen[-1]

    @property
    def area(self) -> float:
        """Enclosed area in square metres (positive)."""
        v = self.vertices
        n = len(v)
        return 0.5 * sum(v[i][0] * v[(i + 1) % n][1] - v[(i + 1) % n][0] * v[i][1] for i in range(n))

    def bounds(self) -> tuple[float, float, float, float]:
        """``(xmin, ymin, xmax, ymax)``."""
        xs = [x for x, _ in self.vertices]
        ys = [y for _, y in self.vertices]
        return (min(xs), min(ys), max(xs), max(ys))

    def vertex_arclengths(self) -> tuple[float, ...]:
        """Arclength of each vertex (where normals are undefined)."""
        return self._cumlen[:-1]

    # ------------------------------------------------------------- boundary
    def boundary(self, s: float) -> BoundaryPoint:
        """Point and inward normal at arclength ``s`` (wrapped into ``[0, perimeter)``).

        At a vertex the point belongs to the edge that *starts* there.
        """
        s = finite(s, "arclength") % self.perimeter
        cum = self._cumlen
        i = int(np.searchsorted(cum, s, side="right")) - 1
        i = min(i, len(self.edges) - 1)
        ax, ay, ex, ey, l2, nx, ny = self.edges[i]
        frac = (s - cum[i]) / math.sqrt(l2)
        return BoundaryPoint((ax + frac * ex, ay + frac * ey), (nx, ny), s)

    def boundary_batch(self, s: ArrayLike) -> tuple[Array, Array]:
        """Vectorised :meth:`boundary`: points ``(N, 2)`` and normals ``(N, 2)``."""
        s = np.mod(np.asarray(s, dtype=np.float64), self.perimeter)
        cum = np.asarray(self._cumlen)
        i = np.minimum(np.searchsorted(cum, s, side="right") - 1, len(self.edges) - 1)
        e = self._edge_arrays[i]
        frac = (s - cum[i]) / np.sqrt(e[:, 4])
        pts = np.stack([e[:, 0] + frac * e[:, 2], e[:, 1] + frac * e[:, 3]], axis=1)
        return pts, e[:, 5:7].copy()

    def project(self, p: ArrayLike) -> BoundaryPoint:
        """Nearest boundary point to ``p``, with its inward normal and arclength.

        Raises
        ------
        CrmgraspError
            If the nearest point is a vertex, where the normal is undefined.
        """
        px, py = as_point(p, "point")
        best: tuple[float, int, float] | None = None
        for i, (ax, ay, ex, ey, l2, _, _) in enumerate(self.edges):
            t = min(1.0, max(0.0, ((px - ax) * ex + (py - ay) * ey) / l2))
            dx, dy = ax + t * ex - px, ay + t * ey - py
            d2 = dx * dx + dy * dy
            if best is None or d2 < best[0]:
                best = (d2, i, t)
        assert best is not None
        _, i, t = best
        ax, ay, ex, ey, l2, nx, ny = self.edges[i]
        if t <= 0.0 or t >= 1.0:
            vx, vy = (ax, ay) if t <= 0.0 else (ax + ex, ay + ey)
            raise CrmgraspError(
                f"point ({px:g}, {py:g}) projects onto vertex ({vx:g}, {vy:g}), where the "
                "normal is undefined; move it along an edge"
            )
        off = (px - ax) * nx + (py - ay) * ny  # signed distance inside the edge's line
        return BoundaryPoint((px - off * nx, py - off * ny), (nx, ny), self._cumlen[i] + t * math.sqrt(l2))

    def _edge_distances2(self, px: float, py: float) -> list[float]:
        out = []
        for ax, ay, ex, ey, l2, _, _ in self.edges:
            t = min(1.0, max(0.0, ((px - ax) * ex + (py - ay) * ey) / l2))
            dx, dy = ax + t * ex - px, ay + t * ey - py
            out.append(dx * dx + dy * dy)
        return out

    def distance(self, p: ArrayLike) -> float:
        """Unsigned distance from ``p`` to the boundary, in metres."""
        return math.sqrt(min(self._edge_distances2(*as_point(p, "point"))))

    def edge_index(self, p: ArrayLike) -> int:
        """Index of the edge nearest ``p`` (edge ``i`` runs from vertex ``i`` to ``i + 1``)."""
        d2 = self._edge_distances2(*as_point(p, "point"))
        return d2.index(min(d2))

    def edge_length(self, i: int) -> float:
        """Length of edge ``i`` in metres."""
        return math.sqrt(self.edges[i][4])

    # --------------------------------------------------------------- inside
    def contains(self, p: ArrayLike) -> bool:
        """True if ``p`` is strictly inside (farther than :data:`EPS` from the boundary).

        Convex polygons test the signed distance to every edge's line; others count
        crossings of a ray toward +x and then check the distance to the boundary.
        """
        px, py = (p[0], p[1]) if isinstance(p, tuple) else as_point(p, "point")
        return contains(px, py, self.edges, self.convex)

    def contains_batch(self, p: ArrayLike) -> NDArray[np.bool_]:
        """Vectorised :meth:`contains` over points of shape ``(N, 2)``."""
        pts = _points(p)
        with np.errstate(all="ignore"):
            return self.contains_xy(pts[:, 0], pts[:, 1])

    def contains_xy(self, x: Array, y: Array) -> NDArray[np.bool_]:
        """:meth:`contains` on coordinate columns (no validation; NaN is outside).
        Call inside ``np.errstate(all="ignore")``."""
        if self.convex:  # one whole-column pass per edge (a short-axis reduction is slower)
            return self._columns.contains(np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64))
        px, py = x[:, None], y[:, None]
        e = self._edge_arrays
        eax, eay, eex, eey, el2 = e[:, 0], e[:, 1], e[:, 2], e[:, 3], e[:, 4]
        by = eay + eey
        straddle = (eay > py) != (by > py)
        xint = eax + (py - eay) * eex / eey
        inside = (np.count_nonzero(straddle & (px < xint), axis=1) % 2) == 1
        t = np.minimum(1.0, np.maximum(0.0, ((px - eax) * eex + (py - eay) * eey) / el2))
        dx, dy = eax + t * eex - px, eay + t * eey - py
        near = np.any(dx * dx + dy * dy <= EPS * EPS, axis=1)
        return inside & ~near

    # ------------------------------------------------------------ ray entry
    def ray_entry(self, origin: tuple[float, float], direction: tuple[float, float], u_max: float) -> Entry | None:
        """First point where the segment ``origin + u direction``, ``0 <= u <= u_max``,
        crosses the boundary from outside to inside (``direction . n > 0``).

        ``direction`` need not be unit length; ``u`` is in its units. Returns
        ``None`` if the segment never enters the object. On a convex polygon the
        entry edge is found from the vertices' sides of the line
        (:func:`crmgrasp._scalar.convex_entry`: a line through a vertex, along an
        edge, or passing a vertex closer than ``LINE_TOL`` enters at that vertex,
        by the lower-index edge of those that qualify); otherwise the smallest
        ``u`` over the edges wins and ties (a ray through a vertex) go to the lower
        edge index.
        """
        entry = convex_entry if self.convex else first_entry
        hit = entry(origin[0], origin[1], direction[0], direction[1], u_max, self.edges)
        return None if hit is None else Entry(hit[0], (hit[1], hit[2]), (hit[3], hit[4]))

    def ray_entry_batch(self, origin: Array, direction: Array, u_max: Array) -> tuple[Array, Array, Array]:
        """Vectorised :meth:`ray_entry` over ``N`` segments.

        Returns ``u`` of shape ``(N,)`` (``inf`` where the segment never enters),
        entry points ``(N, 2)`` and inward normals ``(N, 2)`` (NaN where none).
        """
        return _ray_entry_rows(self, origin, direction, u_max)

    def ray_entry_xy(
        self, ox: Array, oy: Array, dx: Array, dy: Array, u_max: Array
    ) -> tuple[Array, Array, Array, Array, Array]:
        """:meth:`ray_entry` on columns: ``u`` (``inf`` if none), entry ``x``, ``y`` and
        normal ``nx``, ``ny`` (NaN if none). Call inside ``np.errstate(all="ignore")``."""
        if self.convex:
            out = np.empty((4, len(ox)))
            ok, u = self._columns.entry(ox, oy, dx, dy, u_max + EPS, out)
            hx, hy, hnx, hny = (np.where(ok, row, np.nan) for row in out)
            return np.where(ok, u, np.inf), hx, hy, hnx, hny
        u_best = np.full(len(ox), np.inf)
        bnx, bny = np.full(len(ox), np.nan), np.full(len(ox), np.nan)
        hi = u_max + EPS
        for ax, ay, ex, ey, l2, nx, ny in self.edges:  # running minimum; ties keep the earlier edge
            denom = dx * nx + dy * ny
            u = ((ax - ox) * nx + (ay - oy) * ny) / denom
            s = (((ox + u * dx) - ax) * ex + ((oy + u * dy) - ay) * ey) / l2
            better = (denom > 0.0) & (u >= -EPS) & (u <= hi) & (s >= -_S_TOL) & (s <= 1.0 + _S_TOL) & (u < u_best)
            u_best = np.where(better, u, u_best)
            bnx = np.where(better, nx, bnx)
            bny = np.where(better, ny, bny)
        hit = u_best != np.inf
        px = np.where(hit, ox + u_best * dx, np.nan)
        py = np.where(hit, oy + u_best * dy, np.nan)
        return u_best, px, py, bnx, bny


def _check_simple(pts: list[tuple[float, float]]) -> None:
    n = len(pts)
    for i in range(n):
        p, q = pts[i], pts[(i + 1) % n]
        if p == q:
            raise CrmgraspError(f"polygon has a repeated vertex {p} (zero-length edge {i})")
    for i in range(n):
        p, q = pts[i], pts[(i + 1) % n]
        r = pts[(i + 2) % n]
        ux, uy, wx, wy = q[0] - p[0], q[1] - p[1], r[0] - q[0], r[1] - q[1]
        if ux * wy - uy * wx == 0.0 and ux * wx + uy * wy < 0.0:
            raise CrmgraspError(f"polygon is not simple: edges {i} and {(i + 1) % n} fold back")
        for j in range(i + 2, n):
            if i == 0 and j == n - 1:
                continue
            if _segments_cross(p, q, pts[j], pts[(j + 1) % n]):
                raise CrmgraspError(f"polygon is not simple: edges {i} and {j} intersect")

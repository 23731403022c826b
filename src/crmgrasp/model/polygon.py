"""Simple polygons, convex or not (see [`crmgrasp.model.geometry`][] for the conventions)."""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence, Sized
from dataclasses import dataclass
from functools import cached_property
from itertools import chain
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from crmgrasp._validation import CrmgraspError, as_point, finite, shown
from crmgrasp.model.shape import EPS, LINE_TOL, MAX_COORD, S_TOL, Array, BoundaryPoint, Entry

__all__ = [
    "Polygon",
    "Edges",
    "MAX_COORD",
    "MAX_VERTICES",
    "rigid_motion",
    "inside",
    "first_entry",
    "convex_edge",
    "convex_entry",
]

MAX_VERTICES = 512
"""The most vertices a polygon may have (the self-intersection test grows with their
square; object families draw within it)."""

Edges = tuple[tuple[float, float, float, float, float, float, float], ...]
"""Per edge ``(ax, ay, ex, ey, l2, nx, ny)``: start, edge vector, squared length,
inward unit normal ([`Polygon.edges`][])."""


def _bounded(pts: Sequence[tuple[float, float]]) -> float:
    """The largest ``|coordinate|`` of ``pts``; a one-line error if one is not finite
    (NaN included) or beyond [`MAX_COORD`][crmgrasp.model.shape.MAX_COORD]."""
    flat = [abs(c) for p in pts for c in p]
    largest = max(flat)
    if not (largest <= MAX_COORD and math.isfinite(sum(flat))):  # the sum catches a NaN anywhere
        raise CrmgraspError(f"a vertex is not finite or beyond +-{MAX_COORD:g} m")
    return largest


def rigid_motion(pts: Iterable[tuple[float, float]], angle: float, dx: float, dy: float) -> list[tuple[float, float]]:
    """``pts`` rotated by ``angle`` (radians, counter-clockwise) about the origin, then
    translated by ``(dx, dy)`` (metres): ``(c x - s y + dx, s x + c y + dy)`` with
    ``c, s = cos(angle), sin(angle)``."""
    c, s = math.cos(angle), math.sin(angle)
    return [(c * x - s * y + dx, s * x + c * y + dy) for x, y in pts]


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

    def __init__(self, vertices: ArrayLike, _simple: bool = False) -> None:
        """``_simple=True`` (for the package's own constructions, a new list of ``(x, y)``
        pairs of Python floats: rectangles, regular polygons) skips the self-intersection
        test, the only check whose cost grows with the square of the vertices, and takes the
        list as it is; every other check still runs."""
        if _simple:  # the package's own list of (x, y) pairs
            raw: list[Any] = vertices  # type: ignore[assignment]
        else:
            count = len(vertices) if isinstance(vertices, Sized) else 0
            if count > MAX_VERTICES:  # before any work on them
                raise CrmgraspError(f"a polygon may have at most {MAX_VERTICES} vertices, got {count}")
            try:
                raw = list(vertices)  # type: ignore[call-overload, arg-type]
            except TypeError:
                raise CrmgraspError(f"polygon vertices must be a sequence of (x, y), got {shown(vertices)}") from None
        if len(raw) > MAX_VERTICES:
            raise CrmgraspError(f"a polygon may have at most {MAX_VERTICES} vertices, got {len(raw)}")
        if len(raw) < 3:
            raise CrmgraspError(f"a polygon needs at least 3 vertices, got {len(raw)}")
        if _simple:  # the package's own (x, y) pairs of floats: one bound check for all
            pts = raw
            scale = _bounded(pts)
        else:
            pts = [as_point(v, f"vertex {i}") for i, v in enumerate(raw)]
            for i, (x, y) in enumerate(pts):
                if abs(x) > MAX_COORD or abs(y) > MAX_COORD:
                    raise CrmgraspError(f"vertex {i} ({x:g}, {y:g}) is beyond +-{MAX_COORD:g} m")
            scale = max(map(abs, chain.from_iterable(pts)))
        area2, (x0, y0) = 0.0, pts[0]  # twice the signed area, summed edge by edge from the first
        for x1, y1 in pts[1:] + pts[:1]:
            area2 += x0 * y1 - x1 * y0
            x0, y0 = x1, y1
        scale = scale or 1.0
        if abs(area2) <= 1e-12 * scale * scale:
            raise CrmgraspError("polygon has zero area")
        if area2 < 0:
            pts.reverse()
        if not _simple:
            _check_simple(pts)
        object.__setattr__(self, "vertices", tuple(pts))

    def moved(self, angle: float, dx: float, dy: float) -> Polygon:
        """This polygon rotated by ``angle`` (radians, counter-clockwise) about the origin,
        then translated by ``(dx, dy)`` (metres). A rigid motion keeps a simple polygon
        simple, its area and its orientation, so only the bound on the coordinates is
        checked again.

        >>> Polygon([(0, 0), (1, 0), (0, 1)]).moved(0.0, 1.0, 2.0).vertices
        ((1.0, 2.0), (2.0, 2.0), (1.0, 3.0))
        """
        pts = tuple(rigid_motion(self.vertices, angle, dx, dy))
        _bounded(pts)
        out = object.__new__(Polygon)  # simple, with this polygon's area and orientation
        object.__setattr__(out, "vertices", pts)
        return out

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
    def edge_array(self) -> Array:
        """[`edges`][] as a read-only ``(E, 7)`` float array (for the compiled kernels)."""
        arr = np.array(self.edges, dtype=np.float64)
        arr.flags.writeable = False
        return arr

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
        """True if ``p`` is strictly inside (farther than [`EPS`][] from the boundary):
        `inside` on this polygon's edges."""
        px, py = (p[0], p[1]) if isinstance(p, tuple) else as_point(p, "point")
        return inside(px, py, self.edges, self.convex)

    # ------------------------------------------------------------ ray entry
    def ray_entry(self, origin: tuple[float, float], direction: tuple[float, float], u_max: float) -> Entry | None:
        """First point where the segment ``origin + u direction``, ``0 <= u <= u_max``,
        crosses the boundary from outside to inside (``direction . n > 0``).

        ``direction`` need not be unit length; ``u`` is in its units. Returns
        ``None`` if the segment never enters the object. A convex polygon uses
        `convex_entry` (the entry edge from the vertices' sides of the line: a
        line through a vertex, along an edge, or passing a vertex closer than
        [`LINE_TOL`][] enters at that vertex, by the lower-index edge of those that
        qualify); any other polygon `first_entry` (the smallest ``u`` over the
        edges; ties, a ray through a vertex, go to the lower edge index).
        """
        entry = convex_entry if self.convex else first_entry
        hit = entry(origin[0], origin[1], direction[0], direction[1], u_max, self.edges)
        return None if hit is None else Entry(hit[0], (hit[1], hit[2]), (hit[3], hit[4]))


def _check_simple(pts: list[tuple[float, float]]) -> None:
    """Refuse repeated vertices, edges folding back onto the previous one, and edges that
    touch or cross ([`_segments_cross`][]), reporting the first such pair ``(i, j)``
    in order. Only pairs whose bounding boxes share a cell of a uniform grid (about
    ``n`` cells) are tested: every touching pair does, so the answer is that of testing
    all pairs, in near-linear time for ordinary polygons."""
    n = len(pts)
    for i in range(n):
        p, q = pts[i], pts[(i + 1) % n]
        if p == q:
            raise CrmgraspError(f"polygon has a repeated vertex {p} (zero-length edge {i})")
    candidates = _grid_pairs(pts)
    for i in range(n):
        p, q = pts[i], pts[(i + 1) % n]
        r = pts[(i + 2) % n]
        ux, uy, wx, wy = q[0] - p[0], q[1] - p[1], r[0] - q[0], r[1] - q[1]
        if ux * wy - uy * wx == 0.0 and ux * wx + uy * wy < 0.0:
            raise CrmgraspError(f"polygon is not simple: edges {i} and {(i + 1) % n} fold back")
        for j in candidates.get(i, ()):
            if _segments_cross(p, q, pts[j], pts[(j + 1) % n]):
                raise CrmgraspError(f"polygon is not simple: edges {i} and {j} intersect")


def _grid_pairs(pts: list[tuple[float, float]]) -> dict[int, list[int]]:
    """Per edge ``i``, the sorted edges ``j > i + 1`` (not the edge closing the ring with
    edge 0) whose bounding boxes share a grid cell with edge ``i``'s."""
    n = len(pts)
    xs, ys = [x for x, _ in pts], [y for _, y in pts]
    x0, y0 = min(xs), min(ys)
    side = max(1, math.isqrt(n))
    wx = (max(xs) - x0) / side or 1.0
    wy = (max(ys) - y0) / side or 1.0

    def cell(v: float, lo: float, w: float) -> int:
        return min(side - 1, max(0, int((v - lo) / w)))

    cells: dict[tuple[int, int], list[int]] = {}
    for i in range(n):
        (ax, ay), (bx, by) = pts[i], pts[(i + 1) % n]
        cx0, cx1 = cell(min(ax, bx), x0, wx), cell(max(ax, bx), x0, wx)
        cy0, cy1 = cell(min(ay, by), y0, wy), cell(max(ay, by), y0, wy)
        for cx in range(cx0, cx1 + 1):
            for cy in range(cy0, cy1 + 1):
                cells.setdefault((cx, cy), []).append(i)
    pairs: dict[int, set[int]] = {}
    for members in cells.values():
        for a in range(len(members)):
            for b in range(a + 1, len(members)):
                i, j = members[a], members[b]  # i < j: edges are added in order
                if j >= i + 2 and not (i == 0 and j == n - 1):
                    pairs.setdefault(i, set()).add(j)
    return {i: sorted(js) for i, js in pairs.items()}


# ------------------------------------------------------------------ the rules
# Plain functions of a polygon's edge tuples: the readable definition of the inside
# test and of first entry. The compiled kernels (crmgrasp.kernels) implement the
# same expressions in the same order and are tested equal to these bit for bit.


def inside(px: float, py: float, edges: Edges, convex: bool) -> bool:
    """Strictly inside (farther than ``EPS`` from the boundary).

    Convex polygons: ``(p - a_i) . n_i > EPS`` for every edge ``i``. Others: an odd
    number of edges cross the ray from ``p`` toward +x, and no edge is within
    ``EPS`` of ``p``.
    """
    if convex:
        for ax, ay, _, _, _, nx, ny in edges:
            if (px - ax) * nx + (py - ay) * ny <= EPS:
                return False
        return True
    odd = False
    for ax, ay, ex, ey, _, _, _ in edges:
        if (ay > py) != (ay + ey > py) and px < ax + (py - ay) * ex / ey:
            odd = not odd
    if not odd:
        return False
    for ax, ay, ex, ey, l2, _, _ in edges:
        t = min(1.0, max(0.0, ((px - ax) * ex + (py - ay) * ey) / l2))
        dx, dy = ax + t * ex - px, ay + t * ey - py
        if dx * dx + dy * dy <= EPS * EPS:
            return False
    return True


def first_entry(
    ox: float, oy: float, dx: float, dy: float, u_max: float, edges: Edges
) -> tuple[float, float, float, float, float] | None:
    """First entry ``(u, x, y, nx, ny)`` of the segment ``o + u d``, ``0 <= u <= u_max``
    (``EPS`` slack), through an edge it crosses inward (``d . n > 0``) within the edge
    (``S_TOL`` slack); ties go to the lower edge index; ``None`` if it never enters."""
    hi = u_max + EPS
    best: tuple[float, float, float, float, float] | None = None
    for ax, ay, ex, ey, l2, enx, eny in edges:
        denom = dx * enx + dy * eny
        if denom <= 0.0:
            continue
        u = ((ax - ox) * enx + (ay - oy) * eny) / denom
        if u < -EPS or u > hi:
            continue
        qx, qy = ox + u * dx, oy + u * dy
        s = ((qx - ax) * ex + (qy - ay) * ey) / l2
        if s < -S_TOL or s > 1.0 + S_TOL:
            continue
        if best is None or u < best[0]:
            best = (u, qx, qy, enx, eny)
    return best


def convex_edge(ox: float, oy: float, dx: float, dy: float, edges: Edges) -> int:
    """The edge through which the line ``o + u d`` enters a convex polygon, or -1.

    Vertex ``j``'s side of the line is the sign of ``c_j = d x (v_j - o) = dx (v_jy -
    oy) - dy (v_jx - ox)``: left (``c_j > tol``), right (``c_j < -tol``) or on the
    line, with ``tol = LINE_TOL (|dx| + |dy|)``. Edge ``i`` (vertex ``i`` to ``i +
    1``) is crossed inward when its start is not on the right, its end not on the
    left, and not both are on the line; the first such edge is returned. A line
    through a vertex, or along an edge, or missing a corner by less than
    ``LINE_TOL``, thus enters at that vertex, as `first_entry`'s slack does.
    """
    tol = LINE_TOL * (abs(dx) + abs(dy))
    ntol = -tol
    first = prev = 0.0
    i = -1
    for vx, vy, _, _, _, _, _ in edges:
        c = dx * (vy - oy) - dy * (vx - ox)
        if i < 0:
            first = c
        elif prev >= ntol and c <= tol and (prev > tol or c < ntol):  # start not right, end not left, not both on
            return i
        prev = c
        i += 1
    if prev >= ntol and first <= tol and (prev > tol or first < ntol):
        return i
    return -1


def convex_entry(
    ox: float, oy: float, dx: float, dy: float, u_max: float, edges: Edges
) -> tuple[float, float, float, float, float] | None:
    """`first_entry` for a convex polygon: the entry edge from the vertices'
    sides of the line ([`convex_edge`][]), then ``u = ((a_i - o) . n_i) / (d . n_i)``,
    accepted when ``d . n_i > 0`` and ``-EPS <= u <= u_max + EPS``. Away from
    vertices this is `first_entry`'s edge and ``u``, bit for bit."""
    i = convex_edge(ox, oy, dx, dy, edges)
    if i < 0:
        return None
    ax, ay, _, _, _, enx, eny = edges[i]
    denom = dx * enx + dy * eny
    if not denom > 0.0:
        return None
    u = ((ax - ox) * enx + (ay - oy) * eny) / denom
    if not (u >= -EPS and u <= u_max + EPS):
        return None
    return (u, ox + u * dx, oy + u * dy, enx, eny)

"""Whole-column geometry and the batched CRM kernel for convex polygons (numpy).

The generic batched path (:func:`crmgrasp.batch.execute_columns` on any shape)
loops over edges with a running minimum, about 35 whole-array operations per
edge. On a convex polygon far fewer suffice, and the results stay equal to the
scalar path bit for bit because both evaluate the same expressions:

- *inside*: the signed distance to each edge's line, ``(x - a) . n > EPS``, with
  the terms of a zero normal component dropped and a unit component's product
  skipped (``x * 1 == x``, ``x * -1 == -x`` and adding ``+-0`` never change a
  comparison with ``EPS``), e.g. two operations per edge of an axis-aligned box;
- *first entry*: the vertices' sides of the line decide the entry edge
  (:func:`crmgrasp._scalar.convex_entry`); a bit code of the strict sides and one
  table look-up replace the loop over edges, and the rare rows with a vertex
  within ``LINE_TOL`` of the line take the scalar rule;
- *the CRM*: selections by the contact labels are made on ``(4, N)`` blocks, and
  the feasibility test works on the stationary and the moved contact directly
  (``b - a`` is ``+-(moved - stationary)``, and a product with ``+-1`` is exact).

All functions take and return ``(N,)`` columns or ``(8, N)`` blocks (rows ``ax,
ay, anx, any, bx, by, bnx, bny``) and are called inside
``np.errstate(all="ignore")``.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import partial

import numpy as np
from numpy.typing import NDArray

from ._geombase import EPS
from ._scalar import LINE_TOL, convex_edge

__all__ = ["ConvexColumns", "execute_convex", "pair_checks"]

F64 = NDArray[np.float64]
Bools = NDArray[np.bool_]
Contacts = F64 | tuple[F64, F64, F64, F64]  # rows x, y, nx, ny

_TABLE_MAX = 12  # a look-up table of 2**E entries up to this many edges, argmax beyond


def _x_minus(ax: float, x: F64, y: F64) -> F64:
    return x - ax


def _minus_x(ax: float, x: F64, y: F64) -> F64:
    return ax - x


def _y_minus(ay: float, x: F64, y: F64) -> F64:
    return y - ay


def _minus_y(ay: float, x: F64, y: F64) -> F64:
    return ay - y


def _x_scaled(ax: float, nx: float, x: F64, y: F64) -> F64:
    return (x - ax) * nx


def _y_scaled(ay: float, ny: float, x: F64, y: F64) -> F64:
    return (y - ay) * ny


def _general(ax: float, ay: float, nx: float, ny: float, x: F64, y: F64) -> F64:
    return (x - ax) * nx + (y - ay) * ny


def _side(ax: float, ay: float, nx: float, ny: float) -> Callable[[F64, F64], F64]:
    """``(x, y) -> (x - a) . n`` with zero and unit factors dropped (same comparisons
    with ``EPS``); partials of module functions, so polygons stay picklable."""
    if ny == 0.0 and nx in (1.0, -1.0):
        return partial(_x_minus if nx == 1.0 else _minus_x, ax)
    if nx == 0.0 and ny in (1.0, -1.0):
        return partial(_y_minus if ny == 1.0 else _minus_y, ay)
    if ny == 0.0:
        return partial(_x_scaled, ax, nx)
    if nx == 0.0:
        return partial(_y_scaled, ay, ny)
    return partial(_general, ax, ay, nx, ny)


def _transition_table(n: int) -> NDArray[np.intp]:
    """Per bit pattern of "vertex j is left of the line", the first edge ``i`` whose
    start is left and whose end is not; ``n`` (no entry) when there is none."""
    table = np.full(1 << n, n, dtype=np.intp)
    for code in range(1 << n):
        for i in range(n):
            if code >> i & 1 and not code >> ((i + 1) % n) & 1:
                table[code] = i
                break
    return table


class ConvexColumns:
    """Per-polygon constants for whole-column tests on a convex polygon.

    Parameters
    ----------
    edges
        :attr:`crmgrasp.geometry.Polygon.edges` of a convex polygon.
    """

    def __init__(self, edges: tuple[tuple[float, float, float, float, float, float, float], ...]) -> None:
        self.n = len(edges)
        self.edges = edges
        self.verts = tuple((e[0], e[1]) for e in edges)
        self._sides = tuple(_side(e[0], e[1], e[5], e[6]) for e in edges)
        pad = [np.nan]  # index n: no entry; NaN makes the entry test fail
        self.ax, self.ay = np.array([e[0] for e in edges] + pad), np.array([e[1] for e in edges] + pad)
        self.nx, self.ny = np.array([e[5] for e in edges] + pad), np.array([e[6] for e in edges] + pad)
        self.table = _transition_table(self.n) if self.n <= _TABLE_MAX else None

    def contains(self, x: F64, y: F64) -> Bools:
        """Strictly inside: ``(x - a_i) . n_i > EPS`` for every edge ``i`` (NaN is outside)."""
        sides = iter(self._sides)
        inside = next(sides)(x, y) > EPS
        for side in sides:
            inside &= side(x, y) > EPS
        return inside

    def entry_edge(self, ox: F64, oy: F64, dx: F64, dy: F64) -> NDArray[np.intp]:
        """Per row, :func:`crmgrasp._scalar.convex_edge` (``n`` for none): by table
        look-up on the vertices' strict sides; rows with a vertex within the
        tolerance of the line (rare) go through the scalar rule."""
        gy: dict[float, F64] = {}  # dx (v_y - oy) and dy (v_x - ox), once per distinct coordinate
        gx: dict[float, F64] = {}
        for vx, vy in self.verts:
            if vy not in gy:
                gy[vy] = dx * (vy - oy)
            if vx not in gx:
                gx[vx] = dy * (vx - ox)
        cross = [gy[vy] - gx[vx] for vx, vy in self.verts]
        closest = np.abs(cross[0])
        for c in cross[1:]:
            closest = np.minimum(closest, np.abs(c))
        near = closest <= LINE_TOL * (np.abs(dx) + np.abs(dy))
        if self.table is None:
            left = np.stack([c > 0.0 for c in cross])
            hits = left & ~np.roll(left, -1, axis=0)
            idx = np.where(hits.any(axis=0), hits.argmax(axis=0), self.n)
        else:  # bit j of the code: vertex j is left (bytes are views of the booleans up to 8 edges)
            wide = self.n > 8
            code: NDArray[np.integer] = (cross[0] > 0.0).astype(np.uint16) if wide else (cross[0] > 0.0).view(np.uint8)
            for j in range(1, self.n):
                bit: NDArray[np.integer] = (
                    (cross[j] > 0.0).astype(np.uint16) if wide else (cross[j] > 0.0).view(np.uint8)
                )
                code |= bit << j
            idx = self.table.take(code)
        if near.any():
            for r in np.flatnonzero(near).tolist():
                i = convex_edge(float(ox[r]), float(oy[r]), float(dx[r]), float(dy[r]), self.edges)
                idx[r] = i if i >= 0 else self.n
        return idx

    def entry(self, ox: F64, oy: F64, dx: F64, dy: F64, hi: F64, out: F64) -> tuple[Bools, F64]:
        """First entry of the segment ``o + u d``, ``u <= hi - EPS`` (``hi`` includes the
        slack), as :func:`crmgrasp._scalar.convex_entry`. Writes the entry point and
        inward normal into the rows of ``out`` (``(4, N)``; NaN or meaningless where
        there is none) and returns ``(entered, u)``."""
        idx = self.entry_edge(ox, oy, dx, dy)
        nx = self.nx.take(idx, out=out[2])
        ny = self.ny.take(idx, out=out[3])
        denom = dx * nx + dy * ny
        u = ((self.ax.take(idx) - ox) * nx + (self.ay.take(idx) - oy) * ny) / denom
        ok = (denom > 0.0) & (u >= -EPS) & (u <= hi)
        np.add(ox, u * dx, out=out[0])
        np.add(oy, u * dy, out=out[1])
        return ok, u


def pair_checks(
    contains: Callable[[F64, F64], Bools], depth: float, tol: float, first: Contacts, second: Contacts, q: F64
) -> tuple[F64, Bools]:
    """Distance and palm test (SPEC section 2) of the configurations made of the
    contacts ``first`` and ``second`` (each ``(4, N)``: ``x, y, nx, ny``), labelled
    so that ``x_b - x_a = q (x_second - x_first)`` with ``q = +-1`` per row.

    Returns ``|x_b - x_a|`` and the palm error (contacts coincide, a normal faces
    the palm side, or the palm point is inside), bit for bit as
    :func:`crmgrasp.hand.feasible` on the labelled configuration: ``q`` times a
    difference is the labelled difference exactly, and the tests are symmetric.
    """
    x1, y1, n1x, n1y = first
    x2, y2, n2x, n2y = second
    ddx, ddy = x2 - x1, y2 - y1
    dist = np.sqrt(ddx * ddx + ddy * ddy)
    ux, uy = (q * ddy) / dist, ((-q) * ddx) / dist
    palm = (n1x * ux + n1y * uy > tol) | (n2x * ux + n2y * uy > tol) | (dist == 0.0)
    palm |= contains(0.5 * (x1 + x2) + depth * ux, 0.5 * (y1 + y2) + depth * uy)
    return dist, palm


def execute_convex(
    cc: ConvexColumns,
    aperture: float,
    depth: float,
    tol: float,
    cfg: F64,
    sen: F64,
    c_is_b: Bools,
    f_is_b: Bools,
    rr: F64,
) -> tuple[F64, NDArray[np.int8]]:
    """:func:`crmgrasp.batch.execute_columns` on a convex polygon: new ``(8, N)`` block
    and error codes, equal bit for bit to :func:`crmgrasp.hand.execute_crm` per row."""
    n = cfg.shape[1]
    same = c_is_b == f_is_b
    sg = np.where(same, 1.0, -1.0)  # approach along +n_f (c == f) or -n_f
    q = np.where(c_is_b, 1.0, -1.0)  # b - a = q (moved - stationary)
    fx, fy, fnx, fny = np.where(f_is_b, sen[4:], sen[:4])  # goal-line frame (sensed)
    still = np.where(c_is_b, cfg[:4], cfg[4:])  # the contact that stays
    sx, sy = still[0], still[1]
    # goal line x_f + r tau_f + t n_f and its chord within the aperture of the stationary contact
    bx, by = fx + rr * fny, fy - rr * fnx
    wx, wy = bx - sx, by - sy
    qa = fnx * fnx + fny * fny
    qb = wx * fnx + wy * fny
    qc = wx * wx + wy * wy - aperture * aperture
    sr = sg * np.sqrt(qb * qb - qa * qc)  # NaN where the line misses the disc: no entry below
    nqb = -qb
    t0, t1 = (nqb - sr) / qa, (nqb + sr) / qa
    ox, oy = bx + t0 * fnx, by + t0 * fny
    dx, dy = sg * fnx, sg * fny
    moved = np.empty((4, n))
    ok, _ = cc.entry(ox, oy, dx, dy, np.abs(t1 - t0) + EPS, moved)
    ok = ok > cc.contains(ox, oy)  # a start inside the object is an aperture error
    dist, palm = pair_checks(cc.contains, depth, tol, still, moved, q)
    good = ok & (dist <= aperture)
    errors = (~good).view(np.int8) + (palm & good).view(np.int8) * np.int8(2)
    done = good > palm
    new = np.empty_like(cfg)
    new[:4] = np.where(done > c_is_b, moved, cfg[:4])
    new[4:] = np.where(done & c_is_b, moved, cfg[4:])
    return new, errors

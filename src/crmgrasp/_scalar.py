"""A fused plain-Python CRM step for the single environment (noise-free polygon tasks).

The scalar path (:func:`crmgrasp.sim.step`) is built from small functions that
return named tuples: clear, but about twenty Python calls per CRM. This module
evaluates the same floating-point expressions, in the same order, inside two
functions working on a flat 8-tuple ``(ax, ay, anx, any, bx, by, bnx, bny)``, so
its results equal :func:`crmgrasp.sim.step` bit for bit (the tests check it) at a
fraction of the interpreter overhead. It is what :class:`crmgrasp.env.CRMGraspEnv`
runs on noise-free polygon tasks (numba's per-call dispatch made a compiled version
of this step no faster, so there is none).

``edges`` is :attr:`crmgrasp.geometry.Polygon.edges`: per edge ``(ax, ay, ex, ey,
l2, nx, ny)`` (start, edge vector, squared length, inward unit normal).
"""

from __future__ import annotations

import math

from ._geombase import _S_TOL as S_TOL
from ._geombase import EPS

__all__ = [
    "crm_step",
    "observe_mu",
    "contains",
    "first_entry",
    "convex_edge",
    "convex_entry",
    "LINE_TOL",
    "tan_term",
    "Vec8",
    "Edges",
]

ANTIPODAL_TOL = 1e-12
_INF = math.inf
_sqrt = math.sqrt

Vec8 = tuple[float, float, float, float, float, float, float, float]
Edges = tuple[tuple[float, float, float, float, float, float, float], ...]


def contains(px: float, py: float, edges: Edges, convex: bool) -> bool:
    """Strictly inside (farther than ``EPS`` from the boundary): convex polygons test
    the signed distance to every edge's line; others count crossings of a ray toward
    +x, then check the distance to the boundary (:meth:`crmgrasp.geometry.Polygon.contains`)."""
    if convex:
        for ax, ay, _, _, _, nx, ny in edges:
            if (px - ax) * nx + (py - ay) * ny <= EPS:
                return False
        return True
    inside = False
    for ax, ay, ex, ey, _, _, _ in edges:
        if (ay > py) != (ay + ey > py) and px < ax + (py - ay) * ex / ey:
            inside = not inside
    if not inside:
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


LINE_TOL = 1e-12
"""A vertex closer than this (metres) to a line counts as on it (:func:`convex_edge`)."""


def convex_edge(ox: float, oy: float, dx: float, dy: float, edges: Edges) -> int:
    """The edge through which the line ``o + u d`` enters a convex polygon, or -1.

    Vertex ``j``'s side of the line is the sign of ``c_j = d x (v_j - o) = dx (v_jy -
    oy) - dy (v_jx - ox)``: left (``c_j > tol``), right (``c_j < -tol``) or on the
    line, with ``tol = LINE_TOL (|dx| + |dy|)``. Edge ``i`` (vertex ``i`` to ``i +
    1``) is crossed inward when its start is not on the right, its end not on the
    left, and not both are on the line; the first such edge is returned. A line
    through a vertex, or along an edge, or missing a corner by less than
    ``LINE_TOL``, thus enters at that vertex, as :func:`first_entry`'s slack does.
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
    """:func:`first_entry` for a convex polygon: the entry edge from the vertices'
    sides of the line (:func:`convex_edge`), then ``u = ((a_i - o) . n_i) / (d . n_i)``,
    accepted when ``d . n_i > 0`` and ``-EPS <= u <= u_max + EPS``. Away from
    vertices this is :func:`first_entry`'s edge and ``u``, bit for bit; the batched
    path (:mod:`crmgrasp._columns`) evaluates the same rule without a loop over edges.
    """
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


def crm_step(
    v: Vec8, c_is_b: bool, f_is_b: bool, r: float, edges: Edges, convex: bool, aperture: float, depth: float, tol: float
) -> tuple[int, Vec8]:
    """Noise-free CRM ``(c, f, r)`` from configuration ``v``.

    Returns the error code (0 none, 1 aperture, 2 palm) and the new configuration
    (``v`` itself on error), as :func:`crmgrasp.hand.execute_crm` with
    ``sensed = config``: goal line ``x_f + r tau_f + t n_f``; chord within the
    aperture ``A`` of the stationary contact (``|w + t n|^2 = A^2``); approach from
    ``t_lo`` along ``+n_f`` when ``c == f``, else from ``t_hi`` along ``-n_f``; first
    entry; then the feasibility test of the new configuration.
    """
    fo = 4 if f_is_b else 0
    so = 0 if c_is_b else 4
    fx, fy, fnx, fny = v[fo], v[fo + 1], v[fo + 2], v[fo + 3]
    bx, by = fx + r * fny, fy - r * fnx
    wx, wy = bx - v[so], by - v[so + 1]
    qa = fnx * fnx + fny * fny
    qb = wx * fnx + wy * fny
    qc = wx * wx + wy * wy - aperture * aperture
    disc = qb * qb - qa * qc
    if disc < 0.0:
        return 1, v
    root = _sqrt(disc)
    t_lo, t_hi = (-qb - root) / qa, (-qb + root) / qa
    if c_is_b == f_is_b:
        t0, t1, dx, dy = t_lo, t_hi, fnx, fny
    else:
        t0, t1, dx, dy = t_hi, t_lo, -1.0 * fnx, -1.0 * fny
    ox, oy = bx + t0 * fnx, by + t0 * fny
    if contains(ox, oy, edges, convex):
        return 1, v
    hit = (convex_entry if convex else first_entry)(ox, oy, dx, dy, abs(t1 - t0), edges)
    if hit is None:
        return 1, v
    _, px, py, nx, ny = hit
    new: Vec8 = (v[0], v[1], v[2], v[3], px, py, nx, ny) if c_is_b else (px, py, nx, ny, v[4], v[5], v[6], v[7])
    ax, ay, anx, any_, bx, by, bnx, bny = new
    dx, dy = bx - ax, by - ay
    dist = _sqrt(dx * dx + dy * dy)
    if dist > aperture:
        return 1, v
    if dist == 0.0:
        return 2, v
    ux, uy = dy / dist, -dx / dist
    if anx * ux + any_ * uy > tol or bnx * ux + bny * uy > tol:
        return 2, v
    if contains(0.5 * (ax + bx) + depth * ux, 0.5 * (ay + by) + depth * uy, edges, convex):
        return 2, v
    return 0, new


def tan_term(x: float, y: float, nx: float, ny: float, ox: float, oy: float) -> float:
    """``tan`` of the angle between the inward normal at ``(x, y)`` and the direction
    to ``(ox, oy)`` (:func:`crmgrasp.quality.min_friction`'s per-contact term)."""
    dx, dy = ox - x, oy - y
    dot = nx * dx + ny * dy
    if dot <= 0.0:
        return _INF
    t = abs(nx * dy - ny * dx) / dot
    return 0.0 if t < ANTIPODAL_TOL else t


def observe_mu(v: Vec8) -> tuple[float, float, float, float]:
    """``(rho, m_a, m_b, min_friction)`` of configuration ``v``, as
    :func:`crmgrasp.sensing.observe` and :func:`crmgrasp.quality.min_friction`."""
    ax, ay, anx, any_, bx, by, bnx, bny = v
    sx, sy = anx + bnx, any_ + bny
    dx, dy = bx - ax, by - ay
    mu = max(tan_term(ax, ay, anx, any_, bx, by), tan_term(bx, by, bnx, bny, ax, ay))
    return sx * sx + sy * sy, dx * bny - dy * bnx, -dx * any_ + dy * anx, mu

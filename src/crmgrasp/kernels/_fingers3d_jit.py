"""Compiled (numba) steps of a spatial hand with three or more contacts on one solid.

Each function evaluates exactly the floating-point expressions of the readable rules in
the same order, as `crmgrasp.kernels._spatial_jit` does for two contacts: feasibility with
the table, the palm and the fingers' order, the CRM transition with the chord within
reach of every still contact ([`crmgrasp.model.spatial`][]), the observation ``rho,
|m_a|, |m_b|, |m_c|, ...``, the bins ([`crmgrasp.model.sensing`][]), the start rule of
[`crmgrasp.tasks.spatial.SurfaceStarts`][] and the least friction (the compiled copy of
[`crmgrasp.model.quality3d.least_friction_3d`][], `crmgrasp.kernels._closure_jit`). The
solid's inside test, its entry and the approach along a chord are the two-contact kernel's
own functions. numba compiles without ``fastmath``; the tests hold every result equal to
the readable rules bit for bit.

Layouts: a state ``v`` is one row of six floats per contact, ``[x_a, n_a, x_b, n_b, ...]``;
``acts`` the ``(A, 4)`` CRMs ``(c, f, r_1, r_2)`` (contact indices); ``vals`` the ``(1 + n,
1)`` observation; ``p``, ``q``, ``planes`` and ``cyl`` the two-contact kernel's parameters
([`crmgrasp.kernels.spatial.spatial_params`][]); ``tol`` the least friction's tolerances
([`crmgrasp.kernels.closure.closure_params`][]) and ``edges`` its cone edges.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from crmgrasp.kernels._closure_jit import above, decided_friction, least_friction
from crmgrasp.kernels._compile import compiled
from crmgrasp.kernels._fingers_jit import _index
from crmgrasp.kernels._spatial_jit import (
    APERTURE,
    DEPTH,
    HX,
    HY,
    HZ,
    INF,
    KIND,
    MIN_SEP,
    PALM_TOL,
    SURF,
    UP,
    _axis,
    _contains,
    _cross,
    _dot,
    _goal_line,
    _land,
    _max,
    _min,
    _norm,
    _on_table,
    _project,
)


@compiled
def _spread(c, n):  # type: ignore[no-untyped-def]
    """``_spread``: the largest and the smallest distance between two contacts."""
    far, near = 0.0, INF
    for i in range(n):
        for j in range(i + 1, n):
            a, b = 6 * i, 6 * j
            dist = _norm(c[b] - c[a], c[b + 1] - c[a + 1], c[b + 2] - c[a + 2])
            far, near = _max(far, dist), _min(near, dist)
    return far, near


@compiled
def _crossed(c, n):  # type: ignore[no-untyped-def]
    """``_crossed``: positions along ``a -> z`` not increasing strictly in label order."""
    z = 6 * (n - 1)
    dx, dy, dz = c[z] - c[0], c[z + 1] - c[1], c[z + 2] - c[2]
    last = 0.0
    for i in range(1, n):
        k = 6 * i
        s = _dot(c[k] - c[0], c[k + 1] - c[1], c[k + 2] - c[2], dx, dy, dz)
        if s <= last:
            return True
        last = s
    return False


@compiled
def _feasible(c, n, planes, cyl, p, q):  # type: ignore[no-untyped-def]
    """[`crmgrasp.model.spatial.feasible3d`][] of the row ``c`` (``n >= 3`` contacts): 0
    none, 1 aperture, 2 palm."""
    z = 6 * (n - 1)
    dx, dy, dz = c[z] - c[0], c[z + 1] - c[1], c[z + 2] - c[2]
    dist = _norm(dx, dy, dz)
    if dist > p[APERTURE]:
        return 1
    far, near = _spread(c, n)
    if far > p[APERTURE]:
        return 1
    if near <= p[MIN_SEP]:
        return 2
    for i in range(n):
        if _on_table(c[6 * i + 2], p, q):
            return 2
    ux, uy, uz = _axis(dx / dist, dy / dist, dz / dist, p)  # dist > 0: near <= dist
    tol = p[PALM_TOL]
    if _dot(c[3], c[4], c[5], ux, uy, uz) > tol or _dot(c[z + 3], c[z + 4], c[z + 5], ux, uy, uz) > tol:
        return 2
    if _crossed(c, n):
        return 2
    sx, sy, sz = c[0], c[1], c[2]
    for i in range(1, n):
        sx, sy, sz = sx + c[6 * i], sy + c[6 * i + 1], sz + c[6 * i + 2]
    h = p[DEPTH]
    px, py, pz = sx / n + h * ux, sy / n + h * uy, sz / n + h * uz
    if _contains(px, py, pz, planes, cyl, q[KIND], p[SURF]) or _on_table(pz, p, q):
        return 2
    return 0


@compiled
def _crm(v, n, ci, fi, r1, r2, planes, cyl, p, q, out):  # type: ignore[no-untyped-def]
    """[`crmgrasp.model.spatial.execute_crm3d`][] (noise-free: the goal line from the true
    frame) of contact ``ci`` onto ``fi``'s line from the row ``v`` into ``out``; returns the
    error code."""
    for i in range(6 * n):
        out[i] = v[i]
    bx, by, bz, nx, ny, nz = _goal_line(v, 6 * fi, r1, r2, p)
    t_lo, t_hi = -INF, INF
    for s in range(n):
        if s == ci:
            continue
        k = 6 * s
        wx, wy, wz = bx - v[k], by - v[k + 1], bz - v[k + 2]
        qb = _dot(wx, wy, wz, nx, ny, nz)
        qc = _dot(wx, wy, wz, wx, wy, wz) - p[APERTURE] * p[APERTURE]
        disc = qb * qb - qc
        if disc < 0.0:
            return 1
        t_lo, t_hi = _max(t_lo, -qb - math.sqrt(disc)), _min(t_hi, -qb + math.sqrt(disc))
    if t_lo > t_hi:
        return 1
    code, px, py, pz, mx, my, mz = _land(bx, by, bz, nx, ny, nz, t_lo, t_hi, ci == fi, planes, cyl, p, q)
    if code != 0:
        return code
    m = 6 * ci
    out[m], out[m + 1], out[m + 2], out[m + 3], out[m + 4], out[m + 5] = px, py, pz, mx, my, mz
    code = _feasible(out, n, planes, cyl, p, q)
    if code != 0:
        for i in range(6 * n):
            out[i] = v[i]
    return code


@compiled
def _observe(c, n, vals):  # type: ignore[no-untyped-def]
    """[`crmgrasp.model.spatial.observe3d`][] of the row ``c`` into ``vals[:, 0]``: ``rho``
    and per contact ``j`` the magnitude of ``sum_{i != j} (x_i - x_j) x n_i``."""
    sx, sy, sz = c[3], c[4], c[5]
    for i in range(1, n):
        sx, sy, sz = sx + c[6 * i + 3], sy + c[6 * i + 4], sz + c[6 * i + 5]
    vals[0, 0] = _dot(sx, sy, sz, sx, sy, sz)
    for j in range(n):
        xj = 6 * j
        first = True
        mx, my, mz = 0.0, 0.0, 0.0
        for i in range(n):
            if i == j:
                continue
            k = 6 * i
            tx, ty, tz = _cross(c[k] - c[xj], c[k + 1] - c[xj + 1], c[k + 2] - c[xj + 2], c[k + 3], c[k + 4], c[k + 5])
            if first:
                mx, my, mz, first = tx, ty, tz, False
            else:
                mx, my, mz = mx + tx, my + ty, mz + tz
        vals[1 + j, 0] = _norm(mx, my, mz)


@njit(cache=True)
def _split(c, n):  # type: ignore[no-untyped-def]
    """The row ``c``'s ``(n, 3)`` points and normals."""
    points, normals = np.empty((n, 3)), np.empty((n, 3))
    for i in range(n):
        for k in range(3):
            points[i, k], normals[i, k] = c[6 * i + k], c[6 * i + 3 + k]
    return points, normals


@njit(cache=True)
def _mu(c, n, tol, edges, goal):  # type: ignore[no-untyped-def]
    """The least friction of the row ``c`` (``least_friction_3d`` with ``edges`` cone edges);
    with ``goal >= 0``, a friction that decides it against ``goal`` (``decided_friction``)."""
    points, normals = _split(c, n)
    if goal >= 0.0:
        return decided_friction(points, normals, edges, tol, goal)
    return least_friction(points, normals, edges, tol)


@njit(cache=True)
def step_one(v, action, acts, n, planes, cyl, th, strides, abs_m, p, q, tol, edges, out, vals, known, mu_v, goal):  # type: ignore[no-untyped-def]
    """One noise-free CRM ``acts[action]`` from the row ``v``: the new configuration into
    ``out``, its observation into ``vals[:, 0]``; returns ``(error code, bin index, least
    friction)``, as [`crmgrasp.sim.step`][] (with ``goal >= 0`` a friction that decides the
    least friction against ``goal``: [`_mu`][]). With ``known``, ``vals`` and ``mu_v`` already
    hold the observation and least friction of ``v``: after an error (the row unchanged)
    they are the step's own, not computed again."""
    code = _crm(
        v, n, int(acts[action, 0]), int(acts[action, 1]), acts[action, 2], acts[action, 3], planes, cyl, p, q, out
    )
    if code != 0 and known:
        return code, _index(vals, 0, code, th, strides, abs_m), mu_v
    _observe(out, n, vals)
    return code, _index(vals, 0, code, th, strides, abs_m), _mu(out, n, tol, edges, goal)


@njit(cache=True)
def begin_one(v, n, th, strides, abs_m, tol, edges, vals, goal):  # type: ignore[no-untyped-def]
    """The observation of the row ``v`` into ``vals[:, 0]``; returns ``(bin index, least
    friction)``, as [`crmgrasp.sim.begin`][] (``goal`` as in [`step_one`][])."""
    _observe(v, n, vals)
    return _index(vals, 0, 0, th, strides, abs_m), _mu(v, n, tol, edges, goal)


@njit(cache=True)
def accept_start(d, n, planes, cyl, p, q, tol, edges, mu_goal, out):  # type: ignore[no-untyped-def]
    """[`crmgrasp.tasks.spatial.SurfaceStarts`][]' decision on one try's directions ``d``
    (``n x 3``): the candidate into ``out``; True when it is a start (every direction
    nonzero and projected onto the solid, not every contact on a face turned up, feasible,
    least friction above ``mu_goal``)."""
    for i in range(n):
        if _norm(d[i, 0], d[i, 1], d[i, 2]) == 0.0:
            return False
    for i in range(n):
        if not _project(d[i], planes, cyl, p, q, out, 6 * i):
            return False
    up = p[UP]
    top = True
    for i in range(n):
        k = 6 * i
        top = top and _dot(out[k + 3], out[k + 4], out[k + 5], p[HX], p[HY], p[HZ]) <= -up
    if top or _feasible(out, n, planes, cyl, p, q) != 0:
        return False
    points, normals = _split(out, n)
    return above(points, normals, edges, tol, mu_goal)  # not (least friction <= mu_goal)


__all__ = ["accept_start", "begin_one", "step_one"]


# compiled sources: 558933e4e9fd694b1d93f83c8874066d0040613a9f2d6aa5735db199130e247f

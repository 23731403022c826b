"""Compiled (numba) least friction of three or more spatial contacts.

Each function evaluates exactly the floating-point expressions of the readable rules in
the same order: the contacts' frames and unit edge wrenches of
[`crmgrasp.model.quality3d`][] (``_cone_frames``, ``_wrenches``, `tangent_basis`), the
rank test and the linear program of [`crmgrasp.model.quality.positively_spans`][] (the
simplex method of [`crmgrasp.model.lp`][], pivot by pivot) and the bisection of
[`crmgrasp.model.quality3d.least_friction_3d`][]. numba compiles without ``fastmath`` and
``math.cos``, ``math.sin``, ``math.tan`` call the same C library as Python's, so the
results equal the readable rules bit for bit (the tests check it). The rank comes from
LAPACK's singular values, as numpy's does.

No constant of the model is written here: the tolerances arrive in ``tol`` (layout below,
built by [`crmgrasp.kernels.closure.closure_params`][] from the model's modules).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

# indices into tol
THETA_MAX, THETA_TOL, RANK_TOL, LP_TOL, OPT_TOL = range(5)
PIVOT_TOL, FEASIBILITY_TOL, ANTIPODAL_TOL, ARM_MIN, MAX_PIVOTS = range(5, 10)
N_TOL = 10


@njit(cache=True)
def _frames(p, nrm, arm_min):  # type: ignore[no-untyped-def]
    """``_cone_frames``: arms ``(n, 3)``, tangents ``(n, 6)`` (``t1``, ``t2``) and ``rho``."""
    count = p.shape[0]
    c0, c1, c2 = p[0, 0], p[0, 1], p[0, 2]
    for i in range(1, count):
        c0, c1, c2 = c0 + p[i, 0], c1 + p[i, 1], c2 + p[i, 2]
    c0, c1, c2 = c0 / count, c1 / count, c2 / count
    arms = np.empty((count, 3))
    tang = np.empty((count, 6))
    longest = -math.inf
    for i in range(count):
        a0, a1, a2 = p[i, 0] - c0, p[i, 1] - c1, p[i, 2] - c2
        arms[i, 0], arms[i, 1], arms[i, 2] = a0, a1, a2
        length = math.sqrt(a0 * a0 + a1 * a1 + a2 * a2)
        if length > longest:
            longest = length
        n0, n1, n2 = nrm[i, 0], nrm[i, 1], nrm[i, 2]
        m0, m1, m2 = abs(n0), abs(n1), abs(n2)
        k = 0 if (m0 <= m1 and m0 <= m2) else (1 if m1 <= m2 else 2)  # the first of the least
        e0, e1, e2 = (1.0 if k == 0 else 0.0), (1.0 if k == 1 else 0.0), (1.0 if k == 2 else 0.0)
        u0, u1, u2 = n1 * e2 - n2 * e1, n2 * e0 - n0 * e2, n0 * e1 - n1 * e0
        un = math.sqrt(u0 * u0 + u1 * u1 + u2 * u2)
        u0, u1, u2 = u0 / un, u1 / un, u2 / un
        tang[i, 0], tang[i, 1], tang[i, 2] = u0, u1, u2
        tang[i, 3], tang[i, 4], tang[i, 5] = n1 * u2 - n2 * u1, n2 * u0 - n0 * u2, n0 * u1 - n1 * u0
    rho = longest if longest > arm_min else arm_min
    return arms, tang, rho


@njit(cache=True)
def _wrenches(arms, nrm, tang, rho, mu, edges):  # type: ignore[no-untyped-def]
    """``_wrenches``: the ``(6, n edges)`` unit edge wrenches."""
    count = arms.shape[0]
    w = np.empty((6, count * edges))
    scale = math.sqrt(1.0 + mu * mu)
    for i in range(count):
        for j in range(edges):
            phi = 2.0 * math.pi * j / edges
            co, si = math.cos(phi), math.sin(phi)
            col = i * edges + j
            f0 = (nrm[i, 0] + mu * (co * tang[i, 0] + si * tang[i, 3])) / scale
            f1 = (nrm[i, 1] + mu * (co * tang[i, 1] + si * tang[i, 4])) / scale
            f2 = (nrm[i, 2] + mu * (co * tang[i, 2] + si * tang[i, 5])) / scale
            x0, x1, x2 = arms[i, 0], arms[i, 1], arms[i, 2]
            w[0, col], w[1, col], w[2, col] = f0, f1, f2
            w[3, col] = (x1 * f2 - x2 * f1) / rho
            w[4, col] = (x2 * f0 - x0 * f2) / rho
            w[5, col] = (x0 * f1 - x1 * f0) / rho
    return w


@njit(cache=True)
def _pivot(t, cost, basis, r, j):  # type: ignore[no-untyped-def]
    """``crmgrasp.model.lp._pivot``."""
    width = t.shape[1]
    p = t[r, j]
    for c in range(width):
        t[r, c] = t[r, c] / p
    for i in range(t.shape[0]):
        if i != r:
            f = t[i, j]
            for c in range(width):
                t[i, c] = t[i, c] - f * t[r, c]
    f = cost[j]
    for c in range(width):
        cost[c] = cost[c] - f * t[r, c]
    basis[r] = j


@njit(cache=True)
def _simplex(t, cost, basis, columns, tol):  # type: ignore[no-untyped-def]
    """``crmgrasp.model.lp._simplex``: true when it ends, false when rounding stops it."""
    for _ in range(int(tol[MAX_PIVOTS])):
        j = -1
        for c in range(columns):
            if cost[c] < -tol[OPT_TOL]:
                j = c
                break
        if j < 0:
            return True
        r, best = -1, math.inf
        for i in range(t.shape[0]):
            if t[i, j] > tol[PIVOT_TOL]:
                ratio = t[i, -1] / t[i, j]
                if ratio < best or (ratio == best and basis[i] < basis[r]):
                    r, best = i, ratio
        if r < 0:
            return False
        _pivot(t, cost, basis, r, j)
    return False


@njit(cache=True)
def max_least_weight(w, tol):  # type: ignore[no-untyped-def]
    """[`crmgrasp.model.lp.max_least_weight`][]: ``d*``, ``-inf`` (infeasible) or NaN."""
    k, m = w.shape
    rows, structural = k + 1, m + 1
    width = structural + rows + 1
    t = np.zeros((rows, width))
    for i in range(k):
        for j in range(m):
            t[i, j] = w[i, j]
    for j in range(m):
        for i in range(k):
            t[i, m] = t[i, m] + w[i, j]
    for j in range(m):
        t[k, j] = 1.0
    t[k, m] = float(m)
    for i in range(rows):
        t[i, structural + i] = 1.0
    t[k, width - 1] = 1.0
    basis = np.empty(rows, dtype=np.int64)
    for i in range(rows):
        basis[i] = structural + i
    cost = np.zeros(width)
    for i in range(rows):
        for c in range(structural):
            cost[c] = cost[c] - t[i, c]
        cost[width - 1] = cost[width - 1] - t[i, width - 1]
    if not _simplex(t, cost, basis, structural, tol):
        return math.nan
    if -cost[width - 1] > tol[FEASIBILITY_TOL]:
        return -math.inf
    for r in range(rows):
        if basis[r] >= structural:
            for c in range(structural):
                if abs(t[r, c]) > tol[PIVOT_TOL]:
                    _pivot(t, cost, basis, r, c)
                    break
    for c in range(width):
        cost[c] = 0.0
    cost[m] = -1.0
    for r in range(rows):
        if basis[r] == m:
            for c in range(width):
                cost[c] = cost[c] + t[r, c]
    if not _simplex(t, cost, basis, structural, tol):
        return math.nan
    return cost[width - 1]


@njit(cache=True)
def _spans(w, tol):  # type: ignore[no-untyped-def]
    """[`crmgrasp.model.quality.positively_spans`][]: full rank and ``d* > LP_TOL``."""
    if np.linalg.matrix_rank(w, tol[RANK_TOL]) < w.shape[0]:
        return False
    return max_least_weight(w, tol) > tol[LP_TOL]


@njit(cache=True)
def least_friction(p, nrm, edges, tol):  # type: ignore[no-untyped-def]
    """[`crmgrasp.model.quality3d.least_friction_3d`][] of the contacts ``p``, ``nrm``
    (``(n, 3)``, ``n >= 3``)."""
    arms, tang, rho = _frames(p, nrm, tol[ARM_MIN])
    lo, hi = 0.0, tol[THETA_MAX]
    while hi - lo > tol[THETA_TOL]:
        mid = 0.5 * (lo + hi)
        if _spans(_wrenches(arms, nrm, tang, rho, math.tan(mid), edges), tol):
            hi = mid
        else:
            lo = mid
    if hi == tol[THETA_MAX]:
        return math.inf
    mu = math.tan(hi)
    return 0.0 if mu < tol[ANTIPODAL_TOL] else mu

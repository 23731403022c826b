"""Compiled (numba) least friction of three spatial contacts: [`crmgrasp.model.tripod`][].

Each function evaluates exactly the floating-point expressions of the readable rule in the same
order (the squeezes' rows, the forces that vanish, the Dinkelbach steps and their programs,
solved by the simplex method of `crmgrasp.kernels._lp_jit` with the artificial columns kept, for
the multipliers), so the results equal it bit for bit (the tests check it). The tolerances
arrive in ``tol`` (the layout of `crmgrasp.kernels._lp_jit`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from crmgrasp.kernels._lp_jit import ANTIPODAL_TOL, COLLINEAR_TOL, MAX_PROGRAMS, MU_MAX, REL_TOL, solve


@njit(cache=True)
def _pair(q):  # type: ignore[no-untyped-def]
    """``tripod.PAIRS[q]``: the contacts squeeze ``q`` joins."""
    return (0, 1) if q == 0 else ((0, 2) if q == 1 else (1, 2))


@njit(cache=True)
def _rows(arms, nrm, tang, rho, edges, tol):  # type: ignore[no-untyped-def]
    """``tripod._rows``: ``(rows, True)``, or ``(zeros, False)`` for collinear contacts."""
    d = np.empty((3, 3, 3))
    for i in range(3):
        for j in range(3):
            for c in range(3):
                d[i, j, c] = (arms[j, c] - arms[i, c]) / rho
    u0, u1, u2, v0, v1, v2 = d[0, 1, 0], d[0, 1, 1], d[0, 1, 2], d[0, 2, 0], d[0, 2, 1], d[0, 2, 2]
    c0, c1, c2 = u1 * v2 - u2 * v1, u2 * v0 - u0 * v2, u0 * v1 - u1 * v0
    rows = np.zeros((3, 1 + edges, 3))
    if math.sqrt(c0 * c0 + c1 * c1 + c2 * c2) <= tol[COLLINEAR_TOL]:
        return rows, False
    half = math.pi / edges
    inscribed = math.cos(half)
    for q in range(3):
        i, j = _pair(q)
        for side in range(2):
            me, other = (i, j) if side == 0 else (j, i)
            e0, e1, e2 = d[me, other, 0], d[me, other, 1], d[me, other, 2]
            along1 = tang[me, 0] * e0 + tang[me, 1] * e1 + tang[me, 2] * e2
            along2 = tang[me, 3] * e0 + tang[me, 4] * e1 + tang[me, 5] * e2
            rows[me, 0, q] = nrm[me, 0] * e0 + nrm[me, 1] * e1 + nrm[me, 2] * e2
            for k in range(edges):
                psi = (2 * k + 1) * half
                rows[me, 1 + k, q] = (math.cos(psi) * along1 + math.sin(psi) * along2) / inscribed
    return rows, True


@njit(cache=True)
def _at(rows, i, k, a):  # type: ignore[no-untyped-def]
    """``rows[i, k] . a`` written out."""
    return rows[i, k, 0] * a[0] + rows[i, k, 1] * a[1] + rows[i, k, 2] * a[2]


@njit(cache=True)
def _ratio(rows, a, normal):  # type: ignore[no-untyped-def]
    """``tripod._ratio``."""
    worst = 0.0
    for i in range(3):
        n = _at(rows, i, 0, a)
        if not n > 0.0:
            return math.inf
        normal[i] = n
        gauge = -math.inf
        for k in range(1, rows.shape[1]):
            gauge = max(gauge, _at(rows, i, k, a))
        worst = max(worst, gauge / n)
    return worst


@njit(cache=True)
def _squeeze(rows, q):  # type: ignore[no-untyped-def]
    """``tripod._squeeze``."""
    worst = 0.0
    first, second = _pair(q)
    for i in (first, second):
        n = rows[i, 0, q]
        if not n > 0.0:
            return math.inf
        gauge = -math.inf
        for k in range(1, rows.shape[1]):
            gauge = max(gauge, rows[i, k, q])
        worst = max(worst, gauge / n)
    return worst


@njit(cache=True)
def _lightest(rows, i):  # type: ignore[no-untyped-def]
    """``tripod._lightest``: contact ``i``'s least ratio in the contacts' plane (``q1 < q2`` the
    squeezes that join ``i``, which are the pairs' indices as ``_pair`` numbers them)."""
    q1, q2 = _pair(i)
    nu1, nu2 = rows[i, 0, q1], rows[i, 0, q2]
    nn = nu1 * nu1 + nu2 * nu2
    if nn == 0.0:
        return math.inf
    b1, b2 = nu1 / nn, nu2 / nn
    terms = rows.shape[1] - 1
    c, s = np.empty(terms), np.empty(terms)
    for k in range(terms):
        c[k] = rows[i, 1 + k, q1] * b1 + rows[i, 1 + k, q2] * b2
        s[k] = rows[i, 1 + k, q2] * nu1 - rows[i, 1 + k, q1] * nu2
    best = math.inf
    for k in range(terms):
        for m in range(terms):
            if s[k] > 0.0 > s[m]:
                lam = (c[m] - c[k]) / (s[k] - s[m])
                top = -math.inf
                for j in range(terms):
                    top = max(top, c[j] + lam * s[j])
                best = min(best, top)
    return best


@njit(cache=True)
def _vanishing(rows, lightest):  # type: ignore[no-untyped-def]
    """``tripod._vanishing``: ``B``."""
    best = math.inf
    for q in range(3):
        best = min(best, max(_squeeze(rows, q), lightest[2 - q]))
    return best


@njit(cache=True)
def _program(rows, theta, w, tol):  # type: ignore[no-untyped-def]
    """``tripod._program``: ``-F(theta)`` (NaN when the method fails) and its ``a``."""
    terms = rows.shape[1] - 1
    m = 3 * terms
    width = m + 1 + 4 + 1
    t = np.zeros((4, width))
    scale = 1.0 + theta
    for i in range(3):
        for k in range(terms):
            col = i * terms + k
            for r in range(3):
                t[r, col] = (rows[i, 1 + k, r] - theta * rows[i, 0, r]) / scale
            t[3, col] = w[i]
    for r in range(3):
        t[r, m] = rows[0, 0, r] + rows[1, 0, r] + rows[2, 0, r]
    for r in range(4):
        t[r, m + 1 + r] = 1.0
    t[3, width - 1] = 1.0
    c = np.zeros(m + 1)
    c[m] = 1.0
    a = np.zeros(3)
    status, cost = solve(t, c, width - 1, tol)
    if status != 0:
        return math.nan, a
    a[0], a[1], a[2] = -cost[m + 1], -cost[m + 2], -cost[m + 3]
    return -cost[width - 1] * scale, a


@njit(cache=True)
def tripod_friction(arms, nrm, tang, rho, edges, tol, low, bar):  # type: ignore[no-untyped-def]
    """[`crmgrasp.model.tripod.least_friction_tripod`][] of three contacts' arms, normals,
    tangents ``(3, 6)`` and ``rho``. With ``low >= 0`` it stops as soon as the grasp at ``low``
    is decided (the kernel's shortcut; the readable rule has none): it returns the lower bound
    ``max_i rho_i`` once that exceeds ``bar`` (above ``low`` by a margin), else the larger of it
    and the first ``theta <= low`` (an upper bound), else the least friction."""
    rows, ok = _rows(arms, nrm, tang, rho, edges, tol)
    if not ok:
        return math.inf
    lightest = np.empty(3)
    for i in range(3):
        lightest[i] = _lightest(rows, i)
    lower = max(lightest[0], max(lightest[1], lightest[2]))
    if low >= 0.0 and lower > bar:
        return lower
    bound = _vanishing(rows, lightest)
    theta = min(bound, tol[MU_MAX])
    if lower < bound:
        theta = _dinkelbach(rows, theta, tol, low)
    theta = max(lower, theta)
    if theta >= tol[MU_MAX]:
        return math.inf
    return 0.0 if theta < tol[ANTIPODAL_TOL] else theta


@njit(cache=True)
def _dinkelbach(rows, theta, tol, low):  # type: ignore[no-untyped-def]
    """``tripod._dinkelbach``; with ``low >= 0`` stopped once ``theta <= low``."""
    w, normal = np.ones(3), np.empty(3)
    for _ in range(int(tol[MAX_PROGRAMS])):
        if theta <= low:
            break
        gap, a = _program(rows, theta, w, tol)
        if not gap > 0.0:
            break
        ratio = _ratio(rows, a, normal)
        if not ratio < theta:
            break
        theta = ratio
        for i in range(3):
            w[i] = normal[i]
        if gap <= tol[REL_TOL] * theta:
            break
    return theta


# compiled sources: 558933e4e9fd694b1d93f83c8874066d0040613a9f2d6aa5735db199130e247f

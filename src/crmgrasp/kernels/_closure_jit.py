"""Compiled (numba) least friction of three or more spatial contacts: the search, and the dispatch.

Each function evaluates exactly the floating-point expressions of the readable rules in
the same order: the contacts' frames and unit edge wrenches of
[`crmgrasp.model.quality3d`][] (``_cone_frames``, ``_wrenches``, `tangent_basis`; the
edges' cosines and sines computed once per configuration, the same values), the linear
program and the rank test of [`crmgrasp.model.quality.positively_spans`][] (the simplex
method of [`crmgrasp.model.lp`][], pivot by pivot) and the bracketing search of
[`crmgrasp.model.quality3d.least_friction_3d`][] (its midpoints and secant guesses). numba
compiles without ``fastmath`` and ``math.cos``, ``math.sin``, ``math.tan`` call the same C
library as Python's, so the results equal the readable rules bit for bit (the tests check it).

Three shortcuts leave every returned value unchanged. The program runs before the rank
test, and the rank is tested only when the program says the wrenches span (the answer is
the conjunction of the two). The rank is certified by a Cholesky factorisation of
``W W^T - CERTIFIED_GAP I`` when that succeeds (then LAPACK's singular values, which
numpy's rank counts, are all far above the tolerance) and comes from the singular values
otherwise. Pivots update only the columns the method reads: the artificial columns never
enter the basis and are never read, so they are left stale. Together they took the
compiled least friction from 212-286 to 62-77 us per configuration on the configurations
of random tripod episodes, when the rule was a bisection of 24 programs; the search's
guesses then halved the programs (``python benchmarks/bench_tripod.py``, which times it
alone, against the bisection, and the step).
A start filter needs only whether the least friction exceeds ``mu_goal``, and a step made to
decide the grasp only whether it is at most ``mu_goal``: [`decided_friction`][] runs the same
search and stops as soon as its bracket decides that ([`above`][] is its comparison).

Three contacts take the exact rule of [`crmgrasp.model.tripod`][] instead
(`crmgrasp.kernels._tripod_jit`, unless the tolerances' ``TRIPOD_EXACT`` is 0), the search
being the rule of four; deciding only, it stops once its lower bound is above ``mu_goal`` (by
the margin) or its upper bound at most ``mu_goal``.

No constant of the model is written here: the tolerances arrive in ``tol`` (the layout of
`crmgrasp.kernels._lp_jit`, built by [`crmgrasp.kernels.closure.closure_params`][] from the
model's modules).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from crmgrasp.kernels._lp_jit import (
    ANTIPODAL_TOL,
    ARM_MIN,
    CERTIFIED_GAP,
    CERTIFIED_RANK_TOL,
    DECIDED_MARGIN,
    FIRST_PROBE,
    GUIDE_FLOOR,
    GUIDE_MAX,
    GUIDE_NEAR,
    GUIDE_REACH,
    GUIDE_WIDEN,
    LP_TOL,
    RANK_TOL,
    THETA_MAX,
    THETA_TOL,
    TRIPOD_EXACT,
    max_least_weight,
)
from crmgrasp.kernels._tripod_jit import tripod_friction


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
def _edge_angles(edges):  # type: ignore[no-untyped-def]
    """``cos phi_j`` and ``sin phi_j``, ``phi_j = 2 pi j / edges``, as ``_wrenches`` computes them."""
    co, si = np.empty(edges), np.empty(edges)
    for j in range(edges):
        phi = 2.0 * math.pi * j / edges
        co[j], si[j] = math.cos(phi), math.sin(phi)
    return co, si


@njit(cache=True)
def _wrenches(arms, nrm, tang, rho, mu, co, si, w):  # type: ignore[no-untyped-def]
    """``_wrenches``: the ``(6, n edges)`` unit edge wrenches into ``w`` (the edges' angles
    from [`_edge_angles`][])."""
    count, edges = arms.shape[0], co.shape[0]
    scale = math.sqrt(1.0 + mu * mu)
    for i in range(count):
        for j in range(edges):
            col = i * edges + j
            f0 = (nrm[i, 0] + mu * (co[j] * tang[i, 0] + si[j] * tang[i, 3])) / scale
            f1 = (nrm[i, 1] + mu * (co[j] * tang[i, 1] + si[j] * tang[i, 4])) / scale
            f2 = (nrm[i, 2] + mu * (co[j] * tang[i, 2] + si[j] * tang[i, 5])) / scale
            x0, x1, x2 = arms[i, 0], arms[i, 1], arms[i, 2]
            w[0, col], w[1, col], w[2, col] = f0, f1, f2
            w[3, col] = (x1 * f2 - x2 * f1) / rho
            w[4, col] = (x2 * f0 - x0 * f2) / rho
            w[5, col] = (x0 * f1 - x1 * f0) / rho


@njit(cache=True)
def _full_rank(w, tol, g):  # type: ignore[no-untyped-def]
    """``rank W == rows`` as ``np.linalg.matrix_rank(W, RANK_TOL)`` decides it: certified
    by a Cholesky factorisation of ``W W^T - CERTIFIED_GAP I`` (scratch ``g``, ``k x k``)
    when it succeeds, the singular values otherwise ([`crmgrasp.kernels.closure.CERTIFIED_GAP`][])."""
    k, m = w.shape
    if tol[RANK_TOL] < tol[CERTIFIED_RANK_TOL]:
        for i in range(k):
            for j in range(i + 1):
                s = 0.0
                for c in range(m):
                    s += w[i, c] * w[j, c]
                g[i, j] = s
            g[i, i] -= tol[CERTIFIED_GAP]
        certified = True
        for j in range(k):
            d = g[j, j]
            for c in range(j):
                d -= g[j, c] * g[j, c]
            if not d > 0.0:
                certified = False
                break
            d = math.sqrt(d)
            g[j, j] = d
            for i in range(j + 1, k):
                s = g[i, j]
                for c in range(j):
                    s -= g[i, c] * g[j, c]
                g[i, j] = s / d
        if certified:
            return True
    return np.linalg.matrix_rank(w, tol[RANK_TOL]) >= k


@njit(cache=True)
def _search(p, nrm, edges, tol, low, bar):  # type: ignore[no-untyped-def]
    """The search of [`crmgrasp.model.quality3d.least_friction_3d`][] on the contacts ``p``,
    ``nrm``: its last bracket ``(a, b)`` (the cones open at ``a``, close at ``b``) and 0, probe
    by probe as ``quality3d._search`` ([`_next_probe`][] picks each). A probe closes when
    ``quality.span_margin`` exceeds ``LP_TOL``: the same conjunction of program and rank, the
    program first here (a probe it rejects needs no rank), so ``d`` of a closing probe is the
    same value. With ``low >= 0`` it stops early (see [`above`][]): -1 once ``tan(b) <= low``
    (a probe closed), 1 once ``tan(a) > bar``."""
    arms, tang, rho = _frames(p, nrm, tol[ARM_MIN])
    co, si = _edge_angles(edges)
    w, g = np.empty((6, arms.shape[0] * edges)), np.empty((6, 6))
    early = low >= 0.0
    a, b, d1, b2, d2 = 0.0, tol[THETA_MAX], math.nan, math.nan, math.nan
    reach, guesses = tol[GUIDE_REACH], 0
    while b - a > tol[THETA_TOL]:
        if early:
            if b < tol[THETA_MAX] and math.tan(b) <= low:
                return a, b, -1
            if a > 0.0 and math.tan(a) > bar:
                return a, b, 1
        x, guess = _next_probe(a, b, d1, b2, d2, reach, guesses, tol)
        guesses += guess
        _wrenches(arms, nrm, tang, rho, math.tan(x), co, si, w)
        d = max_least_weight(w, tol)
        if d > tol[LP_TOL] and _full_rank(w, tol, g):
            a, b, d1, b2, d2, reach = a, x, d, b, d1, tol[GUIDE_REACH]
        else:
            a = x
            if guess:
                reach = tol[GUIDE_WIDEN] * reach
    return a, b, 0


@njit(cache=True)
def _next_probe(a, b, d1, b2, d2, reach, guesses, tol):  # type: ignore[no-untyped-def]
    """``quality3d._next_probe``: the next half-angle, and 1 when it is a guess (0 for the
    midpoint)."""
    target = tol[LP_TOL]
    if a == 0.0 and b == tol[THETA_MAX] and tol[FIRST_PROBE] > 0.0:  # nothing probed yet
        return math.atan(tol[FIRST_PROBE]), 0
    if guesses < tol[GUIDE_MAX] and d1 > target and d2 > d1 and b2 > tol[GUIDE_FLOOR]:
        root = b - (d1 - target) * (b2 - b) / (d2 - d1)
        err = reach * (b - root) * (b2 - root)
        near = tol[GUIDE_NEAR] * tol[THETA_TOL]
        x = root + err if b - root > near else root - (b - root) - max(err, near)
        if a < x < b:
            return x, 1
    return 0.5 * (a + b), 0


@njit(cache=True)
def _friction(hi, tol):  # type: ignore[no-untyped-def]
    """The least friction from the search's last upper end: ``inf`` if no probe closed,
    0 below the antipodal tolerance, ``tan(hi)`` otherwise."""
    if hi == tol[THETA_MAX]:
        return math.inf
    mu = math.tan(hi)
    return 0.0 if mu < tol[ANTIPODAL_TOL] else mu


@njit(cache=True)
def decided_friction(p, nrm, edges, tol, mu_goal):  # type: ignore[no-untyped-def]
    """A friction that decides the grasp as [`least_friction`][] does (``mu_goal >= 0``): at
    most ``mu_goal`` exactly when the least friction is. The same search, stopped as soon as
    its bracket decides that comparison: the upper end only falls and the lower end only
    rises, so once ``tan(hi)`` (a probe that closed) is below ``mu_goal`` the least friction
    will be too, and once ``tan(lo)`` is above both ``mu_goal`` and the antipodal tolerance it
    will stay above (``inf`` included). It returns that end's friction (the cones close at
    ``tan(hi)``: an upper bound of the least friction; they are open at ``tan(lo)``: a lower
    bound), or the least friction itself where the search ends undecided. Both ends are
    compared with a relative margin ([`crmgrasp.kernels.closure.DECIDED_MARGIN`][])."""
    bar = max(mu_goal, tol[ANTIPODAL_TOL]) * (1.0 + tol[DECIDED_MARGIN])
    if p.shape[0] == 3 and tol[TRIPOD_EXACT] > 0.0:
        return _tripod(p, nrm, edges, tol, mu_goal, bar)
    lo, hi, decided = _search(p, nrm, edges, tol, mu_goal * (1.0 - tol[DECIDED_MARGIN]), bar)
    if decided > 0:
        return math.tan(lo)
    return _friction(hi, tol)


@njit(cache=True)
def above(p, nrm, edges, tol, mu_goal):  # type: ignore[no-untyped-def]
    """``not (least_friction(p, nrm, edges, tol) <= mu_goal)`` (``mu_goal >= 0``), the same
    answer, from [`decided_friction`][]: a start filter needs only this comparison, and most
    candidates decide it in a few probes."""
    return not (decided_friction(p, nrm, edges, tol, mu_goal) <= mu_goal)


@njit(cache=True)
def least_friction(p, nrm, edges, tol):  # type: ignore[no-untyped-def]
    """[`crmgrasp.model.quality3d.least_friction_3d`][] of the contacts ``p``, ``nrm``
    (``(n, 3)``, ``n >= 3``)."""
    if p.shape[0] == 3 and tol[TRIPOD_EXACT] > 0.0:
        return _tripod(p, nrm, edges, tol, -1.0, 0.0)
    _, hi, _ = _search(p, nrm, edges, tol, -1.0, 0.0)
    return _friction(hi, tol)


@njit(cache=True)
def _tripod(p, nrm, edges, tol, low, bar):  # type: ignore[no-untyped-def]
    """Three contacts' least friction by the exact rule (`crmgrasp.kernels._tripod_jit`) on
    their frames; with ``low >= 0`` stopped once the grasp at ``low`` is decided."""
    arms, tang, rho = _frames(p, nrm, tol[ARM_MIN])
    return tripod_friction(arms, nrm, tang, rho, edges, tol, low, bar)


# compiled sources: 558933e4e9fd694b1d93f83c8874066d0040613a9f2d6aa5735db199130e247f

"""Compiled (numba) simplex method of [`crmgrasp.model.lp`][], and the layout of the closure
tolerances.

Each function evaluates exactly the floating-point expressions of the readable method in the
same order, pivot by pivot, so the results equal it bit for bit (the tests check it). A
caller that reads only the structural columns and the right-hand side passes ``live`` equal
to the structural count: the artificial columns are then never updated (they never enter the
basis, and the ratio test reads only the entering column), which changes no value the method
returns; one that reads the rows' multipliers from the artificial columns passes them all.

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
CERTIFIED_GAP, CERTIFIED_RANK_TOL, DECIDED_MARGIN = range(10, 13)  # the kernel's own margins
GUIDE_REACH, GUIDE_WIDEN, GUIDE_NEAR, GUIDE_FLOOR, GUIDE_MAX = range(13, 18)  # the search's guesses
DEGENERATE_STREAK, FIRST_PROBE = 18, 19
COLLINEAR_TOL, MU_MAX, REL_TOL, MAX_PROGRAMS, TRIPOD_EXACT = range(20, 25)  # the tripod's rule
N_TOL = 25


@njit(cache=True)
def _pivot(t, cost, basis, r, j, live):  # type: ignore[no-untyped-def]
    """``crmgrasp.model.lp._pivot`` on the first ``live`` columns and the right-hand side (the
    module docstring)."""
    width = t.shape[1]
    rhs = width - 1
    p = t[r, j]
    for c in range(live):
        t[r, c] = t[r, c] / p
    t[r, rhs] = t[r, rhs] / p
    for i in range(t.shape[0]):
        if i != r:
            f = t[i, j]
            for c in range(live):
                t[i, c] = t[i, c] - f * t[r, c]
            t[i, rhs] = t[i, rhs] - f * t[r, rhs]
    f = cost[j]
    for c in range(live):
        cost[c] = cost[c] - f * t[r, c]
    cost[rhs] = cost[rhs] - f * t[r, rhs]
    basis[r] = j


@njit(cache=True)
def _entering(cost, columns, bland, tol):  # type: ignore[no-untyped-def]
    """``crmgrasp.model.lp._entering``: Bland's or Dantzig's entering column, -1 if none."""
    j, least = -1, -tol[OPT_TOL]
    for c in range(columns):
        if cost[c] < least:
            if bland:
                return c
            j, least = c, cost[c]
    return j


@njit(cache=True)
def _simplex(t, cost, basis, columns, live, tol):  # type: ignore[no-untyped-def]
    """``crmgrasp.model.lp._simplex``: true when it ends, false when rounding stops it."""
    streak = 0
    for _ in range(int(tol[MAX_PIVOTS])):
        j = _entering(cost, columns, streak >= tol[DEGENERATE_STREAK], tol)
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
        streak = streak + 1 if best <= 0.0 else 0
        _pivot(t, cost, basis, r, j, live)
    return False


@njit(cache=True)
def solve(t, c, live, tol):  # type: ignore[no-untyped-def]
    """[`crmgrasp.model.lp.solve`][] on the tableau ``t = [A, I, b]`` (in place) and the costs
    ``c`` of ``A``'s columns, updating the first ``live`` columns: ``(status, cost)``."""
    rows, width = t.shape
    structural = c.shape[0]
    rhs = width - 1
    basis = np.empty(rows, dtype=np.int64)
    for i in range(rows):
        basis[i] = structural + i
    cost = np.zeros(width)
    for i in range(rows):
        for col in range(structural):
            cost[col] = cost[col] - t[i, col]
        cost[rhs] = cost[rhs] - t[i, rhs]
    if not _simplex(t, cost, basis, structural, live, tol):
        return 2, cost
    if -cost[rhs] > tol[FEASIBILITY_TOL]:
        return 1, cost
    for r in range(rows):
        if basis[r] >= structural:
            for col in range(structural):
                if abs(t[r, col]) > tol[PIVOT_TOL]:
                    _pivot(t, cost, basis, r, col, live)
                    break
    for col in range(width):
        cost[col] = 0.0
    for col in range(structural):
        cost[col] = c[col]
    for r in range(rows):
        cb = c[basis[r]] if basis[r] < structural else 0.0
        if cb != 0.0:
            for col in range(live):
                cost[col] = cost[col] - cb * t[r, col]
            cost[rhs] = cost[rhs] - cb * t[r, rhs]
    if not _simplex(t, cost, basis, structural, live, tol):
        return 2, cost
    return 0, cost


@njit(cache=True)
def max_least_weight(w, tol):  # type: ignore[no-untyped-def]
    """[`crmgrasp.model.lp.max_least_weight`][]: ``d*``, ``-inf`` (infeasible) or NaN. The
    artificial columns keep their zeros: the method never reads them (the module docstring)."""
    k, m = w.shape
    rows, structural = k + 1, m + 1
    width = structural + rows + 1
    rhs = width - 1
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
    t[k, rhs] = 1.0
    c = np.zeros(structural)
    c[m] = -1.0
    status, cost = solve(t, c, structural, tol)
    if status == 1:
        return -math.inf
    if status == 2:
        return math.nan
    return cost[rhs]


# compiled sources: 558933e4e9fd694b1d93f83c8874066d0040613a9f2d6aa5735db199130e247f

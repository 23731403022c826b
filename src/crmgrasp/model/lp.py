"""The force-closure linear program, solved as written ([docs/model.md section 5][model-5]).

Columns ``w_1 .. w_m`` of ``W`` (``(k, m)``) positively span R^k, the origin strictly inside
their convex hull, iff ``rank W = k`` and some convex combination of them with every weight
positive is the origin. The largest least weight of such a combination is the optimum of

    max d  s.t.  W mu + (W 1) d = 0,  1 . mu + m d = 1,  mu >= 0,  d >= 0

(weights ``lambda_j = mu_j + d``, so ``d`` is their least); [`max_least_weight`][] returns it
(``-inf`` when no convex combination is the origin at all).

It is solved by the two-phase simplex method on a dense tableau ([`solve`][], which also
solves the three-contact least friction's programs of [`crmgrasp.model.tripod`][]): phase 1 starts from one
artificial variable per row and minimises their sum (a positive minimum: infeasible);
phase 2 maximises ``d`` from the basis phase 1 found. Each pivot enters the column of most
negative reduced cost (below ``-OPT_TOL``; the first such column on ties: Dantzig's rule) and
leaves the row of least ratio, the one with the smallest basic variable on ties. Every
right-hand side but one is 0, so many pivots are degenerate (least ratio 0, the objective
unchanged), and Dantzig's rule alone could cycle through them: after ``DEGENERATE_STREAK``
degenerate pivots in a row, columns enter by Bland's rule (the first whose reduced cost is
below ``-OPT_TOL``), which cannot cycle from any basis, until a pivot improves the objective.
No basis recurs across an improving pivot, so the method ends. On the spatial model's tripod
wrenches Dantzig's rule takes about 11 pivots a program where Bland's rule alone took 25.
Sums run left to right and each update is written
out, element by element, so that a compiled copy (`crmgrasp.kernels`) repeats every
floating-point operation and returns the same optimum bit for bit.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

__all__ = ["max_least_weight", "solve", "OPT_TOL", "PIVOT_TOL", "FEASIBILITY_TOL", "MAX_PIVOTS", "DEGENERATE_STREAK"]

F64 = NDArray[np.float64]

OPT_TOL = 1e-10
"""A reduced cost below ``-OPT_TOL`` improves the objective (the column may enter)."""

PIVOT_TOL = 1e-9
"""Only tableau entries above ``PIVOT_TOL`` take part in the ratio test."""

FEASIBILITY_TOL = 1e-9
"""Phase 1 ending with the artificial variables' sum above this: no feasible point."""

MAX_PIVOTS = 10_000
"""More pivots than this in one phase: the method has broken down (NaN)."""

DEGENERATE_STREAK = 50
"""After this many degenerate pivots in a row (least ratio at most 0), columns enter by
Bland's rule instead of Dantzig's until a pivot is not degenerate (0: Bland's rule throughout,
the rule before Dantzig's)."""


def _tableau(w: F64) -> F64:
    """The tableau ``[W, W 1, I, 0; 1, m, I, 1]`` of the program (``k + 1`` rows; columns:
    ``mu_1 .. mu_m``, ``d``, the ``k + 1`` artificial variables, the right-hand side)."""
    k, m = w.shape
    rows = k + 1
    t = np.zeros((rows, m + 1 + rows + 1))
    t[:k, :m] = w
    for j in range(m):  # W 1, summed left to right
        t[:k, m] += w[:, j]
    t[k, :m] = 1.0
    t[k, m] = float(m)
    for i in range(rows):
        t[i, m + 1 + i] = 1.0
    t[k, -1] = 1.0
    return t


def _pivot(t: F64, cost: F64, basis: list[int], r: int, j: int) -> None:
    """Make column ``j`` basic in row ``r``: the row divided by its pivot, then ``f`` times it
    subtracted from each other row and from the cost row, ``f`` their entry in column ``j``."""
    t[r] = t[r] / t[r, j]
    for i in range(len(t)):
        if i != r:
            t[i] = t[i] - t[i, j] * t[r]
    cost[:] = cost - cost[j] * t[r]
    basis[r] = j


def _entering(cost: F64, columns: int, bland: bool) -> int:
    """The column to enter (-1: none improves): the first below ``-OPT_TOL`` by Bland's rule,
    else the most negative below it, the first on ties (Dantzig's rule)."""
    j, least = -1, -OPT_TOL
    for c in range(columns):
        if cost[c] < least:
            if bland:
                return c
            j, least = c, cost[c]
    return j


def _simplex(t: F64, cost: F64, basis: list[int], columns: int) -> bool:
    """Pivot until no column below ``columns`` has a reduced cost below ``-OPT_TOL``
    (Dantzig's rule, then Bland's after a streak of degenerate pivots: above): true. False
    when the pivots have lost the precision to go on: an improving column with no entry above
    ``PIVOT_TOL`` (the program is bounded, so only rounding makes one), or more pivots than
    the method can need on a tableau this size."""
    streak = 0
    for _ in range(MAX_PIVOTS):
        j = _entering(cost, columns, streak >= DEGENERATE_STREAK)
        if j < 0:
            return True
        r, best = -1, math.inf
        for i in range(len(t)):
            if t[i, j] > PIVOT_TOL:
                ratio = t[i, -1] / t[i, j]
                if ratio < best or (ratio == best and basis[i] < basis[r]):
                    r, best = i, ratio
        if r < 0:
            return False
        streak = streak + 1 if best <= 0.0 else 0
        _pivot(t, cost, basis, r, j)
    return False


def solve(t: F64, c: F64) -> tuple[int, F64]:
    """The two-phase simplex method on the tableau ``t = [A, I, b]`` (``rows`` rows, ``b >= 0``,
    the identity columns artificial), in place: ``min c . x`` s.t. ``A x = b``, ``x >= 0``, ``c``
    the costs of ``A``'s columns (the module docstring's pivots).

    Returns ``(status, cost)``: status 0 at an optimum, 1 when no ``x`` is feasible (phase 1
    ends above ``FEASIBILITY_TOL``), 2 when rounding stops the method; ``cost`` the last
    reduced-cost row ``c - A^T y`` over every column (the artificial columns cost 0 in phase 2,
    so their entries are ``-y``, minus the rows' multipliers ``y``), its last entry minus the
    optimum ``c . x``.
    """
    rows = len(t)
    structural = len(c)
    basis = [structural + i for i in range(rows)]
    cost = np.zeros(t.shape[1])  # phase 1: the artificials' sum, priced out of their rows
    for i in range(rows):
        cost[:structural] = cost[:structural] - t[i, :structural]
        cost[-1] = cost[-1] - t[i, -1]
    if not _simplex(t, cost, basis, structural):
        return 2, cost
    if -cost[-1] > FEASIBILITY_TOL:
        return 1, cost
    for r in range(rows):  # an artificial still basic (at 0) leaves for any structural column
        if basis[r] >= structural:
            j = next((col for col in range(structural) if abs(t[r, col]) > PIVOT_TOL), -1)
            if j >= 0:
                _pivot(t, cost, basis, r, j)
    cost = np.zeros(t.shape[1])  # phase 2: c, priced out of the basic rows
    cost[:structural] = c
    for r in range(rows):
        cb = c[basis[r]] if basis[r] < structural else 0.0
        if cb != 0.0:
            cost[:] = cost - cb * t[r]
    if not _simplex(t, cost, basis, structural):
        return 2, cost
    return 0, cost


def max_least_weight(w: F64) -> float:
    """The program's optimum ``d*`` for the columns of ``w`` (``(k, m)``, finite), ``-inf``
    when no convex combination of them is the origin (see the module docstring), or NaN
    when rounding stops the method (near-degenerate columns: on the spatial model's
    wrenches this was met only at frictions below 1e-6, near a frictionless equilibrium;
    [`crmgrasp.model.quality.positively_spans`][] counts it as not spanning). [`solve`][]
    minimises ``-d``.

    Examples
    --------
    The columns ``e_1, e_2, -e_1 - e_2`` make the origin with weights 1/3 each:

    >>> max_least_weight(np.array([[1.0, 0.0, -1.0], [0.0, 1.0, -1.0]]))
    0.3333333333333333
    >>> max_least_weight(np.array([[1.0, 0.0], [0.0, 1.0]]))
    -inf
    """
    m = w.shape[1]
    c = np.zeros(m + 1)
    c[m] = -1.0
    status, cost = solve(_tableau(w), c)
    return (float(cost[-1]), -math.inf, math.nan)[status]

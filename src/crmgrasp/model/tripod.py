"""The least friction of three spatial point contacts, exactly (docs/model-3d.md section 9).

Three contact forces ``f_1, f_2, f_3`` in equilibrium (no net force, no net moment) are the
internal forces of the grasp: for contacts at non-collinear points ``x_i`` they are exactly

    f_i = sum_{j != i} a_ij (x_j - x_i),   a_ij = a_ji,

three squeezes along the triangle's sides with any real weights ``a = (a_12, a_13, a_23)``
(the grasp map of three non-collinear contacts has rank 6, so its null space has dimension
9 - 6 = 3, and these three are independent and balanced). The contacts are force closure
with friction ``mu`` exactly when some internal force lies strictly inside every friction
cone (the grasp map is onto), and each polyhedral cone of the spatial model (``E`` edges
``n_i + mu (cos phi_j t1_i + sin phi_j t2_i)``, ``phi_j = 2 pi j / E``) holds ``f`` exactly
when ``gamma_i(f) <= mu N_i(f)``: ``N_i = n_i . f`` the normal force and ``gamma_i`` the gauge
of the cone's cross-section, the regular ``E``-gon with vertices on the unit circle,

    gamma_i(f) = max_k (cos psi_k (t1_i . f) + sin psi_k (t2_i . f)) / cos(pi / E),
    psi_k = (2k + 1) pi / E

(a facet's outward normal and its distance ``cos(pi / E)`` from the centre). So the least
friction of three contacts is

    mu* = inf { max_i gamma_i(f(a)) / N_i(f(a)) : N_i(f(a)) > 0 for every i },

a minimum of a maximum of ratios of linear functions of ``a``, over an open set. It is found
exactly, in two parts ([`least_friction_tripod`][]):

* **One force vanishing.** The infimum may be approached while one contact's force goes to 0
  (a squeeze between the other two, the third touching ever more lightly). Its value is then
  ``max(mu_jk, rho_i)``: ``mu_jk`` the friction the squeeze between contacts ``j`` and ``k``
  alone needs (``a = e_jk``), and ``rho_i`` the least ratio of contact ``i`` over the forces it
  can press with in the plane of the three contacts (``f_i = s (x_j - x_i) + t (x_k - x_i)``,
  a one-dimensional minimum of a convex piecewise-linear function, found at a crossing of
  two of its pieces). ``B`` is the least of the three.
* **Every force pressing.** Otherwise the infimum is attained, and the generalised
  Dinkelbach method finds it (J.-P. Crouzeix, J. A. Ferland and S. Schaible, "An algorithm
  for generalized fractional programs", J. Optim. Theory Appl. 47, 1985): from ``theta =
  min(B, MU_MAX)`` and weights ``w = 1``, the linear program

      F(theta) = min z  s.t.  gamma_ik(a) - theta N_i(a) <= z w_i  (every i and facet k),
                              N_1(a) + N_2(a) + N_3(a) = 1

  is negative exactly when some internal force has every ratio below ``theta``; its optimum
  ``a`` then gives the next ``theta = max_i gamma_i / N_i`` (strictly less) and the next
  weights ``w_i = N_i(a)``, which makes the convergence superlinear. It stops when ``F`` is 0
  (``theta`` is the least friction: ``B`` when the first program finds nothing below it), when
  a step no longer lowers ``theta``, or once ``-F <= REL_TOL theta`` ([`REL_TOL`][]).

Every internal force presses contact ``i`` with a force in the contacts' plane, so
``max_i rho_i <= mu* <= B``: where the lower bound meets ``B`` the least friction is ``B``,
with no program (an antipodal squeeze and a third finger whose normal leaves the plane by
``atan(s)`` need exactly ``s``). The answer is the larger of the method's last ``theta`` and
``max_i rho_i`` (the same in exact arithmetic; in floating point it keeps the answer above the
lower bound, which the compiled kernel uses to decide a grasp early).

Each ``theta`` the method returns is the largest ratio of an internal force it holds, so the
contacts close with any friction above it: the answer is an upper bound of ``mu*`` within
``REL_TOL`` relative (and ``B``, a limit of such forces, is the threshold itself). The program
is solved through its dual by the simplex method of [`crmgrasp.model.lp`][] (four rows: the
``sum lambda_ik (gamma_ik - theta N_i) + zeta (N_1 + N_2 + N_3) = 0`` rows and ``sum
lambda_ik w_i = 1``; minimise ``zeta = -F``), whose multipliers are ``a`` and ``-z``. On the
tripod tasks' configurations the rule takes 2.2 (boxes) and 1.2 (cups) programs a
configuration where a search over the cone's half-angle took 12 and a bisection 24
(``benchmarks/bench_tripod.py``).

Collinear contacts (the triangle's area below [`COLLINEAR_TOL`][] in units of ``rho^2``) never
close: no contact force has a moment about their line. A friction of [`MU_MAX`][] or more
counts as none (``inf``).

Every sum is written out in a fixed order so that the compiled copy
(`crmgrasp.kernels._tripod_jit`) repeats it bit for bit.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from crmgrasp.model import lp
from crmgrasp.model.quality import ANTIPODAL_TOL

__all__ = ["least_friction_tripod", "COLLINEAR_TOL", "MU_MAX", "REL_TOL", "MAX_PROGRAMS", "PAIRS"]

F64 = NDArray[np.float64]

PAIRS = ((0, 1), (0, 2), (1, 2))
"""The squeezes ``a = (a_12, a_13, a_23)``: the contacts each joins (0-based)."""

COLLINEAR_TOL = 1e-10
"""Contacts whose ``|(x_2 - x_1) x (x_3 - x_1)| / rho^2`` is at most this lie on a line: no
closure (``inf``)."""

MU_MAX = 1e6
"""No closure at a friction below this counts as none (``inf``)."""

REL_TOL = 1e-12
"""The method stops once the program's ``-F(theta)`` is at most this times ``theta``."""

MAX_PROGRAMS = 50
"""At most this many programs per configuration (rounding could otherwise lower ``theta`` by
a unit in the last place at a time)."""


def _rows(arms: F64, normals: F64, tangents: F64, rho: float, edges: int) -> F64 | None:
    """``(3, 1 + edges, 3)``: for contact ``i``, row 0 is ``N_i`` and row ``1 + k`` the facet
    term ``gamma_ik`` as linear functions of ``a`` (columns: [`PAIRS`][]); ``None`` for collinear
    contacts. ``tangents[i]`` is ``(t1_i, t2_i)`` flattened."""
    d = np.empty((3, 3, 3))  # d[i, j] = (x_j - x_i) / rho
    for i in range(3):
        for j in range(3):
            d[i, j] = (arms[j] - arms[i]) / rho
    u, v = d[0, 1], d[0, 2]
    c0, c1, c2 = u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]
    if math.sqrt(c0 * c0 + c1 * c1 + c2 * c2) <= COLLINEAR_TOL:
        return None
    half = math.pi / edges
    inscribed = math.cos(half)
    rows = np.zeros((3, 1 + edges, 3))
    for q, (i, j) in enumerate(PAIRS):
        for me, other in ((i, j), (j, i)):
            e = d[me, other]
            n, t = normals[me], tangents[me]
            along1 = t[0] * e[0] + t[1] * e[1] + t[2] * e[2]
            along2 = t[3] * e[0] + t[4] * e[1] + t[5] * e[2]
            rows[me, 0, q] = n[0] * e[0] + n[1] * e[1] + n[2] * e[2]
            for k in range(edges):
                psi = (2 * k + 1) * half
                rows[me, 1 + k, q] = (math.cos(psi) * along1 + math.sin(psi) * along2) / inscribed
    return rows


def _at(row: F64, a: F64) -> float:
    """``row . a`` written out."""
    return float(row[0] * a[0] + row[1] * a[1] + row[2] * a[2])


def _ratio(rows: F64, a: F64, normal: F64) -> float:
    """``max_i gamma_i(a) / N_i(a)`` (``inf`` when some ``N_i <= 0``), ``N_i`` into ``normal``."""
    worst = 0.0
    for i in range(3):
        n = _at(rows[i, 0], a)
        if not n > 0.0:
            return math.inf
        normal[i] = n
        gauge = -math.inf
        for k in range(1, rows.shape[1]):
            gauge = max(gauge, _at(rows[i, k], a))
        worst = max(worst, gauge / n)
    return worst


def _squeeze(rows: F64, q: int) -> float:
    """The friction the squeeze ``q`` alone needs, ``max`` over its two contacts of ``gamma / N``
    (``inf`` where ``N <= 0``)."""
    worst = 0.0
    for i in PAIRS[q]:
        n = rows[i, 0, q]
        if not n > 0.0:
            return math.inf
        gauge = -math.inf
        for k in range(1, rows.shape[1]):
            gauge = max(gauge, rows[i, k, q])
        worst = max(worst, gauge / n)
    return worst


def _lightest(rows: F64, i: int) -> float:
    """``rho_i``: the least ``gamma_i / N_i`` over contact ``i``'s forces in the contacts' plane
    (``s`` and ``t`` the weights of its two squeezes). On the line ``N_i = 1``, ``(s, t) = b +
    lam p`` with ``b = nu / |nu|^2`` and ``p = (-nu_2, nu_1)``, ``nu`` the normal forces of the
    two squeezes, each facet term is ``c_k + lam s_k`` and the gauge is their maximum, convex
    in ``lam``; its least value lies where a rising term crosses a falling one."""
    q1, q2 = (q for q, pair in enumerate(PAIRS) if i in pair)
    nu1, nu2 = rows[i, 0, q1], rows[i, 0, q2]
    nn = nu1 * nu1 + nu2 * nu2
    if nn == 0.0:
        return math.inf
    b1, b2 = nu1 / nn, nu2 / nn
    terms = rows.shape[1] - 1
    c = [rows[i, 1 + k, q1] * b1 + rows[i, 1 + k, q2] * b2 for k in range(terms)]
    s = [rows[i, 1 + k, q2] * nu1 - rows[i, 1 + k, q1] * nu2 for k in range(terms)]
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


def _vanishing(rows: F64, lightest: list[float]) -> float:
    """``B``: the least of ``max(mu_jk, rho_i)`` over the three squeezes (``lightest[i]`` is
    ``rho_i``)."""
    best = math.inf
    for q, (i, j) in enumerate(PAIRS):
        best = min(best, max(_squeeze(rows, q), lightest[3 - i - j]))
    return best


def _program(rows: F64, theta: float, w: F64) -> tuple[float, F64]:
    """``-F(theta)`` and its optimal ``a`` (the module docstring's dual, solved by
    [`crmgrasp.model.lp.solve`][]); NaN when the method fails. Its facet columns are scaled by
    ``1 / (1 + theta)`` (the primal's rows, each scaled by a positive number: the same ``a``),
    so ``-F = zeta (1 + theta)``."""
    terms = rows.shape[1] - 1
    m = 3 * terms
    t = np.zeros((4, m + 1 + 4 + 1))
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
    t[3, -1] = 1.0
    c = np.zeros(m + 1)
    c[m] = 1.0
    status, cost = lp.solve(t, c)
    if status != 0:
        return math.nan, np.zeros(3)
    a = np.array([-cost[m + 1], -cost[m + 2], -cost[m + 3]])
    return -cost[-1] * scale, a


def least_friction_tripod(arms: F64, normals: F64, tangents: F64, rho: float, edges: int) -> float:
    """The least friction of three contacts (the module docstring): ``arms`` ``x_i - c`` and
    inward unit ``normals`` ``(3, 3)``, ``tangents`` ``(3, 6)`` (each contact's ``t1, t2``),
    ``rho`` the longest arm, ``edges`` of each cone. ``inf`` when they never close, 0 below
    [`crmgrasp.model.quality.ANTIPODAL_TOL`][].

    Examples
    --------
    Contacts on a cylinder's equator, 120 degrees apart, pressing through its axis: a
    frictionless equilibrium.

    >>> from crmgrasp.model.quality3d import tangent_basis
    >>> arms = np.array([(np.cos(x), np.sin(x), 0.0) for x in (0.0, 2 * np.pi / 3, 4 * np.pi / 3)])
    >>> tangents = np.array([np.concatenate(tangent_basis(-a)) for a in arms])
    >>> least_friction_tripod(arms, -arms, tangents, 1.0, 8)
    0.0
    """
    rows = _rows(arms, normals, tangents, rho, edges)
    if rows is None:
        return math.inf
    lightest = [_lightest(rows, i) for i in range(3)]
    lower, bound = max(lightest), _vanishing(rows, lightest)
    theta = min(bound, MU_MAX)
    if lower < bound:  # else the least friction is B: no force does better than rho_i
        theta = _dinkelbach(rows, theta)
    theta = max(lower, theta)  # the same in exact arithmetic; so rounding keeps the bounds' order
    if theta >= MU_MAX:
        return math.inf
    return 0.0 if theta < ANTIPODAL_TOL else theta


def _dinkelbach(rows: F64, theta: float) -> float:
    """The method's steps from ``theta`` (``B`` or ``MU_MAX``) and weights 1: the last
    ``theta`` (the module docstring)."""
    w, normal = np.ones(3), np.empty(3)
    for _ in range(MAX_PROGRAMS):
        gap, a = _program(rows, theta, w)
        if not gap > 0.0:
            break
        ratio = _ratio(rows, a, normal)
        if not ratio < theta:
            break
        theta, w = ratio, normal.copy()
        if gap <= REL_TOL * theta:
            break
    return theta

"""Compiled (numba) per-row loops for a planar hand of any number of contacts on a polygon.

Each function evaluates exactly the floating-point expressions of the model's readable
rules in the same order, as [`crmgrasp.kernels._polygon_jit`][] does for two contacts:
feasibility and the CRM transition ([`crmgrasp.model.hand`][]), the observation
([`crmgrasp.model.sensing`][]) and the least friction ([`crmgrasp.model.quality`][]).
The polygon's inside test and a CRM's approach and entry are the two-contact kernel's own
functions.
numba compiles without ``fastmath``; the tests hold every result equal to the readable
rules bit for bit.

Layouts: configurations are ``(N, 4 n)`` rows, per contact ``x, y, nx, ny``; ``p`` and
``q`` are the two-contact kernel's parameter arrays ([`crmgrasp.kernels.polygon.params`][]);
``fp`` holds the quality's constants (``CLOSURE_TOL, SPAN_TOL, THETA_MAX, ANGLE_TOL,
ARM_MIN``).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from crmgrasp.kernels._compile import compiled
from crmgrasp.kernels._polygon_jit import (
    ANTIPODAL_TOL,
    APERTURE,
    approach,
    chord,
    feasible,
)

CLOSURE_TOL, SPAN_TOL, THETA_MAX, ANGLE_TOL, ARM_MIN = range(5)
N_FP = 5


@compiled
def _crm(cfg, sen, j, n, ci, fi, r, e, p, q, new, jn):  # type: ignore[no-untyped-def]
    """[`crmgrasp.model.hand.execute_crm`][] on row ``j`` of ``cfg`` (true) and ``sen``
    (sensed), contact ``ci`` moving onto contact ``fi``'s line: the result into row ``jn`` of
    ``new``; returns the error code."""
    w = 4 * n
    for k in range(w):
        new[jn, k] = cfg[j, k]
    fo, mo = 4 * fi, 4 * ci
    fx, fy, fnx, fny = sen[j, fo], sen[j, fo + 1], sen[j, fo + 2], sen[j, fo + 3]
    bx, by = fx + r * fny, fy - r * fnx
    t_lo, t_hi = -np.inf, np.inf
    for k in range(n):
        if k == ci:
            continue
        reached, lo, hi = chord(bx, by, fnx, fny, cfg[j, 4 * k], cfg[j, 4 * k + 1], p[APERTURE])
        if not reached:
            return 1
        if lo > t_lo:  # Python's max(t_lo, lo)
            t_lo = lo
        if hi < t_hi:  # Python's min(t_hi, hi)
            t_hi = hi
    if t_lo > t_hi:
        return 1
    code, px, py, nx, ny = approach(bx, by, fnx, fny, t_lo, t_hi, ci == fi, e, p, q)
    if code:
        return code
    new[jn, mo], new[jn, mo + 1], new[jn, mo + 2], new[jn, mo + 3] = px, py, nx, ny
    code = feasible(new, jn, n, e, p, q)
    if code != 0:
        for k in range(w):
            new[jn, k] = cfg[j, k]
    return code


@compiled
def _observe(s, j, n, out, jo):  # type: ignore[no-untyped-def]
    """[`crmgrasp.model.sensing.observe`][] of row ``j`` of the sensed rows ``s``: ``rho``
    then the moment about each contact into row ``jo`` of ``out``."""
    sx, sy = s[j, 2], s[j, 3]
    for k in range(1, n):
        sx += s[j, 4 * k + 2]
        sy += s[j, 4 * k + 3]
    out[0, jo] = sx * sx + sy * sy
    for m in range(n):
        px, py = s[j, 4 * m], s[j, 4 * m + 1]
        total, first = 0.0, True
        for i in range(n):
            if i != m:
                term = (s[j, 4 * i] - px) * s[j, 4 * i + 3] - (s[j, 4 * i + 1] - py) * s[j, 4 * i + 2]
                total = term if first else total + term
                first = False
        out[1 + m, jo] = total


@njit(cache=True)
def _basis(c, j, n, fp):  # type: ignore[no-untyped-def]
    """[`crmgrasp.model.quality._basis`][]: per contact its normal's and tangent's wrenches."""
    cx, cy = 0.0, 0.0
    for k in range(n):
        cx += c[j, 4 * k]
    for k in range(n):
        cy += c[j, 4 * k + 1]
    cx, cy = cx / n, cy / n
    scale = 0.0
    for k in range(n):
        dx, dy = c[j, 4 * k] - cx, c[j, 4 * k + 1] - cy
        scale = max(scale, np.sqrt(dx * dx + dy * dy))
    scale = max(scale, fp[ARM_MIN])
    b = np.empty((n, 6))
    for k in range(n):
        nx, ny = c[j, 4 * k + 2], c[j, 4 * k + 3]
        rx, ry = (c[j, 4 * k] - cx) / scale, (c[j, 4 * k + 1] - cy) / scale
        b[k, 0], b[k, 1], b[k, 2] = nx, ny, rx * ny - ry * nx
        b[k, 3], b[k, 4], b[k, 5] = ny, -nx, -rx * nx - ry * ny
    return b


@njit(cache=True)
def _spans(b, theta, fp, ws):  # type: ignore[no-untyped-def]
    """[`crmgrasp.model.quality._positively_span`][] of the cone edges at ``theta``."""
    co, si = np.cos(theta), np.sin(theta)
    n = b.shape[0]
    for k in range(n):
        for d in range(3):
            ws[2 * k, d] = co * b[k, d] + si * b[k, 3 + d]
            ws[2 * k + 1, d] = co * b[k, d] - si * b[k, 3 + d]
    m = 2 * n
    spans = False
    for i in range(m):
        a0, a1, a2 = ws[i, 0], ws[i, 1], ws[i, 2]
        for k in range(i + 1, m):
            b0, b1, b2 = ws[k, 0], ws[k, 1], ws[k, 2]
            y0, y1, y2 = a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0
            norm = np.sqrt(y0 * y0 + y1 * y1 + y2 * y2)
            if norm < fp[SPAN_TOL]:
                continue
            spans = True
            tol = fp[CLOSURE_TOL] * norm
            below, above = False, False
            for t in range(m):
                d = y0 * ws[t, 0] + y1 * ws[t, 1] + y2 * ws[t, 2]
                below = below or d < -tol
                above = above or d > tol
                if below and above:  # both sides seen: the rest cannot change the answer
                    break
            if not (below and above):
                return False
    return spans


@njit(cache=True)
def _mu(c, j, n, fp, antipodal_tol):  # type: ignore[no-untyped-def]
    """[`crmgrasp.model.quality.least_friction`][] of row ``j``."""
    b = _basis(c, j, n, fp)
    ws = np.empty((2 * n, 3))
    if _spans(b, 0.0, fp, ws):
        return 0.0
    if not _spans(b, fp[THETA_MAX], fp, ws):
        return np.inf
    lo, hi = 0.0, fp[THETA_MAX]
    while hi - lo > fp[ANGLE_TOL]:
        mid = 0.5 * (lo + hi)
        if _spans(b, mid, fp, ws):
            hi = mid
        else:
            lo = mid
    mu = np.tan(hi)
    return 0.0 if mu < antipodal_tol else mu


@compiled
def _index(out, jo, code, th, strides, abs_m):  # type: ignore[no-untyped-def]
    """`crmgrasp.model.sensing.Discretizer.index` of column ``jo`` of ``out``."""
    idx = code
    for i in range(th.shape[0]):
        v = out[i, jo]
        if abs_m and i > 0:
            v = abs(v)
        for t in range(th.shape[1]):
            if v >= th[i, t]:
                idx += strides[i]
    return idx


@compiled
def execute_rows(cfg, sen, n, ci, fi, r, e, p, q, new, err):  # type: ignore[no-untyped-def]
    """One CRM per row: ``new[j]``, ``err[j]`` from ``cfg[j]`` (true) and ``sen[j]`` (sensed)."""
    for j in range(cfg.shape[0]):
        err[j] = _crm(cfg, sen, j, n, ci[j], fi[j], r[j], e, p, q, new, j)


@njit(cache=True)
def observe_rows(cfg, sen, n, err, th, strides, abs_m, p, fp, values, index, mu):  # type: ignore[no-untyped-def]
    """Observation (``values``: ``(1 + n, N)``) and bin index of each sensed row, least
    friction of each true row."""
    for j in range(cfg.shape[0]):
        _observe(sen, j, n, values, j)
        index[j] = _index(values, j, err[j], th, strides, abs_m)
        mu[j] = _mu(cfg, j, n, fp, p[ANTIPODAL_TOL])


@njit(cache=True)
def uniform_start(s, cum, perimeter, e, n, p, q, fp, mu_goal, out):  # type: ignore[no-untyped-def]
    """[`crmgrasp.tasks.starts.uniform_candidate`][] on the arclengths ``s``: the contacts at
    ``s`` (``Polygon.boundary``: wrapped by the perimeter, on the edge whose cumulative
    length ``cum`` is the last at or below it) into row 0 of ``out``; returns whether the
    start is taken (no contact on a vertex, feasible, least friction above ``mu_goal``)."""
    m = e.shape[0]
    for c in range(n):
        for v in range(m):
            if s[c] == cum[v]:  # a vertex: its normal is undefined
                return False
    for c in range(n):
        sc = s[c] % perimeter
        i = -1
        for v in range(m + 1):
            if cum[v] <= sc:
                i = v
        i = min(i, m - 1)
        frac = (sc - cum[i]) / np.sqrt(e[i, 4])
        out[0, 4 * c] = e[i, 0] + frac * e[i, 2]
        out[0, 4 * c + 1] = e[i, 1] + frac * e[i, 3]
        out[0, 4 * c + 2] = e[i, 5]
        out[0, 4 * c + 3] = e[i, 6]
    if feasible(out, 0, n, e, p, q) != 0:
        return False
    return _mu(out, 0, n, fp, p[ANTIPODAL_TOL]) > mu_goal


@njit(cache=True)
def step_one(v, action, acts, n, e, th, strides, abs_m, p, q, fp, out, vals, known, mu_v):  # type: ignore[no-untyped-def]
    """One noise-free CRM ``acts[action]`` of the single environment from row 0 of ``v``: the
    new configuration into row 0 of ``out``, its observation into ``vals[:, 0]``; returns
    ``(error code, bin index, least friction)``, as [`crmgrasp.sim.step`][]. With ``known``,
    ``vals[:, 0]`` and ``mu_v`` already hold the observation and least friction of ``v``'s row:
    after an error (the row unchanged) they are the step's own, not computed again."""
    code = _crm(v, v, 0, n, int(acts[action, 0]), int(acts[action, 1]), acts[action, 2], e, p, q, out, 0)
    if code != 0 and known:
        return code, _index(vals, 0, code, th, strides, abs_m), mu_v
    _observe(out, 0, n, vals, 0)
    return code, _index(vals, 0, code, th, strides, abs_m), _mu(out, 0, n, fp, p[ANTIPODAL_TOL])


@njit(cache=True)
def begin_one(v, n, th, strides, abs_m, p, fp, vals):  # type: ignore[no-untyped-def]
    """The observation of row 0 of ``v`` (noise-free) into ``vals[:, 0]``; returns ``(bin
    index, least friction)``, as [`crmgrasp.sim.begin`][]."""
    _observe(v, 0, n, vals, 0)
    return _index(vals, 0, 0, th, strides, abs_m), _mu(v, 0, n, fp, p[ANTIPODAL_TOL])


# compiled sources: 558933e4e9fd694b1d93f83c8874066d0040613a9f2d6aa5735db199130e247f

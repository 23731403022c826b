"""Optional compiled kernels (numba, extra ``crmgrasp[fast]``) for polygonal objects.

Each function is a per-row loop that evaluates exactly the floating-point
expressions of the scalar path (:mod:`crmgrasp.geometry`, :mod:`crmgrasp.hand`,
:mod:`crmgrasp.quality`, :mod:`crmgrasp.sensing`) in the same order. numba compiles
without ``fastmath``, so LLVM neither reassociates nor fuses them: the results
equal the scalar and numpy paths bit for bit (the tests check it). No random draws
happen here: callers pass uniforms drawn from their seeded ``numpy.random.Generator``.

``AVAILABLE`` is false when numba is not installed or ``CRMGRASP_NUMBA=0`` is set;
the numpy path is then used everywhere.
"""

from __future__ import annotations

import os

import numpy as np

# The scalar path's tolerances; numba freezes them into the compiled (and cached)
# code, so clear ``__pycache__`` after changing one.
from ._scalar import ANTIPODAL_TOL, EPS, LINE_TOL, S_TOL

try:  # pragma: no cover - depends on the optional extra
    if os.environ.get("CRMGRASP_NUMBA", "1") == "0":
        raise ImportError("disabled by CRMGRASP_NUMBA=0")
    from numba import njit

    AVAILABLE = True
except ImportError:  # pragma: no cover - depends on the optional extra
    AVAILABLE = False

    def njit(*args, **kwargs):  # type: ignore[no-untyped-def, no-redef]
        """Stand-in so the module imports without numba; the kernels are unused then."""

        def wrap(fn):  # type: ignore[no-untyped-def]
            return fn

        return wrap


__all__ = ["AVAILABLE", "execute_rows", "corner_candidates", "observe_rows", "step_rows"]


@njit(cache=True)
def _contains(px, py, e, convex):  # type: ignore[no-untyped-def]
    n = e.shape[0]
    if convex:
        for i in range(n):
            if (px - e[i, 0]) * e[i, 5] + (py - e[i, 1]) * e[i, 6] <= EPS:
                return False
        return True
    inside = False
    for i in range(n):
        ax, ay, ex, ey = e[i, 0], e[i, 1], e[i, 2], e[i, 3]
        by = ay + ey
        if (ay > py) != (by > py):
            if px < ax + (py - ay) * ex / ey:
                inside = not inside
    if not inside:
        return False
    for i in range(n):
        ax, ay, ex, ey, l2 = e[i, 0], e[i, 1], e[i, 2], e[i, 3], e[i, 4]
        t = min(1.0, max(0.0, ((px - ax) * ex + (py - ay) * ey) / l2))
        dx, dy = ax + t * ex - px, ay + t * ey - py
        if dx * dx + dy * dy <= EPS * EPS:
            return False
    return True


@njit(cache=True)
def _feasible(ax, ay, anx, any_, bx, by, bnx, bny, e, convex, aperture, palm_depth, tol):  # type: ignore[no-untyped-def]
    dx, dy = bx - ax, by - ay
    dist = np.sqrt(dx * dx + dy * dy)
    if dist > aperture:
        return 1
    if dist == 0.0:
        return 2
    ux, uy = dy / dist, -dx / dist
    if anx * ux + any_ * uy > tol or bnx * ux + bny * uy > tol:
        return 2
    if _contains(0.5 * (ax + bx) + palm_depth * ux, 0.5 * (ay + by) + palm_depth * uy, e, convex):
        return 2
    return 0


@njit(cache=True)
def _execute_col(cfg, sen, j, c_is_b, f_is_b, r, e, convex, aperture, palm_depth, tol, new):  # type: ignore[no-untyped-def]
    """CRM on column ``j``: writes ``new[:, j]``, returns the error code (0, 1, 2)."""
    for k in range(8):
        new[k, j] = cfg[k, j]
    fo = 4 if f_is_b else 0
    mo = 4 if c_is_b else 0
    so = 4 - mo
    fx, fy, fnx, fny = sen[fo, j], sen[fo + 1, j], sen[fo + 2, j], sen[fo + 3, j]
    bx, by = fx + r * fny, fy - r * fnx
    wx, wy = bx - cfg[so, j], by - cfg[so + 1, j]
    qa = fnx * fnx + fny * fny
    qb = wx * fnx + wy * fny
    qc = wx * wx + wy * wy - aperture * aperture
    disc = qb * qb - qa * qc
    if disc < 0.0:
        return 1
    root = np.sqrt(disc)
    t_lo, t_hi = (-qb - root) / qa, (-qb + root) / qa
    same = c_is_b == f_is_b
    t0, t1 = (t_lo, t_hi) if same else (t_hi, t_lo)
    ox, oy = bx + t0 * fnx, by + t0 * fny
    if _contains(ox, oy, e, convex):
        return 1
    sign = 1.0 if same else -1.0
    dx, dy = sign * fnx, sign * fny
    u_max = abs(t1 - t0)
    if convex:
        k = _convex_edge(ox, oy, dx, dy, e)
        if k < 0:
            return 1
        nx, ny = e[k, 5], e[k, 6]
        denom = dx * nx + dy * ny
        if not denom > 0.0:
            return 1
        best = ((e[k, 0] - ox) * nx + (e[k, 1] - oy) * ny) / denom
        if not (best >= -EPS and best <= u_max + EPS):
            return 1
        px, py = ox + best * dx, oy + best * dy
        return _finish(cfg, j, mo, px, py, nx, ny, e, convex, aperture, palm_depth, tol, new)
    best, px, py, nx, ny = np.inf, 0.0, 0.0, 0.0, 0.0
    for i in range(e.shape[0]):
        ax, ay, ex, ey, l2, enx, eny = e[i, 0], e[i, 1], e[i, 2], e[i, 3], e[i, 4], e[i, 5], e[i, 6]
        denom = dx * enx + dy * eny
        if denom <= 0.0:
            continue
        u = ((ax - ox) * enx + (ay - oy) * eny) / denom
        if u < -EPS or u > u_max + EPS:
            continue
        qx, qy = ox + u * dx, oy + u * dy
        s = ((qx - ax) * ex + (qy - ay) * ey) / l2
        if s < -S_TOL or s > 1.0 + S_TOL:
            continue
        if u < best:
            best, px, py, nx, ny = u, qx, qy, enx, eny
    if best == np.inf:
        return 1
    return _finish(cfg, j, mo, px, py, nx, ny, e, convex, aperture, palm_depth, tol, new)


@njit(cache=True)
def _line_side(c, tol):  # type: ignore[no-untyped-def]
    return 1 if c > tol else (-1 if c < -tol else 0)


@njit(cache=True)
def _convex_edge(ox, oy, dx, dy, e):  # type: ignore[no-untyped-def]
    """:func:`crmgrasp._scalar.convex_edge` (-1 if none)."""
    n = e.shape[0]
    tol = LINE_TOL * (abs(dx) + abs(dy))
    s0 = _line_side(dx * (e[0, 1] - oy) - dy * (e[0, 0] - ox), tol)
    s = s0
    for i in range(n):
        s1 = _line_side(dx * (e[i + 1, 1] - oy) - dy * (e[i + 1, 0] - ox), tol) if i + 1 < n else s0
        if s >= 0 and s1 <= 0 and (s > 0 or s1 < 0):
            return i
        s = s1
    return -1


@njit(cache=True)
def _finish(cfg, j, mo, px, py, nx, ny, e, convex, aperture, palm_depth, tol, new):  # type: ignore[no-untyped-def]
    """Feasibility of column ``j`` with the mover at the entry; writes ``new[:, j]`` if feasible."""
    c = (
        (px, py, nx, ny, cfg[4, j], cfg[5, j], cfg[6, j], cfg[7, j])
        if mo == 0
        else (cfg[0, j], cfg[1, j], cfg[2, j], cfg[3, j], px, py, nx, ny)
    )
    code = _feasible(c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7], e, convex, aperture, palm_depth, tol)
    if code == 0:
        for k in range(8):
            new[k, j] = c[k]
    return code


@njit(cache=True)
def execute_rows(cfg, sen, c_is_b, f_is_b, rr, e, convex, aperture, palm_depth, tol, new, err):  # type: ignore[no-untyped-def]
    """CRM per column of the ``(8, N)`` blocks ``cfg`` (true) and ``sen`` (sensed);
    writes ``new`` (``(8, N)``) and ``err`` (``(N,)``), as :func:`crmgrasp.hand.execute_crm`."""
    for j in range(cfg.shape[1]):
        err[j] = _execute_col(cfg, sen, j, c_is_b[j], f_is_b[j], rr[j], e, convex, aperture, palm_depth, tol, new)


@njit(cache=True)
def _tan(x, y, nx, ny, ox, oy):  # type: ignore[no-untyped-def]
    dx, dy = ox - x, oy - y
    dot = nx * dx + ny * dy
    if dot <= 0.0:
        return np.inf
    t = abs(nx * dy - ny * dx) / dot
    return 0.0 if t < ANTIPODAL_TOL else t


@njit(cache=True)
def _observe_col(cfg, sen, j, out):  # type: ignore[no-untyped-def]
    sx, sy = sen[2, j] + sen[6, j], sen[3, j] + sen[7, j]
    dx, dy = sen[4, j] - sen[0, j], sen[5, j] - sen[1, j]
    out[0] = sx * sx + sy * sy
    out[1] = dx * sen[7, j] - dy * sen[6, j]
    out[2] = -dx * sen[3, j] + dy * sen[2, j]
    ta = _tan(cfg[0, j], cfg[1, j], cfg[2, j], cfg[3, j], cfg[4, j], cfg[5, j])
    tb = _tan(cfg[4, j], cfg[5, j], cfg[6, j], cfg[7, j], cfg[0, j], cfg[1, j])
    out[3] = max(ta, tb)


@njit(cache=True)
def observe_rows(cfg, sen, rho, m_a, m_b, mu):  # type: ignore[no-untyped-def]
    """Observation of the sensed block and min friction of the true block, per column."""
    out = np.empty(4)
    for j in range(cfg.shape[1]):
        _observe_col(cfg, sen, j, out)
        rho[j], m_a[j], m_b[j], mu[j] = out[0], out[1], out[2], out[3]


@njit(cache=True)
def _bin(v, t):  # type: ignore[no-untyped-def]
    """:func:`crmgrasp.sensing._bins` for one value (``searchsorted`` puts NaN last)."""
    if t.shape[0] > 3 and v != v:
        return t.shape[0]
    k = 0
    for i in range(t.shape[0]):
        if v >= t[i]:
            k += 1
    return k


@njit(cache=True)
def _clip(x, lo, hi):  # type: ignore[no-untyped-def]
    """``np.minimum(np.maximum(x, lo), hi)`` (NaN stays NaN)."""
    y = lo if x < lo else x
    return hi if y > hi else y


@njit(cache=True)
def step_rows(cfg, c_is_b, f_is_b, rr, reset, starts, e, convex, aperture, palm_depth, tol, bins, abs_m, bound, out):  # type: ignore[no-untyped-def]
    """One noise-free vector-environment step in one pass: per column ``j`` of ``cfg``
    (``(8, N)``), the next start (``starts[:, k]``, in order) where ``reset[j]``, else
    the CRM ``(c_is_b, f_is_b, rr)[j]``; then its observation (clipped to the space),
    bin index and min friction. ``bins`` holds the discretizer's thresholds
    ``(rho, m_a, m_b)``; ``out`` the outputs ``(new, rho, m_a, m_b, error, index, mu)``."""
    new, rho, m_a, m_b, error, index, mu = out
    t_rho, t_ma, t_mb = bins
    na, nb = t_ma.shape[0] + 1, t_mb.shape[0] + 1
    obs = np.empty(4)
    k = 0
    for j in range(cfg.shape[1]):
        if reset[j]:
            for i in range(8):
                new[i, j] = starts[i, k]
            k += 1
            code = 0
        else:
            code = _execute_col(cfg, cfg, j, c_is_b[j], f_is_b[j], rr[j], e, convex, aperture, palm_depth, tol, new)
        _observe_col(new, new, j, obs)
        ma, mb = (abs(obs[1]), abs(obs[2])) if abs_m else (obs[1], obs[2])
        index[j] = ((_bin(obs[0], t_rho) * na + _bin(ma, t_ma)) * nb + _bin(mb, t_mb)) * 3 + code
        rho[j, 0] = 4.0 if obs[0] > 4.0 else obs[0]
        m_a[j, 0] = _clip(obs[1], -bound, bound)
        m_b[j, 0] = _clip(obs[2], -bound, bound)
        error[j] = code
        mu[j] = obs[3]


@njit(cache=True)
def corner_candidates(u, e, convex, aperture, palm_depth, tol, mu_goal, out):  # type: ignore[no-untyped-def]
    """Corner-start candidates from uniforms ``u`` (``(4, m)``: corner, fraction in,
    fraction out, coin); writes the accepted ones to ``out[:, :count]``; returns count."""
    nv = e.shape[0]
    count = 0
    for j in range(u.shape[1]):
        if u[1, j] == 0.0 or u[2, j] == 0.0:
            continue
        k = int(u[0, j] * nv)
        ki = (k - 1) % nv
        x1, y1 = e[ki, 0] + u[1, j] * e[ki, 2], e[ki, 1] + u[1, j] * e[ki, 3]
        x2, y2 = e[k, 0] + u[2, j] * e[k, 2], e[k, 1] + u[2, j] * e[k, 3]
        if u[3, j] < 0.5:
            c = (x1, y1, e[ki, 5], e[ki, 6], x2, y2, e[k, 5], e[k, 6])
        else:
            c = (x2, y2, e[k, 5], e[k, 6], x1, y1, e[ki, 5], e[ki, 6])
        if _feasible(c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7], e, convex, aperture, palm_depth, tol) != 0:
            continue
        ta = _tan(c[0], c[1], c[2], c[3], c[4], c[5])
        tb = _tan(c[4], c[5], c[6], c[7], c[0], c[1])
        if max(ta, tb) <= mu_goal:
            continue
        for i in range(8):
            out[i, count] = c[i]
        count += 1
    return count

"""Compiled (numba) per-row loops for polygonal objects.

Each function evaluates exactly the floating-point expressions of the model's
reference rules in the same order: the inside test and first entry
(`crmgrasp.model.polygon`), feasibility and the CRM transition
([`crmgrasp.model.hand`][]), the observation and bins ([`crmgrasp.model.sensing`][]), min
friction ([`crmgrasp.model.quality`][]) and the start rule ([`crmgrasp.tasks`][]).
numba compiles without ``fastmath``, so LLVM neither reassociates nor fuses them,
and the results equal the reference bit for bit (the tests check it). The per-row
loops and their helpers compile without reference counting, the helpers inlined
(``crmgrasp.kernels._compile``).

No constant of the model is written here: every tolerance and parameter arrives
in the array ``p`` (layout below, built by [`crmgrasp.kernels.polygon.params`][]
from the model's modules at each kernel's construction), so the on-disk cache can
never hold a stale copy of one. No random draws happen here.

Layouts: configurations are ``(N, 8)`` rows ``[ax, ay, anx, any, bx, by, bnx,
bny]``; ``e`` is the polygon's ``(E, 7)`` edge array; ``acts`` an ``(A, 3)`` array
of CRMs ``(c is b, f is b, r)``; ``th`` the ``(3, K)`` bin thresholds of ``rho``,
``m_a``, ``m_b``, padded with ``+inf`` (which no value reaches).
"""

from __future__ import annotations

import numpy as np

from crmgrasp.kernels._compile import compiled, inlined

# indices into the parameter array p
APERTURE, DEPTH, PALM_TOL, EPS, S_TOL, LINE_TOL, ANTIPODAL_TOL, MU_GOAL, BOUND, MIN_SEP = range(10)
# indices into the integer array q
CONVEX, NA, NB, ABS_M = range(4)
N_P, N_Q = 10, 4


@inlined
def _unpack(p, q):  # type: ignore[no-untyped-def]
    """The parameter arrays as tuples: values the compiler keeps in registers (an
    array's loads would be repeated after every store to an output array)."""
    return (p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], p[8], p[9]), (q[0], q[1], q[2], q[3])


@inlined
def _inside(px, py, e, convex, eps):  # type: ignore[no-untyped-def]
    """`crmgrasp.model.polygon.inside`."""
    n = e.shape[0]
    if convex:
        for i in range(n):
            if (px - e[i, 0]) * e[i, 5] + (py - e[i, 1]) * e[i, 6] <= eps:
                return False
        return True
    odd = False
    for i in range(n):
        ax, ay, ex, ey = e[i, 0], e[i, 1], e[i, 2], e[i, 3]
        if (ay > py) != (ay + ey > py):
            if px < ax + (py - ay) * ex / ey:
                odd = not odd
    if not odd:
        return False
    for i in range(n):
        ax, ay, ex, ey, l2 = e[i, 0], e[i, 1], e[i, 2], e[i, 3], e[i, 4]
        t = min(1.0, max(0.0, ((px - ax) * ex + (py - ay) * ey) / l2))
        dx, dy = ax + t * ex - px, ay + t * ey - py
        if dx * dx + dy * dy <= eps * eps:
            return False
    return True


@inlined
def feasible(c, j, n, e, p, q):  # type: ignore[no-untyped-def]
    """[`crmgrasp.model.hand.feasible`][] of row ``j`` of ``c`` (``n`` contacts): 0 none, 1
    aperture, 2 palm. Shared by every planar kernel."""
    z = 4 * (n - 1)
    dx, dy = c[j, z] - c[j, 0], c[j, z + 1] - c[j, 1]
    dist = np.sqrt(dx * dx + dy * dy)
    if dist > p[APERTURE]:
        return 1
    far, near = 0.0, np.inf
    for a in range(n):
        for b in range(a + 1, n):
            ex, ey = c[j, 4 * b] - c[j, 4 * a], c[j, 4 * b + 1] - c[j, 4 * a + 1]
            d = np.sqrt(ex * ex + ey * ey)
            far, near = max(far, d), min(near, d)
    if far > p[APERTURE]:
        return 1
    if near <= p[MIN_SEP]:
        return 2
    ux, uy = dy / dist, -dx / dist
    tol = p[PALM_TOL]
    if c[j, 2] * ux + c[j, 3] * uy > tol or c[j, z + 2] * ux + c[j, z + 3] * uy > tol:
        return 2
    last = 0.0
    for k in range(1, n if n > 2 else 1):  # the fingers cross (three or more contacts)
        s = (c[j, 4 * k] - c[j, 0]) * -uy + (c[j, 4 * k + 1] - c[j, 1]) * ux
        if s <= last:
            return 2
        last = s
    sx, sy = c[j, 0], c[j, 1]
    for k in range(1, n):
        sx += c[j, 4 * k]
        sy += c[j, 4 * k + 1]
    h = p[DEPTH]
    if _inside(sx / n + h * ux, sy / n + h * uy, e, q[CONVEX], p[EPS]):
        return 2
    return 0


@inlined
def _side(c, tol):  # type: ignore[no-untyped-def]
    return 1 if c > tol else (-1 if c < -tol else 0)


@inlined
def _convex_edge(ox, oy, dx, dy, e, line_tol):  # type: ignore[no-untyped-def]
    """[`crmgrasp.model.polygon.convex_edge`][] (-1 if none)."""
    n = e.shape[0]
    tol = line_tol * (abs(dx) + abs(dy))
    s0 = _side(dx * (e[0, 1] - oy) - dy * (e[0, 0] - ox), tol)
    s = s0
    for i in range(n):
        s1 = _side(dx * (e[i + 1, 1] - oy) - dy * (e[i + 1, 0] - ox), tol) if i + 1 < n else s0
        if s >= 0 and s1 <= 0 and (s > 0 or s1 < 0):
            return i
        s = s1
    return -1


@inlined
def _entry(ox, oy, dx, dy, u_max, e, convex, p):  # type: ignore[no-untyped-def]
    """[`crmgrasp.model.polygon.Polygon.ray_entry`][]: ``(entered, x, y, nx, ny)``."""
    eps = p[EPS]
    if convex:
        k = _convex_edge(ox, oy, dx, dy, e, p[LINE_TOL])
        if k < 0:
            return False, 0.0, 0.0, 0.0, 0.0
        nx, ny = e[k, 5], e[k, 6]
        denom = dx * nx + dy * ny
        if not denom > 0.0:
            return False, 0.0, 0.0, 0.0, 0.0
        u = ((e[k, 0] - ox) * nx + (e[k, 1] - oy) * ny) / denom
        if not (u >= -eps and u <= u_max + eps):
            return False, 0.0, 0.0, 0.0, 0.0
        return True, ox + u * dx, oy + u * dy, nx, ny
    s_tol = p[S_TOL]
    hi = u_max + eps
    best, bx, by, bnx, bny = np.inf, 0.0, 0.0, 0.0, 0.0
    for i in range(e.shape[0]):
        ax, ay, ex, ey, l2, enx, eny = e[i, 0], e[i, 1], e[i, 2], e[i, 3], e[i, 4], e[i, 5], e[i, 6]
        denom = dx * enx + dy * eny
        if denom <= 0.0:
            continue
        u = ((ax - ox) * enx + (ay - oy) * eny) / denom
        if u < -eps or u > hi:
            continue
        qx, qy = ox + u * dx, oy + u * dy
        s = ((qx - ax) * ex + (qy - ay) * ey) / l2
        if s < -s_tol or s > 1.0 + s_tol:
            continue
        if u < best:
            best, bx, by, bnx, bny = u, qx, qy, enx, eny
    return best != np.inf, bx, by, bnx, bny


@inlined
def chord(bx, by, fnx, fny, sx, sy, aperture):  # type: ignore[no-untyped-def]
    """Step 2 of [`crmgrasp.model.hand.execute_crm`][] for one still contact at ``(sx, sy)``:
    ``(reached, t_lo, t_hi)``, where the goal line ``b + t n_f`` is within the aperture of
    it. Shared by every planar kernel."""
    wx, wy = bx - sx, by - sy
    qa = fnx * fnx + fny * fny
    qb = wx * fnx + wy * fny
    qc = wx * wx + wy * wy - aperture * aperture
    disc = qb * qb - qa * qc
    if disc < 0.0:
        return False, 0.0, 0.0
    root = np.sqrt(disc)
    return True, (-qb - root) / qa, (-qb + root) / qa


@inlined
def approach(bx, by, fnx, fny, t_lo, t_hi, same, e, p, q):  # type: ignore[no-untyped-def]
    """Steps 3-5 of [`crmgrasp.model.hand.execute_crm`][] on the goal line ``b + t n_f`` with
    chord ``[t_lo, t_hi]``: start at the chord's far end (``t_lo`` when the contact moves
    in its own frame), refuse a start inside, enter along the line:
    ``(code, x, y, nx, ny)``, code 0 or 1 (aperture). Shared by every planar kernel."""
    t0, t1 = (t_lo, t_hi) if same else (t_hi, t_lo)
    ox, oy = bx + t0 * fnx, by + t0 * fny
    convex = q[CONVEX]
    if _inside(ox, oy, e, convex, p[EPS]):
        return 1, 0.0, 0.0, 0.0, 0.0
    sign = 1.0 if same else -1.0
    ok, px, py, nx, ny = _entry(ox, oy, sign * fnx, sign * fny, abs(t1 - t0), e, convex, p)
    if not ok:
        return 1, 0.0, 0.0, 0.0, 0.0
    return 0, px, py, nx, ny


@inlined
def _crm(cfg, sen, j, c_is_b, f_is_b, r, e, p, q, new, jn):  # type: ignore[no-untyped-def]
    """[`crmgrasp.model.hand.execute_crm`][] on row ``j`` of ``cfg`` (true) and ``sen``
    (sensed): writes the resulting configuration into row ``jn`` of ``new``; returns
    the error code. (Rows by index, not views: a view costs reference counting.)"""
    for k in range(8):
        new[jn, k] = cfg[j, k]
    fo = 4 if f_is_b else 0
    mo = 4 if c_is_b else 0
    so = 4 - mo
    fx, fy, fnx, fny = sen[j, fo], sen[j, fo + 1], sen[j, fo + 2], sen[j, fo + 3]
    bx, by = fx + r * fny, fy - r * fnx
    reached, t_lo, t_hi = chord(bx, by, fnx, fny, cfg[j, so], cfg[j, so + 1], p[APERTURE])
    if not reached:
        return 1
    code, px, py, nx, ny = approach(bx, by, fnx, fny, t_lo, t_hi, c_is_b == f_is_b, e, p, q)
    if code:
        return code
    new[jn, mo], new[jn, mo + 1], new[jn, mo + 2], new[jn, mo + 3] = px, py, nx, ny
    code = feasible(new, jn, 2, e, p, q)
    if code != 0:
        for k in range(8):
            new[jn, k] = cfg[j, k]
    return code


@inlined
def _tan(x, y, nx, ny, ox, oy, antipodal_tol):  # type: ignore[no-untyped-def]
    """[`crmgrasp.model.quality.tan_term`][]."""
    dx, dy = ox - x, oy - y
    dot = nx * dx + ny * dy
    if dot <= 0.0:
        return np.inf
    t = abs(nx * dy - ny * dx) / dot
    return 0.0 if t < antipodal_tol else t


@inlined
def _mu(c, j, antipodal_tol):  # type: ignore[no-untyped-def]
    """[`crmgrasp.model.quality.min_friction`][] of row ``j`` of ``c``."""
    ta = _tan(c[j, 0], c[j, 1], c[j, 2], c[j, 3], c[j, 4], c[j, 5], antipodal_tol)
    tb = _tan(c[j, 4], c[j, 5], c[j, 6], c[j, 7], c[j, 0], c[j, 1], antipodal_tol)
    return max(ta, tb)


@inlined
def _observe(s, j):  # type: ignore[no-untyped-def]
    """[`crmgrasp.model.sensing.observe`][] of row ``j`` of the sensed rows ``s``:
    ``(rho, m_a, m_b)``."""
    sx, sy = s[j, 2] + s[j, 6], s[j, 3] + s[j, 7]
    dx, dy = s[j, 4] - s[j, 0], s[j, 5] - s[j, 1]
    return sx * sx + sy * sy, dx * s[j, 7] - dy * s[j, 6], -dx * s[j, 3] + dy * s[j, 2]


@inlined
def _bin(v, th, row):  # type: ignore[no-untyped-def]
    """[`crmgrasp.model.sensing._bin`][]: how many thresholds of row ``row`` of ``th``
    ``v`` reaches."""
    k = 0
    for i in range(th.shape[1]):
        if v >= th[row, i]:
            k += 1
    return k


@inlined
def bin_index(rho, m_a, m_b, code, th, na, nb, abs_m):  # type: ignore[no-untyped-def]
    """`crmgrasp.model.sensing.Discretizer.index_of` (``na``, ``nb``: the moment bin
    counts; ``abs_m``: moments binned by magnitude)."""
    if abs_m:
        m_a, m_b = abs(m_a), abs(m_b)
    return ((_bin(rho, th, 0) * na + _bin(m_a, th, 1)) * nb + _bin(m_b, th, 2)) * 3 + code


@inlined
def _index(rho, m_a, m_b, code, th, q):  # type: ignore[no-untyped-def]
    """[`bin_index`][] with the bin counts of ``q``."""
    return bin_index(rho, m_a, m_b, code, th, q[NA], q[NB], q[ABS_M])


@compiled
def execute_rows(cfg, sen, c_is_b, f_is_b, r, e, p, q, new, err):  # type: ignore[no-untyped-def]
    """One CRM per row: ``new[j]``, ``err[j]`` from ``cfg[j]`` (true) and ``sen[j]`` (sensed)."""
    p, q = _unpack(p, q)
    for j in range(cfg.shape[0]):
        err[j] = _crm(cfg, sen, j, c_is_b[j], f_is_b[j], r[j], e, p, q, new, j)


@compiled
def observe_rows(cfg, sen, err, th, p, q, rho, m_a, m_b, index, mu):  # type: ignore[no-untyped-def]
    """Observation and bin index of each sensed row, min friction of each true row."""
    p, q = _unpack(p, q)
    for j in range(cfg.shape[0]):
        o0, o1, o2 = _observe(sen, j)
        rho[j], m_a[j], m_b[j] = o0, o1, o2
        index[j] = _index(o0, o1, o2, err[j], th, q)
        mu[j] = _mu(cfg, j, p[ANTIPODAL_TOL])


@compiled
def step_one(v, action, acts, e, th, p, q, out):  # type: ignore[no-untyped-def]
    """One noise-free CRM of the single environment from the configuration in the first
    8 columns of ``v`` (one row): the new configuration into ``out[0, :8]``, then ``rho, m_a, m_b,
    min_friction`` into ``out[0, 8:12]``; returns ``(error code, bin index)``."""
    p, q = _unpack(p, q)
    code = _crm(v, v, 0, acts[action, 0] != 0.0, acts[action, 1] != 0.0, acts[action, 2], e, p, q, out, 0)
    o0, o1, o2 = _observe(out, 0)
    out[0, 8], out[0, 9], out[0, 10] = o0, o1, o2
    out[0, 11] = _mu(out, 0, p[ANTIPODAL_TOL])
    return code, _index(o0, o1, o2, code, th, q)


@compiled
def begin_one(v, th, p, q, out):  # type: ignore[no-untyped-def]
    """The observation of the configuration in the first 8 columns of ``v`` (one row,
    noise-free) into
    ``out[0, 8:11]`` and its min friction into ``out[0, 11]``; returns its bin index
    (error none), as [`crmgrasp.sim.begin`][]."""
    p, q = _unpack(p, q)
    o0, o1, o2 = _observe(v, 0)
    out[0, 8], out[0, 9], out[0, 10] = o0, o1, o2
    out[0, 11] = _mu(v, 0, p[ANTIPODAL_TOL])
    return _index(o0, o1, o2, 0, th, q)


@inlined
def _clip(x, lo, hi):  # type: ignore[no-untyped-def]
    """``np.minimum(np.maximum(x, lo), hi)`` (NaN stays NaN)."""
    y = lo if x < lo else x
    return hi if y > hi else y


@compiled
def step_rows(cfg, actions, acts, reset, starts, e, th, p, q, new, rho, m_a, m_b, err, index, mu):  # type: ignore[no-untyped-def]
    """One noise-free vector-environment step in one pass: per row ``j``, the next start
    (``starts[k]``, in order) where ``reset[j]``, else the CRM ``acts[actions[j]]``; then
    its observation (clipped to the observation space: ``rho <= 4``, ``|m| <= bound``),
    bin index and min friction. ``rho``, ``m_a``, ``m_b`` are ``(N, 1)``."""
    p, q = _unpack(p, q)
    bound = p[BOUND]
    k = 0
    for j in range(cfg.shape[0]):
        if reset[j]:
            for i in range(8):
                new[j, i] = starts[k, i]
            k += 1
            code = 0
        else:
            a = actions[j]
            code = _crm(cfg, cfg, j, acts[a, 0] != 0.0, acts[a, 1] != 0.0, acts[a, 2], e, p, q, new, j)
        o0, o1, o2 = _observe(new, j)
        index[j] = _index(o0, o1, o2, code, th, q)
        rho[j, 0] = 4.0 if o0 > 4.0 else o0
        m_a[j, 0] = _clip(o1, -bound, bound)
        m_b[j, 0] = _clip(o2, -bound, bound)
        err[j] = code
        mu[j] = _mu(new, j, p[ANTIPODAL_TOL])


@compiled
def corner_rows(u, e, p, q, out):  # type: ignore[no-untyped-def]
    """[`crmgrasp.tasks.accept_corner_candidates`][]: the accepted corner-start
    candidates of the uniforms ``u`` (``(4, m)``) into ``out[:count]``; returns count."""
    p, q = _unpack(p, q)
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
            out[count, 0], out[count, 1], out[count, 2], out[count, 3] = x1, y1, e[ki, 5], e[ki, 6]
            out[count, 4], out[count, 5], out[count, 6], out[count, 7] = x2, y2, e[k, 5], e[k, 6]
        else:
            out[count, 0], out[count, 1], out[count, 2], out[count, 3] = x2, y2, e[k, 5], e[k, 6]
            out[count, 4], out[count, 5], out[count, 6], out[count, 7] = x1, y1, e[ki, 5], e[ki, 6]
        if feasible(out, count, 2, e, p, q) != 0:
            continue
        if _mu(out, count, p[ANTIPODAL_TOL]) <= p[MU_GOAL]:
            continue
        count += 1
    return count


@compiled
def edge_rows(v, e):  # type: ignore[no-untyped-def]
    """[`crmgrasp.model.polygon.Polygon.edges`][] of the counter-clockwise vertices ``v``
    (``(E, 2)``) into ``e`` (``(E, 7)``: start, edge vector, squared length, inward unit
    normal), the same operations in the same order; returns
    [`Polygon.convex`][crmgrasp.model.polygon.Polygon.convex] (every turn left or straight)."""
    n = v.shape[0]
    for i in range(n):
        k = i + 1 if i + 1 < n else 0
        ax, ay = v[i, 0], v[i, 1]
        ex, ey = v[k, 0] - ax, v[k, 1] - ay
        length = np.sqrt(ex * ex + ey * ey)
        e[i, 0], e[i, 1], e[i, 2], e[i, 3] = ax, ay, ex, ey
        e[i, 4], e[i, 5], e[i, 6] = ex * ex + ey * ey, -ey / length, ex / length
    for i in range(n):
        k = i + 1 if i + 1 < n else 0
        if e[i, 2] * e[k, 3] - e[i, 3] * e[k, 2] < 0.0:
            return False
    return True


# compiled sources: 558933e4e9fd694b1d93f83c8874066d0040613a9f2d6aa5735db199130e247f

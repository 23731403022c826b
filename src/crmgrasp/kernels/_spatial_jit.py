"""Compiled (numba) steps of the spatial model on one solid: a convex polyhedron, a
closed cylinder or a closed triangle mesh, on a table.

Each function evaluates exactly the floating-point expressions of the reference rules in
the same order: [`crmgrasp.model.solids`][] (inside test, first entry, radial
projection), [`crmgrasp.model.spatial`][] (tangent frame, feasibility with the table,
the CRM transition, the observation), [`crmgrasp.model.quality3d.min_friction_3d`][],
the bins of [`crmgrasp.model.sensing`][] and the start rule of
[`crmgrasp.tasks.spatial.SurfaceStarts`][]. numba compiles without ``fastmath``, so
the results equal the reference bit for bit (the tests check it). Python's ``min`` and
``max`` are written out as they decide (``min(a, b)`` is ``b if b < a else a``).

No constant of the model is written here: tolerances and parameters arrive in ``p``
and ``q`` (built by [`crmgrasp.kernels.spatial.spatial_params`][]). Layouts: a state
``v`` is one row ``[x_a, n_a, x_b, n_b]`` (12 columns); ``planes`` the polyhedron's
``(m, 4)`` faces ``(a, b)`` (kind 0), or the mesh's ``(m, 12)`` triangles (kind 2,
`crmgrasp.kernels._mesh_jit`); ``cyl`` the cylinder's ``[o, e, R, H]`` (8; kind 1), or
for a mesh its inside test's ray direction in the first three; ``acts`` the
``(A, 4)`` CRMs ``(c is b, f is b, r_1, r_2)``; ``th`` the padded bin thresholds.
"""

from __future__ import annotations

import math

from crmgrasp.kernels._compile import compiled
from crmgrasp.kernels._mesh_jit import contains as mesh_contains
from crmgrasp.kernels._mesh_jit import entry as mesh_entry
from crmgrasp.kernels._polygon_jit import bin_index

# indices into p
APERTURE, DEPTH, PALM_TOL, SURF, ANTIPODAL_TOL, MU_GOAL, MIN_SEP, TABLE, UP = range(9)
HX, HY, HZ, GX, GY, GZ, CX, CY, CZ, FAR, TIE, PARALLEL = range(9, 21)
N_P = 21
# indices into q
KIND, HAS_TABLE, NA, NB, ABS_M = range(5)
N_Q = 5
POLYHEDRON, CYLINDER, MESH = range(3)  # the values of q[KIND]
INF = math.inf


@compiled
def _min(a, b):  # type: ignore[no-untyped-def]
    return b if b < a else a


@compiled
def _max(a, b):  # type: ignore[no-untyped-def]
    return b if b > a else a


@compiled
def _dot(ax, ay, az, bx, by, bz):  # type: ignore[no-untyped-def]
    return ax * bx + ay * by + az * bz


@compiled
def _cross(ax, ay, az, bx, by, bz):  # type: ignore[no-untyped-def]
    return ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx


@compiled
def _norm(x, y, z):  # type: ignore[no-untyped-def]
    return math.sqrt(x * x + y * y + z * z)


@compiled
def _local(x, y, z, cyl):  # type: ignore[no-untyped-def]
    """[`Cylinder._local`][]: axial coordinate and radial vector."""
    rx, ry, rz = x - cyl[0], y - cyl[1], z - cyl[2]
    s = _dot(rx, ry, rz, cyl[3], cyl[4], cyl[5])
    return s, rx - s * cyl[3], ry - s * cyl[4], rz - s * cyl[5]


@compiled
def _contains(x, y, z, planes, cyl, kind, surf):  # type: ignore[no-untyped-def]
    if kind == MESH:
        return mesh_contains(planes, cyl, x, y, z, surf)
    if kind == POLYHEDRON:
        for k in range(planes.shape[0]):
            if not (planes[k, 0] * x + planes[k, 1] * y + planes[k, 2] * z - planes[k, 3] < -surf):
                return False
        return True
    s, qx, qy, qz = _local(x, y, z, cyl)
    return surf < s and s < cyl[7] - surf and _norm(qx, qy, qz) < cyl[6] - surf


@compiled
def _entry_poly(o, d, umax, planes, surf, tie):  # type: ignore[no-untyped-def]
    t_in, t_out, face = -INF, INF, -1
    for k in range(planes.shape[0]):
        a0, a1, a2, b = planes[k, 0], planes[k, 1], planes[k, 2], planes[k, 3]
        ad = a0 * d[0] + a1 * d[1] + a2 * d[2]
        gap = b - (a0 * o[0] + a1 * o[1] + a2 * o[2])
        if ad == 0.0:
            if gap < -surf:
                return False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
            continue
        t = gap / ad
        if ad < 0.0:
            if t > t_in + tie:
                t_in, face = t, k
        else:
            t_out = _min(t_out, t)
    if face < 0 or t_in > t_out + surf or t_in < -surf or t_in > umax + surf:
        return False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    return (
        True,
        o[0] + t_in * d[0],
        o[1] + t_in * d[1],
        o[2] + t_in * d[2],
        -planes[face, 0],
        -planes[face, 1],
        -planes[face, 2],
    )


@compiled
def _entry_cyl(o, d, umax, cyl, surf, tie):  # type: ignore[no-untyped-def]
    ex, ey, ez, radius, height = cyl[3], cyl[4], cyl[5], cyl[6], cyl[7]
    s0, r0x, r0y, r0z = _local(o[0], o[1], o[2], cyl)
    sd = _dot(d[0], d[1], d[2], ex, ey, ez)
    rdx, rdy, rdz = d[0] - sd * ex, d[1] - sd * ey, d[2] - sd * ez
    no_cap = sd == 0.0
    if no_cap:
        if not (0.0 <= s0 and s0 <= height):
            return False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
        slab_in, slab_out = -INF, INF
        sign = 0.0
    else:
        t_a, t_b = (0.0 - s0) / sd, (height - s0) / sd
        slab_in, slab_out = _min(t_a, t_b), _max(t_a, t_b)
        sign = 1.0 if sd > 0 else -1.0
    qa = _dot(rdx, rdy, rdz, rdx, rdy, rdz)
    qb = _dot(r0x, r0y, r0z, rdx, rdy, rdz)
    qc = _dot(r0x, r0y, r0z, r0x, r0y, r0z) - radius * radius
    if qa == 0.0:
        if qc > 0.0:
            return False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
        side_in, side_out = -INF, INF
    else:
        disc = qb * qb - qa * qc
        if disc < 0.0:
            return False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
        root = math.sqrt(disc)
        side_in, side_out = (-qb - root) / qa, (-qb + root) / qa
    t_in = _max(side_in, slab_in)
    if t_in > _min(side_out, slab_out) + surf or t_in < -surf or t_in > umax + surf:
        return False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    px, py, pz = o[0] + t_in * d[0], o[1] + t_in * d[1], o[2] + t_in * d[2]
    if side_in >= slab_in - tie or no_cap:
        _, qx, qy, qz = _local(px, py, pz, cyl)
        n = _norm(qx, qy, qz)
        return True, px, py, pz, -qx / n, -qy / n, -qz / n
    if sign > 0:
        return True, px, py, pz, ex, ey, ez
    return True, px, py, pz, -ex, -ey, -ez


@compiled
def _entry(o, d, umax, planes, cyl, kind, surf, tie):  # type: ignore[no-untyped-def]
    if kind == MESH:
        return mesh_entry(o, d, umax, planes, surf, tie)
    if kind == POLYHEDRON:
        return _entry_poly(o, d, umax, planes, surf, tie)
    return _entry_cyl(o, d, umax, cyl, surf, tie)


@compiled
def _axis(vx, vy, vz, p):  # type: ignore[no-untyped-def]
    """``v x h / |v x h|`` (``v x g`` when ``v`` is parallel to ``h``): the tangent
    ``t_1`` of a normal and the palm direction ``u`` of a contact direction."""
    tx, ty, tz = _cross(vx, vy, vz, p[HX], p[HY], p[HZ])
    if _norm(tx, ty, tz) < p[PARALLEL]:
        tx, ty, tz = _cross(vx, vy, vz, p[GX], p[GY], p[GZ])
    n = _norm(tx, ty, tz)
    return tx / n, ty / n, tz / n


@compiled
def _on_table(z, p, q):  # type: ignore[no-untyped-def]
    return q[HAS_TABLE] != 0 and z <= p[TABLE] + p[SURF]


@compiled
def _feasible(c, planes, cyl, p, q):  # type: ignore[no-untyped-def]
    """[`crmgrasp.model.spatial.feasible3d`][] of the row ``c``: 0 none, 1 aperture, 2 palm."""
    dx, dy, dz = c[6] - c[0], c[7] - c[1], c[8] - c[2]
    dist = _norm(dx, dy, dz)
    if dist > p[APERTURE]:
        return 1
    if dist <= p[MIN_SEP] or _on_table(c[2], p, q) or _on_table(c[8], p, q):
        return 2
    ux, uy, uz = _axis(dx / dist, dy / dist, dz / dist, p)
    tol = p[PALM_TOL]
    if _dot(c[3], c[4], c[5], ux, uy, uz) > tol or _dot(c[9], c[10], c[11], ux, uy, uz) > tol:
        return 2
    h = p[DEPTH]
    px = 0.5 * (c[0] + c[6]) + h * ux
    py = 0.5 * (c[1] + c[7]) + h * uy
    pz = 0.5 * (c[2] + c[8]) + h * uz
    if _contains(px, py, pz, planes, cyl, q[KIND], p[SURF]) or _on_table(pz, p, q):
        return 2
    return 0


@compiled
def _goal_line(v, sf, r1, r2, p):  # type: ignore[no-untyped-def]
    """The goal line of a CRM whose frame contact starts at column ``sf`` of ``v``: its base
    ``x_f + r_1 t_1 + r_2 t_2`` and direction ``n_f``
    ([`crmgrasp.model.spatial.goal_chord3d`][], [`tangent_frame`][crmgrasp.model.spatial.tangent_frame])."""
    nx, ny, nz = v[sf + 3], v[sf + 4], v[sf + 5]
    t1x, t1y, t1z = _axis(nx, ny, nz, p)
    t2x, t2y, t2z = _cross(t1x, t1y, t1z, nx, ny, nz)
    bx = v[sf] + r1 * t1x + r2 * t2x
    by = v[sf + 1] + r1 * t1y + r2 * t2y
    bz = v[sf + 2] + r1 * t1z + r2 * t2z
    return bx, by, bz, nx, ny, nz


@compiled
def _land(bx, by, bz, nx, ny, nz, t_lo, t_hi, same, planes, cyl, p, q):  # type: ignore[no-untyped-def]
    """The approach of [`crmgrasp.model.spatial.execute_crm3d`][] along its chord: the goal
    line ``b + t n`` within ``[t_lo, t_hi]``, walked along ``n`` from ``t_lo`` for an
    opposition of a contact onto itself (``same``), against it from ``t_hi`` otherwise,
    lifted above the table; returns ``(error code, x, y, z, n_x, n_y, n_z)`` of the new
    contact (the code 0 when it lands; feasibility is the caller's)."""
    t0, t1 = (t_lo, t_hi) if same else (t_hi, t_lo)
    start = (bx + t0 * nx, by + t0 * ny, bz + t0 * nz)
    ahead = (nx, ny, nz) if same else (-nx, -ny, -nz)
    length = abs(t1 - t0)
    kind, surf = q[KIND], p[SURF]
    if _contains(start[0], start[1], start[2], planes, cyl, kind, surf):
        return 1, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    if q[HAS_TABLE] != 0 and _on_table(start[2], p, q):
        rise = ahead[2]
        up = (p[TABLE] + 2.0 * surf - start[2]) / rise if rise > 0.0 else INF
        if up >= length:
            return 2, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
        moved = (start[0] + up * ahead[0], start[1] + up * ahead[1], start[2] + up * ahead[2])
        if _contains(moved[0], moved[1], moved[2], planes, cyl, kind, surf):
            return 2, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
        start, length = moved, length - up
    hit, px, py, pz, mx, my, mz = _entry(start, ahead, length, planes, cyl, kind, surf, p[TIE])
    return (0 if hit else 1), px, py, pz, mx, my, mz


@compiled
def _crm(v, c_is_b, f_is_b, r1, r2, planes, cyl, p, q, out):  # type: ignore[no-untyped-def]
    """[`crmgrasp.model.spatial.execute_crm3d`][] (noise-free: the goal line from the
    true frame) from the row ``v`` into the row ``out``; returns the error code."""
    for i in range(12):
        out[i] = v[i]
    still = 0 if c_is_b else 6
    bx, by, bz, nx, ny, nz = _goal_line(v, 6 if f_is_b else 0, r1, r2, p)
    wx, wy, wz = bx - v[still], by - v[still + 1], bz - v[still + 2]
    qb = _dot(wx, wy, wz, nx, ny, nz)
    qc = _dot(wx, wy, wz, wx, wy, wz) - p[APERTURE] * p[APERTURE]
    disc = qb * qb - qc
    if disc < 0.0:
        return 1
    t_lo, t_hi = -qb - math.sqrt(disc), -qb + math.sqrt(disc)
    code, px, py, pz, mx, my, mz = _land(bx, by, bz, nx, ny, nz, t_lo, t_hi, c_is_b == f_is_b, planes, cyl, p, q)
    if code != 0:
        return code
    m = 6 if c_is_b else 0
    out[m], out[m + 1], out[m + 2], out[m + 3], out[m + 4], out[m + 5] = px, py, pz, mx, my, mz
    code = _feasible(out, planes, cyl, p, q)
    if code != 0:
        for i in range(12):
            out[i] = v[i]
    return code


@compiled
def _observe(c):  # type: ignore[no-untyped-def]
    """[`crmgrasp.model.spatial.observe3d`][]: ``rho``, ``|m_a|``, ``|m_b|``."""
    sx, sy, sz = c[3] + c[9], c[4] + c[10], c[5] + c[11]
    ma = _cross(c[6] - c[0], c[7] - c[1], c[8] - c[2], c[9], c[10], c[11])
    mb = _cross(c[0] - c[6], c[1] - c[7], c[2] - c[8], c[3], c[4], c[5])
    return _dot(sx, sy, sz, sx, sy, sz), _norm(ma[0], ma[1], ma[2]), _norm(mb[0], mb[1], mb[2])


@compiled
def _mu(c, antipodal_tol):  # type: ignore[no-untyped-def]
    """[`crmgrasp.model.quality3d.min_friction_3d`][] of the row ``c``."""
    worst = 0.0
    for i in (0, 6):
        j = 6 - i
        dx, dy, dz = c[j] - c[i], c[j + 1] - c[i + 1], c[j + 2] - c[i + 2]
        length = _norm(dx, dy, dz)
        if length == 0.0:
            return INF
        cos = _dot(c[i + 3], c[i + 4], c[i + 5], dx, dy, dz) / length
        if cos <= 0.0:
            return INF
        sx, sy, sz = _cross(c[i + 3], c[i + 4], c[i + 5], dx, dy, dz)
        sin = _norm(sx, sy, sz) / length
        tan = sin / cos
        worst = _max(worst, 0.0 if tan < antipodal_tol else tan)
    return worst


@compiled
def _index(rho, m_a, m_b, code, th, q):  # type: ignore[no-untyped-def]
    """`crmgrasp.model.sensing.Discretizer.index_of`."""
    return bin_index(rho, m_a, m_b, code, th, q[NA], q[NB], q[ABS_M])


@compiled
def step_one(v, action, acts, planes, cyl, th, p, q, out):  # type: ignore[no-untyped-def]
    """One noise-free CRM from the state ``v`` (12): the new state into ``out[:12]``,
    ``rho, m_a, m_b, min friction`` into ``out[12:16]``; returns ``(error code, bin index)``."""
    code = _crm(
        v, acts[action, 0] != 0.0, acts[action, 1] != 0.0, acts[action, 2], acts[action, 3], planes, cyl, p, q, out
    )
    o0, o1, o2 = _observe(out)
    out[12], out[13], out[14] = o0, o1, o2
    out[15] = _mu(out, p[ANTIPODAL_TOL])
    return code, _index(o0, o1, o2, code, th, q)


@compiled
def begin_one(v, th, p, q, out):  # type: ignore[no-untyped-def]
    """The observation and min friction of the state ``v`` into ``out[12:16]``; returns its
    bin index (error none)."""
    o0, o1, o2 = _observe(v)
    out[12], out[13], out[14] = o0, o1, o2
    out[15] = _mu(v, p[ANTIPODAL_TOL])
    return _index(o0, o1, o2, 0, th, q)


@compiled
def _project(d, planes, cyl, p, q, out, at):  # type: ignore[no-untyped-def]
    """[`crmgrasp.model.solids.surface_point`][] of the direction ``d`` into ``out[at:at + 6]``."""
    n = _norm(d[0], d[1], d[2])
    ux, uy, uz = d[0] / n, d[1] / n, d[2] / n
    far = p[FAR]
    o = (p[CX] + far * ux, p[CY] + far * uy, p[CZ] + far * uz)
    hit, px, py, pz, mx, my, mz = _entry(o, (-ux, -uy, -uz), 2.0 * far, planes, cyl, q[KIND], p[SURF], p[TIE])
    out[at], out[at + 1], out[at + 2], out[at + 3], out[at + 4], out[at + 5] = px, py, pz, mx, my, mz
    return hit


@compiled
def accept_start(d, planes, cyl, p, q, out):  # type: ignore[no-untyped-def]
    """[`crmgrasp.tasks.spatial.SurfaceStarts`][]' decision on one try's directions
    ``d`` (2 x 3): the candidate into ``out`` (12); True when it is a start."""
    if _norm(d[0, 0], d[0, 1], d[0, 2]) == 0.0 or _norm(d[1, 0], d[1, 1], d[1, 2]) == 0.0:
        return False
    if not (_project(d[0], planes, cyl, p, q, out, 0) and _project(d[1], planes, cyl, p, q, out, 6)):
        return False
    up = p[UP]
    top_a = _dot(out[3], out[4], out[5], p[HX], p[HY], p[HZ]) <= -up
    top_b = _dot(out[9], out[10], out[11], p[HX], p[HY], p[HZ]) <= -up
    if top_a and top_b:
        return False
    if _feasible(out, planes, cyl, p, q) != 0:
        return False
    return not (_mu(out, p[ANTIPODAL_TOL]) <= p[MU_GOAL])


# compiled sources: 558933e4e9fd694b1d93f83c8874066d0040613a9f2d6aa5735db199130e247f

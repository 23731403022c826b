"""Compiled (numba) queries of a closed triangle mesh: the inside test and the first entry
of a ray, for the spatial kernels (`crmgrasp.kernels._spatial_jit` calls them for a solid
of kind 2).

Each function evaluates exactly the floating-point expressions of
[`crmgrasp.model.mesh.TriangleMesh`][] in the same order (Moller-Trumbore crossings, the
nearest point of a triangle by its Voronoi regions, the parity of a ray's crossings), so
the results equal the readable rules bit for bit (the tests check it). Layout: ``tri`` is
the ``(m, 12)`` array of the triangles ``[a, b, c, n]`` (corners counter-clockwise seen
from outside, and the unit outward normal the mesh computed), built by
[`crmgrasp.kernels.spatial.solid_params`][]; ``ray`` the inside test's ray direction
([`PARITY_RAY`][crmgrasp.model.mesh.PARITY_RAY]).
"""

from __future__ import annotations

import math

from crmgrasp.kernels._compile import compiled

INF = math.inf


@compiled
def _d3(ax, ay, az, bx, by, bz):  # type: ignore[no-untyped-def]
    return ax * bx + ay * by + az * bz


@compiled
def _hit(tri, k, ox, oy, oz, dx, dy, dz):  # type: ignore[no-untyped-def]
    """`TriangleMesh._hit`: ``(True, t)`` where ``o + t d`` crosses triangle ``k``, else
    ``(False, 0)``."""
    ax, ay, az = tri[k, 0], tri[k, 1], tri[k, 2]
    e1x, e1y, e1z = tri[k, 3] - ax, tri[k, 4] - ay, tri[k, 5] - az
    e2x, e2y, e2z = tri[k, 6] - ax, tri[k, 7] - ay, tri[k, 8] - az
    pvx, pvy, pvz = dy * e2z - dz * e2y, dz * e2x - dx * e2z, dx * e2y - dy * e2x
    det = _d3(e1x, e1y, e1z, pvx, pvy, pvz)
    if det == 0.0:
        return False, 0.0
    inv = 1.0 / det
    tx, ty, tz = ox - ax, oy - ay, oz - az
    u = _d3(tx, ty, tz, pvx, pvy, pvz) * inv
    if u < 0.0 or u > 1.0:
        return False, 0.0
    qx, qy, qz = ty * e1z - tz * e1y, tz * e1x - tx * e1z, tx * e1y - ty * e1x
    w = _d3(dx, dy, dz, qx, qy, qz) * inv
    if w < 0.0 or u + w > 1.0:
        return False, 0.0
    return True, _d3(e2x, e2y, e2z, qx, qy, qz) * inv


@compiled
def _closest(tri, k, px, py, pz):  # type: ignore[no-untyped-def]
    """`crmgrasp.model.mesh._closest_on_triangle`: the point of triangle ``k`` nearest ``p``."""
    ax, ay, az = tri[k, 0], tri[k, 1], tri[k, 2]
    bx, by, bz = tri[k, 3], tri[k, 4], tri[k, 5]
    cx, cy, cz = tri[k, 6], tri[k, 7], tri[k, 8]
    abx, aby, abz = bx - ax, by - ay, bz - az
    acx, acy, acz = cx - ax, cy - ay, cz - az
    d1 = _d3(abx, aby, abz, px - ax, py - ay, pz - az)
    d2 = _d3(acx, acy, acz, px - ax, py - ay, pz - az)
    if d1 <= 0.0 and d2 <= 0.0:
        return ax, ay, az
    d3 = _d3(abx, aby, abz, px - bx, py - by, pz - bz)
    d4 = _d3(acx, acy, acz, px - bx, py - by, pz - bz)
    if d3 >= 0.0 and d4 <= d3:
        return bx, by, bz
    vc = d1 * d4 - d3 * d2
    if vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
        s = d1 / (d1 - d3)
        return ax + s * abx, ay + s * aby, az + s * abz
    d5 = _d3(abx, aby, abz, px - cx, py - cy, pz - cz)
    d6 = _d3(acx, acy, acz, px - cx, py - cy, pz - cz)
    if d6 >= 0.0 and d5 <= d6:
        return cx, cy, cz
    vb = d5 * d2 - d1 * d6
    if vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
        s = d2 / (d2 - d6)
        return ax + s * acx, ay + s * acy, az + s * acz
    va = d3 * d6 - d5 * d4
    if va <= 0.0 and (d4 - d3) >= 0.0 and (d5 - d6) >= 0.0:
        s = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        return bx + s * (cx - bx), by + s * (cy - by), bz + s * (cz - bz)
    denom = 1.0 / (va + vb + vc)
    sb, sc = vb * denom, vc * denom
    return ax + abx * sb + acx * sc, ay + aby * sb + acy * sc, az + abz * sb + acz * sc


@compiled
def distance(tri, px, py, pz):  # type: ignore[no-untyped-def]
    """`TriangleMesh.distance`: from ``p`` to the surface (the least over the triangles)."""
    best = INF
    for k in range(tri.shape[0]):
        qx, qy, qz = _closest(tri, k, px, py, pz)
        rx, ry, rz = px - qx, py - qy, pz - qz
        d = math.sqrt(_d3(rx, ry, rz, rx, ry, rz))
        if d < best:
            best = d
    return best


@compiled
def contains(tri, ray, px, py, pz, surf):  # type: ignore[no-untyped-def]
    """`TriangleMesh.contains`: an odd number of triangles crossed (``t > 0``) by the ray
    ``p + t ray``, and more than ``surf`` from the surface."""
    crossings = 0
    for k in range(tri.shape[0]):
        hit, t = _hit(tri, k, px, py, pz, ray[0], ray[1], ray[2])
        if hit and t > 0.0:
            crossings += 1
    return crossings % 2 == 1 and distance(tri, px, py, pz) > surf


@compiled
def entry(o, d, umax, tri, surf, tie):  # type: ignore[no-untyped-def]
    """`TriangleMesh.ray_entry`: ``(hit, x, y, z, n_x, n_y, n_z)``, the first crossing of
    ``o + u d`` (``-surf <= u <= umax + surf``) into a triangle facing the ray, with the
    inward normal; among those within ``tie`` of the nearest, the lowest index."""
    best_t, best = INF, -1
    for k in range(tri.shape[0]):
        if _d3(tri[k, 9], tri[k, 10], tri[k, 11], d[0], d[1], d[2]) >= 0.0:
            continue
        hit, t = _hit(tri, k, o[0], o[1], o[2], d[0], d[1], d[2])
        if not hit or t < -surf or t > umax + surf:
            continue
        if t < best_t - tie:
            best_t, best = t, k
    if best < 0:
        return False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    return (
        True,
        o[0] + best_t * d[0],
        o[1] + best_t * d[1],
        o[2] + best_t * d[2],
        -tri[best, 9],
        -tri[best, 10],
        -tri[best, 11],
    )


# compiled sources: 558933e4e9fd694b1d93f83c8874066d0040613a9f2d6aa5735db199130e247f

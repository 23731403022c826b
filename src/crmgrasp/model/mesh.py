"""Closed triangle meshes: spatial objects that need not be convex (docs/model-3d.md section 1).

A [`TriangleMesh`][] is a list of corners and of triangles (corner indices, counter-
clockwise seen from outside). It is checked on construction, one line per problem: at
least four triangles, finite corners, no degenerate triangle, every edge shared by
exactly two triangles (a closed, manifold surface) traversed once in each direction (a
consistent orientation), and a positive enclosed volume (faces pointing outward).

It answers what the spatial CRM transition asks of any solid: strictly inside
(`contains`: an odd number of crossings of a ray, and farther than
[`SURFACE`][crmgrasp.model.solids.SURFACE] from every triangle), the first entry of a ray
with the inward normal there (`ray_entry`: the nearest triangle the ray crosses
while entering, lowest index among those within [`TIE`][crmgrasp.model.solids.TIE]), and
for placing and drawing it, its centre (of volume), support, ``gap`` and rigid motion.
The compiled spatial kernel repeats these rules (`crmgrasp.kernels._mesh_jit`) with the
same results bit for bit.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from crmgrasp._validation import CrmgraspError
from crmgrasp.model.shape import check_reach
from crmgrasp.model.solids import SURFACE, TIE, _rotation, cross, dot, norm

__all__ = ["PARITY_RAY", "TriangleMesh", "open_cup"]

F64 = NDArray[np.float64]
PARITY_RAY = np.array([0.5773502691896258, 0.5773502691896257, 0.5773502691896259]) + np.array([1e-3, -2e-3, 0.0])
"""The direction of the inside test's ray: off every axis and diagonal, so that it rarely
grazes an edge of a mesh built on a grid."""


def _closest_on_triangle(p: F64, a: F64, b: F64, c: F64) -> F64:
    """The point of triangle ``abc`` nearest ``p`` (by its Voronoi regions)."""
    ab, ac, ap = b - a, c - a, p - a
    d1, d2 = dot(ab, ap), dot(ac, ap)
    if d1 <= 0.0 and d2 <= 0.0:
        return a
    bp = p - b
    d3, d4 = dot(ab, bp), dot(ac, bp)
    if d3 >= 0.0 and d4 <= d3:
        return b
    vc = d1 * d4 - d3 * d2
    if vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
        return a + d1 / (d1 - d3) * ab
    cp = p - c
    d5, d6 = dot(ab, cp), dot(ac, cp)
    if d6 >= 0.0 and d5 <= d6:
        return c
    vb = d5 * d2 - d1 * d6
    if vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
        return a + d2 / (d2 - d6) * ac
    va = d3 * d6 - d5 * d4
    if va <= 0.0 and (d4 - d3) >= 0.0 and (d5 - d6) >= 0.0:
        return b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b)
    denom = 1.0 / (va + vb + vc)
    return a + ab * (vb * denom) + ac * (vc * denom)


def _cross_rows(u: F64, v: F64) -> F64:
    """Row-wise ``u x v`` of two ``(m, 3)`` arrays, written out: the same products and
    differences as ``np.cross`` (so the same bits), without its axis handling, which costs
    more than the products on a mesh's few hundred rows."""
    out = np.empty_like(u)
    out[:, 0] = u[:, 1] * v[:, 2] - u[:, 2] * v[:, 1]
    out[:, 1] = u[:, 2] * v[:, 0] - u[:, 0] * v[:, 2]
    out[:, 2] = u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0]
    return out


@functools.lru_cache(maxsize=64)
def _check_closed(faces: tuple[tuple[int, int, int], ...]) -> None:
    """Every edge in exactly two triangles, once in each direction. It depends on the faces
    alone, so a family's meshes (one topology, many sizes and poses) check it once
    (cached; a mesh that fails raises each time)."""
    directed: dict[tuple[int, int], int] = {}
    for i, tri in enumerate(faces):
        for a, b in ((tri[0], tri[1]), (tri[1], tri[2]), (tri[2], tri[0])):
            if (a, b) in directed:
                raise CrmgraspError(
                    f"mesh edge ({a}, {b}) is used twice in one direction (triangles {directed[(a, b)]} "
                    f"and {i}): faces are inconsistently oriented or the mesh is not manifold"
                )
            directed[(a, b)] = i
    for a, b in directed:
        if (b, a) not in directed:
            raise CrmgraspError(f"the mesh is open: edge ({a}, {b}) belongs to one triangle only")


def _checked_pieces(pieces: Any, corners: int) -> tuple[tuple[int, ...], ...]:
    """``pieces`` as tuples of corner indices: each four or more distinct indices in
    ``0..corners - 1`` (one line naming the first bad piece otherwise)."""
    if not isinstance(pieces, (tuple, list)):
        raise CrmgraspError(f"mesh pieces must be a list of corner-index lists, got {type(pieces).__name__}")
    out = []
    for i, piece in enumerate(pieces):
        ok = isinstance(piece, (tuple, list)) and all(isinstance(k, int) and not isinstance(k, bool) for k in piece)
        if not ok or len(set(piece)) < 4 or len(set(piece)) != len(piece):
            raise CrmgraspError(f"mesh piece {i} must be 4 or more distinct corner indices")
        if min(piece) < 0 or max(piece) >= corners:
            raise CrmgraspError(f"mesh piece {i} refers to a corner outside 0..{corners - 1}")
        out.append(tuple(piece))
    return tuple(out)


@dataclass(frozen=True)
class TriangleMesh:
    """A closed, manifold, outward-oriented triangle mesh (metres)."""

    vertices: tuple[tuple[float, float, float], ...]
    faces: tuple[tuple[int, int, int], ...]
    pieces: tuple[tuple[int, ...], ...] = ()
    """Optional: convex pieces, each a tuple of corner indices, whose convex hulls together
    make up the solid (for simulators that collide convex shapes only, as MuJoCo does); not
    part of the model's rules, which use the triangles. [`open_cup`][] gives its own."""
    _v: F64 = field(init=False, repr=False, compare=False)
    _f: NDArray[np.int64] = field(init=False, repr=False, compare=False)
    _n: F64 = field(init=False, repr=False, compare=False)
    _centre: F64 = field(init=False, repr=False, compare=False)
    volume: float = field(init=False, repr=False, compare=False)
    """The enclosed volume, m^3."""

    def __post_init__(self) -> None:
        v = np.asarray(self.vertices, dtype=np.float64)
        if v.ndim != 2 or v.shape[1] != 3 or len(v) < 4 or not np.isfinite(v).all():
            raise CrmgraspError(f"a mesh needs 4 or more finite corners (x, y, z), got shape {v.shape}")
        check_reach(v, "a mesh's corner")
        try:
            f = np.asarray(self.faces, dtype=np.int64)
        except (TypeError, ValueError):
            raise CrmgraspError("mesh faces must be triples of corner indices") from None
        if f.ndim != 2 or f.shape[1] != 3 or len(f) < 4:
            raise CrmgraspError(f"a mesh needs 4 or more triangles (i, j, k), got shape {f.shape}")
        if f.min() < 0 or f.max() >= len(v):
            raise CrmgraspError(f"a mesh face refers to a corner outside 0..{len(v) - 1}")
        a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
        normals = _cross_rows(b - a, c - a)
        area2 = np.linalg.norm(normals, axis=1)
        if (area2 <= 1e-12).any():
            raise CrmgraspError(f"mesh triangle {int(np.argmax(area2 <= 1e-12))} is degenerate (zero area)")
        faces = tuple(map(tuple, f.tolist()))
        _check_closed(faces)
        object.__setattr__(self, "pieces", _checked_pieces(self.pieces, len(v)))
        signed = np.einsum("ij,ij->i", a, _cross_rows(b, c))  # six times each tetrahedron's volume
        volume = float(signed.sum()) / 6.0
        if volume <= 0.0:
            raise CrmgraspError(
                f"the mesh's faces point inward (enclosed volume {volume:.3g} m^3): list each triangle's corners "
                "counter-clockwise seen from outside"
            )
        object.__setattr__(self, "vertices", tuple(map(tuple, v.tolist())))
        object.__setattr__(self, "faces", faces)
        object.__setattr__(self, "_v", v)
        object.__setattr__(self, "_f", f)
        object.__setattr__(self, "_n", normals / area2[:, None])
        object.__setattr__(self, "_centre", (signed[:, None] * (a + b + c)).sum(axis=0) / (4.0 * signed.sum()))
        object.__setattr__(self, "volume", volume)

    @property
    def corner_array(self) -> F64:
        """The corners, ``(n, 3)`` (metres; a copy)."""
        return self._v.copy()

    @property
    def face_array(self) -> NDArray[np.int64]:
        """The triangles' corner indices, ``(m, 3)`` (a copy)."""
        return self._f.copy()

    @property
    def unit_normals(self) -> F64:
        """The triangles' unit outward normals, ``(m, 3)`` (a copy)."""
        return self._n.copy()

    # ---------------------------------------------------------------- queries
    def _triangle(self, k: int) -> tuple[F64, F64, F64]:
        i, j, m = self.faces[k]
        return self._v[i], self._v[j], self._v[m]

    def _hit(self, k: int, o: F64, d: F64) -> float | None:
        """Where ``o + t d`` crosses triangle ``k`` (Moller-Trumbore), or None."""
        a, b, c = self._triangle(k)
        e1, e2 = b - a, c - a
        pv = cross(d, e2)
        det = dot(e1, pv)
        if det == 0.0:
            return None
        inv = 1.0 / det
        tv = o - a
        u = dot(tv, pv) * inv
        if u < 0.0 or u > 1.0:
            return None
        qv = cross(tv, e1)
        w = dot(d, qv) * inv
        if w < 0.0 or u + w > 1.0:
            return None
        return dot(e2, qv) * inv

    def distance(self, p: ArrayLike) -> float:
        """The distance from ``p`` to the surface (metres)."""
        x = np.asarray(p, dtype=np.float64)
        return min(norm(x - _closest_on_triangle(x, *self._triangle(k))) for k in range(len(self.faces)))

    def contains(self, p: ArrayLike) -> bool:
        """Strictly inside: an odd number of crossings of a ray from ``p``, and more than
        [`SURFACE`][] from the surface."""
        x = np.asarray(p, dtype=np.float64)
        return self._odd(x) and self.distance(x) > SURFACE

    def _odd(self, x: F64) -> bool:
        """An odd number of triangles crossed by the inside test's ray from ``x``."""
        hits = (self._hit(k, x, PARITY_RAY) for k in range(len(self.faces)))
        return sum(1 for t in hits if t is not None and t > 0.0) % 2 == 1

    def gap(self, p: ArrayLike) -> float:
        """The distance to the surface, negative inside (metres)."""
        x = np.asarray(p, dtype=np.float64)
        d = self.distance(x)
        return -d if self._odd(x) and d > SURFACE else d

    def ray_entry(self, origin: ArrayLike, direction: ArrayLike, u_max: float) -> tuple[F64, F64] | None:
        """Where ``origin + u direction`` (``0 <= u <= u_max``, within [`SURFACE`][]) first
        crosses a triangle it enters (outward normal against the ray), with the inward normal;
        among entries within [`TIE`][] of the nearest, the lowest triangle index."""
        o, d = np.asarray(origin, dtype=np.float64), np.asarray(direction, dtype=np.float64)
        best_t, best = math.inf, -1
        for k in range(len(self.faces)):
            if dot(self._n[k], d) >= 0.0:
                continue
            t = self._hit(k, o, d)
            if t is None or t < -SURFACE or t > u_max + SURFACE:
                continue
            if t < best_t - TIE:
                best_t, best = t, k
        if best < 0:
            return None
        return o + best_t * d, -self._n[best]

    @property
    def centre(self) -> F64:
        """The centre of volume (inside for the usual shapes; the spatial starts cast rays
        toward it): the tetrahedra from the origin to each triangle, their centres weighted by
        their signed volumes (computed once, on construction; a copy)."""
        return self._centre.copy()

    def support(self, d: ArrayLike) -> float:
        """``min_x d . x`` over the solid (attained at a corner)."""
        return float(np.min(self._v @ np.asarray(d, dtype=np.float64)))

    def moved(self, rotation: ArrayLike, translation: ArrayLike) -> TriangleMesh:
        """The mesh after ``x -> R x + t``."""
        r, t = _rotation(rotation), np.asarray(translation, dtype=np.float64)
        return TriangleMesh(tuple(map(tuple, (self._v @ r.T + t).tolist())), self.faces, self.pieces)

    @classmethod
    def from_arrays(cls, vertices: ArrayLike, faces: ArrayLike) -> TriangleMesh:
        """A mesh from a ``(n, 3)`` corner array and an ``(m, 3)`` index array."""
        return cls(
            tuple(map(tuple, np.asarray(vertices, dtype=float).tolist())), tuple(map(tuple, np.asarray(faces).tolist()))
        )

    def describe(self) -> dict[str, Any]:
        """Corners and triangles (and convex pieces, if any) as plain data."""
        out: dict[str, Any] = {
            "kind": "mesh",
            "vertices": [list(v) for v in self.vertices],
            "faces": [list(f) for f in self.faces],
        }
        if self.pieces:
            out["pieces"] = [list(p) for p in self.pieces]
        return out


def open_cup(
    radius: float,
    height: float,
    wall: float = 0.005,
    segments: int = 24,
    rotation: ArrayLike | None = None,
    translation: ArrayLike = (0.0, 0.0, 0.0),
) -> TriangleMesh:
    """An open cup standing on the table: a cylinder of outer ``radius`` and ``height``
    (metres) with a ``wall`` thick side and bottom and no top, its circles as regular
    ``segments``-gons. Closed as a solid (outer wall, rim, inner wall, inner bottom, outer
    bottom), so a line through the opening enters the inner wall or the inner bottom. With a
    ``rotation``, the cup posed by ``x -> R x + t`` (``t`` the ``translation``): the mesh
    ``open_cup(...).moved(R, t)`` gives, built once."""
    if not (isinstance(segments, int) and not isinstance(segments, bool) and 8 <= segments <= 256):
        raise CrmgraspError(f"segments must be an integer in [8, 256], got {segments!r}")
    for name, value in (("radius", radius), ("height", height), ("wall", wall)):
        if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
            raise CrmgraspError(f"cup {name} must be a finite number > 0, got {value!r}")
    if wall >= radius or wall >= height:
        raise CrmgraspError(f"cup wall {wall:g} m must be thinner than the radius {radius:g} and the height {height:g}")
    n, inner = segments, radius - wall
    ang = [2.0 * math.pi * k / n for k in range(n)]
    rings = [(radius, 0.0), (radius, height), (inner, height), (inner, wall)]  # outer bottom .. inner bottom
    v: list[Any] = [(r * math.cos(a), r * math.sin(a), z) for r, z in rings for a in ang]
    v += [(0.0, 0.0, 0.0), (0.0, 0.0, wall)]  # the centres of the outer and the inner bottom
    if rotation is not None:
        rot, t = _rotation(rotation), np.asarray(translation, dtype=np.float64)
        v = (np.asarray(v, dtype=np.float64) @ rot.T + t).tolist()  # as `TriangleMesh.moved` poses it
    return TriangleMesh(tuple(map(tuple, v)), *_cup_topology(n))


@functools.lru_cache(maxsize=16)
def _cup_topology(n: int) -> tuple[tuple[tuple[int, int, int], ...], tuple[tuple[int, ...], ...]]:
    """The faces and convex pieces of an open cup of ``n``-gon circles (its corners: the outer
    bottom, outer top, inner top and inner bottom rings, then the two bottom centres)."""
    faces: list[tuple[int, int, int]] = []
    for ring in range(3):  # outer wall, rim, inner wall: quads between consecutive rings
        lo, hi = ring * n, (ring + 1) * n
        for k in range(n):
            j = (k + 1) % n
            faces += [(lo + k, lo + j, hi + j), (lo + k, hi + j, hi + k)]
    out_c, in_c = 4 * n, 4 * n + 1
    for k in range(n):
        j = (k + 1) % n
        faces.append((out_c, j, k))  # outer bottom, facing down
        faces.append((in_c, 3 * n + k, 3 * n + j))  # inner bottom, facing up into the cup
    # convex pieces: the bottom (the outer bottom ring and the inner bottom ring), and one
    # block of the wall per side, from the outer bottom edge to the rim and the inner bottom
    # edge; in a section (r, z) the bottom is the trapezoid (0, 0), (R, 0), (R - w, w), (0, w)
    # and a block the quadrilateral (R, 0), (R, H), (R - w, H), (R - w, w): their union is the
    # section of the cup (tests/test_mesh.py checks it by sampling)
    bottom = (*range(n), *range(3 * n, 4 * n))
    blocks = [tuple(ring * n + i for ring in range(4) for i in (k, (k + 1) % n)) for k in range(n)]
    return tuple(faces), (bottom, *blocks)

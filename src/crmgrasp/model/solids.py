"""Spatial solids: convex polyhedra and closed cylinders (docs/model-3d.md section 1).

Each solid answers the three questions the spatial CRM transition asks: is a point
strictly inside (`contains`), where does a ray first enter and with which inward
normal (`ray_entry`), and, for placing and drawing it, its centre, its support
``min_x d . x`` (`support`) and its pose after a rigid motion (`moved`).
[`surface_point`][] is the radial projection of a direction onto the surface, the
one way the spatial starts put a contact on any solid.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from crmgrasp._validation import CrmgraspError, float_array, positive
from crmgrasp.model.shape import EPS, check_reach

__all__ = [
    "TIE",
    "SURFACE",
    "ConvexPolyhedron",
    "box3d",
    "Cylinder",
    "Solid",
    "rotation_z",
    "surface_point",
    "cross",
    "dot",
    "norm",
]

F64 = NDArray[np.float64]
SURFACE = EPS
"""Metres: a point within this of the surface is on it, not inside (the planar model's
[`EPS`][crmgrasp.model.shape.EPS])."""

TIE = 1e-12
"""Metres along a ray: surfaces it enters within this of each other are entered together
(an edge or a vertex); [`ConvexPolyhedron.ray_entry`][] and [`Cylinder.ray_entry`][]
then choose by a stated rule."""


def _rotation(rotation: ArrayLike) -> F64:
    r = np.asarray(rotation, dtype=np.float64)
    if r.shape != (3, 3) or not np.isfinite(r).all() or np.abs(r @ r.T - np.eye(3)).max() > 1e-9:
        raise CrmgraspError("a rotation must be a finite orthonormal 3 x 3 matrix")
    if dot(r[0], cross(r[1], r[2])) < 0.0:  # the determinant
        raise CrmgraspError("a rotation must have determinant +1 (a reflection turns faces inside out)")
    return r


def dot(u: Any, v: Any) -> float:
    """``u . v`` of two 3-vectors, written out in this order (the compiled kernel repeats it,
    so the two agree bit for bit)."""
    return float(u[0] * v[0] + u[1] * v[1] + u[2] * v[2])


def norm(u: Any) -> float:
    """``|u| = sqrt(u . u)``."""
    return math.sqrt(dot(u, u))


def cross(u: Any, v: Any) -> F64:
    """``u x v`` of two 3-vectors, written out (``np.cross`` costs ~10x more on one pair)."""
    a0, a1, a2 = u
    b0, b1, b2 = v
    return np.array([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0])


def rotation_z(angle: float) -> F64:
    """The rotation by ``angle`` (radians) about ``z``."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _unit(v: ArrayLike, name: str) -> F64:
    u = float_array(v, name)
    length = math.sqrt(u.dot(u)) if u.shape == (3,) else 0.0  # what np.linalg.norm computes
    if not (math.isfinite(length) and length > 0.0 and np.isfinite(u).all()):
        raise CrmgraspError(f"{name} must be a finite non-zero 3-vector, got {v!r}")
    return u / length


Plane = tuple[float, float, float, float]


def _unit_planes(rows: F64) -> tuple[Plane, ...]:
    """The planes ``rows`` (``(m, 4)``: ``a_x, a_y, a_z, b``) checked (four or more, finite,
    no zero normal) and scaled to unit normals, as tuples."""
    if rows.ndim != 2 or rows.shape[1] != 4 or len(rows) < 4:
        raise CrmgraspError(f"a convex polyhedron needs 4 or more finite planes (a_x, a_y, a_z, b), got {rows.shape}")
    return _scaled(rows.tolist())


def _scaled(rows: Iterable[Sequence[float]]) -> tuple[Plane, ...]:
    """Each plane ``(a, b)`` divided by ``|a| = sqrt(a_x^2 + a_y^2 + a_z^2)`` (summed in that
    order, as numpy sums a row of three), refused if not finite or ``a = 0``."""
    out = []
    for a0, a1, a2, b in rows:
        length = math.sqrt(a0 * a0 + a1 * a1 + a2 * a2)
        if not math.isfinite(length + b):  # a NaN or an infinity among the four
            raise CrmgraspError("a convex polyhedron needs 4 or more finite planes (a_x, a_y, a_z, b)")
        if length == 0.0:
            raise CrmgraspError("a face normal of the polyhedron is zero")
        out.append((a0 / length, a1 / length, a2 / length, b / length))
    return tuple(out)


@dataclass(frozen=True)
class ConvexPolyhedron:
    """``{x : a_k . x <= b_k}`` for unit outward normals ``a_k`` (rows of ``planes``:
    ``(a_x, a_y, a_z, b)``); bounded and with an interior (checked on construction by
    the caller's vertices being inside, see [`box3d`][])."""

    planes: tuple[Plane, ...]

    def __post_init__(self) -> None:
        object.__setattr__(self, "planes", _unit_planes(float_array(self.planes, "a polyhedron's planes")))
        check_reach([b for *_, b in self.planes], "a polyhedron's face (its distance from the origin)")

    def contains(self, p: ArrayLike) -> bool:
        """Strictly inside: more than [`SURFACE`][] inside every face."""
        x = np.asarray(p, dtype=np.float64)
        return all(a0 * x[0] + a1 * x[1] + a2 * x[2] - b < -SURFACE for a0, a1, a2, b in self.planes)

    def ray_entry(self, origin: ArrayLike, direction: ArrayLike, u_max: float) -> tuple[F64, F64] | None:
        """Where ``origin + u direction`` (``0 <= u <= u_max``) first enters the solid,
        with the inward normal there; ``None`` if it does not. Among faces entered at
        the same ``u`` (an edge or a vertex, within 1e-12), the lowest index wins."""
        o, d = np.asarray(origin, dtype=np.float64), np.asarray(direction, dtype=np.float64)
        t_in, t_out, face = -math.inf, math.inf, -1
        for k, (a0, a1, a2, b) in enumerate(self.planes):
            ad = a0 * d[0] + a1 * d[1] + a2 * d[2]
            gap = b - (a0 * o[0] + a1 * o[1] + a2 * o[2])
            if ad == 0.0:
                if gap < -SURFACE:
                    return None
                continue
            t = gap / ad
            if ad < 0.0:
                if t > t_in + TIE:
                    t_in, face = t, k
            else:
                t_out = min(t_out, t)
        if face < 0 or t_in > t_out + SURFACE or t_in < -SURFACE or t_in > u_max + SURFACE:
            return None
        a = np.array(self.planes[face][:3])
        return o + t_in * d, -a

    @cached_property
    def vertices(self) -> F64:
        """The corners, ``(m, 3)``: every point where three faces meet that lies on or
        inside all the others (found once, from all triples of faces)."""
        rows = np.array(self.planes)
        found: list[F64] = []
        for i, j, k in itertools.combinations(range(len(rows)), 3):
            a = rows[[i, j, k], :3]
            if abs(np.linalg.det(a)) < 1e-12:
                continue
            x = np.linalg.solve(a, rows[[i, j, k], 3])
            if np.all(rows[:, :3] @ x - rows[:, 3] <= 1e-9) and not any(np.allclose(x, v, atol=1e-9) for v in found):
                found.append(x)
        if len(found) < 4:
            raise CrmgraspError("the polyhedron's faces bound no solid (fewer than 4 corners)")
        return np.array(found)

    def gap(self, p: ArrayLike) -> float:
        """``max_k (a_k . p - b_k)``: 0 on the surface, negative inside, positive outside
        (metres; the distance to the surface on and near a face)."""
        x = np.asarray(p, dtype=np.float64)
        return float(np.max(np.array(self.planes)[:, :3] @ x - np.array(self.planes)[:, 3]))

    @property
    def centre(self) -> F64:
        """The mean of the corners (inside: the solid is convex)."""
        corners = self.vertices
        return np.add.reduce(corners, axis=0) / len(corners)  # what .mean(axis=0) computes, without its overhead

    def support(self, d: ArrayLike) -> float:
        """``min_x d . x`` over the solid (metres for a unit ``d``)."""
        return float(np.min(self.vertices @ np.asarray(d, dtype=np.float64)))

    def moved(self, rotation: ArrayLike, translation: ArrayLike) -> ConvexPolyhedron:
        """The solid after ``x -> R x + t``: faces ``(R a, b + (R a) . t)``."""
        return self._rigid(_rotation(rotation), np.asarray(translation, dtype=np.float64))

    def yawed(self, angle: float, dx: float, dy: float) -> ConvexPolyhedron:
        """`moved` by the rotation of ``angle`` (radians) about ``z`` and the translation
        ``(dx, dy, 0)`` (metres), without checking the rotation it builds itself."""
        return self._rigid(rotation_z(angle), np.array([dx, dy, 0.0]))

    def _rigid(self, r: F64, t: F64) -> ConvexPolyhedron:
        """Faces ``(R a, b + (R a) . t)``, scaled to unit normals; the dot product of three
        written out, summed from ``0.0`` and in order (the sign of a zero included; tested).
        ``R a`` is numpy's product, whose last bit may depend on the BLAS kernel the machine
        picks (docs/development.md)."""
        normals = (np.array(self.planes)[:, :3] @ r.T).tolist()
        t0, t1, t2 = t.tolist()
        offsets = [f[3] for f in self.planes]
        rows = [(n0, n1, n2, b + (((0.0 + n0 * t0) + n1 * t1) + n2 * t2)) for (n0, n1, n2), b in zip(normals, offsets)]
        out = object.__new__(ConvexPolyhedron)
        object.__setattr__(out, "planes", _scaled(rows))
        if "vertices" in self.__dict__:  # corners already known: move them too (cheaper than solving again)
            out.__dict__["vertices"] = self.vertices @ r.T + t
        return out


def box3d(lo: ArrayLike, hi: ArrayLike) -> ConvexPolyhedron:
    """The axis-aligned box ``[lo, hi]`` (faces in the order -x, +x, -y, +y, -z, +z)."""
    lo_, hi_ = float_array(lo, "a box's lo corner"), float_array(hi, "a box's hi corner")
    if lo_.shape != (3,) or hi_.shape != (3,):
        raise CrmgraspError(f"a box needs finite lo < hi in every coordinate, got {lo!r} and {hi!r}")
    (x0, y0, z0), (x1, y1, z1) = lo_.tolist(), hi_.tolist()
    sides = (x1 - x0, y1 - y0, z1 - z0)
    if not all(d > 0.0 and math.isfinite(d) for d in sides):  # NaN fails the first test
        raise CrmgraspError(f"a box needs finite lo < hi in every coordinate, got {lo!r} and {hi!r}")
    check_reach((x0, y0, z0, x1, y1, z1), "a box's corner")
    box = object.__new__(ConvexPolyhedron)  # the planes are unit already: the constructor would divide by 1.0
    planes = (
        (-1.0, 0.0, 0.0, -x0),
        (1.0, 0.0, 0.0, x1),
        (0.0, -1.0, 0.0, -y0),
        (0.0, 1.0, 0.0, y1),
        (0.0, 0.0, -1.0, -z0),
        (0.0, 0.0, 1.0, z1),
    )
    object.__setattr__(box, "planes", planes)
    box.__dict__["vertices"] = np.array([[x, y, z] for x in (x0, x1) for y in (y0, y1) for z in (z0, z1)])
    return box


@dataclass(frozen=True)
class Cylinder:
    """A closed solid cylinder: base centre ``origin``, unit ``axis``, ``radius`` and
    ``height`` (metres). It is convex: the intersection of an infinite cylinder and the
    slab between its two caps, so a line enters it where it has entered both."""

    origin: tuple[float, float, float]
    axis: tuple[float, float, float]
    radius: float
    height: float

    def __post_init__(self) -> None:
        o = float_array(self.origin, "cylinder origin")
        if o.shape != (3,) or not np.all(np.isfinite(o)):
            raise CrmgraspError(f"cylinder origin must be a finite 3-vector, got {self.origin!r}")
        object.__setattr__(self, "origin", tuple(o.tolist()))
        object.__setattr__(self, "axis", tuple(_unit(self.axis, "cylinder axis").tolist()))
        object.__setattr__(self, "radius", positive(self.radius, "cylinder radius"))
        object.__setattr__(self, "height", positive(self.height, "cylinder height"))
        check_reach((*self.origin, self.radius, self.height), "a cylinder's origin, radius or height")

    def _local(self, p: F64) -> tuple[float, F64]:
        """``(axial coordinate, radial vector)`` of ``p``."""
        e = np.array(self.axis)
        rel = p - np.array(self.origin)
        s = dot(rel, e)
        return s, rel - s * e

    def contains(self, p: ArrayLike) -> bool:
        """Strictly inside: more than [`SURFACE`][] inside the side and both caps."""
        s, radial = self._local(np.asarray(p, dtype=np.float64))
        return SURFACE < s < self.height - SURFACE and norm(radial) < self.radius - SURFACE

    def ray_entry(self, origin: ArrayLike, direction: ArrayLike, u_max: float) -> tuple[F64, F64] | None:
        """First entry of ``origin + u direction``, ``0 <= u <= u_max``, with the inward
        normal: a cap's (``+-axis``) or the side's (toward the axis); where both are entered
        at the same ``u`` (within 1e-12), the side."""
        o, d = np.asarray(origin, dtype=np.float64), np.asarray(direction, dtype=np.float64)
        e = np.array(self.axis)
        s0, r0 = self._local(o)
        sd = dot(d, e)
        rd = d - sd * e
        # the slab 0 <= s <= H
        if sd == 0.0:
            if not 0.0 <= s0 <= self.height:
                return None
            slab_in, slab_out, cap = -math.inf, math.inf, None
        else:
            t_a, t_b = (0.0 - s0) / sd, (self.height - s0) / sd
            slab_in, slab_out = min(t_a, t_b), max(t_a, t_b)
            cap = e if sd > 0 else -e  # the cap entered first: the bottom (inward +e) going up
        # the infinite cylinder |r0 + t rd| <= R
        qa, qb, qc = dot(rd, rd), dot(r0, rd), dot(r0, r0) - self.radius * self.radius
        if qa == 0.0:
            if qc > 0.0:
                return None
            side_in, side_out = -math.inf, math.inf
        else:
            disc = qb * qb - qa * qc
            if disc < 0.0:
                return None
            root = math.sqrt(disc)
            side_in, side_out = (-qb - root) / qa, (-qb + root) / qa
        t_in = max(side_in, slab_in)
        if t_in > min(side_out, slab_out) + SURFACE or t_in < -SURFACE or t_in > u_max + SURFACE:
            return None
        point = o + t_in * d
        if side_in >= slab_in - TIE or cap is None:
            _, radial = self._local(point)
            return point, -radial / norm(radial)
        return point, cap

    def gap(self, p: ArrayLike) -> float:
        """``max(-s, s - H, |radial| - R)``: 0 on the surface, negative inside, positive
        outside (metres; the distance to the surface on and near it)."""
        s, radial = self._local(np.asarray(p, dtype=np.float64))
        return max(-s, s - self.height, norm(radial) - self.radius)

    @property
    def centre(self) -> F64:
        """The middle of the axis."""
        return np.array(self.origin) + 0.5 * self.height * np.array(self.axis)

    def support(self, d: ArrayLike) -> float:
        """``min_x d . x``: the lower of the two rims, ``c . d - R sqrt(1 - (e . d)^2)``."""
        dv = np.asarray(d, dtype=np.float64)
        e, o = np.array(self.axis), np.array(self.origin)
        ed = float(e @ dv)
        rim = self.radius * math.sqrt(max(0.0, float(dv @ dv) - ed * ed))
        return min(float(o @ dv), float((o + self.height * e) @ dv)) - rim

    def moved(self, rotation: ArrayLike, translation: ArrayLike) -> Cylinder:
        """The cylinder after ``x -> R x + t``."""
        return self._rigid(_rotation(rotation), np.asarray(translation, dtype=np.float64))

    def yawed(self, angle: float, dx: float, dy: float) -> Cylinder:
        """`moved` by the rotation of ``angle`` (radians) about ``z`` and the translation
        ``(dx, dy, 0)`` (metres), without checking the rotation it builds itself."""
        return self._rigid(rotation_z(angle), np.array([dx, dy, 0.0]))

    def _rigid(self, r: F64, t: F64) -> Cylinder:
        return Cylinder(tuple(r @ np.array(self.origin) + t), tuple(r @ np.array(self.axis)), self.radius, self.height)  # type: ignore[arg-type]


Solid = ConvexPolyhedron | Cylinder
"""The objects the spatial model takes (both convex)."""


def surface_point(solid: Any, direction: ArrayLike) -> tuple[F64, F64] | None:
    """Where the line from the solid's centre along ``direction`` last leaves it, with the
    inward normal there: the radial projection of a direction onto the surface, found as
    the first entry of the reverse ray from outside. A convex solid contains its centre, so
    it always exists; on a non-convex mesh whose centre is outside, the ray may miss
    (``None``: the starts then draw again)."""
    d = np.asarray(direction, dtype=np.float64)
    d = d / norm(d)
    c = solid.centre
    far = 1.0 + float(np.max(np.abs(c)))  # beyond the solid: every solid here is < 1 m from its centre
    return solid.ray_entry(c + far * d, -d, 2.0 * far)  # type: ignore[no-any-return]

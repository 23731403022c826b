"""The spatial model's objects, hand and CRM transition (docs/model-3d.md sections 1-4).

Implemented so far: convex polyhedra (:class:`ConvexPolyhedron`, :func:`box3d`), closed
cylinders (:class:`Cylinder`: the cup without its opening), the
two-contact hand (:class:`Hand3D`: aperture, palm depth, back-off, the vertical and
forward axes ``h`` and ``g``), feasibility (:func:`feasible3d`), the CRM transition
(:func:`execute_crm3d`, offsets ``r = (r_1, r_2)`` in the tangent frame of
:func:`tangent_frame`), the observation (:func:`observe3d`: ``rho``, ``|m_a|``,
``|m_b|``) and sensing noise (:func:`sense3d`). Written on plain floats and small numpy vectors, readably; it is the
definition any faster path will be tested against. Open cups, meshes, tasks and
learning in 3-D are not built yet.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from crmgrasp._validation import CrmgraspError, non_negative, positive
from crmgrasp.model.hand import Error
from crmgrasp.model.shape import EPS

__all__ = [
    "Contact3D",
    "Config3D",
    "ConvexPolyhedron",
    "box3d",
    "Cylinder",
    "Solid",
    "Hand3D",
    "CRM3D",
    "Outcome3D",
    "tangent_frame",
    "feasible3d",
    "execute_crm3d",
    "observe3d",
    "sense3d",
]

F64 = NDArray[np.float64]
SURFACE = EPS
"""Metres: a point within this of the surface is on it, not inside (the planar model's
:data:`~crmgrasp.model.shape.EPS`)."""


class Contact3D(NamedTuple):
    """A contact: position ``x`` (metres) and inward unit normal ``n`` (3-tuples)."""

    x: tuple[float, float, float]
    n: tuple[float, float, float]


class Config3D(NamedTuple):
    """The two contacts ``a`` and ``b``."""

    a: Contact3D
    b: Contact3D


def _unit(v: ArrayLike, name: str) -> F64:
    u = np.asarray(v, dtype=np.float64)
    if u.shape != (3,) or not np.all(np.isfinite(u)) or np.linalg.norm(u) == 0.0:
        raise CrmgraspError(f"{name} must be a finite non-zero 3-vector, got {v!r}")
    return u / np.linalg.norm(u)


@dataclass(frozen=True, eq=False)
class ConvexPolyhedron:
    """``{x : a_k . x <= b_k}`` for unit outward normals ``a_k`` (rows of ``planes``:
    ``(a_x, a_y, a_z, b)``); bounded and with an interior (checked on construction by
    the caller's vertices being inside, see :func:`box3d`)."""

    planes: tuple[tuple[float, float, float, float], ...]

    def __post_init__(self) -> None:
        rows = np.asarray(self.planes, dtype=np.float64)
        if rows.ndim != 2 or rows.shape[1] != 4 or len(rows) < 4 or not np.all(np.isfinite(rows)):
            raise CrmgraspError(
                f"a convex polyhedron needs 4 or more finite planes (a_x, a_y, a_z, b), got {rows.shape}"
            )
        norms = np.linalg.norm(rows[:, :3], axis=1)
        if np.any(norms == 0.0):
            raise CrmgraspError("a face normal of the polyhedron is zero")
        rows = rows / norms[:, None]
        object.__setattr__(self, "planes", tuple(tuple(float(v) for v in r) for r in rows))

    def contains(self, p: ArrayLike) -> bool:
        """Strictly inside: more than :data:`SURFACE` inside every face."""
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
                if t > t_in + 1e-12:
                    t_in, face = t, k
            else:
                t_out = min(t_out, t)
        if face < 0 or t_in > t_out + SURFACE or t_in < -SURFACE or t_in > u_max + SURFACE:
            return None
        a = np.array(self.planes[face][:3])
        return o + t_in * d, -a


def box3d(lo: ArrayLike, hi: ArrayLike) -> ConvexPolyhedron:
    """The axis-aligned box ``[lo, hi]`` (faces in the order -x, +x, -y, +y, -z, +z)."""
    lo_, hi_ = np.asarray(lo, dtype=np.float64), np.asarray(hi, dtype=np.float64)
    if lo_.shape != (3,) or hi_.shape != (3,) or not np.all(hi_ > lo_):
        raise CrmgraspError(f"a box needs lo < hi in every coordinate, got {lo!r} and {hi!r}")
    return ConvexPolyhedron(
        (
            (-1.0, 0.0, 0.0, -lo_[0]),
            (1.0, 0.0, 0.0, hi_[0]),
            (0.0, -1.0, 0.0, -lo_[1]),
            (0.0, 1.0, 0.0, hi_[1]),
            (0.0, 0.0, -1.0, -lo_[2]),
            (0.0, 0.0, 1.0, hi_[2]),
        )
    )


@dataclass(frozen=True, eq=False)
class Cylinder:
    """A closed solid cylinder: base centre ``origin``, unit ``axis``, ``radius`` and
    ``height`` (metres). It is convex: the intersection of an infinite cylinder and the
    slab between its two caps, so a line enters it where it has entered both."""

    origin: tuple[float, float, float]
    axis: tuple[float, float, float]
    radius: float
    height: float

    def __post_init__(self) -> None:
        o = np.asarray(self.origin, dtype=np.float64)
        if o.shape != (3,) or not np.all(np.isfinite(o)):
            raise CrmgraspError(f"cylinder origin must be a finite 3-vector, got {self.origin!r}")
        object.__setattr__(self, "origin", tuple(o.tolist()))
        object.__setattr__(self, "axis", tuple(_unit(self.axis, "cylinder axis").tolist()))
        object.__setattr__(self, "radius", positive(self.radius, "cylinder radius"))
        object.__setattr__(self, "height", positive(self.height, "cylinder height"))

    def _local(self, p: F64) -> tuple[float, F64]:
        """``(axial coordinate, radial vector)`` of ``p``."""
        e = np.array(self.axis)
        rel = p - np.array(self.origin)
        s = float(rel @ e)
        return s, rel - s * e

    def contains(self, p: ArrayLike) -> bool:
        """Strictly inside: more than :data:`SURFACE` inside the side and both caps."""
        s, radial = self._local(np.asarray(p, dtype=np.float64))
        return SURFACE < s < self.height - SURFACE and float(np.linalg.norm(radial)) < self.radius - SURFACE

    def ray_entry(self, origin: ArrayLike, direction: ArrayLike, u_max: float) -> tuple[F64, F64] | None:
        """First entry of ``origin + u direction``, ``0 <= u <= u_max``, with the inward
        normal: a cap's (``+-axis``) or the side's (toward the axis); where both are entered
        at the same ``u`` (within 1e-12), the side."""
        o, d = np.asarray(origin, dtype=np.float64), np.asarray(direction, dtype=np.float64)
        e = np.array(self.axis)
        s0, r0 = self._local(o)
        sd = float(d @ e)
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
        qa, qb, qc = float(rd @ rd), float(r0 @ rd), float(r0 @ r0) - self.radius**2
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
        if side_in >= slab_in - 1e-12 or cap is None:
            _, radial = self._local(point)
            return point, -radial / np.linalg.norm(radial)
        return point, cap


Solid = ConvexPolyhedron | Cylinder
"""The objects the spatial model takes (both convex)."""


@dataclass(frozen=True)
class Hand3D:
    """Aperture ``A``, palm depth, back-off, vertical axis ``h`` and forward axis ``g``
    (docs/model-3d.md section 2); ``r_max`` bounds ``|r|`` (default: the aperture)."""

    aperture: float
    palm_depth: float
    backoff: float = 0.01
    h: tuple[float, float, float] = (0.0, 0.0, 1.0)
    g: tuple[float, float, float] = (1.0, 0.0, 0.0)
    r_max: float | None = None
    min_separation: float = 0.0
    palm_normal_tol: float = 1e-9
    _h: F64 = field(init=False, repr=False, compare=False)
    _g: F64 = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "aperture", positive(self.aperture, "aperture"))
        object.__setattr__(self, "palm_depth", non_negative(self.palm_depth, "palm_depth"))
        object.__setattr__(self, "backoff", non_negative(self.backoff, "backoff"))
        h, g = _unit(self.h, "hand axis h"), _unit(self.g, "hand axis g")
        if abs(float(h @ g)) > 1e-9:
            raise CrmgraspError("the hand's axes h and g must be perpendicular")
        object.__setattr__(self, "_h", h)
        object.__setattr__(self, "_g", g)

    @property
    def reach(self) -> float:
        """The largest ``|r|``."""
        return self.aperture if self.r_max is None else self.r_max


class CRM3D(NamedTuple):
    """``(c, f, r)``: contact ``c`` moves onto the line along ``n_f`` through
    ``x_f + r_1 t_1 + r_2 t_2`` (section 3)."""

    c: str
    f: str
    r: tuple[float, float] = (0.0, 0.0)


class Outcome3D(NamedTuple):
    """The configuration after the CRM (unchanged on an error) and the error."""

    config: Config3D
    error: Error


def tangent_frame(n: ArrayLike, hand: Hand3D) -> tuple[F64, F64]:
    """``t_1 = n x h / |n x h|`` (``n x g`` if ``n`` is parallel to ``h``), ``t_2 = t_1 x n``."""
    nv = np.asarray(n, dtype=np.float64)
    t1 = np.cross(nv, hand._h)
    if np.linalg.norm(t1) < 1e-9:
        t1 = np.cross(nv, hand._g)
    t1 /= np.linalg.norm(t1)
    return t1, np.cross(t1, nv)


def _palm_axis(cfg: Config3D, hand: Hand3D) -> tuple[float, F64]:
    xa, xb = np.array(cfg.a.x), np.array(cfg.b.x)
    dist = float(np.linalg.norm(xb - xa))
    if dist == 0.0:
        return 0.0, np.full(3, np.nan)
    d = (xb - xa) / dist
    u = np.cross(d, hand._h)
    if np.linalg.norm(u) < 1e-9:
        u = np.cross(d, hand._g)
    return dist, u / np.linalg.norm(u)


def feasible3d(obj: Solid, hand: Hand3D, cfg: Config3D) -> Error:
    """Section 2: APERTURE beyond the aperture; PALM for colliding contacts, a surface
    facing the palm, or the palm point inside the object."""
    dist, u = _palm_axis(cfg, hand)
    if dist > hand.aperture:
        return Error.APERTURE
    if dist <= hand.min_separation:
        return Error.PALM
    if float(np.dot(cfg.a.n, u)) > hand.palm_normal_tol or float(np.dot(cfg.b.n, u)) > hand.palm_normal_tol:
        return Error.PALM
    palm = 0.5 * (np.array(cfg.a.x) + np.array(cfg.b.x)) + hand.palm_depth * u
    return Error.PALM if obj.contains(palm) else Error.NONE


def execute_crm3d(obj: Solid, hand: Hand3D, cfg: Config3D, crm: CRM3D, sensed: Config3D | None = None) -> Outcome3D:
    """The CRM transition of section 3 (the goal line from ``sensed``, default ``cfg``)."""
    if crm.c not in ("a", "b") or crm.f not in ("a", "b"):
        raise CrmgraspError(f"contact labels must be 'a' or 'b', got {crm.c!r} and {crm.f!r}")
    r1, r2 = (float(v) for v in crm.r)
    if not (math.isfinite(r1) and math.isfinite(r2)) or math.hypot(r1, r2) > hand.reach:
        raise CrmgraspError(f"CRM offset r = {crm.r!r} must be finite with |r| <= r_max = {hand.reach:g}")
    sensed = cfg if sensed is None else sensed
    still = cfg.a if crm.c == "b" else cfg.b
    frame = sensed.a if crm.f == "a" else sensed.b
    n_f = np.array(frame.n)
    t1, t2 = tangent_frame(n_f, hand)
    base = np.array(frame.x) + r1 * t1 + r2 * t2
    w = base - np.array(still.x)  # |w + t n_f|^2 = A^2, |n_f| = 1
    qb, qc = float(w @ n_f), float(w @ w) - hand.aperture**2
    disc = qb * qb - qc
    if disc < 0.0:
        return Outcome3D(cfg, Error.APERTURE)
    t_lo, t_hi = -qb - math.sqrt(disc), -qb + math.sqrt(disc)
    same = crm.c == crm.f
    t0, t1_ = (t_lo, t_hi) if same else (t_hi, t_lo)
    start = base + t0 * n_f
    if obj.contains(start):
        return Outcome3D(cfg, Error.APERTURE)
    entry = obj.ray_entry(start, n_f if same else -n_f, abs(t1_ - t0))
    if entry is None:
        return Outcome3D(cfg, Error.APERTURE)
    point, normal = entry
    moved = Contact3D(tuple(point.tolist()), tuple(normal.tolist()))  # type: ignore[arg-type]
    new = Config3D(cfg.a, moved) if crm.c == "b" else Config3D(moved, cfg.b)
    err = feasible3d(obj, hand, new)
    return Outcome3D(cfg, err) if err is not Error.NONE else Outcome3D(new, Error.NONE)


def observe3d(cfg: Config3D) -> tuple[float, float, float]:
    """``(rho, |m_a|, |m_b|)``: ``rho = |n_a + n_b|^2``, ``m_a = (x_b - x_a) x n_b``,
    ``m_b = (x_a - x_b) x n_a`` (section 4)."""
    xa, xb, na, nb = (np.array(v) for v in (cfg.a.x, cfg.b.x, cfg.a.n, cfg.b.n))
    s = na + nb
    return float(s @ s), float(np.linalg.norm(np.cross(xb - xa, nb))), float(np.linalg.norm(np.cross(xa - xb, na)))


def sense3d(cfg: Config3D, sigma_n: float, sigma_p: float, rng: np.random.Generator, hand: Hand3D) -> Config3D:
    """One noisy reading of ``cfg`` (docs/model-3d.md section 4): each contact's normal is
    rotated by an angle ``N(0, sigma_n)`` (radians) about the tangent axis
    ``cos(phi) t_1 + sin(phi) t_2`` with ``phi`` uniform in ``[0, 2 pi)``, and its position
    moved by ``N(0, sigma_p^2 I_3)`` (metres). Draws, per contact a then b: ``phi`` (one
    uniform), then four standard normals (angle, x, y, z). No draw when both sigmas are 0.
    ``sigma_n <= pi/4`` and ``sigma_p <= 0.1`` as in the plane."""
    if not (0.0 <= sigma_n <= math.pi / 4) or not (0.0 <= sigma_p <= 0.1):
        raise CrmgraspError(
            f"sensing noise must have 0 <= sigma_n <= pi/4 and 0 <= sigma_p <= 0.1, got {sigma_n}, {sigma_p}"
        )
    if sigma_n == 0.0 and sigma_p == 0.0:
        return cfg
    out = []
    for c in cfg:
        phi = 2.0 * math.pi * float(rng.random())
        angle, dx, dy, dz = (float(v) for v in rng.standard_normal(4))
        n = np.array(c.n)
        t1, t2 = tangent_frame(n, hand)
        k = math.cos(phi) * t1 + math.sin(phi) * t2
        theta = sigma_n * angle
        n2 = n * math.cos(theta) + np.cross(k, n) * math.sin(theta)
        x2 = np.array(c.x) + sigma_p * np.array([dx, dy, dz])
        out.append(Contact3D(tuple(x2.tolist()), tuple((n2 / np.linalg.norm(n2)).tolist())))  # type: ignore[arg-type]
    return Config3D(out[0], out[1])

"""The spatial model's objects, hand and CRM transition (docs/model-3d.md sections 1-4).

The two-contact hand ([`Hand3D`][]: aperture, palm depth, back-off, the vertical and
forward axes ``h`` and ``g``), the palm point ([`palm_point3d`][]), feasibility with
an optional table ([`feasible3d`][]), the CRM transition ([`execute_crm3d`][],
offsets ``r = (r_1, r_2)`` in the tangent frame of [`tangent_frame`][]), the
observation ([`observe3d`][]: ``rho``, ``|m_a|``, ``|m_b|``) and sensing noise
([`sense3d`][]), on any solid of [`crmgrasp.model.solids`][] or
`crmgrasp.model.mesh`. Written on plain floats and small numpy vectors, readably;
it is the definition the compiled spatial kernel is tested against.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from crmgrasp._validation import CrmgraspError, non_negative, positive
from crmgrasp.model.contacts import LABELS
from crmgrasp.model.hand import Error
from crmgrasp.model.solids import SURFACE, ConvexPolyhedron, Cylinder, Solid, _unit, box3d, cross, dot, norm

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
    "faces_palm3d",
    "Chord3D",
    "goal_chord3d",
    "table_lift",
    "palm_point3d",
    "execute_crm3d",
    "observe3d",
    "sense3d",
]

F64 = NDArray[np.float64]

PARALLEL = 1e-9
"""A cross product shorter than this means parallel vectors: the tangent frame and the palm
side then use the hand's forward axis ``g`` instead of ``h``."""


class Contact3D(NamedTuple):
    """A contact: position ``x`` (metres) and inward unit normal ``n`` (3-tuples)."""

    x: tuple[float, float, float]
    n: tuple[float, float, float]


class Config3D(NamedTuple):
    """The two contacts ``a`` and ``b``."""

    a: Contact3D
    b: Contact3D


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
    def labels(self) -> tuple[str, ...]:
        """The contacts' labels, ``('a', 'b')``."""
        return LABELS

    @property
    def reach(self) -> float:
        """The largest ``|r|``."""
        return self.aperture if self.r_max is None else self.r_max

    def check_crm(self, crm: object) -> CRM3D:
        """``crm`` if it is a [`CRM3D`][] with labels ``a``/``b`` and a finite offset of
        length at most [`reach`][]; else a one-line `CrmgraspError`."""
        if not isinstance(crm, CRM3D):
            raise CrmgraspError(f"expected a CRM3D, got {crm!r}")
        if crm.c not in ("a", "b") or crm.f not in ("a", "b"):
            raise CrmgraspError(f"contact labels must be 'a' or 'b', got {crm.c!r} and {crm.f!r}")
        r = np.asarray(crm.r, dtype=np.float64)
        if r.shape != (2,) or not np.all(np.isfinite(r)) or math.hypot(*r.tolist()) > self.reach:
            raise CrmgraspError(f"CRM offset r = {crm.r!r} must be a finite 2-vector, |r| <= r_max = {self.reach:g}")
        return crm


class CRM3D(NamedTuple):
    """``(c, f, r)``: contact ``c`` moves onto the line along ``n_f`` through
    ``x_f + r_1 t_1 + r_2 t_2`` (section 3)."""

    c: str
    f: str
    r: tuple[float, float] = (0.0, 0.0)

    def __str__(self) -> str:
        return f"({self.c},{self.f},({self.r[0]:g},{self.r[1]:g}))"


class Outcome3D(NamedTuple):
    """The configuration after the CRM (unchanged on an error) and the error."""

    config: Config3D
    error: Error


def tangent_frame(n: ArrayLike, hand: Hand3D) -> tuple[F64, F64]:
    """``t_1 = n x h / |n x h|`` (``n x g`` if ``n`` is parallel to ``h``), ``t_2 = t_1 x n``."""
    nv = np.asarray(n, dtype=np.float64)
    t1 = cross(nv, hand._h)
    if norm(t1) < PARALLEL:
        t1 = cross(nv, hand._g)
    t1 = t1 / norm(t1)
    return t1, cross(t1, nv)


def _palm_axis(cfg: Config3D, hand: Hand3D) -> tuple[float, F64]:
    xa, xb = np.array(cfg.a.x), np.array(cfg.b.x)
    dist = norm(xb - xa)
    if dist == 0.0:
        return 0.0, np.full(3, np.nan)
    d = (xb - xa) / dist
    u = cross(d, hand._h)
    if norm(u) < PARALLEL:
        u = cross(d, hand._g)
    return dist, u / norm(u)


def on_table(z: float, table: float | None) -> bool:
    """A height at or below the table plane (within [`SURFACE`][]): where no finger or
    palm can be (``table=None``: no table)."""
    return table is not None and z <= table + SURFACE


def faces_palm3d(cfg: Config3D, hand: Hand3D) -> bool:
    """True if a contact's surface faces the palm side: ``n . u > palm_normal_tol`` for
    ``n_a`` or ``n_b`` (the object would lie between palm and finger); False if the
    contacts coincide."""
    dist, u = _palm_axis(cfg, hand)
    return dist > 0.0 and _faces(cfg, hand, u)


def _faces(cfg: Config3D, hand: Hand3D, u: F64) -> bool:
    return dot(cfg.a.n, u) > hand.palm_normal_tol or dot(cfg.b.n, u) > hand.palm_normal_tol


def feasible3d(obj: Solid, hand: Hand3D, cfg: Config3D, table: float | None = None) -> Error:
    """Section 2: APERTURE beyond the aperture; PALM for colliding contacts, a surface
    facing the palm ([`faces_palm3d`][]), the palm point inside the object, or (with a
    table at height ``table``) a contact or the palm point on or below the table."""
    dist, u = _palm_axis(cfg, hand)
    if dist > hand.aperture:
        return Error.APERTURE
    if dist <= hand.min_separation or on_table(cfg.a.x[2], table) or on_table(cfg.b.x[2], table):
        return Error.PALM
    if _faces(cfg, hand, u):
        return Error.PALM
    palm = _palm_at(cfg, hand, u)
    return Error.PALM if obj.contains(palm) or on_table(float(palm[2]), table) else Error.NONE


def _palm_at(cfg: Config3D, hand: Hand3D, u: F64) -> F64:
    return 0.5 * (np.array(cfg.a.x) + np.array(cfg.b.x)) + hand.palm_depth * u


def palm_point3d(cfg: Config3D, hand: Hand3D) -> F64 | None:
    """Section 2: ``P = (x_a + x_b) / 2 + p u``, ``u`` the palm side; ``None`` when the
    contacts coincide."""
    dist, u = _palm_axis(cfg, hand)
    return None if dist == 0.0 else _palm_at(cfg, hand, u)


class Chord3D(NamedTuple):
    """Where a CRM's approach runs: from ``start`` along the unit vector ``ahead`` for
    ``length`` metres (the goal line's chord within the aperture of the stationary
    contact, walked toward it for an opposition, away for a slide)."""

    start: F64
    ahead: F64
    length: float


def goal_chord3d(hand: Hand3D, crm: CRM3D, frame: Contact3D, still: Contact3D) -> Chord3D | None:
    """Section 3: the goal line ``x_f + r_1 t_1 + r_2 t_2 + t n_f`` (``frame`` is contact
    ``f`` as sensed) and its chord ``|x(t) - x_still| <= A``; ``None`` (an aperture error)
    if the line misses that sphere."""
    r1, r2 = (float(v) for v in crm.r)
    n_f = np.array(frame.n)
    t1, t2 = tangent_frame(n_f, hand)
    base = np.array(frame.x) + r1 * t1 + r2 * t2
    w = base - np.array(still.x)  # |w + t n_f|^2 = A^2, |n_f| = 1
    qb, qc = dot(w, n_f), dot(w, w) - hand.aperture * hand.aperture
    disc = qb * qb - qc
    if disc < 0.0:
        return None
    t_lo, t_hi = -qb - math.sqrt(disc), -qb + math.sqrt(disc)
    same = crm.c == crm.f
    t0, t1_ = (t_lo, t_hi) if same else (t_hi, t_lo)
    return Chord3D(base + t0 * n_f, (n_f if same else -n_f), abs(t1_ - t0))


def table_lift(chord: Chord3D, table: float | None) -> float:
    """How far along the chord its start must move to be above the table: 0 if it already
    is (or there is no table), else the distance to ``table + 2 SURFACE`` (``inf`` if
    the chord does not rise)."""
    if table is None or not on_table(float(chord.start[2]), table):
        return 0.0
    rise = float(chord.ahead[2])
    return (table + 2.0 * SURFACE - float(chord.start[2])) / rise if rise > 0.0 else math.inf


def execute_crm3d(
    obj: Solid,
    hand: Hand3D,
    cfg: Config3D,
    crm: CRM3D,
    sensed: Config3D | None = None,
    table: float | None = None,
) -> Outcome3D:
    """The CRM transition of section 3 (the goal line from ``sensed``, default ``cfg``).

    With a table at height ``table``: a chord end on or below the table moves up the
    line to where it crosses the table plane (the finger approaches from the table's
    surface); if the line never rises above the table before the chord ends, or that
    point is inside the object, the CRM is a palm error (the hand would meet the table)."""
    hand.check_crm(crm)
    sensed = cfg if sensed is None else sensed
    still = cfg.a if crm.c == "b" else cfg.b
    chord = goal_chord3d(hand, crm, sensed.a if crm.f == "a" else sensed.b, still)
    if chord is None:
        return Outcome3D(cfg, Error.APERTURE)
    start, ahead, length = chord
    if obj.contains(start):
        return Outcome3D(cfg, Error.APERTURE)
    up = table_lift(chord, table)
    if up > 0.0:
        if up >= length or obj.contains(start + up * ahead):
            return Outcome3D(cfg, Error.PALM)
        start, length = start + up * ahead, length - up
    entry = obj.ray_entry(start, ahead, length)
    if entry is None:
        return Outcome3D(cfg, Error.APERTURE)
    point, normal = entry
    moved = Contact3D(tuple(point.tolist()), tuple(normal.tolist()))  # type: ignore[arg-type]
    new = Config3D(cfg.a, moved) if crm.c == "b" else Config3D(moved, cfg.b)
    err = feasible3d(obj, hand, new, table)
    return Outcome3D(cfg, err) if err is not Error.NONE else Outcome3D(new, Error.NONE)


def observe3d(cfg: Config3D) -> tuple[float, float, float]:
    """``(rho, |m_a|, |m_b|)``: ``rho = |n_a + n_b|^2``, ``m_a = (x_b - x_a) x n_b``,
    ``m_b = (x_a - x_b) x n_a`` (section 4)."""
    xa, xb, na, nb = (np.array(v) for v in (cfg.a.x, cfg.b.x, cfg.a.n, cfg.b.n))
    s = na + nb
    return dot(s, s), norm(cross(xb - xa, nb)), norm(cross(xa - xb, na))


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
        n2 = n * math.cos(theta) + cross(k, n) * math.sin(theta)
        x2 = np.array(c.x) + sigma_p * np.array([dx, dy, dz])
        out.append(Contact3D(tuple(x2.tolist()), tuple((n2 / np.linalg.norm(n2)).tolist())))  # type: ignore[arg-type]
    return Config3D(out[0], out[1])

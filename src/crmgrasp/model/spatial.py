"""The spatial model's objects, hand and CRM transition (docs/model-3d.md sections 1-4 and 9).

The hand of two or more contacts ([`Hand3D`][]: aperture, palm depth, back-off, the vertical
and forward axes ``h`` and ``g``), the palm point ([`palm_point3d`][]), feasibility with
an optional table ([`feasible3d`][]), the CRM transition ([`execute_crm3d`][],
offsets ``r = (r_1, r_2)`` in the tangent frame of [`tangent_frame`][]), the
observation ([`observe3d`][]: ``rho``, ``|m_a|``, ``|m_b|``, ...) and sensing noise
([`sense3d`][]), on any solid of [`crmgrasp.model.solids`][] or
`crmgrasp.model.mesh`. Written on plain floats and small numpy vectors, readably;
it is the definition the compiled spatial kernel is tested against.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from crmgrasp._validation import CrmgraspError, finite, non_negative, positive, shown
from crmgrasp.model.contacts import Labelled, label_index, labels_of
from crmgrasp.model.hand import Error
from crmgrasp.model.mesh import TriangleMesh
from crmgrasp.model.solids import SURFACE, ConvexPolyhedron, Cylinder, Solid, _unit, box3d, cross, dot, norm

__all__ = [
    "Contact3D",
    "Config3D",
    "Grip3D",
    "config3d",
    "check_contacts3d",
    "check_solid",
    "SOLIDS",
    "UNIT_TOL",
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


class Grip3D(Labelled[Contact3D]):
    """The contacts ``a, b, c, ...`` of a hand with three or more, in label order (indexed
    by position or label)."""

    __slots__ = ()


def config3d(contacts: Sequence[Contact3D]) -> Config3D | Grip3D:
    """The configuration of ``contacts`` in label order: a [`Config3D`][] for two, a
    [`Grip3D`][] for more (the one place that picks the type)."""
    if len(contacts) == 2:
        return Config3D(contacts[0], contacts[1])
    return Grip3D(*contacts)


Contacts3D = Config3D | Grip3D

SOLIDS = (ConvexPolyhedron, Cylinder, TriangleMesh)
"""The kinds of solid the spatial rules step."""


def check_solid(obj: object) -> Solid:
    """``obj`` if it is a solid the spatial rules step (a [`ConvexPolyhedron`][], a
    [`Cylinder`][] or a [`TriangleMesh`][crmgrasp.model.mesh.TriangleMesh]); a one-line error otherwise."""
    if not isinstance(obj, SOLIDS):
        raise CrmgraspError(f"a spatial object must be a ConvexPolyhedron, Cylinder or TriangleMesh, got {shown(obj)}")
    return obj  # type: ignore[return-value]


UNIT_TOL = 1e-6
"""How far a given contact normal's length may lie from 1 before [`check_contacts3d`][] refuses it."""


def check_contacts3d(config: object, name: str = "configuration", contacts: int | None = None) -> Contacts3D:
    """``config`` if it is a [`Config3D`][] (two contacts) or a [`Grip3D`][] (more; ``contacts``
    of them when given) of finite [`Contact3D`][]s with unit normals (within [`UNIT_TOL`][]),
    wherever they lie; else a one-line error naming ``name``."""
    count = len(config) if contacts is None and isinstance(config, (Config3D, Grip3D)) else contacts or 2
    kind = Config3D if count == 2 else Grip3D
    if not isinstance(config, kind) or len(config) != count or not all(isinstance(c, Contact3D) for c in config):
        raise CrmgraspError(f"{name} must be a {kind.__name__} of {count} Contact3D, got {shown(config, 200)}")
    for label, c in zip(labels_of(count), config):
        x, n = _triple(c.x), _triple(c.n)
        if x is None or n is None:
            raise CrmgraspError(f"{name}: contact {label} must be finite 3-vectors, got {shown(tuple(c), 200)}")
        if abs(math.sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]) - 1.0) > UNIT_TOL:
            raise CrmgraspError(f"{name}: contact {label}'s normal must be a unit vector, got {shown(c.n, 200)}")
    return config


def _triple(v: object) -> list[float] | None:
    """``v`` as three finite floats, or None (text is no vector)."""
    if isinstance(v, (str, bytes)):
        return None
    try:
        out = [float(e) for e in v]  # type: ignore[attr-defined]
    except (TypeError, ValueError, OverflowError):
        return None
    return out if len(out) == 3 and all(map(math.isfinite, out)) else None


@dataclass(frozen=True)
class Hand3D:
    """Aperture ``A``, palm depth, back-off, vertical axis ``h`` and forward axis ``g``
    (docs/model-3d.md section 2); ``r_max`` bounds ``|r|`` (default: the aperture);
    ``contacts`` fingers (2 to 4, labelled ``a, b, c, d``: section 9)."""

    aperture: float
    palm_depth: float
    backoff: float = 0.01
    h: tuple[float, float, float] = (0.0, 0.0, 1.0)
    g: tuple[float, float, float] = (1.0, 0.0, 0.0)
    r_max: float | None = None
    min_separation: float = 0.0
    palm_normal_tol: float = 1e-9
    contacts: int = 2
    _h: F64 = field(init=False, repr=False, compare=False)
    _g: F64 = field(init=False, repr=False, compare=False)
    _labels: tuple[str, ...] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "aperture", positive(self.aperture, "aperture"))
        object.__setattr__(self, "palm_depth", non_negative(self.palm_depth, "palm_depth"))
        object.__setattr__(self, "backoff", non_negative(self.backoff, "backoff"))
        h, g = _unit(self.h, "hand axis h"), _unit(self.g, "hand axis g")
        if abs(float(h @ g)) > 1e-9:
            raise CrmgraspError("the hand's axes h and g must be perpendicular")
        object.__setattr__(self, "_h", h)
        object.__setattr__(self, "_g", g)
        object.__setattr__(self, "_labels", labels_of(self.contacts))  # a one-line error outside 2 to 4

    @property
    def labels(self) -> tuple[str, ...]:
        """The contacts' labels, ``('a', 'b')`` for two."""
        return self._labels

    @property
    def reach(self) -> float:
        """The largest ``|r|``."""
        return self.aperture if self.r_max is None else self.r_max

    def check_crm(self, crm: object) -> CRM3D:
        """``crm`` if it is a [`CRM3D`][] naming the hand's contacts and a finite offset of
        length at most [`reach`][]; else a one-line `CrmgraspError`."""
        if not isinstance(crm, CRM3D):
            raise CrmgraspError(f"expected a CRM3D, got {crm!r}")
        labels = self.labels
        if crm.c not in labels or crm.f not in labels:
            names = " or ".join(f"{x!r}" for x in labels) if len(labels) == 2 else ", ".join(labels)
            raise CrmgraspError(f"contact labels must be {names}, got {crm.c!r} and {crm.f!r}")
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

    config: Contacts3D
    error: Error


def tangent_frame(n: ArrayLike, hand: Hand3D) -> tuple[F64, F64]:
    """``t_1 = n x h / |n x h|`` (``n x g`` if ``n`` is parallel to ``h``), ``t_2 = t_1 x n``."""
    nv = np.asarray(n, dtype=np.float64)
    t1 = cross(nv, hand._h)
    if norm(t1) < PARALLEL:
        t1 = cross(nv, hand._g)
    t1 = t1 / norm(t1)
    return t1, cross(t1, nv)


def _palm_axis(cfg: Contacts3D, hand: Hand3D) -> tuple[float, F64]:
    """``(|x_z - x_a|, u)``: the outer contacts' distance (first ``a``, last ``z``) and the
    palm side ``u = d x h / |d x h|`` (``d x g`` if ``d`` is parallel to ``h``), ``d`` the unit
    vector from ``a`` to ``z``; ``u`` is NaN if they coincide."""
    a, *_, z = cfg
    xa, xb = np.array(a.x), np.array(z.x)
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


def faces_palm3d(cfg: Contacts3D, hand: Hand3D) -> bool:
    """True if an outer contact's surface faces the palm side: ``n . u > palm_normal_tol`` for
    ``n_a`` or ``n_z`` (the object would lie between palm and finger); False if they
    coincide."""
    dist, u = _palm_axis(cfg, hand)
    return dist > 0.0 and _faces(cfg, hand, u)


def _faces(cfg: Contacts3D, hand: Hand3D, u: F64) -> bool:
    a, *_, z = cfg
    return dot(a.n, u) > hand.palm_normal_tol or dot(z.n, u) > hand.palm_normal_tol


def _spread(cfg: Contacts3D) -> tuple[float, float]:
    """The largest and the smallest distance between two contacts (m)."""
    far, near = 0.0, math.inf
    contacts = list(cfg)
    for i, p in enumerate(contacts):
        for q in contacts[i + 1 :]:
            dist = norm(np.array(q.x) - np.array(p.x))
            far, near = max(far, dist), min(near, dist)
    return far, near


def _crossed(cfg: Contacts3D) -> bool:
    """True if the contacts' positions along ``d`` (from ``a`` toward ``z``) do not increase
    strictly in label order (never for two contacts)."""
    a, *rest = cfg
    xa = np.array(a.x)
    d = np.array(rest[-1].x) - xa
    last = 0.0
    for c in rest:
        s = dot(np.array(c.x) - xa, d)
        if s <= last:
            return True
        last = s
    return False


def feasible3d(obj: Solid, hand: Hand3D, cfg: Contacts3D, table: float | None = None) -> Error:
    """Sections 2 and 9: APERTURE if two contacts are more than ``A`` apart; PALM for
    colliding contacts, an outer contact facing the palm ([`faces_palm3d`][]), crossed
    fingers (three or more: positions along a -> z not increasing), the palm point inside
    the object, or (with a table at height ``table``) a contact or the palm point on or
    below the table."""
    dist, u = _palm_axis(cfg, hand)
    if dist > hand.aperture:
        return Error.APERTURE
    near = dist
    if len(cfg) > 2:
        far, near = _spread(cfg)
        if far > hand.aperture:
            return Error.APERTURE
    if near <= hand.min_separation or any(on_table(c.x[2], table) for c in cfg):
        return Error.PALM
    if _faces(cfg, hand, u) or (len(cfg) > 2 and _crossed(cfg)):
        return Error.PALM
    palm = _palm_at(cfg, hand, u)
    return Error.PALM if obj.contains(palm) or on_table(float(palm[2]), table) else Error.NONE


def _palm_at(cfg: Contacts3D, hand: Hand3D, u: F64) -> F64:
    """``mean_i x_i + p u``, the sum taken in label order (``(x_a + x_b) / 2 + p u`` for two)."""
    first, *rest = cfg
    total = np.array(first.x)
    for c in rest:
        total = total + np.array(c.x)
    return total / len(cfg) + hand.palm_depth * u


def palm_point3d(cfg: Contacts3D, hand: Hand3D) -> F64 | None:
    """Sections 2 and 9: ``P = mean_i x_i + p u``, ``u`` the palm side; ``None`` when the
    outer contacts coincide."""
    dist, u = _palm_axis(cfg, hand)
    return None if dist == 0.0 else _palm_at(cfg, hand, u)


class Chord3D(NamedTuple):
    """Where a CRM's approach runs: from ``start`` along the unit vector ``ahead`` for
    ``length`` metres (the goal line's chord within the aperture of the stationary
    contact, walked toward it for an opposition, away for a slide)."""

    start: F64
    ahead: F64
    length: float


def goal_chord3d(hand: Hand3D, crm: CRM3D, frame: Contact3D, stills: Sequence[Contact3D]) -> Chord3D | None:
    """Sections 3 and 9: the goal line ``x_f + r_1 t_1 + r_2 t_2 + t n_f`` (``frame`` is
    contact ``f`` as sensed) and its chord within ``A`` of every contact that stays still
    (``|x(t) - x_s| <= A`` for each ``s`` in ``stills``: the intersection of their chords);
    ``None`` (an aperture error) if the line misses one of those spheres or the chords do
    not overlap."""
    r1, r2 = (float(v) for v in crm.r)
    n_f = np.array(frame.n)
    t1, t2 = tangent_frame(n_f, hand)
    base = np.array(frame.x) + r1 * t1 + r2 * t2
    t_lo, t_hi = -math.inf, math.inf
    for still in stills:
        w = base - np.array(still.x)  # |w + t n_f|^2 = A^2, |n_f| = 1
        qb, qc = dot(w, n_f), dot(w, w) - hand.aperture * hand.aperture
        disc = qb * qb - qc
        if disc < 0.0:
            return None
        t_lo, t_hi = max(t_lo, -qb - math.sqrt(disc)), min(t_hi, -qb + math.sqrt(disc))
    if t_lo > t_hi:
        return None
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
    cfg: Contacts3D,
    crm: CRM3D,
    sensed: Contacts3D | None = None,
    table: float | None = None,
) -> Outcome3D:
    """The CRM transition of section 3 (the goal line from ``sensed``, default ``cfg``).

    With a table at height ``table``: a chord end on or below the table moves up the
    line to where it crosses the table plane (the finger approaches from the table's
    surface); if the line never rises above the table before the chord ends, or that
    point is inside the object, the CRM is a palm error (the hand would meet the table)."""
    check_solid(obj)
    if not isinstance(hand, Hand3D):
        raise CrmgraspError(f"execute_crm3d needs a Hand3D, got {shown(hand)}")
    hand.check_crm(crm)
    check_contacts3d(cfg, "configuration", hand.contacts)
    sensed = cfg if sensed is None else check_contacts3d(sensed, "reading", hand.contacts)
    if table is not None:
        table = finite(table, "table height")
    moving = label_index(crm.c)
    stills = [c for i, c in enumerate(cfg) if i != moving]
    chord = goal_chord3d(hand, crm, sensed[label_index(crm.f)], stills)
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
    new = config3d([moved if i == moving else c for i, c in enumerate(cfg)])
    err = feasible3d(obj, hand, new, table)
    return Outcome3D(cfg, err) if err is not Error.NONE else Outcome3D(new, Error.NONE)


def observe3d(cfg: Contacts3D) -> tuple[float, ...]:
    """``(rho, |m_a|, |m_b|, ...)``: ``rho = |sum_i n_i|^2`` and, per contact ``j``, the moment
    magnitude ``|m_j|``, ``m_j = sum_{i != j} (x_i - x_j) x n_i`` (sections 4 and 9; for two
    contacts ``m_a = (x_b - x_a) x n_b``, ``m_b = (x_a - x_b) x n_a``). Sums run in label order
    from the first term, so that two contacts give the two-contact formulas bit for bit."""
    check_contacts3d(cfg, "observe3d")
    xs, ns = [np.array(c.x) for c in cfg], [np.array(c.n) for c in cfg]
    s = ns[0]
    for n in ns[1:]:
        s = s + n
    moments = []
    for j, xj in enumerate(xs):
        terms = [cross(xi - xj, ni) for i, (xi, ni) in enumerate(zip(xs, ns)) if i != j]
        m = terms[0]
        for t in terms[1:]:
            m = m + t
        moments.append(norm(m))
    return (dot(s, s), *moments)


def sense3d(cfg: Contacts3D, sigma_n: float, sigma_p: float, rng: np.random.Generator, hand: Hand3D) -> Contacts3D:
    """One noisy reading of ``cfg`` (docs/model-3d.md section 4): each contact's normal is
    rotated by an angle ``N(0, sigma_n)`` (radians) about the tangent axis
    ``cos(phi) t_1 + sin(phi) t_2`` with ``phi`` uniform in ``[0, 2 pi)``, and its position
    moved by ``N(0, sigma_p^2 I_3)`` (metres). Draws, per contact a then b: ``phi`` (one
    uniform), then four standard normals (angle, x, y, z), contacts in label order. No draw
    when both sigmas are 0.
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
    return config3d(out)

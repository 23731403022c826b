"""The planar hand and contact relative motions ([docs/model.md sections 2, 3 and 8][model-2]).

A hand has ``n`` contacts (``Hand.contacts``, 2 by default) labelled ``a, b, ...`` in
order; ``z`` below is the last one (``b`` for two contacts). Every rule is written once
for any ``n``; for two contacts it is the paper's model.

Palm model
----------
With ``d = (x_z - x_a) / |x_z - x_a|`` and ``u = (d_y, -d_x)`` (the right of the
directed segment a -> z), the palm point is ``P = mean_i x_i + h u`` (for two contacts
``(x_a + x_b) / 2 + h u``). A configuration is feasible iff every two contacts are
at most ``A`` apart (else APERTURE) and the palm is clear (else PALM): ``P`` not
strictly inside the object; the outer contacts do not face the palm side,
``n_a . u <= tol`` and ``n_z . u <= tol``, with ``tol = Hand.palm_normal_tol``
(default 1e-9); no two contacts collide (closer than ``Hand.min_separation``, default
0: only coincident contacts, which leave ``u`` undefined); and the fingers do not
cross: the contacts' positions along ``d`` increase strictly in label order (a middle
contact lies strictly between ``a`` and ``z``; it may face the palm, wrapping around
the object). Under large sensing noise a CRM can land the moving contact a fraction
of a millimetre from another one; a hand with fingertips of diameter ``D`` models that
with ``min_separation = D``. The geometry (``u``, ``P``, the facing and crossing tests)
is in [`crmgrasp.model.palm`][]; [`feasible`][] applies the rule.

CRM ``(c, f, r)``
-----------------
1. Goal line ``p(t) = x_f + r tau_f + t n_f`` in the (sensed) frame of contact f.
2. Reach: the chord ``[t_lo, t_hi]`` of the line within distance A of every contact
   that stays still (the intersection of their chords); if the line misses a disc, or
   the chords do not overlap: APERTURE.
3. Start at ``t_lo`` when ``c == f`` (approach along ``+n_f``), else at ``t_hi``
   (approach along ``-n_f``). The moving contact backs off by ``d`` along its
   outward normal, travels to the start, then approaches along the line.
4. Start strictly inside the object, or no entry before the chord's other end:
   APERTURE.
5. The new contact is the first entry point, with the inward normal there.
6. New configuration's palm not clear: PALM.
7. On any error the configuration is unchanged and the error is observed.

With sensing noise the goal line comes from *sensed* contacts while motion,
contact and the stationary contact's reach are in the true world.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from enum import IntEnum
from typing import NamedTuple, Protocol

import numpy as np
from numpy.typing import ArrayLike

from crmgrasp._validation import CrmgraspError, as_point, finite, generator, non_negative, positive, shown
from crmgrasp.model.contacts import (
    ALL_LABELS,
    Config,
    Contact,
    Grip,
    check_contacts,
    label_index,
    labels_of,
    make_config,
    replaced,
)
from crmgrasp.model.geometry import Shape
from crmgrasp.model.palm import crossed, outer_faces, palm_at, palm_axis, palm_point, spread
from crmgrasp.model.shape import check_shape


class Sensor(Protocol):
    """What [`Hand.execute`][] reads the goal line's frame through: a sensor model such as
    [`SensorNoise`][crmgrasp.model.sensing.SensorNoise] (written as a protocol so that the hand,
    whose error flags the sensing module bins, does not import that module)."""

    @property
    def active(self) -> bool: ...

    def sense(self, config: Config | Grip, rng: np.random.Generator) -> Config | Grip: ...


__all__ = [
    "Hand",
    "CRM",
    "Error",
    "GoalLine",
    "Outcome",
    "check_config",
    "CONTACT_TOL",
    "feasible",
    "execute_crm",
]

PALM_NORMAL_TOL = 1e-9
"""Slack on ``n . u <= 0`` in the palm test (unitless)."""


class Error(IntEnum):
    """Error flag of a CRM (paper's epsilon_0, epsilon_1, epsilon_2), observed after it."""

    NONE = 0
    APERTURE = 1
    PALM = 2


@dataclass(frozen=True)
class CRM:
    """A contact relative motion: move contact ``c`` onto a line in contact ``f``'s frame.

    Parameters
    ----------
    c
        Label of the contact that moves, ``'a'``, ``'b'``, ... (a contact of the hand).
    f
        Label of the frame contact.
    r
        Offset of the goal line along the frame tangent ``tau_f = n_f x z``, metres.

    Examples
    --------
    >>> CRM("a", "b", 0.0)
    CRM('a', 'b', 0)
    >>> CRM.parse("b,b,-0.08")
    CRM('b', 'b', -0.08)
    """

    c: str
    f: str
    r: float = 0.0
    ci: int = field(init=False, repr=False, compare=False)
    """Index of ``c`` (0 for a, 1 for b, ...)."""
    fi: int = field(init=False, repr=False, compare=False)
    """Index of ``f``."""

    def __post_init__(self) -> None:
        object.__setattr__(self, "ci", label_index(self.c))
        object.__setattr__(self, "fi", label_index(self.f))
        object.__setattr__(self, "r", finite(self.r, "CRM offset r"))

    def __repr__(self) -> str:
        return f"CRM({self.c!r}, {self.f!r}, {self.r:g})"

    def __str__(self) -> str:
        return f"({self.c},{self.f},{self.r:g})"

    @classmethod
    def parse(cls, text: str) -> CRM:
        """Parse ``"c,f,r"``, e.g. ``"a,b,0"``."""
        parts = [p.strip() for p in str(text).split(",")]
        if len(parts) != 3:
            raise CrmgraspError(f"CRM must be written c,f,r (e.g. a,b,0), got {shown(text)}")
        return cls(parts[0], parts[1], finite(parts[2], "CRM offset r"))

    @property
    def opposition(self) -> bool:
        """True for an opposition CRM ``(c, other, 0)``."""
        return self.c != self.f and self.r == 0.0


class GoalLine(NamedTuple):
    """The CRM's goal line ``base + t direction`` and its reachable chord ``[t_lo, t_hi]``."""

    base: tuple[float, float]
    direction: tuple[float, float]
    t_lo: float
    t_hi: float

    def at(self, t: float) -> tuple[float, float]:
        """Point at parameter ``t``."""
        return (self.base[0] + t * self.direction[0], self.base[1] + t * self.direction[1])


class Outcome(NamedTuple):
    """Result of executing a CRM.

    ``path`` lists the waypoints of the moving contact: its start, the back-off
    point, the approach start, and the new contact (or, on error, the point where
    the attempt stopped and the original contact again).
    """

    config: Config | Grip
    error: Error
    path: tuple[tuple[float, float], ...]
    goal: GoalLine | None


@dataclass(frozen=True)
class Hand:
    """A planar hand of two or more contacts ([docs/model.md sections 2 and 8][model-2]).

    Parameters
    ----------
    aperture
        Maximum distance between any two contacts, metres (> 0).
    palm_depth
        Distance ``h`` of the palm point from the contacts' centroid (their midpoint for
        two), metres (>= 0).
    backoff
        Distance ``d`` a moving contact first retreats along its outward normal,
        metres (>= 0). Drawn and followed by real executors; it does not change
        outcomes in this kinematic model.
    r_max
        Largest allowed ``|r|`` of a CRM, metres. Defaults to the aperture: a goal
        line offset farther than A from the frame contact is out of reach.
    palm_normal_tol
        Largest ``n . u`` a contact may have (the sine of the angle by which its
        surface may face the palm side) before the palm test fails. Default 1e-9.
        Under sensing noise an opposition lands slightly misaligned and one normal
        then faces the palm side by a hair; a real fingertip tolerates a few
        degrees, which a larger value (e.g. ``sin(10 deg)``) models.
    min_separation
        Contacts this close or closer (metres) collide: a PALM error. Default 0: only
        coincident contacts. Must be below the aperture.
    contacts
        The number of contacts (fingers), labelled ``a, b, c, ...``: 2 (the paper's
        hand, the default) to [`MAX_CONTACTS`][crmgrasp.model.contacts.MAX_CONTACTS].
    """

    aperture: float
    palm_depth: float
    backoff: float = 0.01
    r_max: float | None = None
    palm_normal_tol: float = PALM_NORMAL_TOL
    min_separation: float = 0.0
    contacts: int = 2

    def __post_init__(self) -> None:
        labels_of(self.contacts)  # 2 to MAX_CONTACTS, else a one-line error
        object.__setattr__(self, "aperture", positive(self.aperture, "hand aperture"))
        object.__setattr__(self, "palm_depth", non_negative(self.palm_depth, "hand palm_depth"))
        object.__setattr__(self, "backoff", non_negative(self.backoff, "hand backoff"))
        r_max = self.aperture if self.r_max is None else positive(self.r_max, "hand r_max")
        object.__setattr__(self, "r_max", r_max)
        tol = non_negative(self.palm_normal_tol, "hand palm_normal_tol")
        if tol >= 1.0:
            raise CrmgraspError(f"hand palm_normal_tol must be < 1, got {tol}")
        object.__setattr__(self, "palm_normal_tol", tol)
        sep = non_negative(self.min_separation, "hand min_separation")
        if sep >= self.aperture:
            raise CrmgraspError(f"hand min_separation must be below the aperture {self.aperture:g}, got {sep:g}")
        object.__setattr__(self, "min_separation", sep)

    @property
    def labels(self) -> tuple[str, ...]:
        """The contacts' labels in order (``('a', 'b')`` for two)."""
        return ALL_LABELS[: self.contacts]

    @property
    def reach(self) -> float:
        """The largest ``|r|`` of a CRM (``r_max``, metres)."""
        assert self.r_max is not None
        return self.r_max

    def check_crm(self, crm: CRM) -> CRM:
        """Return ``crm`` if it names contacts of this hand and ``|r| <= r_max``, else raise
        `CrmgraspError`."""
        if not isinstance(crm, CRM):
            raise CrmgraspError(f"expected a CRM, got {crm!r}")
        if max(crm.ci, crm.fi) >= self.contacts:
            missing = crm.c if crm.ci >= self.contacts else crm.f
            raise CrmgraspError(
                f"CRM {crm} names contact {missing!r}, but the hand has contacts {', '.join(self.labels)}"
            )
        assert self.r_max is not None
        if abs(crm.r) > self.r_max:
            raise CrmgraspError(f"CRM offset r = {crm.r:g} is beyond r_max = {self.r_max:g}")
        return crm

    def contact(self, obj: Shape, *points: ArrayLike, **labelled: ArrayLike) -> Config | Grip:
        """Configuration with contacts at the boundary points nearest ``points``, one per
        contact in label order, or given by label (``a=(x, y), b=(x, y)``); each a finite
        ``(x, y)`` in metres."""
        if labelled:
            if points or set(labelled) != set(self.labels):
                raise CrmgraspError(
                    f"give one point per contact ({', '.join(self.labels)}), in order or by label; "
                    f"got {len(points)} in order and {', '.join(labelled) or 'none'} by label"
                )
            points = tuple(labelled[lab] for lab in self.labels)
        if len(points) != self.contacts:
            raise CrmgraspError(f"the hand has {self.contacts} contacts; got {len(points)} points")
        check_shape(obj)
        near = [obj.project(as_point(p, f"contact {lab}")) for p, lab in zip(points, ALL_LABELS)]
        return make_config([Contact(*q.point, *q.normal) for q in near])

    def palm(self, config: Config | Grip) -> tuple[float, float]:
        """Palm point ``P`` of a configuration."""
        return palm_point(config, self.palm_depth)

    def feasible(self, obj: Shape, config: Config | Grip) -> Error:
        """``Error.NONE`` if ``config`` is feasible, else the violated constraint;
        ``config`` is checked first ([`check_config`][]: finite, unit normals, on ``obj``,
        one contact per finger)."""
        return feasible(obj, self, check_config(obj, config, contacts=self.contacts))

    def execute(
        self,
        obj: Shape,
        config: Config | Grip,
        crm: CRM,
        *,
        noise: Sensor | None = None,
        rng: np.random.Generator | None = None,
        sensed: Config | Grip | None = None,
    ) -> Outcome:
        """Execute ``crm`` from ``config`` on ``obj`` ([docs/model.md section 3][model-3]).

        The goal line is computed from ``sensed`` if given; otherwise from a fresh
        reading through ``noise`` (which then needs ``rng``); otherwise from the
        true configuration. ``config`` is checked ([`check_config`][]); the pure
        transition [`execute_crm`][] checks nothing.
        """
        self.check_crm(crm)
        check_config(obj, config, contacts=self.contacts)
        if rng is not None:
            generator(rng)
        if noise is not None and not (hasattr(noise, "active") and callable(getattr(noise, "sense", None))):
            raise CrmgraspError(f"noise must be a sensor model such as SensorNoise, got {shown(noise)}")
        if sensed is not None:
            check_contacts(sensed, "sensed", self.contacts)
        if sensed is None and noise is not None and noise.active:
            if rng is None:
                raise CrmgraspError("sensing noise needs a numpy Generator (rng)")
            sensed = noise.sense(config, rng)
        return execute_crm(obj, self, config, crm, sensed)


CONTACT_TOL = 1e-6
"""How far (m) a given contact may lie from the object's boundary, and its normal's
length from 1, before [`check_config`][] refuses it."""


def check_config(
    obj: Shape, config: object, name: str = "configuration", *, contacts: int | None = None
) -> Config | Grip:
    """``config`` if it is a [`Config`][crmgrasp.model.contacts.Config] (or a
    [`Grip`][crmgrasp.model.contacts.Grip]) of ``contacts`` contacts (any number when
    ``None``) with finite coordinates, unit normals and points on the boundary of ``obj``
    (both within [`CONTACT_TOL`][]); else a one-line `CrmgraspError`."""
    check_shape(obj)
    if not isinstance(config, (Config, Grip)) or not all(isinstance(c, Contact) for c in config):
        kind = "a Config of two Contacts" if contacts in (2, None) else f"a Grip of {contacts} Contacts"
        raise CrmgraspError(f"{name} must be {kind}, got {shown(config)}")
    if contacts is not None and len(config) != contacts:
        raise CrmgraspError(f"{name} has {len(config)} contacts; the hand has {contacts}")
    for label, c in zip(ALL_LABELS, config):
        if not all(math.isfinite(v) for v in c):
            raise CrmgraspError(f"{name}: contact {label} must be finite, got {tuple(c)}")
        if abs(math.hypot(c.nx, c.ny) - 1.0) > CONTACT_TOL:
            raise CrmgraspError(f"{name}: contact {label}'s normal must be a unit vector, got ({c.nx:g}, {c.ny:g})")
        off = obj.distance(c.point)
        if off > CONTACT_TOL:
            raise CrmgraspError(f"{name}: contact {label} at ({c.x:g}, {c.y:g}) is {off:.3g} m off the object")
    return config


def feasible(obj: Shape, hand: Hand, config: Config | Grip) -> Error:
    """Feasibility of a configuration ([docs/model.md sections 2 and 8][model-2]), as an [`Error`][]:
    APERTURE if two contacts are more than ``A`` apart; PALM if two collide (at most
    ``min_separation`` apart, coincident by default), an outer contact faces the palm side
    ([`faces_palm`][crmgrasp.model.palm.faces_palm]), the fingers cross (positions along
    a -> z not increasing) or the palm point ([`palm_point`][crmgrasp.model.palm.palm_point])
    is inside."""
    dist, ux, uy = palm_axis(config)
    if dist > hand.aperture:
        return Error.APERTURE
    if len(config) == 2:
        near = dist
    else:
        far, near = spread(config)
        if far > hand.aperture:
            return Error.APERTURE
    a, *_, z = config
    if near <= hand.min_separation or outer_faces(a, z, ux, uy, hand.palm_normal_tol):
        return Error.PALM
    if len(config) > 2 and crossed(config, ux, uy):
        return Error.PALM
    if obj.contains(palm_at(config, ux, uy, hand.palm_depth)):
        return Error.PALM
    return Error.NONE


def goal_line(crm: CRM, sensed: Config | Grip, stills: Sequence[Contact], aperture: float) -> GoalLine | None:
    """Goal line of ``crm`` in the sensed frame and its chord within ``aperture`` of every
    contact in ``stills`` (those that do not move).

    Solves ``|base + t n_f - x_s|^2 = A^2`` for ``t`` per still contact ``s`` and
    intersects the intervals; ``None`` if the line misses a disc of radius A around a
    still contact or the intervals do not overlap.
    """
    f = sensed[crm.fi]
    base = (f.x + crm.r * f.ny, f.y - crm.r * f.nx)
    qa = f.nx * f.nx + f.ny * f.ny
    t_lo, t_hi = -math.inf, math.inf
    for still in stills:
        wx, wy = base[0] - still.x, base[1] - still.y
        qb = wx * f.nx + wy * f.ny
        qc = wx * wx + wy * wy - aperture * aperture
        disc = qb * qb - qa * qc
        if disc < 0.0:
            return None
        root = math.sqrt(disc)
        t_lo, t_hi = max(t_lo, (-qb - root) / qa), min(t_hi, (-qb + root) / qa)
    if t_lo > t_hi:
        return None
    return GoalLine(base, (f.nx, f.ny), t_lo, t_hi)


def execute_crm(
    obj: Shape, hand: Hand, config: Config | Grip, crm: CRM, sensed: Config | Grip | None = None
) -> Outcome:
    """Pure CRM transition: ``(object, hand, config, crm, sensed config) -> Outcome``.

    See the module docstring for the algorithm. ``sensed`` defaults to ``config``
    (no sensing noise).
    """
    if sensed is None:
        sensed = config
    mover = config[crm.ci]
    origin = (mover.x, mover.y)
    backed = (mover.x - hand.backoff * mover.nx, mover.y - hand.backoff * mover.ny)
    line = goal_line(crm, sensed, [c for i, c in enumerate(config) if i != crm.ci], hand.aperture)
    if line is None:
        return Outcome(config, Error.APERTURE, (origin, backed, origin), None)
    same = crm.c == crm.f
    t0, t1 = (line.t_lo, line.t_hi) if same else (line.t_hi, line.t_lo)
    start = line.at(t0)
    if obj.contains(start):
        return Outcome(config, Error.APERTURE, (origin, backed, origin), line)
    sign = 1.0 if same else -1.0
    direction = (sign * line.direction[0], sign * line.direction[1])
    entry = obj.ray_entry(start, direction, abs(t1 - t0))
    if entry is None:
        return Outcome(config, Error.APERTURE, (origin, backed, start, line.at(t1), origin), line)
    moved = Contact(entry.point[0], entry.point[1], entry.normal[0], entry.normal[1])
    new = replaced(config, crm.ci, moved)
    err = feasible(obj, hand, new)
    if err is not Error.NONE:
        return Outcome(config, err, (origin, backed, start, entry.point, origin), line)
    return Outcome(new, Error.NONE, (origin, backed, start, entry.point), line)

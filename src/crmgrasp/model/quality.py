"""Grasp quality for planar point contacts with Coulomb friction ([docs/model.md section 5][model-5]).

Two contacts
------------
``min_friction(config) = max_i tan(theta_i)``, where ``theta_i`` is the angle
between contact ``i``'s inward normal ``n_i`` and the unit vector from ``x_i`` to
the other contact ``x_j``. The grasp is force closure for friction coefficient
``mu`` iff both segments lie strictly inside their friction cones, i.e.
``min_friction < mu`` (Nguyen 1988). ``min_friction == 0`` is a frictionless
equilibrium (an antipodal grasp; ``tan(theta) < 1e-12`` is treated as 0 so that
floating-point rounding of an antipodal pair still gives exactly 0); ``inf`` means some angle reaches 90 degrees.

Three or more contacts
----------------------
``min_friction`` of three or more contacts is the least ``mu`` at which
[`closes`][] holds: the primitive wrenches of the friction-cone edges
``f = n cos(theta) +- tau sin(theta)`` (``mu = tan(theta)``, ``tau = (n_y, -n_x)``)
positively span the planar wrench space, decided exactly. Vectors of rank 3 fail to positively span R^3 iff some
``y != 0`` has ``y . w >= 0`` for all of them; the cone of such ``y`` is pointed, so it
has an extreme ray, and every extreme ray is normal to two of the wrenches,
``y = +-(w_i x w_j)``. So ``closes`` tries those ``2 C(m, 2)`` candidates, with no
linear program. Closure only grows with ``theta``; the least angle is found by
bisection to [`ANGLE_TOL`][] radians, and ``mu = tan(theta)`` at the bracket's upper end (0 below
[`ANTIPODAL_TOL`][], ``inf`` if the contacts do not close even at ``90 - 1e-7``
degrees). For two contacts ``min_friction`` keeps the closed form above, which
the bisection matches (a test).

Any number of contacts, by linear programming
---------------------------------------------
[`force_closure`][] tests whether the primitive wrenches
``w = (f_x, f_y, (x - c) x f)`` of the friction-cone edges ``f = n +- mu tau``
positively span the planar wrench space R^3: the origin must be strictly inside
their convex hull. This is the linear program
``max d  s.t.  W lambda = 0, sum lambda = 1, lambda_j >= d``; force closure iff
``rank W = 3`` and ``d* > 0``. For two contacts the LP agrees with
``min_friction < mu`` for squeezing grasps, and also accepts expanding (internal)
grasps, whose normals point away from each other, which ``min_friction`` (a
squeezing hand, [docs/model.md section 5][model-5]) reports as ``inf``.
"""

from __future__ import annotations

import functools
import math

import numpy as np
from numpy.typing import ArrayLike

from crmgrasp._validation import CrmgraspError, non_negative, shown
from crmgrasp.model.contacts import Config, Grip, check_contacts
from crmgrasp.model.lp import max_least_weight

__all__ = [
    "min_friction",
    "least_friction",
    "closes",
    "tan_term",
    "is_force_closure",
    "force_closure",
    "positively_spans",
    "span_margin",
    "LP_TOL",
    "RANK_TOL",
    "ANTIPODAL_TOL",
]

LP_TOL = 1e-9
"""Margin the force-closure LP's optimum must exceed (unitless, wrenches normalised)."""

RANK_TOL = 1e-10
"""Singular values of the wrench matrix above this count toward its rank (unitless)."""

ANTIPODAL_TOL = 1e-12
"""``tan(theta)`` below this is rounding error of an antipodal pair and counts as 0."""


def tan_term(x: float, y: float, nx: float, ny: float, ox: float, oy: float) -> float:
    """``tan`` of the angle between the inward normal ``n`` at ``(x, y)`` and the
    direction ``d`` to ``(ox, oy)``: ``|n x d| / (n . d)``; ``inf`` when ``n . d <= 0``
    (90 degrees or more), 0 below [`ANTIPODAL_TOL`][]."""
    dx, dy = ox - x, oy - y
    dot = nx * dx + ny * dy
    if dot <= 0.0:
        return math.inf
    t = abs(nx * dy - ny * dx) / dot
    return 0.0 if t < ANTIPODAL_TOL else t


def min_friction(config: Config | Grip) -> float:
    """Least Coulomb friction coefficient making the grasp force closure: the closed form
    for two contacts, [`least_friction`][] for more.

    Examples
    --------
    >>> from crmgrasp.model.contacts import Config, Grip, check_contacts, Contact
    >>> min_friction(Config(Contact(0, 0.05, 0, -1), Contact(0, -0.05, 0, 1)))
    0.0
    >>> round(min_friction(Config(Contact(0, 0.05, 0, -1), Contact(0.01, -0.05, 0, 1))), 6)
    0.1
    >>> round(min_friction(Config(Contact(-0.15, 0, 1, 0), Contact(0, -0.05, 0, 1))), 9)   # corner
    3.0
    >>> min_friction(Config(Contact(-0.15, 0, 1, 0), Contact(0.15, 0, 0, 1)))   # 90 degrees
    inf

    A configuration with a non-finite coordinate or a normal that is not a unit vector is
    refused ([`check_contacts`][crmgrasp.model.contacts.check_contacts]).
    """
    contacts = check_contacts(config, "min_friction")
    if len(contacts) > 2:
        return least_friction(contacts)
    a, b = contacts
    return max(tan_term(a.x, a.y, a.nx, a.ny, b.x, b.y), tan_term(b.x, b.y, b.nx, b.ny, a.x, a.y))


CLOSURE_TOL = 1e-12
"""How far (unitless; for unit wrenches and a unit plane normal) a wrench must lie on each
side of a candidate plane in [`closes`][]."""

ANGLE_TOL = 1e-12
"""Radians: [`least_friction`][] brackets the least cone half-angle this closely."""

_SPAN_TOL = 1e-12  # a candidate normal shorter than this: two wrenches are parallel
_ARM_MIN = 1e-12  # metres: the torque scale of contacts that (nearly) coincide
_THETA_MAX = math.pi / 2 - 1e-9  # closure beyond this half-angle counts as none: inf
Wrench = tuple[float, float, float]


def _basis(contacts: Config | Grip) -> list[tuple[Wrench, Wrench]]:
    """Per contact the wrenches ``(v_x, v_y, ((x - c) x v) / L)`` of its normal ``v = n`` and
    of its tangent ``v = tau = (n_y, -n_x)``, about the contacts' centroid ``c``, torques
    scaled by the largest arm ``L``; a cone edge is ``cos(theta) N +- sin(theta) T``."""
    n = len(contacts)
    cx = sum(c.x for c in contacts) / n
    cy = sum(c.y for c in contacts) / n
    scale = 0.0
    for c in contacts:
        dx, dy = c.x - cx, c.y - cy
        scale = max(scale, math.sqrt(dx * dx + dy * dy))
    scale = max(scale, _ARM_MIN)
    out = []
    for c in contacts:
        rx, ry = (c.x - cx) / scale, (c.y - cy) / scale
        out.append(((c.nx, c.ny, rx * c.ny - ry * c.nx), (c.ny, -c.nx, -rx * c.nx - ry * c.ny)))
    return out


def _edges(basis: list[tuple[Wrench, Wrench]], theta: float) -> list[Wrench]:
    """The cone-edge wrenches ``cos(theta) N +- sin(theta) T`` of every contact (unit forces)."""
    co, si = math.cos(theta), math.sin(theta)
    out = []
    for (n0, n1, n2), (t0, t1, t2) in basis:
        out.append((co * n0 + si * t0, co * n1 + si * t1, co * n2 + si * t2))
        out.append((co * n0 - si * t0, co * n1 - si * t1, co * n2 - si * t2))
    return out


def _positively_span(ws: list[Wrench]) -> bool:
    """Whether ``ws`` positively span R^3, decided exactly (module docstring): some two span
    a plane, and for every such plane's normal ``y`` some wrench lies more than
    [`CLOSURE_TOL`][] ``|y|`` on each side."""
    spans = False
    for i, (a0, a1, a2) in enumerate(ws):
        for b0, b1, b2 in ws[i + 1 :]:
            y0, y1, y2 = a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0
            norm = math.sqrt(y0 * y0 + y1 * y1 + y2 * y2)
            if norm < _SPAN_TOL:
                continue
            spans = True
            tol = CLOSURE_TOL * norm
            below = above = False
            for w0, w1, w2 in ws:
                d = y0 * w0 + y1 * w1 + y2 * w2
                below = below or d < -tol
                above = above or d > tol
                if below and above:  # both sides seen: the rest cannot change the answer
                    break
            if not (below and above):
                return False
    return spans


def closes(contacts: Config | Grip, theta: float) -> bool:
    """Whether the contacts are force closure with friction cones of half-angle ``theta``
    (radians; friction ``tan(theta)``): the cone edges' wrenches positively span the planar
    wrench space, decided exactly (module docstring)."""
    return _positively_span(_edges(_basis(contacts), theta))


@functools.lru_cache(maxsize=1 << 14)
def _least_friction(contacts: Config | Grip) -> float:
    basis = _basis(contacts)
    if _positively_span(_edges(basis, 0.0)):
        return 0.0
    if not _positively_span(_edges(basis, _THETA_MAX)):
        return math.inf
    lo, hi = 0.0, _THETA_MAX
    while hi - lo > ANGLE_TOL:
        mid = 0.5 * (lo + hi)
        if _positively_span(_edges(basis, mid)):
            hi = mid
        else:
            lo = mid
    mu = math.tan(hi)
    return 0.0 if mu < ANTIPODAL_TOL else mu


def least_friction(contacts: Config | Grip) -> float:
    """The least friction coefficient at which ``contacts`` (any number) are force closure:
    ``tan`` of the least cone half-angle at which [`closes`][] holds, bracketed by
    bisection to [`ANGLE_TOL`][] (the upper end; module docstring). Results are cached
    (a configuration is a hashable tuple; the least recently used of ``2**14`` go first).

    Examples
    --------
    Three contacts on an equilateral triangle's sides, their normals through its centroid,
    close with any friction; two of them need ``tan 30`` degrees:

    >>> from crmgrasp.model.contacts import Contact, Grip
    >>> s, c = math.sin(math.pi / 6), math.cos(math.pi / 6)
    >>> tri = Grip(Contact(-c * s, -s * s, c, s), Contact(0.0, 0.5, 0.0, -1.0), Contact(c * s, -s * s, -c, s))
    >>> least_friction(tri)
    0.0
    >>> round(least_friction(Grip(tri[0], tri[1])), 9)
    0.577350269
    """
    return _least_friction(contacts)


def is_force_closure(config: Config, mu: float) -> bool:
    """True iff the two-contact grasp is force closure with friction ``mu`` (>= 0)."""
    return min_friction(config) < non_negative(mu, "friction coefficient mu")


def force_closure(points: ArrayLike, normals: ArrayLike, mu: float) -> bool:
    """Planar force closure of ``n`` frictional point contacts, by linear programming.

    Parameters
    ----------
    points
        Contact positions, shape ``(n, 2)``, metres.
    normals
        Inward unit normals, shape ``(n, 2)``.
    mu
        Coulomb friction coefficient (>= 0).

    Examples
    --------
    >>> force_closure([(0, 0.05), (0, -0.05)], [(0, -1), (0, 1)], 0.2)
    True
    >>> force_closure([(0, 0.05), (0, -0.05)], [(0, -1), (0, 1)], 0.0)
    False
    """
    try:
        p = np.asarray(points, dtype=np.float64)
        n = np.asarray(normals, dtype=np.float64)
    except (TypeError, ValueError):
        raise CrmgraspError(
            f"points and normals must be arrays of numbers, got {shown(points)} and {shown(normals)}"
        ) from None
    if p.ndim != 2 or p.shape[1] != 2 or n.shape != p.shape or len(p) == 0:
        raise CrmgraspError(f"points and normals must both have shape (n, 2), got {p.shape} and {n.shape}")
    if not (np.all(np.isfinite(p)) and np.all(np.isfinite(n))):
        raise CrmgraspError("contact points and normals must be finite")
    mu = non_negative(mu, "friction coefficient mu")
    n = n / np.linalg.norm(n, axis=1, keepdims=True)
    tau = np.stack([n[:, 1], -n[:, 0]], axis=1)
    forces = np.concatenate([n + mu * tau, n - mu * tau]) / math.sqrt(1.0 + mu * mu)
    arms = np.concatenate([p, p]) - p.mean(axis=0)
    scale = max(float(np.max(np.linalg.norm(arms, axis=1))), 1e-12)
    torques = (arms[:, 0] * forces[:, 1] - arms[:, 1] * forces[:, 0]) / scale
    return positively_spans(np.column_stack([forces, torques]).T)  # (3, m)


def positively_spans(wrenches: np.ndarray) -> bool:
    """Whether the columns of ``wrenches`` (``(k, m)``) positively span R^k: the origin is
    strictly inside their convex hull. Linear program
    ``max d  s.t.  W lambda = 0, sum lambda = 1, lambda_j >= d``
    ([`crmgrasp.model.lp.max_least_weight`][], solved by the simplex method as written); true
    iff ``rank W = k`` and ``d* > LP_TOL`` ([`span_margin`][]). The one force-closure test of
    the planar ([`force_closure`][]) and the spatial ([`crmgrasp.model.quality3d`][]) models."""
    return span_margin(wrenches) > LP_TOL


def span_margin(wrenches: np.ndarray) -> float:
    """The optimum ``d*`` of [`positively_spans`][]' program when ``rank W = k``, ``-inf`` when
    the rank falls short (the program is then not solved): the columns positively span R^k iff
    this exceeds ``LP_TOL``. The spatial least friction's search reads ``d*`` of the probes
    that close ([`crmgrasp.model.quality3d.least_friction_3d`][])."""
    k, _ = wrenches.shape
    if np.linalg.matrix_rank(wrenches, tol=RANK_TOL) < k:
        return -math.inf
    return max_least_weight(wrenches)

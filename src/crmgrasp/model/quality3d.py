"""Grasp quality for spatial point contacts with Coulomb friction (docs/model-3d.md section 5).

Conventions: points in metres, shape ``(n, 3)``; inward unit normals, shape ``(n, 3)``
(unit within 1e-6; a normal points from the contact into the object).

* [`min_friction_3d`][], two contacts: ``max_i tan(theta_i)``, ``theta_i`` the angle
  between ``n_i`` and the unit vector from ``x_i`` to the other contact; the friction
  the squeeze between them needs (0 for an antipodal pair; ``inf`` when an angle
  reaches 90 degrees). Two point contacts never make a spatial grasp force closure:
  no contact force has a moment about the line through both contacts, so a rotation
  about it is unresisted (a soft finger's torsional friction would be needed). The
  two-contact success rule of the spatial model is therefore ``min_friction_3d <=
  mu_goal``, as in the plane.
* [`least_friction_3d`][], three or more contacts (docs/model-3d.md section 9): the least
  ``mu`` at which [`force_closure_3d`][] holds. Three contacts take the exact rule of
  [`crmgrasp.model.tripod`][] (their internal forces, [`TRIPOD_EXACT`][]); four take a search:
  ``tan`` of the least cone half-angle,
  bracketed to [`THETA_TOL_3D`][] (the upper end) by a first probe at [`FIRST_PROBE`][],
  midpoints and secant guesses (``_search``); ``inf`` if no probe below ``mu = 1e6`` closes. Closure only grows with
  ``mu`` (each polyhedral cone contains the one of a smaller ``mu``, up to the scaling of its
  edges, which leaves positive spanning unchanged), so the bracket is exact up to its
  tolerance, whichever probes narrow it. Two contacts never close: their
  rule stays the squeeze of [`min_friction_3d`][].
* [`primitive_wrenches`][]: each contact's friction cone ``{f : |f_t| <= mu f_n}``
  is replaced by the inscribed polyhedral cone of ``edges`` edges
  ``f_ij = n_i + mu (cos phi_j t1_i + sin phi_j t2_i)``, ``phi_j = 2 pi j / edges``,
  scaled to unit length; the wrench of edge ``j`` of contact ``i`` is
  ``(f_ij, (x_i - c) x f_ij / rho)`` with ``c`` the contacts' centroid and ``rho`` the
  largest ``|x_i - c|`` (so that torques are in force units).
* [`force_closure_3d`][]: the primitive wrenches positively span R^6
  ([`crmgrasp.model.quality.positively_spans`][], the same linear program as the
  planar test). The polyhedral cone is inside the circular one, so a grasp closed
  here is closed with the true cones; ``edges`` (8 by default) sets the resolution.
* [`ferrari_canny`][]: the L1 epsilon metric, the radius of the largest ball about
  the origin inside the convex hull of the primitive wrenches (0 when the origin is
  not strictly inside: not force closure). Computed from the hull's facets (Qhull).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from crmgrasp._validation import CrmgraspError, float_array, non_negative
from crmgrasp.model import quality
from crmgrasp.model.quality import ANTIPODAL_TOL, positively_spans, span_margin
from crmgrasp.model.solids import cross, dot, norm
from crmgrasp.model.tripod import least_friction_tripod

__all__ = [
    "min_friction_3d",
    "least_friction_3d",
    "THETA_TOL_3D",
    "primitive_wrenches",
    "force_closure_3d",
    "ferrari_canny",
    "tangent_basis",
    "ARM_MIN",
    "EDGES",
]

F64 = NDArray[np.float64]


def _contacts(points: ArrayLike, normals: ArrayLike, count: int | None = None) -> tuple[F64, F64]:
    """Checked ``(n, 3)`` points and unit normals (one-line errors)."""
    p, n = float_array(points, "contact points"), float_array(normals, "contact normals")
    if p.ndim != 2 or p.shape[1] != 3 or n.shape != p.shape or len(p) == 0:
        raise CrmgraspError(f"points and normals must both have shape (n, 3), got {p.shape} and {n.shape}")
    if count is not None and len(p) != count:
        raise CrmgraspError(f"this metric takes {count} contacts, got {len(p)}")
    if not (np.all(np.isfinite(p)) and np.all(np.isfinite(n))):
        raise CrmgraspError("contact points and normals must be finite")
    lengths = np.linalg.norm(n, axis=1)
    if np.any(np.abs(lengths - 1.0) > 1e-6):
        raise CrmgraspError(f"contact normals must be unit vectors, got lengths {np.round(lengths, 6).tolist()}")
    return p, n


def tangent_basis(normal: F64) -> tuple[F64, F64]:
    """``(t1, t2)``: unit tangents with ``(t1, t2, n)`` right-handed; ``t1`` is
    ``n x e`` normalised, ``e`` the coordinate axis least aligned with ``n`` (the first of
    equals). Written out ([`crmgrasp.model.solids.cross`][], [`crmgrasp.model.solids.norm`][]),
    so that the compiled least friction repeats it bit for bit."""
    mags = [abs(v) for v in normal]
    e = np.zeros(3)
    e[mags.index(min(mags))] = 1.0
    t1 = cross(normal, e)
    t1 = t1 / norm(t1)
    return t1, cross(normal, t1)


def min_friction_3d(points: ArrayLike, normals: ArrayLike) -> float:
    """The friction two contacts' squeeze needs, ``max_i tan(theta_i)`` (see the module
    docstring).

    Examples
    --------
    >>> min_friction_3d([(0.05, 0, 0), (-0.05, 0, 0)], [(-1, 0, 0), (1, 0, 0)])
    0.0
    >>> t = np.radians(30.0)
    >>> round(min_friction_3d([(0.05, 0, 0), (-0.05, 0, 0)], [(-np.cos(t), 0, np.sin(t)), (1, 0, 0)]), 6)
    0.57735
    """
    p, n = _contacts(points, normals, 2)
    worst = 0.0
    for i, j in ((0, 1), (1, 0)):
        d = p[j] - p[i]
        length = norm(d)
        if length == 0.0:
            return math.inf
        cos = dot(n[i], d) / length
        if cos <= 0.0:
            return math.inf
        sin = norm(cross(n[i], d)) / length
        tan = sin / cos
        worst = max(worst, 0.0 if tan < ANTIPODAL_TOL else tan)
    return worst


THETA_TOL_3D = 1e-7
"""The search's resolution of the least friction cone half-angle, radians
([`least_friction_3d`][]): on three-contact configurations of the tripod tasks it took about
12-13 linear programs (24 for a plain bisection; the exact rule takes 1-2;
`benchmarks/bench_tripod.py` counts them)."""

_THETA_MAX_3D = math.atan(1e6)  # no closure below this half-angle counts as none: inf

GUIDE_REACH = 3.0
"""How far above the secant root a guess goes, in units of ``(b - x_s)(b2 - x_s)`` (per
radian: about the curvature of the program's optimum ``d*`` near the threshold on the tripod
tasks' grips), so that it closes just above the threshold ([`least_friction_3d`][]). Like the
four constants below it decides only which half-angles are probed, never the bracket's rule."""

GUIDE_WIDEN = 8.0
"""The reach's factor after a guess that opened."""

GUIDE_NEAR = 0.25
"""Once the secant root is within this fraction of [`THETA_TOL_3D`][] below the lowest closed
probe, the next guess goes as far below the root, to open there and end the search."""

GUIDE_FLOOR = 1e-3
"""No guess from closed probes below this half-angle (radians): near a frictionless equilibrium
the program's answers are not monotone in the half-angle (NaN among closed probes), so
midpoints decide there."""

GUIDE_MAX = 16
"""At most this many guesses per configuration; midpoints after that (so the search ends)."""

FIRST_PROBE = 0.0505
"""The friction of the search's first probe, 1% above the spatial tasks' default goal (0.05):
a search stopped as soon as it decides a grasp at that goal (the start filter, a step asked
only to decide the grasp) then ends after one program for every configuration whose least
friction lies above it. The midpoint of the remaining bracket follows. Like the guesses'
constants it decides only which half-angles are probed (0: the midpoint first)."""


TRIPOD_EXACT = True
"""Three contacts take the exact rule of [`crmgrasp.model.tripod`][] (False: the search, as four
contacts do; the rule before, kept as the benchmark's peer)."""

EDGES = 8
"""Edges of each contact's polyhedral friction cone in [`least_friction_3d`][] (its default)."""


def least_friction_3d(points: ArrayLike, normals: ArrayLike, edges: int = EDGES) -> float:
    """The least friction coefficient at which ``n >= 3`` contacts are force closure with
    polyhedral cones of ``edges`` edges (see the module docstring): exactly for three
    ([`crmgrasp.model.tripod.least_friction_tripod`][]), by the search for four, ``inf`` for two.

    Examples
    --------
    Three contacts on a cylinder's equator, 120 degrees apart, their normals through its
    axis: a frictionless equilibrium, which closes with any friction:

    >>> pts = [(np.cos(a), np.sin(a), 0.0) for a in (0.0, 2 * np.pi / 3, 4 * np.pi / 3)]
    >>> least_friction_3d(pts, [(-x, -y, 0.0) for x, y, _ in pts]) < 1e-6
    True
    """
    frames = _cone_frames(points, normals)
    if len(frames.arms) < 3:
        return math.inf
    if len(frames.arms) == 3 and TRIPOD_EXACT:
        _check_edges(edges)
        tangents = np.array([np.concatenate(t) for t in frames.tangents])
        return least_friction_tripod(np.array(frames.arms), np.array(frames.normals), tangents, frames.rho, edges)
    b = _search(frames, edges)
    if b == _THETA_MAX_3D:  # no probe closed
        return math.inf
    mu = math.tan(b)
    return 0.0 if mu < ANTIPODAL_TOL else mu


def _search(frames: _Frames, edges: int) -> float:
    """The least closing half-angle's bracket ``(a, b)`` narrowed to [`THETA_TOL_3D`][]: the
    cones open at ``a`` (0 at first) and close at ``b`` (``_THETA_MAX_3D`` at first); each
    probe at ``x`` in between (from [`_next_probe`][]) replaces ``b`` if the cones close there,
    ``a`` if not. Returns ``b``."""
    a, b = 0.0, _THETA_MAX_3D
    d1 = b2 = d2 = math.nan  # d* at b, and the closed probe b2 > b before it with its d*
    reach, guesses = GUIDE_REACH, 0
    while b - a > THETA_TOL_3D:
        x, guess = _next_probe(a, b, d1, b2, d2, reach, guesses)
        guesses += guess
        d = span_margin(_wrenches(frames, math.tan(x), edges))
        if d > quality.LP_TOL:  # positively_spans
            b, d1, b2, d2, reach = x, d, b, d1, GUIDE_REACH
        else:
            a = x
            reach = GUIDE_WIDEN * reach if guess else reach
    return b


def _next_probe(a: float, b: float, d1: float, b2: float, d2: float, reach: float, guesses: int) -> tuple[float, int]:
    """The next half-angle to probe in ``(a, b)``, and 1 if it is a guess (0 for the midpoint).

    Near the threshold the program's optimum ``d*`` grows close to linearly with the
    half-angle, and concavely, so the secant through the two lowest closed probes, ``(b2,
    d2)`` and ``(b, d1)``, meets ``d* = LP_TOL`` at ``x_s`` at or just below the threshold,
    within about ``(b - x_s)(b2 - x_s)`` times the curvature. The guess is ``x_s`` plus
    ``reach`` times that (to close just above the threshold), or, once ``b`` is within
    [`GUIDE_NEAR`][] of the tolerance above ``x_s``, as far below ``x_s`` (to open just below
    it). The midpoint otherwise: before two closed probes, below [`GUIDE_FLOOR`][], after
    [`GUIDE_MAX`][] guesses or for a guess outside the bracket; the first probe of all at
    friction [`FIRST_PROBE`][]."""
    target = quality.LP_TOL
    if a == 0.0 and b == _THETA_MAX_3D and FIRST_PROBE > 0.0:  # nothing probed yet
        return math.atan(FIRST_PROBE), 0
    if guesses < GUIDE_MAX and d1 > target and d2 > d1 and b2 > GUIDE_FLOOR:
        root = b - (d1 - target) * (b2 - b) / (d2 - d1)
        err = reach * (b - root) * (b2 - root)
        near = GUIDE_NEAR * THETA_TOL_3D
        x = root + err if b - root > near else root - (b - root) - max(err, near)
        if a < x < b:
            return x, 1
    return 0.5 * (a + b), 0


def primitive_wrenches(points: ArrayLike, normals: ArrayLike, mu: float, edges: int = 8) -> F64:
    """The ``(6, n edges)`` primitive wrenches of the module docstring."""
    return _wrenches(_cone_frames(points, normals), mu, edges)


ARM_MIN = 1e-12
"""The least torque scale ``rho``, metres (contacts all at one point still get wrenches)."""


class _Frames(NamedTuple):
    """What the primitive wrenches take from the contacts, whatever ``mu``: the arms
    ``x_i - c``, the inward normals, each contact's tangents, and the torque scale ``rho``."""

    arms: list[F64]
    normals: list[F64]
    tangents: list[tuple[F64, F64]]
    rho: float


def _cone_frames(points: ArrayLike, normals: ArrayLike) -> _Frames:
    """The contacts' frames: the centroid ``c`` summed contact by contact, each arm
    ``x_i - c``, ``rho`` the longest arm (at least [`ARM_MIN`][])."""
    p, n = _contacts(points, normals)
    count = len(p)
    centre = p[0].copy()
    for i in range(1, count):
        centre = centre + p[i]
    centre = centre / count
    arms = [p[i] - centre for i in range(count)]
    rho = max(max(norm(a) for a in arms), ARM_MIN)
    return _Frames(arms, list(n), [tangent_basis(normal) for normal in n], rho)


def _check_edges(edges: object) -> None:
    """A one-line error unless ``edges`` is an integer in [3, 64]."""
    if isinstance(edges, bool) or not isinstance(edges, int) or not 3 <= edges <= 64:
        raise CrmgraspError(f"edges must be an integer in [3, 64], got {edges!r}")


def _wrenches(frames: _Frames, mu: float, edges: int) -> F64:
    """The ``(6, n edges)`` unit edge wrenches, contact by contact, edge by edge (the angle
    ``phi_j = 2 pi j / edges``), each written out so that the compiled copy repeats it."""
    mu = non_negative(mu, "friction coefficient mu")
    _check_edges(edges)
    scale = math.sqrt(1.0 + mu * mu)
    cols = []
    for x, normal, (t1, t2) in zip(frames.arms, frames.normals, frames.tangents, strict=True):
        for j in range(edges):
            phi = 2.0 * math.pi * j / edges
            co, si = math.cos(phi), math.sin(phi)
            f = (normal + mu * (co * t1 + si * t2)) / scale
            cols.append(np.concatenate([f, cross(x, f) / frames.rho]))
    return np.array(cols).T


def force_closure_3d(points: ArrayLike, normals: ArrayLike, mu: float, edges: int = 8) -> bool:
    """Spatial force closure of ``n`` frictional point contacts (polyhedral cones of
    ``edges`` edges), by the linear program of [`positively_spans`][crmgrasp.model.quality.positively_spans].

    Examples
    --------
    >>> pts = [(np.cos(a), np.sin(a), 0.0) for a in (0.0, 2.1, 4.2)]
    >>> nrm = [(-x, -y, 0.0) for x, y, _ in pts]
    >>> force_closure_3d(pts, nrm, 0.5), force_closure_3d(pts, nrm, 0.0)
    (True, False)
    """
    return positively_spans(primitive_wrenches(points, normals, mu, edges))


def ferrari_canny(points: ArrayLike, normals: ArrayLike, mu: float, edges: int = 8) -> float:
    """The L1 epsilon metric (module docstring): 0 when not force closure."""
    from scipy.spatial import ConvexHull, QhullError  # heavy: imported where used

    w = primitive_wrenches(points, normals, mu, edges).T
    if np.linalg.matrix_rank(w, tol=1e-10) < 6 or len(w) < 7:
        return 0.0
    try:
        hull = ConvexHull(w)
    except QhullError:
        return 0.0
    offsets = hull.equations[:, -1]  # facet: normal . x + offset = 0, normal outward, unit length
    return float(-offsets.max()) if offsets.max() < 0.0 else 0.0

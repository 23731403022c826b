"""Grasp quality for planar point contacts with Coulomb friction (docs/model.md section 5).

Two contacts
------------
``min_friction(config) = max_i tan(theta_i)``, where ``theta_i`` is the angle
between contact ``i``'s inward normal ``n_i`` and the unit vector from ``x_i`` to
the other contact ``x_j``. The grasp is force closure for friction coefficient
``mu`` iff both segments lie strictly inside their friction cones, i.e.
``min_friction < mu`` (Nguyen 1988). ``min_friction == 0`` is a frictionless
equilibrium (an antipodal grasp; ``tan(theta) < 1e-12`` is treated as 0 so that
floating-point rounding of an antipodal pair still gives exactly 0); ``inf`` means some angle reaches 90 degrees.

Any number of contacts
----------------------
[`force_closure`][] tests whether the primitive wrenches
``w = (f_x, f_y, (x - c) x f)`` of the friction-cone edges ``f = n +- mu tau``
positively span the planar wrench space R^3: the origin must be strictly inside
their convex hull. This is the linear program
``max d  s.t.  W lambda = 0, sum lambda = 1, lambda_j >= d``; force closure iff
``rank W = 3`` and ``d* > 0``. For two contacts the LP agrees with
``min_friction < mu`` for squeezing grasps, and also accepts expanding (internal)
grasps, whose normals point away from each other, which ``min_friction`` (a
squeezing hand, docs/model.md section 5) reports as ``inf``.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from crmgrasp._validation import CrmgraspError, non_negative
from crmgrasp.model.contacts import Config, check_contacts

__all__ = [
    "min_friction",
    "tan_term",
    "is_force_closure",
    "force_closure",
    "positively_spans",
    "LP_TOL",
    "ANTIPODAL_TOL",
]

LP_TOL = 1e-9
"""Margin the force-closure LP's optimum must exceed (unitless, wrenches normalised)."""

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


def min_friction(config: Config) -> float:
    """Least Coulomb friction coefficient making the two-contact grasp force closure.

    Examples
    --------
    >>> from crmgrasp.model.contacts import Config, check_contacts, Contact
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
    a, b = check_contacts(config, "min_friction")
    return max(tan_term(a.x, a.y, a.nx, a.ny, b.x, b.y), tan_term(b.x, b.y, b.nx, b.ny, a.x, a.y))


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
    p = np.asarray(points, dtype=np.float64)
    n = np.asarray(normals, dtype=np.float64)
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
    ``max d  s.t.  W lambda = 0, sum lambda = 1, lambda_j >= d``; true iff
    ``rank W = k`` and ``d* > LP_TOL``. The one force-closure test of the planar
    ([`force_closure`][]) and the spatial ([`crmgrasp.model.quality3d`][]) models."""
    from scipy.optimize import linprog  # heavy: imported where used

    k, m = wrenches.shape
    if np.linalg.matrix_rank(wrenches, tol=1e-10) < k:
        return False
    # variables: lambda_1..m, d ; maximise d
    c = np.zeros(m + 1)
    c[-1] = -1.0
    a_eq = np.zeros((k + 1, m + 1))
    a_eq[:k, :m] = wrenches
    a_eq[k, :m] = 1.0
    b_eq = np.zeros(k + 1)
    b_eq[k] = 1.0
    a_ub = np.hstack([-np.eye(m), np.ones((m, 1))])  # d - lambda_j <= 0
    res = linprog(
        c, A_ub=a_ub, b_ub=np.zeros(m), A_eq=a_eq, b_eq=b_eq, bounds=[(0, None)] * m + [(None, 1)], method="highs"
    )
    return bool(res.status == 0 and -res.fun > LP_TOL)

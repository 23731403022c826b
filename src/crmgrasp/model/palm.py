"""The planar hand's palm: where it is and which side it is on ([docs/model.md section 2][model-2]).

With ``d = (x_z - x_a) / |x_z - x_a|`` (``a`` the first contact, ``z`` the last) and
``u = (d_y, -d_x)``, the right of the directed segment a -> z, the palm is on the ``u``
side and the palm point is ``P = mean_i x_i + h u`` (``(x_a + x_b) / 2 + h u`` for two
contacts), ``h`` the palm depth (m). This module holds that geometry and the tests built
on it (an outer contact facing the palm, the spread of the contacts, crossed fingers);
[`crmgrasp.model.hand.feasible`][] applies the feasibility rule with them.
"""

from __future__ import annotations

import itertools
import math

from crmgrasp.model.contacts import Config, Contact, Grip

__all__ = ["palm_axis", "palm_at", "palm_point", "outer_faces", "faces_palm", "spread", "crossed"]


def palm_axis(config: Config | Grip) -> tuple[float, float, float]:
    """``(|x_z - x_a|, u_x, u_y)``: the outer contacts' distance (first ``a``, last ``z``)
    and the unit vector ``u`` to the right of a -> z, the side the palm is on (``u`` is NaN
    if they coincide)."""
    a, *_, b = config  # unpacking, not indexing: a Config's [] also takes labels, in Python
    dx, dy = b.x - a.x, b.y - a.y
    dist = math.sqrt(dx * dx + dy * dy)
    if dist == 0.0:
        return 0.0, math.nan, math.nan
    return dist, dy / dist, -dx / dist


def palm_at(config: Config | Grip, ux: float, uy: float, h: float) -> tuple[float, float]:
    """``mean_i x_i + h u`` (m) for the palm side ``u = (ux, uy)`` and depth ``h`` (m), the sum
    taken in label order (so that the compiled kernels can repeat it bit for bit)."""
    first, *rest = config
    sx, sy = first.x, first.y
    for c in rest:
        sx += c.x
        sy += c.y
    n = len(config)
    return (sx / n + h * ux, sy / n + h * uy)


def outer_faces(a: Contact, b: Contact, ux: float, uy: float, tol: float) -> bool:
    """True if ``n_a . u > tol`` or ``n_b . u > tol`` for the outer contacts ``a`` and ``b``:
    one of their surfaces faces the palm side ``u``."""
    return a.nx * ux + a.ny * uy > tol or b.nx * ux + b.ny * uy > tol


def palm_point(config: Config | Grip, palm_depth: float) -> tuple[float, float]:
    """``P = mean_i x_i + h u`` with ``u`` the right of a -> z (NaN if ``a`` and ``z``
    coincide); ``(x_a + x_b)/2 + h u`` for two contacts."""
    _, ux, uy = palm_axis(config)
    return palm_at(config, ux, uy, palm_depth)


def faces_palm(config: Config | Grip, tol: float) -> bool:
    """True if an outer contact's surface faces the palm side: ``n . u > tol`` for ``n_a``
    or ``n_z`` (the object would lie between palm and finger). False if they coincide."""
    _, ux, uy = palm_axis(config)
    a, *_, b = config
    return outer_faces(a, b, ux, uy, tol)


def spread(config: Config | Grip) -> tuple[float, float]:
    """The largest and the smallest distance between two contacts (m)."""
    far, near = 0.0, math.inf
    for i, p in enumerate(config):
        for q in itertools.islice(config, i + 1, None):
            dx, dy = q.x - p.x, q.y - p.y
            dist = math.sqrt(dx * dx + dy * dy)
            far, near = max(far, dist), min(near, dist)
    return far, near


def crossed(config: Config | Grip, ux: float, uy: float) -> bool:
    """True if the contacts' positions along ``d = (-u_y, u_x)`` (a -> z) do not increase
    strictly in label order (never for two contacts)."""
    a, *rest = config
    last = 0.0
    for c in rest:
        s = (c.x - a.x) * -uy + (c.y - a.y) * ux
        if s <= last:
            return True
        last = s
    return False

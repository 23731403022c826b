"""Exact discs (see [`crmgrasp.model.geometry`][] for the conventions)."""

from __future__ import annotations

import math
from dataclasses import dataclass

from numpy.typing import ArrayLike

from crmgrasp._validation import CrmgraspError, as_point, finite, positive
from crmgrasp.model.shape import EPS, BoundaryPoint, Entry, check_reach

__all__ = ["Disc"]


@dataclass(frozen=True)
class Disc:
    """An exact disc (not a polygon approximation).

    Parameters
    ----------
    radius
        Radius in metres, > 0.
    center
        Centre ``(x, y)`` in metres.

    Examples
    --------
    >>> d = Disc(0.05)
    >>> d.project((0.2, 0.0))
    BoundaryPoint(point=(0.05, 0.0), normal=(-1.0, -0.0), s=0.0)
    >>> [round(v, 12) for v in d.ray_entry((0.0, 0.2), (0.0, -1.0), 1.0).point]
    [0.0, 0.05]
    """

    radius: float
    center: tuple[float, float] = (0.0, 0.0)

    def __post_init__(self) -> None:
        object.__setattr__(self, "radius", positive(self.radius, "disc radius"))
        object.__setattr__(self, "center", as_point(self.center, "disc center"))
        check_reach((self.radius, *self.center), "a disc's radius or center")

    @property
    def perimeter(self) -> float:
        """Circumference in metres."""
        return 2.0 * math.pi * self.radius

    @property
    def area(self) -> float:
        """Area in square metres."""
        return math.pi * self.radius * self.radius

    def bounds(self) -> tuple[float, float, float, float]:
        """``(xmin, ymin, xmax, ymax)``."""
        cx, cy = self.center
        r = self.radius
        return (cx - r, cy - r, cx + r, cy + r)

    def boundary(self, s: float) -> BoundaryPoint:
        """Point at arclength ``s`` CCW from angle 0, normal toward the centre."""
        s = finite(s, "arclength") % self.perimeter
        phi = s / self.radius
        c, si = math.cos(phi), math.sin(phi)
        return BoundaryPoint((self.center[0] + self.radius * c, self.center[1] + self.radius * si), (-c, -si), s)

    def project(self, p: ArrayLike) -> BoundaryPoint:
        """Nearest boundary point to ``p`` (undefined at the centre: raises)."""
        px, py = as_point(p, "point")
        vx, vy = px - self.center[0], py - self.center[1]
        dist = math.sqrt(vx * vx + vy * vy)
        if dist == 0.0:
            raise CrmgraspError("the disc centre has no unique nearest boundary point")
        ux, uy = vx / dist, vy / dist
        s = (math.atan2(uy, ux) % (2.0 * math.pi)) * self.radius
        return BoundaryPoint((self.center[0] + self.radius * ux, self.center[1] + self.radius * uy), (-ux, -uy), s)

    def distance(self, p: ArrayLike) -> float:
        """Unsigned distance from ``p`` to the circle, in metres."""
        px, py = as_point(p, "point")
        vx, vy = px - self.center[0], py - self.center[1]
        return abs(math.sqrt(vx * vx + vy * vy) - self.radius)

    def contains(self, p: ArrayLike) -> bool:
        """True if ``p`` is strictly inside (deeper than [`EPS`][])."""
        px, py = (p[0], p[1]) if isinstance(p, tuple) else as_point(p, "point")
        vx, vy = px - self.center[0], py - self.center[1]
        return math.sqrt(vx * vx + vy * vy) < self.radius - EPS

    def ray_entry(self, origin: tuple[float, float], direction: tuple[float, float], u_max: float) -> Entry | None:
        """First entry of ``origin + u direction`` (``0 <= u <= u_max``) into the disc.

        Solves ``|o + u d - c|^2 = R^2``; the entry is the smaller root. A tangent
        line (zero discriminant) grazes and does not enter.
        """
        ox, oy = origin
        dx, dy = direction
        wx, wy = ox - self.center[0], oy - self.center[1]
        qa = dx * dx + dy * dy
        qb = wx * dx + wy * dy
        qc = wx * wx + wy * wy - self.radius * self.radius
        disc = qb * qb - qa * qc
        if disc <= 0.0:
            return None
        u = (-qb - math.sqrt(disc)) / qa
        if u < -EPS or u > u_max + EPS:
            return None
        px, py = ox + u * dx, oy + u * dy
        nx, ny = self.center[0] - px, self.center[1] - py
        norm = math.sqrt(nx * nx + ny * ny)
        return Entry(u, (px, py), (nx / norm, ny / norm))

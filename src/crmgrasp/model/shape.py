"""Shared geometric primitives: tolerances, result types, the Shape protocol.

See [`crmgrasp.model.geometry`][] for the conventions. The tolerances below are the
only definitions of these numbers: the compiled kernels receive them as
arguments at every call ([`crmgrasp.kernels`][]), so a changed value can never
meet stale compiled code.
"""

from __future__ import annotations

from typing import NamedTuple, Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["EPS", "S_TOL", "LINE_TOL", "BoundaryPoint", "Entry", "Shape"]

EPS = 1e-9
"""Boundary tolerance in metres: points closer than this to the boundary are on it;
an entry up to this far beyond the end of a segment still counts."""

S_TOL = 1e-12
"""Relative slack on the edge parameter, so that a ray through a vertex hits an edge."""

LINE_TOL = 1e-12
"""A polygon vertex closer than this (metres per unit of direction) to a line counts as
on it, when the entry edge of a convex polygon is decided by the vertices' sides."""

Array = NDArray[np.float64]


class BoundaryPoint(NamedTuple):
    """A point on an object's boundary with its inward unit normal and arclength."""

    point: tuple[float, float]
    normal: tuple[float, float]
    s: float


class Entry(NamedTuple):
    """Where a segment ``o + u d`` (``0 <= u <= u_max``) first enters an object."""

    u: float
    point: tuple[float, float]
    normal: tuple[float, float]


@runtime_checkable
class Shape(Protocol):
    """What the hand model needs from an object (a closed planar region).

    ``contains`` and ``ray_entry`` are the model's inside test and first-entry
    rule; every other path (the compiled kernels) is tested equal to them.
    """

    @property
    def perimeter(self) -> float: ...

    def boundary(self, s: float) -> BoundaryPoint: ...

    def project(self, p: ArrayLike) -> BoundaryPoint: ...

    def distance(self, p: ArrayLike) -> float: ...

    def contains(self, p: ArrayLike) -> bool: ...

    def ray_entry(self, origin: tuple[float, float], direction: tuple[float, float], u_max: float) -> Entry | None: ...

    def bounds(self) -> tuple[float, float, float, float]: ...

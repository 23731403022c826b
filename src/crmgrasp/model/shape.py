"""Shared geometric primitives: tolerances, result types, the Shape protocol.

See [`crmgrasp.model.geometry`][] for the conventions. The tolerances below are the
only definitions of these numbers: the compiled kernels receive them as
arguments at every call ([`crmgrasp.kernels`][]), so a changed value can never
meet stale compiled code.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import NamedTuple, Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from crmgrasp._validation import CrmgraspError, shown

__all__ = ["EPS", "S_TOL", "LINE_TOL", "MAX_COORD", "BoundaryPoint", "Entry", "Shape", "check_reach", "check_shape"]

EPS = 1e-9
"""Boundary tolerance in metres: points closer than this to the boundary are on it;
an entry up to this far beyond the end of a segment still counts."""

S_TOL = 1e-12
"""Relative slack on the edge parameter, so that a ray through a vertex hits an edge."""

LINE_TOL = 1e-12
"""A polygon vertex closer than this (metres per unit of direction) to a line counts as
on it, when the entry edge of a convex polygon is decided by the vertices' sides."""

MAX_COORD = 1e6
"""Largest ``|coordinate|`` of an object, and largest size, metres: far beyond any hand, and
far from where products of coordinates overflow or where a metre-scale difference of two
coordinates loses the digits [`EPS`][] needs (a cup placed 1e7 m out had NaN normals)."""

Array = NDArray[np.float64]


def check_reach(values: Array | Iterable[float], name: str) -> None:
    """A one-line error if a value of ``values`` (finite numbers) is beyond
    +-[`MAX_COORD`][] metres."""
    if isinstance(values, np.ndarray):
        largest = float(np.abs(values).max())
    else:  # a few numbers: cheaper in Python (family draws check every object)
        largest = max(abs(float(v)) for v in values)
    if largest > MAX_COORD:
        raise CrmgraspError(f"{name} is beyond +-{MAX_COORD:g} m (largest |value| {largest:g})")


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


def check_shape(obj: object, name: str = "object") -> Shape:
    """``obj`` if it is a [`Shape`][] (a `Polygon`, a `Disc`, ...), else a one-line error."""
    if not isinstance(obj, Shape):
        raise CrmgraspError(f"{name} must be a Shape (Polygon, Disc, ...), got {shown(obj)}")
    return obj

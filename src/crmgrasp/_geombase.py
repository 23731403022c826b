"""Shared geometric primitives: tolerances, result types, the Shape protocol.

See :mod:`crmgrasp.geometry` for the conventions.
"""

from __future__ import annotations

from typing import NamedTuple, Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._validation import CrmgraspError

EPS = 1e-9
"""Boundary tolerance in metres: points closer than this to the boundary are on it."""

_S_TOL = 1e-12  # relative edge-parameter slack so a ray through a vertex hits an edge

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
    """What the hand model needs from an object (a closed planar region)."""

    @property
    def perimeter(self) -> float: ...

    def boundary(self, s: float) -> BoundaryPoint: ...

    def boundary_batch(self, s: ArrayLike) -> tuple[Array, Array]: ...

    def project(self, p: ArrayLike) -> BoundaryPoint: ...

    def contains(self, p: ArrayLike) -> bool: ...

    def contains_batch(self, p: ArrayLike) -> NDArray[np.bool_]: ...

    def ray_entry(self, origin: tuple[float, float], direction: tuple[float, float], u_max: float) -> Entry | None: ...

    def ray_entry_batch(self, origin: Array, direction: Array, u_max: Array) -> tuple[Array, Array, Array]: ...

    def contains_xy(self, x: Array, y: Array) -> NDArray[np.bool_]: ...

    def ray_entry_xy(
        self, ox: Array, oy: Array, dx: Array, dy: Array, u_max: Array
    ) -> tuple[Array, Array, Array, Array, Array]: ...

    def bounds(self) -> tuple[float, float, float, float]: ...


def _points(p: ArrayLike, name: str = "points") -> Array:
    arr = np.asarray(p, dtype=np.float64)
    if arr.ndim == 1:
        arr = arr[None, :]
    if arr.ndim != 2 or arr.shape[1] != 2:
        raise CrmgraspError(f"{name} must have shape (N, 2), got {np.shape(p)}")
    if not np.all(np.isfinite(arr)):
        raise CrmgraspError(f"{name} must be finite")
    return arr


def _ray_entry_rows(shape: Shape, origin: Array, direction: Array, u_max: Array) -> tuple[Array, Array, Array]:
    """``ray_entry_batch`` on ``(N, 2)`` rows via the shape's column method."""
    with np.errstate(all="ignore"):
        u, px, py, nx, ny = shape.ray_entry_xy(origin[:, 0], origin[:, 1], direction[:, 0], direction[:, 1], u_max)
    return u, np.stack([px, py], axis=1), np.stack([nx, ny], axis=1)

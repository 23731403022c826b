"""The continuous action space: CRMs whose offset is a real number in a range.

The paper defines the action space as ``A = C x C x [-r_max, r_max]``: the moving contact,
the frame contact and a real offset ([docs/model.md section 3][model-3]). A [`CRMRange`][]
is one contact pair of that space with the offsets it may take: ``c`` moves onto the line
offset by ``r`` in ``f``'s frame, ``r`` in the box ``[low, high]`` (one coordinate in the
plane, two in space, metres). [`full_ranges`][] is the whole space of a hand: every ordered
pair of its contacts over the largest box of offsets within its reach.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from itertools import product

from crmgrasp._validation import CrmgraspError, finite, integer, listed, positive, shown

__all__ = ["CRMRange", "full_ranges", "grid_points", "MAX_GRID"]

MAX_GRID = 1000
"""The most offsets per coordinate a grid takes ([`grid_points`][]; the command line's
``--offset-grid`` bound too)."""


def grid_points(low: float, high: float, n: int) -> tuple[float, ...]:
    """``n`` offsets evenly spaced over ``[low, high]``, both ends included (the midpoint
    for ``n = 1``); computed as ``low + (high - low) i / (n - 1)``. On a range symmetric
    about 0 the upper half is the lower half negated, so that a mirror (``r -> -r``) maps
    the grid onto itself exactly.

    >>> grid_points(-0.16, 0.16, 5)
    (-0.16, -0.08, 0.0, 0.08, 0.16)
    >>> grid_points(-0.1, 0.1, 1)
    (0.0,)
    """
    n = integer(n, "offsets per coordinate", 1, MAX_GRID)
    low, high = finite(low, "a grid's low end"), finite(high, "a grid's high end")
    if n == 1:
        return (0.5 * (low + high),)
    pts = [low + (high - low) * i / (n - 1) for i in range(n)]
    pts[-1] = high
    if low == -high:
        for i in range(n // 2):
            pts[n - 1 - i] = -pts[i]
        if n % 2:
            pts[n // 2] = 0.0
    return tuple(pts)


@dataclass(frozen=True)
class CRMRange:
    """CRMs ``(c, f, r)`` of one contact pair with the offset ``r`` in a box.

    Parameters
    ----------
    c
        Label of the moving contact (``'a'``, ``'b'``, ...).
    f
        Label of the frame contact.
    low, high
        The box's corners, one entry per offset coordinate (metres): ``low[i] <= r[i] <=
        high[i]``. Equal corners make a fixed CRM.

    Examples
    --------
    >>> rg = CRMRange("a", "a", (-0.16,), (0.16,))
    >>> str(rg), rg.dim
    ('(a,a,[-0.16,0.16])', 1)
    >>> rg.clip((0.3,))
    (0.16,)
    """

    c: str
    f: str
    low: tuple[float, ...]
    high: tuple[float, ...]

    def __post_init__(self) -> None:
        if not isinstance(self.c, str) or not isinstance(self.f, str):
            raise CrmgraspError(f"a CRM range names its contacts by label, got {self.c!r} and {self.f!r}")
        for name, corner in (("low", self.low), ("high", self.high)):
            if isinstance(corner, (str, bytes)) or not isinstance(corner, (tuple, list)):
                raise CrmgraspError(
                    f"a CRM range's {name} is a tuple of offsets (one per coordinate), got {shown(corner)}"
                )
        low = tuple(finite(v, "CRM range low") for v in self.low)
        high = tuple(finite(v, "CRM range high") for v in self.high)
        if not low or len(low) != len(high):
            raise CrmgraspError(f"a CRM range's low and high need the same number of offsets, got {low} and {high}")
        if any(lo > hi for lo, hi in zip(low, high, strict=True)):
            raise CrmgraspError(f"CRM range ({self.c},{self.f}): low {low} exceeds high {high}")
        object.__setattr__(self, "low", low)
        object.__setattr__(self, "high", high)

    def __str__(self) -> str:
        span = ",".join(f"[{lo:g},{hi:g}]" for lo, hi in zip(self.low, self.high, strict=True))
        return f"({self.c},{self.f},{span})"

    @property
    def dim(self) -> int:
        """Offset coordinates (1 in the plane, 2 in space)."""
        return len(self.low)

    @property
    def fixed(self) -> bool:
        """Whether the range holds one offset only."""
        return self.low == self.high

    def clip(self, r: Sequence[float]) -> tuple[float, ...]:
        """``r`` moved into the box coordinate by coordinate."""
        return tuple(min(max(v, lo), hi) for v, lo, hi in zip(r, self.low, self.high, strict=True))

    def corners(self) -> list[tuple[float, ...]]:
        """The box's corners (the offsets farthest from 0: within reach iff the box is)."""
        return list(product(*zip(self.low, self.high, strict=True)))

    def grid(self, n: int) -> list[tuple[float, ...]]:
        """``n`` offsets per coordinate, evenly spaced over the box ([`grid_points`][]), in
        row-major order (``n ** dim`` offsets)."""
        axes = [grid_points(lo, hi, n) for lo, hi in zip(self.low, self.high, strict=True)]
        return list(product(*axes))


def full_ranges(labels: Sequence[str], offset_dim: int, reach: float) -> tuple[CRMRange, ...]:
    """The whole action space of a hand with contacts ``labels``: every ordered pair
    ``(c, f)`` (``c`` major) with offsets in the largest cube within the hand's reach,
    ``|r_i| <= reach / sqrt(offset_dim)`` (``[-r_max, r_max]`` in the plane).

    >>> print(*full_ranges("ab", 1, 0.16))
    (a,a,[-0.16,0.16]) (a,b,[-0.16,0.16]) (b,a,[-0.16,0.16]) (b,b,[-0.16,0.16])
    """
    labels = tuple(labels) if isinstance(labels, str) else listed(labels, "labels")  # "ab": the labels a, b
    reach = positive(reach, "reach")
    offset_dim = integer(offset_dim, "offset_dim", 1, 2)
    half = reach if offset_dim == 1 else reach / math.sqrt(offset_dim)
    while math.hypot(*(half,) * offset_dim) > reach:  # the corners within reach despite rounding
        half = math.nextafter(half, 0.0)
    return tuple(CRMRange(c, f, (-half,) * offset_dim, (half,) * offset_dim) for c in labels for f in labels)

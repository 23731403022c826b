"""The parts every object family shares: ranges and their draws, the pose, the
family protocol and base class, widths and plain-data descriptions
([`crmgrasp.model.families`][] builds the families on them; docs/families.md)."""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import Any, Protocol, runtime_checkable

import numpy as np

from crmgrasp._validation import CrmgraspError, shown
from crmgrasp.model.disc import Disc
from crmgrasp.model.polygon import Polygon
from crmgrasp.model.shape import Shape, check_reach

__all__ = ["MAX_TRIES", "Range", "ShapeFamily", "check_family", "Pose", "place", "width", "family_dict"]

MAX_TRIES = 1000
"""Most draws a family makes for one object before it gives up with an error."""

Range = tuple[float, float]


def _range(
    value: Any, name: str, *, low: float = 0.0, integer: bool = False, most: float = math.inf
) -> tuple[Any, Any]:
    """A checked ``(low, high)``: two finite numbers (integers if ``integer``),
    ``low <= high``, both above ``low`` (or at least it, for integers) and at most ``most``."""
    try:
        lo, hi = value
    except (TypeError, ValueError):
        raise CrmgraspError(f"{name} must be a range (low, high), got {value!r}") from None
    kind = (int,) if integer else (int, float)
    for v in (lo, hi):
        if isinstance(v, bool) or not isinstance(v, kind) or not math.isfinite(v):
            what = "integers" if integer else "finite numbers"
            raise CrmgraspError(f"{name} must be a range of two {what}, got {value!r}")
    if lo > hi:
        raise CrmgraspError(f"{name} range ({lo}, {hi}) is inverted: low > high")
    if integer and lo < low:
        raise CrmgraspError(f"{name} range ({lo}, {hi}) must start at {low} or more")
    if not integer and lo <= low:
        raise CrmgraspError(f"{name} range ({lo}, {hi}) must be above {low}")
    if hi > most:
        raise CrmgraspError(f"{name} range ({lo}, {hi}) must end at {most:g} or less")
    return (int(lo), int(hi)) if integer else (float(lo), float(hi))


def _uniform(rng: np.random.Generator, r: Range) -> float:
    """One draw uniform in ``r`` (one draw even for a fixed value, so the stream's
    layout does not depend on the ranges)."""
    return _at(r, float(rng.random()))


def _at(r: Range, u: float) -> float:
    """The point a fraction ``u`` (a uniform draw in [0, 1)) along ``r``: ``low + u (high - low)``."""
    return r[0] + u * (r[1] - r[0])


def _mid(r: Range) -> float:
    return 0.5 * (r[0] + r[1])


def width(shape: Shape) -> float:
    """The minimum width of ``shape``'s convex hull, metres: the smallest distance
    between two parallel lines enclosing it (for a polygon, attained with one line
    along a hull edge; for a disc, its diameter)."""
    if isinstance(shape, Disc):
        return 2.0 * shape.radius
    assert isinstance(shape, Polygon)
    pts = np.array(shape.vertices)
    best = math.inf
    n = len(pts)
    for i in range(n):
        e = pts[(i + 1) % n] - pts[i]
        length = math.hypot(*e)
        if length == 0.0:
            continue
        rel = pts - pts[i]
        d = np.abs(e[0] * rel[:, 1] - e[1] * rel[:, 0]) / length
        best = min(best, float(d.max()))
    return best


@dataclass(frozen=True)
class Pose:
    """The pose distribution: a rotation by an angle uniform in ``angle`` (radians)
    about the origin, then a translation uniform in ``offset`` along x and along y
    (metres)."""

    angle: Range = (0.0, 2.0 * math.pi)
    offset: Range = (-0.05, 0.05)

    def __post_init__(self) -> None:
        for name in ("angle", "offset"):
            lo, hi = _range(getattr(self, name), f"pose {name}", low=-math.inf)
            object.__setattr__(self, name, (lo, hi))
        check_reach(self.offset, "pose offset")

    def draw(self, rng: np.random.Generator) -> tuple[float, float, float]:
        """``(angle, dx, dy)``: three draws."""
        return self.at(*rng.random(3).tolist())

    def at(self, u: float, v: float, w: float) -> tuple[float, float, float]:
        """The pose of three uniform draws ``u, v, w`` in [0, 1): ``(angle, dx, dy)``."""
        return _at(self.angle, u), _at(self.offset, v), _at(self.offset, w)


def place(shape: Shape, angle: float, dx: float, dy: float) -> Shape:
    """``shape`` rotated by ``angle`` (radians) about the origin, then moved by ``(dx, dy)``."""
    if isinstance(shape, Disc):
        c, s = math.cos(angle), math.sin(angle)
        x, y = shape.center
        return Disc(shape.radius, (c * x - s * y + dx, s * x + c * y + dy))
    if isinstance(shape, Polygon):
        return shape.moved(angle, dx, dy)
    raise CrmgraspError(f"cannot place a {type(shape).__name__}; families draw polygons and discs")


@runtime_checkable
class ShapeFamily(Protocol):
    """A distribution over objects (see the module docstring)."""

    @property
    def pose(self) -> Pose: ...

    def sample(self, rng: np.random.Generator) -> Shape: ...

    def nominal(self) -> Shape: ...

    def min_width(self) -> float: ...

    def describe(self) -> dict[str, Any]: ...


def check_family(family: object) -> ShapeFamily:
    """``family`` if it is a [`ShapeFamily`][] (``BoxFamily()``, ...); one-line error otherwise."""
    if not isinstance(family, ShapeFamily):
        raise CrmgraspError(f"a task family must be a ShapeFamily (BoxFamily(), ...), got {shown(family)}")
    return family


class _Family(ABC):
    """Shared ``sample``: the unposed shape of ``_shape(rng)``, then the pose."""

    pose: Pose
    kind: str = "family"

    @abstractmethod
    def _shape(self, rng: np.random.Generator) -> Shape:
        """The unposed shape: this family's own draws."""

    def sample(self, rng: np.random.Generator) -> Shape:
        """One object: the shape's draws, then the pose's three."""
        return place(self._shape(rng), *self.pose.draw(rng))

    def describe(self) -> dict[str, Any]:
        """The family's kind and parameters as plain data (ranges as lists)."""
        return family_dict(self.kind, self)


def family_dict(kind: str, family: object) -> dict[str, Any]:
    """A dataclass family's ``kind`` and fields as plain data (ranges and poses as lists)."""
    out: dict[str, Any] = {"kind": kind}
    for k, v in vars(family).items():
        if k == "pose":
            out["pose"] = {"angle": list(v.angle), "offset": list(v.offset)}
        elif isinstance(v, tuple):
            out[k] = list(v)
        else:
            out[k] = v
    return out


def _poly(vertices: list[tuple[float, float]]) -> Polygon:
    """The polygon of ``vertices``, centred on its vertices' bounding box."""
    xs, ys = [v[0] for v in vertices], [v[1] for v in vertices]
    cx, cy = 0.5 * (min(xs) + max(xs)), 0.5 * (min(ys) + max(ys))
    return Polygon([(x - cx, y - cy) for x, y in vertices])

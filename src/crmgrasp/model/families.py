"""Object families: distributions over shapes and poses, one object per episode.

A family draws an object anew for each episode: its size and shape from ranges, then
a pose (a rotation about the origin by an angle, then a translation) from the
family's [`Pose`][]. The hand model has no world-fixed direction (docs/model.md:
every rule is written in the contacts' own frames), so the pose changes where the
object lies, not what any CRM does to it; families draw it anyway, so that scenes
look like the world and the invariance is tested, not assumed.

Every family is a frozen dataclass with ``sample(rng) -> Shape`` (all draws from
``rng``, in a documented order: the shape's parameters, then the angle, then the
offset), ``nominal()`` (the shape at the middle of every range, unposed: what a
scene shows for the family), ``min_width()`` (the smallest width, metres, of any
object it can draw: the width a parallel grasp must span at least, compared with
the hand's aperture) and ``describe()`` (its parameters as plain data).

Ranges are ``(low, high)`` with ``low <= high`` (equal: a fixed value); bad ranges,
and parameters that would give non-simple polygons, are refused with one line
naming the parameter. Rejection loops are bounded by [`MAX_TRIES`][].
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from crmgrasp._validation import CrmgraspError
from crmgrasp.model.disc import Disc
from crmgrasp.model.family_base import (
    MAX_TRIES,
    Pose,
    Range,
    ShapeFamily,
    _at,
    _Family,
    _mid,
    _poly,
    _range,
    _uniform,
    check_family,
    family_dict,
    place,
    width,
)
from crmgrasp.model.geometry import Rectangle, regular_polygon
from crmgrasp.model.polygon import MAX_VERTICES, Polygon
from crmgrasp.model.shape import Shape

__all__ = [
    "MAX_TRIES",
    "ShapeFamily",
    "check_family",
    "Pose",
    "place",
    "BoxFamily",
    "DiscFamily",
    "RegularPolygonFamily",
    "ConvexPolygonFamily",
    "UHandleFamily",
    "LShapeFamily",
    "TShapeFamily",
    "StarFamily",
    "FixedShape",
    "MixedFamily",
    "SamplerFamily",
    "width",
    "family_dict",
]


@dataclass(frozen=True)
class BoxFamily(_Family):
    """Rectangles of length and width uniform in their ranges (metres)."""

    length: Range = (0.20, 0.40)
    width: Range = (0.06, 0.14)
    pose: Pose = field(default_factory=Pose)
    kind = "box"

    def __post_init__(self) -> None:
        object.__setattr__(self, "length", _range(self.length, "box length"))
        object.__setattr__(self, "width", _range(self.width, "box width"))

    def _shape(self, rng: np.random.Generator) -> Shape:
        return Rectangle(_uniform(rng, self.length), _uniform(rng, self.width))

    def sample(self, rng: np.random.Generator) -> Shape:
        """One box: length and width, then the pose's three draws (as every family draws;
        the five in one call to ``rng``, the same numbers), built posed as one polygon
        ([`Rectangle`][crmgrasp.model.geometry.Rectangle]'s ``pose``: the same vertices as
        placing ``_shape``'s rectangle, without building that one first)."""
        u = rng.random(5).tolist()  # the stream of five single draws, in one call
        return Rectangle(_at(self.length, u[0]), _at(self.width, u[1]), self.pose.at(*u[2:]))

    def nominal(self) -> Shape:
        """The box at the middle of both ranges."""
        return Rectangle(_mid(self.length), _mid(self.width))

    def min_width(self) -> float:
        return min(self.length[0], self.width[0])


@dataclass(frozen=True)
class DiscFamily(_Family):
    """Discs of radius uniform in ``radius`` (metres): the planar cup."""

    radius: Range = (0.03, 0.07)
    pose: Pose = field(default_factory=Pose)
    kind = "disc"

    def __post_init__(self) -> None:
        object.__setattr__(self, "radius", _range(self.radius, "disc radius"))

    def _shape(self, rng: np.random.Generator) -> Shape:
        return Disc(_uniform(rng, self.radius))

    def nominal(self) -> Shape:
        return Disc(_mid(self.radius))

    def min_width(self) -> float:
        return 2.0 * self.radius[0]


@dataclass(frozen=True)
class RegularPolygonFamily(_Family):
    """Regular ``n``-gons, ``n`` uniform among the integers of ``sides``, circumradius
    uniform in ``radius`` (metres)."""

    sides: tuple[int, int] = (3, 8)
    radius: Range = (0.04, 0.08)
    pose: Pose = field(default_factory=Pose)
    kind = "regular-polygon"

    def __post_init__(self) -> None:
        sides = _range(self.sides, "regular polygon sides", low=3, integer=True, most=MAX_VERTICES)
        object.__setattr__(self, "sides", sides)
        object.__setattr__(self, "radius", _range(self.radius, "regular polygon radius"))

    def _shape(self, rng: np.random.Generator) -> Shape:
        n = self.sides[0] + int(rng.random() * (self.sides[1] - self.sides[0] + 1))
        return regular_polygon(n, _uniform(rng, self.radius))

    def nominal(self) -> Shape:
        return regular_polygon((self.sides[0] + self.sides[1]) // 2, _mid(self.radius))

    def min_width(self) -> float:
        # the width of a regular n-gon grows with n at a fixed circumradius: 3 sides are the narrowest
        return width(regular_polygon(self.sides[0], self.radius[0]))


@dataclass(frozen=True)
class ConvexPolygonFamily(_Family):
    """Random convex polygons: ``n`` (uniform among the integers of ``vertices``)
    points at angles uniform on the circle of a radius uniform in ``radius``,
    redrawn until the centre lies inside with margin (no gap between consecutive
    angles above 150 degrees) and no side is shorter than ``0.1 radius`` (every
    gap at least 2 asin(0.05) rad)."""

    vertices: tuple[int, int] = (3, 8)
    radius: Range = (0.04, 0.08)
    pose: Pose = field(default_factory=Pose)
    kind = "convex-polygon"

    def __post_init__(self) -> None:
        count = _range(self.vertices, "convex polygon vertices", low=3, integer=True, most=MAX_VERTICES)
        object.__setattr__(self, "vertices", count)
        object.__setattr__(self, "radius", _range(self.radius, "convex polygon radius"))
        if self.vertices[0] > 12:
            raise CrmgraspError(f"convex polygon vertices range {self.vertices} must start at 12 or fewer")

    def _shape(self, rng: np.random.Generator) -> Shape:
        n = self.vertices[0] + int(rng.random() * (self.vertices[1] - self.vertices[0] + 1))
        r = _uniform(rng, self.radius)
        min_gap, max_gap = 2.0 * math.asin(0.05), math.radians(150.0)
        for _ in range(MAX_TRIES):
            a = np.sort(rng.random(n) * 2.0 * math.pi)
            gaps = np.diff(np.append(a, a[0] + 2.0 * math.pi))
            if gaps.max() <= max_gap and gaps.min() >= min_gap:
                return Polygon([(r * math.cos(t), r * math.sin(t)) for t in a.tolist()])
        raise CrmgraspError(
            f"convex polygon family: no polygon with {n} vertices met the gap rules in {MAX_TRIES} draws "
            "(too many vertices for the minimum side)"
        )

    def nominal(self) -> Shape:
        return regular_polygon((self.vertices[0] + self.vertices[1]) // 2, _mid(self.radius))

    def min_width(self) -> float:
        # an inscribed polygon containing the centre with margin: a triangle with gaps of at most
        # 150 degrees has width at least that of this isosceles one
        r = self.radius[0]
        t = math.radians(150.0)
        return width(Polygon([(r, 0.0), (r * math.cos(t), r * math.sin(t)), (r * math.cos(-t), r * math.sin(-t))]))


def _check_thickness(kind: str, t: Range, **limits: tuple[Range, float]) -> None:
    """Refuse bars that could reach ``factor`` times the smallest of a dimension."""
    for name, (r, factor) in limits.items():
        if t[1] >= factor * r[0]:
            part = "" if factor == 1.0 else f"{factor:g} x "
            raise CrmgraspError(
                f"{kind} thickness range {t} must stay below {part}the smallest {name} {r[0]}: "
                "thicker bars would give a non-simple polygon"
            )


@dataclass(frozen=True)
class UHandleFamily(_Family):
    """U-shaped handles: outer ``width`` and ``height``, bars of ``thickness``
    (metres); the opening faces +y before the pose. Needs ``2 thickness < width``
    and ``thickness < height`` over the whole ranges."""

    width: Range = (0.16, 0.26)
    height: Range = (0.10, 0.18)
    thickness: Range = (0.03, 0.05)
    pose: Pose = field(default_factory=Pose)
    kind = "u-handle"

    def __post_init__(self) -> None:
        for name in ("width", "height", "thickness"):
            object.__setattr__(self, name, _range(getattr(self, name), f"U handle {name}"))
        _check_thickness("U handle", self.thickness, width=(self.width, 0.5), height=(self.height, 1.0))

    def _u(self, w: float, h: float, t: float) -> Polygon:
        return _poly([(0, 0), (w, 0), (w, h), (w - t, h), (w - t, t), (t, t), (t, h), (0, h)])

    def _shape(self, rng: np.random.Generator) -> Shape:
        return self._u(_uniform(rng, self.width), _uniform(rng, self.height), _uniform(rng, self.thickness))

    def nominal(self) -> Shape:
        return self._u(_mid(self.width), _mid(self.height), _mid(self.thickness))

    def min_width(self) -> float:
        return self.thickness[0]  # a bar, gripped from inside the U and outside


@dataclass(frozen=True)
class LShapeFamily(_Family):
    """L shapes: two arms of length uniform in ``arm`` (drawn independently) and bars
    of ``thickness`` (metres). Needs ``thickness < arm``."""

    arm: Range = (0.12, 0.24)
    thickness: Range = (0.03, 0.06)
    pose: Pose = field(default_factory=Pose)
    kind = "l-shape"

    def __post_init__(self) -> None:
        object.__setattr__(self, "arm", _range(self.arm, "L shape arm"))
        object.__setattr__(self, "thickness", _range(self.thickness, "L shape thickness"))
        _check_thickness("L shape", self.thickness, arm=(self.arm, 1.0))

    def _l(self, a1: float, a2: float, t: float) -> Polygon:
        return _poly([(0, 0), (a1, 0), (a1, t), (t, t), (t, a2), (0, a2)])

    def _shape(self, rng: np.random.Generator) -> Shape:
        return self._l(_uniform(rng, self.arm), _uniform(rng, self.arm), _uniform(rng, self.thickness))

    def nominal(self) -> Shape:
        return self._l(_mid(self.arm), _mid(self.arm), _mid(self.thickness))

    def min_width(self) -> float:
        return self.thickness[0]


@dataclass(frozen=True)
class TShapeFamily(_Family):
    """T shapes: a top bar of ``width``, a total ``height``, bars of ``thickness``
    (metres). Needs ``thickness < width`` and ``thickness < height``."""

    width: Range = (0.14, 0.24)
    height: Range = (0.12, 0.20)
    thickness: Range = (0.03, 0.05)
    pose: Pose = field(default_factory=Pose)
    kind = "t-shape"

    def __post_init__(self) -> None:
        for name in ("width", "height", "thickness"):
            object.__setattr__(self, name, _range(getattr(self, name), f"T shape {name}"))
        _check_thickness("T shape", self.thickness, width=(self.width, 1.0), height=(self.height, 1.0))

    def _t(self, w: float, h: float, t: float) -> Polygon:
        s = t / 2.0
        return _poly(
            [(-s, 0), (s, 0), (s, h - t), (w / 2, h - t), (w / 2, h), (-w / 2, h), (-w / 2, h - t), (-s, h - t)]
        )

    def _shape(self, rng: np.random.Generator) -> Shape:
        return self._t(_uniform(rng, self.width), _uniform(rng, self.height), _uniform(rng, self.thickness))

    def nominal(self) -> Shape:
        return self._t(_mid(self.width), _mid(self.height), _mid(self.thickness))

    def min_width(self) -> float:
        return self.thickness[0]


@dataclass(frozen=True)
class StarFamily(_Family):
    """Stars: ``points`` tips (uniform among its integers) on a circle of radius
    ``outer`` (metres), the notches between them at ``inner`` times that radius."""

    points: tuple[int, int] = (4, 6)
    outer: Range = (0.05, 0.09)
    inner: Range = (0.45, 0.7)
    pose: Pose = field(default_factory=Pose)
    kind = "star"

    def __post_init__(self) -> None:
        points = _range(self.points, "star points", low=3, integer=True, most=MAX_VERTICES // 2)  # 2 vertices a point
        object.__setattr__(self, "points", points)
        object.__setattr__(self, "outer", _range(self.outer, "star outer"))
        inner = _range(self.inner, "star inner")
        if inner[1] >= 1.0:
            raise CrmgraspError(f"star inner range {inner} must stay below 1 (a fraction of the outer radius)")
        object.__setattr__(self, "inner", inner)

    def _star(self, n: int, r: float, f: float) -> Polygon:
        return Polygon(
            [
                (
                    (r if k % 2 == 0 else f * r) * math.cos(math.pi * k / n),
                    (r if k % 2 == 0 else f * r) * math.sin(math.pi * k / n),
                )
                for k in range(2 * n)
            ]
        )

    def _shape(self, rng: np.random.Generator) -> Shape:
        n = self.points[0] + int(rng.random() * (self.points[1] - self.points[0] + 1))
        return self._star(n, _uniform(rng, self.outer), _uniform(rng, self.inner))

    def nominal(self) -> Shape:
        return self._star((self.points[0] + self.points[1]) // 2, _mid(self.outer), _mid(self.inner))

    def min_width(self) -> float:
        return width(self._star(self.points[0], self.outer[0], self.inner[0]))


@dataclass(frozen=True)
class FixedShape(_Family):
    """One polygon of given ``vertices`` ((x, y) in metres), centred on their bounding
    box, posed anew each episode: a family that does not vary in shape (alone, or as a
    member of a [`MixedFamily`][]). Vertex ``i`` of the object is vertex ``i`` of
    ``vertices`` when they are counter-clockwise (clockwise ones are reversed)."""

    vertices: tuple[tuple[float, float], ...]
    pose: Pose = field(default_factory=Pose)
    kind = "polygon"

    def __post_init__(self) -> None:
        try:
            pts = tuple((float(x), float(y)) for x, y in self.vertices)
        except (TypeError, ValueError):
            raise CrmgraspError(f"polygon vertices must be [x, y] pairs of numbers, got {self.vertices!r}") from None
        object.__setattr__(self, "vertices", pts)
        _poly(list(pts))  # the polygon's own checks: finite, at least 3, simple, non-zero area

    def _shape(self, rng: np.random.Generator) -> Shape:
        return _poly(list(self.vertices))

    def nominal(self) -> Shape:
        """The polygon, centred."""
        return _poly(list(self.vertices))

    def min_width(self) -> float:
        return width(self.nominal())


@dataclass(frozen=True)
class MixedFamily:
    """A mixture: member ``i`` with probability ``weights[i] / sum(weights)`` (one
    draw), then that member's draws."""

    members: tuple[Any, ...]
    weights: tuple[float, ...] = ()
    kind = "mixed"

    def __post_init__(self) -> None:
        members = tuple(self.members)
        if not members or not all(isinstance(m, ShapeFamily) for m in members):
            raise CrmgraspError("a mixed family needs one or more member families")
        w = tuple(float(x) for x in (self.weights or [1.0] * len(members)))
        if len(w) != len(members) or not all(math.isfinite(x) and x >= 0 for x in w) or sum(w) <= 0:
            raise CrmgraspError(
                f"mixed family weights must be {len(members)} numbers >= 0 with a positive sum, got {self.weights!r}"
            )
        object.__setattr__(self, "members", members)
        object.__setattr__(self, "weights", w)

    @property
    def pose(self) -> Pose:
        """The first member's pose (each member draws its own)."""
        return self.members[0].pose

    def sample(self, rng: np.random.Generator) -> Shape:
        u = float(rng.random()) * sum(self.weights)
        acc = 0.0
        for m, w in zip(self.members, self.weights, strict=True):
            acc += w
            if u < acc:
                return m.sample(rng)
        return self.members[-1].sample(rng)

    def nominal(self) -> Shape:
        return self.members[int(np.argmax(self.weights))].nominal()

    def min_width(self) -> float:
        return min(m.min_width() for m, w in zip(self.members, self.weights, strict=True) if w > 0)

    def describe(self) -> dict[str, Any]:
        return {"kind": self.kind, "weights": list(self.weights), "members": [m.describe() for m in self.members]}


@dataclass(frozen=True)
class SamplerFamily(_Family):
    """A user's family: ``sampler(rng) -> Shape`` draws the unposed shape, then the
    pose is drawn. ``nominal_shape`` is what scenes show; ``smallest_width`` the
    `min_width` (default: the nominal shape's width)."""

    sampler: Callable[[np.random.Generator], Shape]
    nominal_shape: Shape
    smallest_width: float | None = None
    pose: Pose = field(default_factory=Pose)
    kind = "sampler"

    def __post_init__(self) -> None:
        if not callable(self.sampler):
            raise CrmgraspError(f"a sampler family needs a callable sampler(rng) -> Shape, got {self.sampler!r}")
        if not isinstance(self.nominal_shape, (Polygon, Disc)):
            raise CrmgraspError(f"nominal_shape must be a Polygon or Disc, got {self.nominal_shape!r}")

    def _shape(self, rng: np.random.Generator) -> Shape:
        s = self.sampler(rng)
        if not isinstance(s, (Polygon, Disc)):
            raise CrmgraspError(f"the family's sampler returned {type(s).__name__}, not a Polygon or Disc")
        return s

    def nominal(self) -> Shape:
        return self.nominal_shape

    def min_width(self) -> float:
        return width(self.nominal_shape) if self.smallest_width is None else float(self.smallest_width)

    def describe(self) -> dict[str, Any]:
        return {"kind": self.kind, "sampler": getattr(self.sampler, "__qualname__", repr(self.sampler))}

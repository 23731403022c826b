"""Families of spatial objects on a table: one solid per episode (docs/model-3d.md section 6).

The table is the plane ``z = 0``; every object rests on it. A family draws the object's
dimensions from ranges, then a pose from a [`Pose`][crmgrasp.model.families.Pose]: a
rotation about the vertical axis by the pose's angle (a yaw) and a horizontal
translation. Ranges are checked as for the planar families (one line naming the
parameter).

* [`BoxOnTable`][]: a box of random length, width and height resting on a face with
  a random yaw (drawing all three dimensions covers which face is down): ``Box3D``.
* [`CylinderOnTable`][]: a closed cylinder of random radius and height, upright
  (axis vertical) with probability ``upright``, else lying on its side: ``Cup3D``.
* [`OpenCupOnTable`][]: an open cup ([`open_cup`][crmgrasp.model.mesh.open_cup], a
  triangle mesh: not convex) of random radius and height, upright with probability
  ``upright`` (the opening up), else lying on its side (the opening to the side):
  ``OpenCup3D``.

Each has ``sample(rng)``, ``nominal()`` (the middle of every range, unposed),
``min_width()`` (the smallest distance across any object it draws: the narrowest span
a pinch must reach, compared with the hand's aperture) and ``describe()``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Protocol, runtime_checkable

import numpy as np

from crmgrasp._validation import CrmgraspError
from crmgrasp.model.family_base import Pose, Range, _at, _mid, _range, _uniform, family_dict
from crmgrasp.model.mesh import TriangleMesh, open_cup
from crmgrasp.model.solids import Cylinder, Solid, box3d, rotation_z

__all__ = ["SolidFamily", "BoxOnTable", "CylinderOnTable", "OpenCupOnTable"]


@runtime_checkable
class SolidFamily(Protocol):
    """A distribution over spatial objects on the table."""

    def sample(self, rng: np.random.Generator) -> Solid | TriangleMesh: ...

    def nominal(self) -> Solid | TriangleMesh: ...

    def min_width(self) -> float: ...

    def describe(self) -> dict[str, Any]: ...


def _placed(solid: Solid, rng: np.random.Generator, pose: Pose) -> Solid:
    return solid.yawed(*pose.draw(rng))


def _upright(value: Any) -> float:
    """A checked probability of drawing an object upright."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0.0 <= value <= 1.0:
        raise CrmgraspError(f"upright must be a probability in [0, 1], got {value!r}")
    return float(value)


def _table_pose() -> Pose:
    return Pose(angle=(0.0, 2.0 * math.pi), offset=(-0.02, 0.02))


@dataclass(frozen=True)
class BoxOnTable:
    """Boxes ``length x width x height`` (metres) on the table, centred on the pose's
    offset, turned by its yaw. Draws: length, width, height, then the pose (3)."""

    length: Range = (0.15, 0.30)
    width: Range = (0.06, 0.12)
    height: Range = (0.06, 0.20)
    pose: Pose = field(default_factory=_table_pose)

    def __post_init__(self) -> None:
        for name in ("length", "width", "height"):
            object.__setattr__(self, name, _range(getattr(self, name), f"box {name}"))

    @staticmethod
    def _box(length: float, width: float, height: float) -> Solid:
        return box3d((-length / 2, -width / 2, 0.0), (length / 2, width / 2, height))

    def sample(self, rng: np.random.Generator) -> Solid:
        u = rng.random(6).tolist()  # the stream of six single draws, in one call
        box = self._box(_at(self.length, u[0]), _at(self.width, u[1]), _at(self.height, u[2]))
        return box.yawed(*self.pose.at(*u[3:]))

    def nominal(self) -> Solid:
        return self._box(_mid(self.length), _mid(self.width), _mid(self.height))

    def min_width(self) -> float:
        return min(self.length[0], self.width[0], self.height[0])

    def describe(self) -> dict[str, Any]:
        return family_dict("box3d", self)


@dataclass(frozen=True)
class CylinderOnTable:
    """Closed cylinders (the cup without its opening) of radius ``radius`` and height
    ``height`` (metres): upright with probability ``upright``, else lying on the table
    along the pose's yaw. Draws: radius, height, the upright coin, then the pose (3)."""

    radius: Range = (0.03, 0.07)
    height: Range = (0.06, 0.20)
    upright: float = 0.5
    pose: Pose = field(default_factory=_table_pose)

    def __post_init__(self) -> None:
        object.__setattr__(self, "radius", _range(self.radius, "cylinder radius"))
        object.__setattr__(self, "height", _range(self.height, "cylinder height"))
        object.__setattr__(self, "upright", _upright(self.upright))

    @staticmethod
    def _cylinder(radius: float, height: float, upright: bool) -> Solid:
        if upright:
            return Cylinder((0.0, 0.0, 0.0), (0.0, 0.0, 1.0), radius, height)
        return Cylinder((-height / 2, 0.0, radius), (1.0, 0.0, 0.0), radius, height)

    def sample(self, rng: np.random.Generator) -> Solid:
        radius, height = _uniform(rng, self.radius), _uniform(rng, self.height)
        upright = float(rng.random()) < self.upright
        return _placed(self._cylinder(radius, height, upright), rng, self.pose)

    def nominal(self) -> Solid:
        return self._cylinder(_mid(self.radius), _mid(self.height), self.upright >= 0.5)

    def min_width(self) -> float:
        return min(2.0 * self.radius[0], self.height[0])

    def describe(self) -> dict[str, Any]:
        return family_dict("cylinder", self)


_LYING = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])
"""The rotation about ``y`` that turns a cup's axis ``+z`` to ``+x`` (its opening to the side)."""


@dataclass(frozen=True)
class OpenCupOnTable:
    """Open cups ([`open_cup`][crmgrasp.model.mesh.open_cup]) of outer radius ``radius`` and
    height ``height`` (metres), walls and bottom ``wall`` thick, their circles ``segments``-gons:
    upright with probability ``upright`` (the opening up), else lying on the table with the
    opening along the pose's yaw. Draws: radius, height, the upright coin, then the pose (3),
    as [`CylinderOnTable`][].

    A lying cup is the upright one turned by a quarter turn about ``y`` (its axis from ``+z``
    to ``+x``), moved so that its axis lies at height ``radius`` from ``x = -height / 2`` to
    ``height / 2``, then turned by the yaw and moved by the offset.

    >>> cup = OpenCupOnTable(upright=0.0).sample(np.random.default_rng(0))
    >>> round(cup.support((0.0, 0.0, 1.0)), 12)  # its lowest point is on the table
    0.0
    >>> bool(cup.contains(cup.centre))  # the centre of volume lies in the cavity, not in the material
    False
    """

    radius: Range = (0.03, 0.07)
    height: Range = (0.06, 0.20)
    wall: float = 0.005
    upright: float = 0.5
    segments: int = 24
    pose: Pose = field(default_factory=_table_pose)

    def __post_init__(self) -> None:
        object.__setattr__(self, "radius", _range(self.radius, "open cup radius"))
        object.__setattr__(self, "height", _range(self.height, "open cup height"))
        object.__setattr__(self, "upright", _upright(self.upright))
        thinnest = min(self.radius[0], self.height[0])
        w = self.wall
        if isinstance(w, bool) or not isinstance(w, (int, float)) or not 0.0 < w < thinnest:
            raise CrmgraspError(
                f"open cup wall must be a number in (0, {thinnest:g}) m (below the least radius and height), got {w!r}"
            )
        object.__setattr__(self, "wall", float(w))
        open_cup(self.radius[0], self.height[0], self.wall, self.segments)  # the segments' one-line error, early

    def _cup(self, radius: float, height: float, upright: bool, angle: float, dx: float, dy: float) -> TriangleMesh:
        yaw = rotation_z(angle)
        if upright:
            return open_cup(radius, height, self.wall, self.segments, yaw, (dx, dy, 0.0))
        lift = yaw @ np.array([-height / 2, 0.0, radius]) + np.array([dx, dy, 0.0])
        return open_cup(radius, height, self.wall, self.segments, yaw @ _LYING, lift)

    def sample(self, rng: np.random.Generator) -> TriangleMesh:
        radius, height = _uniform(rng, self.radius), _uniform(rng, self.height)
        upright = float(rng.random()) < self.upright
        return self._cup(radius, height, upright, *self.pose.draw(rng))

    def nominal(self) -> TriangleMesh:
        return self._cup(_mid(self.radius), _mid(self.height), self.upright >= 0.5, 0.0, 0.0, 0.0)

    def min_width(self) -> float:
        return min(2.0 * self.radius[0], self.height[0])

    def describe(self) -> dict[str, Any]:
        return family_dict("open_cup", self)

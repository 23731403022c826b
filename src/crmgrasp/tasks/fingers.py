"""Tasks for a hand with three fingers, each beside its two-finger peer (docs/model.md
section 8).

Both hands of a pair are the paper's (aperture 0.16 m, palm depth 0.12 m), on the same
family and with the same goal, ``mu_goal = 0.15`` (a hard fingertip): the pair measures
what the third contact buys.

* ``triangles`` / ``triangles-3f``: equilateral triangles, circumradius 0.04-0.08 m, in
  any pose. Two contacts need friction ``tan 30 deg = 0.577`` at best, so no two-finger
  start can reach the goal; three contacts whose normals meet close with any friction.
* ``odd-polygons`` / ``odd-polygons-3f``: regular 3-, 5- and 7-gons, equally likely (two
  contacts need ``tan(90 deg / n)``: 0.577, 0.325, 0.228).
* ``box-family-3f`` and ``cup-family-3f``: the boxes of ``box-family`` and the discs of
  ``cup-family`` with three fingers, at their two-finger twins' goal (0.05). Their twins keep
  their own CRMs and starts (the paper's CRMs and corner starts on boxes).

The two-finger tasks take [`default_crms`][crmgrasp.tasks.families.default_crms] and
[`BoundaryStarts`][crmgrasp.tasks.families.BoundaryStarts]; the three-finger tasks take
[`finger_crms`][] (12: six oppositions, six 0.03 m slides), [`FINGER_BINS`][] and
[`UniformStarts`][crmgrasp.tasks.starts.UniformStarts] (three contacts anywhere on the
boundary, resampled until feasible and not a grasp). Both declare the mirror symmetry
(labels reversed).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

from crmgrasp._validation import listed, positive
from crmgrasp.model.contact_model import observation_names
from crmgrasp.model.families import BoxFamily, DiscFamily, MixedFamily, RegularPolygonFamily, ShapeFamily
from crmgrasp.model.hand import CRM, Hand
from crmgrasp.model.sensing import Discretizer
from crmgrasp.tasks.core import PAPER_HAND, Task, register_task
from crmgrasp.tasks.families import family_task
from crmgrasp.tasks.starts import UniformStarts

__all__ = ["FINGER_BINS", "FINGER_TASKS", "HARD_TIP", "THREE_FINGERS", "finger_crms", "three_finger_task"]

HARD_TIP = 0.15
"""``mu_goal`` of the finger tasks: a hard fingertip, below every two-contact grasp of an
odd regular polygon with up to 7 sides."""

THREE_FINGERS: Hand = replace(PAPER_HAND, contacts=3)
"""The paper's hand with a third finger (aperture 0.16 m, palm depth 0.12 m)."""


def finger_crms(labels: Sequence[str] = ("a", "b", "c"), offsets: Sequence[float] = (0.03,)) -> tuple[CRM, ...]:
    """Every opposition ``(c, f, 0)`` over ordered pairs of distinct contacts, then per
    contact and offset ``d`` the slides ``(c, c, d)`` and ``(c, c, -d)``.

    >>> len(finger_crms())
    12
    """
    labels, offsets = listed(labels, "labels"), listed(offsets, "CRM offsets")
    out = [CRM(c, f, 0.0) for c in labels for f in labels if c != f]
    for c in labels:
        for d in offsets:
            d = positive(d, "CRM offset")
            out += [CRM(c, c, d), CRM(c, c, -d)]
    return tuple(out)


FINGER_BINS = Discretizer(
    names=observation_names(THREE_FINGERS.labels), rho=(1.0,), m_a=(0.04,), m_b=(0.04,), m_c=(0.04,)
)
"""The three-finger tasks' bins: ``rho >= 1`` and each moment's magnitude at 0.04 m (the
objects are at most 0.16 m across; of moment thresholds 0.02, 0.04 and 0.10 m, 0.04 gives
the lowest belief-space optimum on ``triangles-3f``: 3.28 CRMs against 3.40 and 3.65 over
200 starts)."""


def three_finger_task(name: str, family: ShapeFamily, description: str, mu_goal: float = HARD_TIP) -> Task:
    """A [`family_task`][crmgrasp.tasks.families.family_task] with [`THREE_FINGERS`][],
    [`finger_crms`][], [`FINGER_BINS`][] and uniform starts (``mu_goal``: [`HARD_TIP`][] by
    default)."""
    return family_task(
        name,
        family,
        hand=THREE_FINGERS,
        actions=finger_crms(THREE_FINGERS.labels),
        discretizer=FINGER_BINS,
        starts=UniformStarts(),
        mu_goal=mu_goal,
        description=description,
    )


def _triangles() -> RegularPolygonFamily:
    return RegularPolygonFamily(sides=(3, 3), radius=(0.04, 0.08))


def _odd() -> MixedFamily:
    return MixedFamily(tuple(RegularPolygonFamily(sides=(n, n), radius=(0.04, 0.08)) for n in (3, 5, 7)))


_TRIANGLES = "equilateral triangles, radius 0.04-0.08 m, any pose; success at friction 0.15"
_ODD = "regular 3-, 5- and 7-gons, radius 0.04-0.08 m, any pose; success at friction 0.15"

FINGER_TASKS = {
    "triangles": lambda: family_task("triangles", _triangles(), mu_goal=HARD_TIP, description=_TRIANGLES),
    "triangles-3f": lambda: three_finger_task("triangles-3f", _triangles(), _TRIANGLES),
    "odd-polygons": lambda: family_task("odd-polygons", _odd(), mu_goal=HARD_TIP, description=_ODD),
    "odd-polygons-3f": lambda: three_finger_task("odd-polygons-3f", _odd(), _ODD),
    "box-family-3f": lambda: three_finger_task(
        "box-family-3f", BoxFamily(), "boxes 0.20-0.40 x 0.06-0.14 m in any pose; success at friction 0.05", 0.05
    ),
    "cup-family-3f": lambda: three_finger_task(
        "cup-family-3f", DiscFamily(), "discs of radius 0.03-0.07 m (the planar cup); success at friction 0.05", 0.05
    ),
}
"""Registered finger tasks: name -> factory."""

for _name, _factory in FINGER_TASKS.items():
    register_task(_name, _factory, overwrite=True)

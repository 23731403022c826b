"""Tasks on object families: starts for any shape, a default CRM set, the registry.

* [`BoundaryStarts`][]: the general start sampler. Contact one uniform in arclength
  on the boundary (or on the part of it within ``near_vertex`` of a vertex), contact
  two uniform in arclength on the boundary points within the hand's aperture of it
  (the same region), a fair coin for which is ``a``; redrawn until the start rule
  holds (feasible and not already a grasp), at most ``max_tries`` times. Vertices
  themselves (no normal) are never drawn.
* [`default_crms`][]: oppose either contact, and slide either contact by each
  offset in both directions: ``2 + 4 len(offsets)`` CRMs.
* [`mirror_symmetry`][]: the action permutation of a CRM set under the mirror
  (``(c, f, r) -> (c', f', -r)``), for families whose distribution of objects and
  starts is mirror-invariant (every family here: each draws reflection-invariant
  shapes, or shapes whose mirror images are drawn with the same density).
* the registered family tasks: ``box-family`` (the paper's hand, CRMs and corner
  starts on a random box), ``cup-family`` (discs), ``polygon-family`` (regular and
  random convex polygons), ``u-handle``, ``l-shape``, ``t-shape``, ``star`` and
  ``mixed`` (boxes, discs, polygons, U handles and L shapes), and ``notch-or-box``
  (two objects alike at the touched corner: the cost-of-failure task). Success is the paper's
  ``mu_goal = 0.05`` except where shapes without parallel sides occur
  (``polygon-family``, ``star``, ``mixed``): [`RUBBER`][].
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import ClassVar

import numpy as np

from crmgrasp._validation import CrmgraspError, listed, positive, tries
from crmgrasp.model.contacts import LABELS, Config, Contact
from crmgrasp.model.families import (
    BoxFamily,
    ConvexPolygonFamily,
    DiscFamily,
    FixedShape,
    LShapeFamily,
    MixedFamily,
    RegularPolygonFamily,
    ShapeFamily,
    StarFamily,
    TShapeFamily,
    UHandleFamily,
    check_family,
)
from crmgrasp.model.geometry import Disc, Polygon, Shape
from crmgrasp.model.hand import CRM, Hand
from crmgrasp.model.planar_model import mirror_crm
from crmgrasp.model.sensing import Discretizer
from crmgrasp.tasks.core import PAPER_BINS, PAPER_CRMS, PAPER_HAND, Task, register_task
from crmgrasp.tasks.presets import VertexStarts
from crmgrasp.tasks.starts import CornerStarts, StartSampler, acceptable
from crmgrasp.tasks.symmetry import Symmetry, symmetry_of

__all__ = [
    "BoundaryStarts",
    "default_crms",
    "mirror_symmetry",
    "family_task",
    "FAMILY_TASKS",
]

Interval = tuple[int, float, float]  # edge (or -1 for a disc), parameter from, parameter to


def _edge_intervals(obj: Polygon, near_vertex: float | None) -> list[Interval]:
    """Parameter intervals of each edge in the region (the whole edge, or its ends
    within ``near_vertex`` of a vertex)."""
    out: list[Interval] = []
    for i, (_, _, _, _, l2, _, _) in enumerate(obj.edges):
        if near_vertex is None:
            out.append((i, 0.0, 1.0))
            continue
        f = min(0.5, near_vertex / math.sqrt(l2))
        out += [(i, 0.0, f), (i, 1.0 - f, 1.0)]
    return out


def _within(obj: Polygon, iv: list[Interval], px: float, py: float, reach: float) -> list[Interval]:
    """The parts of the intervals ``iv`` within ``reach`` of ``(px, py)``:
    ``|a + t e - p|^2 <= reach^2`` is a quadratic inequality in ``t``."""
    out: list[Interval] = []
    for i, t0, t1 in iv:
        ax, ay, ex, ey, l2, _, _ = obj.edges[i]
        b = ex * (ax - px) + ey * (ay - py)
        c = (ax - px) ** 2 + (ay - py) ** 2 - reach * reach
        disc = b * b - l2 * c
        if disc < 0.0:
            continue
        r = math.sqrt(disc)
        lo, hi = max(t0, (-b - r) / l2), min(t1, (-b + r) / l2)
        if hi > lo:
            out.append((i, lo, hi))
    return out


def _pick(obj: Polygon, iv: list[Interval], u: float) -> Contact | None:
    """The point at fraction ``u`` of the intervals' total length (``None`` if they are
    empty or it is a vertex)."""
    lengths = [(t1 - t0) * math.sqrt(obj.edges[i][4]) for i, t0, t1 in iv]
    total = sum(lengths)
    if total <= 0.0:
        return None
    x = u * total
    for (i, t0, t1), length in zip(iv, lengths, strict=True):
        if 0.0 < length and x < length:
            edge, t = i, t0 + (t1 - t0) * (x / length)
            break
        x -= length
    else:
        return None  # rounding put x at the very end
    if t <= 0.0 or t >= 1.0:
        return None
    ax, ay, ex, ey, _, nx, ny = obj.edges[edge]
    return Contact(ax + t * ex, ay + t * ey, nx, ny)


def _disc_contact(d: Disc, theta: float) -> Contact:
    c, s = math.cos(theta), math.sin(theta)
    return Contact(d.center[0] + d.radius * c, d.center[1] + d.radius * s, -c, -s)


@dataclass(frozen=True)
class BoundaryStarts:
    """The general start sampler (see the module docstring). Each attempt draws three
    uniforms: where contact one is, where contact two is, the coin.

    Parameters
    ----------
    near_vertex
        Restrict both contacts to within this distance (metres, along the sides) of a
        polygon vertex, or None for the whole boundary.
    max_tries
        Attempts before giving up with an error naming the object.
    """

    near_vertex: float | None = None
    max_tries: int = 10_000
    kind: ClassVar[str] = "boundary"

    def __post_init__(self) -> None:
        object.__setattr__(self, "max_tries", tries(self.max_tries))
        if self.near_vertex is not None:
            object.__setattr__(self, "near_vertex", positive(self.near_vertex, "near_vertex"))

    def candidate(self, obj: Shape, reach: float, u: Sequence[float]) -> Config | None:
        """The candidate of three uniforms ``u`` (``None`` where a draw has no point)."""
        p: Contact | None
        q: Contact | None
        if isinstance(obj, Disc):
            if self.near_vertex is not None:
                raise CrmgraspError("near_vertex starts need a polygon, got a Disc")
            first = 2.0 * math.pi * u[0]
            spread = 2.0 * math.asin(min(1.0, reach / (2.0 * obj.radius)))
            p, q = _disc_contact(obj, first), _disc_contact(obj, first + spread * (2.0 * u[1] - 1.0))
        elif isinstance(obj, Polygon):
            region = _edge_intervals(obj, self.near_vertex)
            p = _pick(obj, region, u[0])
            if p is None:
                return None
            q = _pick(obj, _within(obj, region, p.x, p.y, reach), u[1])
            if q is None:
                return None
        else:
            raise CrmgraspError(f"boundary starts need a Polygon or Disc, got {type(obj).__name__}")
        assert p is not None and q is not None
        return Config(p, q) if u[2] < 0.5 else Config(q, p)

    def __call__(self, obj: Shape, hand: Hand, mu_goal: float, rng: np.random.Generator) -> Config:
        for _ in range(self.max_tries):
            cfg = self.candidate(obj, hand.aperture, rng.random(3).tolist())
            if cfg is not None and acceptable(obj, hand, mu_goal, cfg):
                return cfg
        raise CrmgraspError(
            f"no feasible boundary start found in {self.max_tries} tries on {obj!r} "
            "(is the object wider than the aperture everywhere?)"
        )


def default_crms(offsets: Sequence[float] = (0.04, 0.08)) -> tuple[CRM, ...]:
    """``(a,b,0)``, ``(b,a,0)``, then for each offset ``d``: ``(a,a,d)``, ``(b,b,-d)``,
    ``(a,a,-d)``, ``(b,b,d)`` (mirror pairs next to each other)."""
    out = [CRM("a", "b", 0.0), CRM("b", "a", 0.0)]
    for d in listed(offsets, "CRM offsets"):
        d = positive(d, "CRM offset")
        out += [CRM("a", "a", d), CRM("b", "b", -d), CRM("a", "a", -d), CRM("b", "b", d)]
    return tuple(out)


def mirror_symmetry(actions: Sequence[CRM], labels: tuple[str, ...] = LABELS) -> Symmetry:
    """The [`Symmetry`][] mapping each CRM to its mirror ``(c', f', -r)`` in ``actions``
    (primes: the hand's ``labels`` reversed); an error if some CRM's mirror is not in the
    set ([`symmetry_of`][crmgrasp.tasks.core.symmetry_of])."""
    return symmetry_of(actions, lambda a: mirror_crm(a, labels))


RUBBER = 0.6
"""``mu_goal`` of the families with polygons that have no parallel sides (a triangle's
best two-contact grasp needs friction tan 30 deg = 0.577): a rubber fingertip."""


def family_task(
    name: str,
    family: ShapeFamily,
    *,
    actions: Sequence[CRM] | None = None,
    starts: StartSampler | None = None,
    hand: Hand = PAPER_HAND,
    discretizer: Discretizer = PAPER_BINS,
    symmetric: bool = True,
    description: str = "",
    **kwargs: object,
) -> Task:
    """A task on ``family`` with the paper's hand and bins by default, the
    [`default_crms`][], [`BoundaryStarts`][] and the mirror symmetry."""
    acts = listed(actions, "actions", "a sequence of CRMs") if actions is not None else default_crms()
    task = Task(
        name=name,
        obj=check_family(family).nominal(),
        hand=hand,
        actions=acts,
        discretizer=discretizer,
        starts=starts if starts is not None else BoundaryStarts(),
        family=family,
        description=description,
        **kwargs,  # type: ignore[arg-type]
    )  # its CRMs checked before their mirror images are looked up
    return replace(task, symmetry=mirror_symmetry(task.actions, hand.labels)) if symmetric else task


def _box_family() -> Task:
    return family_task(
        "box-family",
        BoxFamily(),
        actions=PAPER_CRMS,
        starts=CornerStarts(),
        reference_mean_steps=1.75,  # belief-space optimum over 500 sampled worlds (docs/families.md)
        description="boxes 0.20-0.40 x 0.06-0.14 m in any pose; the paper's hand, CRMs and corner starts",
    )


NOTCHED_BLOCK = ((0.0, 0.0), (0.04, 0.0), (0.04, -0.05), (0.14, -0.05), (0.14, 0.20), (0.0, 0.20))
"""A 0.14 x 0.25 m block with a 0.04 x 0.05 m notch cut from one corner; vertex 0 is the
notch's outer corner, which looks like a box corner to two contacts near it."""

PROBE_SLIDE = 0.06
"""Slide of ``notch-or-box`` (metres): from a contact within 0.035 m of the corner, past
the notch (0.04 m) and short of the box's far end."""


def _notch_or_box() -> Task:
    """The cost-of-failure task (docs/families.md): a corner of a 0.30 x 0.10 m box (4 in
    5 episodes) or of a notched block (1 in 5), touched near vertex 0 with the labels
    fixed. Opposing across (C1) grasps the box and errs on the block (0.25 m > the
    aperture); opposing along (C2) grasps the block and errs on the box (0.30 m); sliding
    the bottom contact past the notch (C5) errs on neither and puts the block's contact
    0.05 m lower, which the moment about b shows (bins at 0.05 m)."""
    shapes = FixedShape(((0.0, 0.0), (0.30, 0.0), (0.30, 0.10), (0.0, 0.10))), FixedShape(NOTCHED_BLOCK)
    s = PROBE_SLIDE
    return family_task(
        "notch-or-box",
        MixedFamily(shapes, (4.0, 1.0)),
        actions=(
            CRM("a", "b", 0.0),
            CRM("b", "a", 0.0),
            CRM("a", "a", s),
            CRM("a", "a", -s),
            CRM("b", "b", s),
            CRM("b", "b", -s),
        ),
        starts=VertexStarts(0, incoming=(0.005, 0.045), outgoing=(0.005, 0.035)),
        discretizer=Discretizer(rho=(1.0,), m_a=(0.05,), m_b=(0.05,)),
        symmetric=False,
        description="a box corner (4 in 5) or a notched block's (1 in 5), alike to the touch; fixed handedness",
    )


def _polygons() -> MixedFamily:
    return MixedFamily((RegularPolygonFamily(), ConvexPolygonFamily()))


FAMILY_TASKS = {
    "box-family": _box_family,
    "cup-family": lambda: family_task(
        "cup-family",
        DiscFamily(),
        reference_mean_steps=1.0,  # one opposition grasps every disc
        description="discs of radius 0.03-0.07 m (the planar cup)",
    ),
    "polygon-family": lambda: family_task(
        "polygon-family",
        _polygons(),
        mu_goal=RUBBER,
        description="regular 3-8-gons and random convex polygons, radius 0.04-0.08 m; success at friction 0.6",
    ),
    "u-handle": lambda: family_task(
        "u-handle", UHandleFamily(), description="U handles 0.16-0.26 x 0.10-0.18 m, bars 0.03-0.05 m"
    ),
    "l-shape": lambda: family_task(
        "l-shape", LShapeFamily(), description="L shapes, arms 0.12-0.24 m, bars 0.03-0.06 m"
    ),
    "t-shape": lambda: family_task("t-shape", TShapeFamily(), description="T shapes 0.14-0.24 x 0.12-0.20 m"),
    "star": lambda: family_task(
        "star", StarFamily(), mu_goal=RUBBER, description="stars with 4-6 points, radius 0.05-0.09 m; friction 0.6"
    ),
    "notch-or-box": _notch_or_box,
    "mixed": lambda: family_task(
        "mixed",
        MixedFamily((BoxFamily(), DiscFamily(), _polygons(), UHandleFamily(), LShapeFamily())),
        mu_goal=RUBBER,
        description="boxes, discs, polygons, U handles and L shapes, equally likely; success at friction 0.6",
    ),
}
"""Registered family tasks: name -> factory."""

for _name, _factory in FAMILY_TASKS.items():
    register_task(_name, _factory, overwrite=True)

"""Spatial tasks: the hand grasping a solid on a table by 3-D CRMs (docs/model-3d.md).

A [`SpatialTask`][] is a [`Task`][crmgrasp.tasks.Task] whose world is the spatial
model's: a solid ([`crmgrasp.model.solids`][]) or a family of solids on the table
([`crmgrasp.model.solid_families`][]), the [`Hand3D`][crmgrasp.model.spatial.Hand3D],
[`CRM3D`][crmgrasp.model.spatial.CRM3D] actions and [`Config3D`][crmgrasp.model.spatial.Config3D]
configurations. It holds the spatial contact model
([`SpatialModel`][crmgrasp.model.spatial_model.SpatialModel]), through which the task's rule
methods (``crm``, ``execute``, ``read``, ``observe``, ``quality``, ``check_config``) run, so
the one episode loop ([`crmgrasp.sim`][]), the learners, the references and the environments
step it unchanged. What the agent sees is the planar model's: ``rho``, ``|m_a|``,
``|m_b|`` in the same bins (24 discretized observations) and the error flag.

Registered tasks: ``box-3d`` (``crmgrasp/Box3D-v0``), ``cup-3d`` (``crmgrasp/Cup3D-v0``), the
open cups of ``open-cup-3d`` (``crmgrasp/OpenCup3D-v0``: a triangle mesh, not convex, on the
readable rules), and the tripods ``box-3d-3f`` and ``cup-3d-3f`` (``crmgrasp/Box3D3F-v0``,
``crmgrasp/Cup3D3F-v0``: a third finger, [`tripod_crms`][], [`TRIPOD_BINS`][]; the same
families and goal; docs/model-3d.md section 9).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import Any, ClassVar

import numpy as np

from crmgrasp._validation import CrmgraspError, finite, listed, positive, tries
from crmgrasp.model.contact_model import observation_names
from crmgrasp.model.hand import Error
from crmgrasp.model.sensing import Discretizer
from crmgrasp.model.solid_families import BoxOnTable, CylinderOnTable, OpenCupOnTable, SolidFamily
from crmgrasp.model.solids import Solid, dot, surface_point
from crmgrasp.model.spatial import CRM3D, Contacts3D, Hand3D, check_solid, config3d
from crmgrasp.model.spatial_model import SpatialModel, contact3d
from crmgrasp.tasks.core import PAPER_BINS, Task, register_task
from crmgrasp.tasks.symmetry import Symmetry, symmetry_of

__all__ = [
    "SpatialTask",
    "SurfaceStarts",
    "spatial_crms",
    "spatial_symmetry",
    "mirrored",
    "MIRROR_INVARIANT",
    "SPATIAL_HAND",
    "TRIPOD_HAND",
    "TRIPOD_BINS",
    "tripod_crms",
    "box_3d",
    "cup_3d",
    "open_cup_3d",
    "box_3d_3f",
    "cup_3d_3f",
    "SPATIAL_TASKS",
]

SPATIAL_HAND = Hand3D(aperture=0.16, palm_depth=0.12, backoff=0.01)
"""The paper's hand in space: aperture 0.16 m, palm depth 0.12 m, vertical axis z."""


TRIPOD_HAND = replace(SPATIAL_HAND, contacts=3)
"""The spatial hand with a third finger (aperture 0.16 m, palm depth 0.12 m)."""

TRIPOD_BINS = Discretizer(
    names=observation_names(TRIPOD_HAND.labels), rho=(1.0,), m_a=(0.04,), m_b=(0.04,), m_c=(0.04,)
)
"""The tripod tasks' bins: ``rho >= 1`` and each moment's magnitude at 0.04 m (the planar
three-finger tasks' bins; 32 observations with the error flag's)."""


def tripod_crms(labels: Sequence[str] = ("a", "b", "c"), lateral: float = 0.03) -> tuple[CRM3D, ...]:
    """The tripod CRMs (18 for three contacts): every opposition ``(c, f, (r_1, 0))`` over
    ordered pairs of distinct contacts, with ``r_1`` in ``0, +lateral, -lateral`` (metres,
    along ``f``'s horizontal tangent ``t_1``).

    Why lateral offsets rather than slides: a tripod's low-friction grasp puts the three
    contacts in one plane with normals that meet (on a cup's side: one height, normals
    through the axis). An opposition onto a contact's line lands at that contact's height;
    with a lateral offset it lands beside the antipode instead of on it, so two CRMs bring
    all three contacts to one height. Of 30 starts each (``python benchmarks/tripod_crms.py``),
    two of these CRMs grasp 30 on ``cup-3d-3f`` and 28 on ``box-3d-3f``, against 13 and 18
    with six centred oppositions and twelve 0.05 m slides (docs/model-3d.md section 9).

    >>> len(tripod_crms())
    18
    """
    d, labels = positive(lateral, "lateral offset"), listed(labels, "labels")
    return tuple(CRM3D(c, f, (r, 0.0)) for c in labels for f in labels if c != f for r in (0.0, d, -d))


def spatial_crms(step: float = 0.05) -> tuple[CRM3D, ...]:
    """The default 3-D CRM set (10): oppose ``a`` onto ``b``'s line, oppose ``b`` onto
    ``a``'s; slide each contact by ``step`` metres along ``+-t_1`` (horizontal) and
    ``+-t_2`` (up or down the face) of its own tangent frame."""
    step = positive(step, "CRM step")
    slides = ((step, 0.0), (-step, 0.0), (0.0, step), (0.0, -step))
    return (
        CRM3D("a", "b", (0.0, 0.0)),
        CRM3D("b", "a", (0.0, 0.0)),
        *(CRM3D("a", "a", r) for r in slides),
        *(CRM3D("b", "b", r) for r in slides),
    )


@dataclass(frozen=True)
class SurfaceStarts:
    """Spatial starts: each contact is the radial projection ([`surface_point`][crmgrasp.model.solids.surface_point])
    of a direction drawn uniformly on the sphere (three standard normals, normalised),
    contacts in label order; the contacts are resampled together until feasible (within
    the aperture, palm clear, no contact on the table), not already a grasp, and not all on
    surfaces facing up (inward normals ``n . h <= -up``, default within 60 degrees of
    straight down): from there no CRM leaves the top, since every goal line is vertical
    and an opposition would have to come from under the table. Draws per try: three
    standard normals per contact (six for two)."""

    max_tries: int = 10_000
    up: float = 0.5
    kind: ClassVar[str] = "surface"

    def __post_init__(self) -> None:
        object.__setattr__(self, "max_tries", tries(self.max_tries))
        up = finite(self.up, "starts.up")
        if not -1.0 <= up <= 1.0:
            raise CrmgraspError(f"starts.up is a cosine and must be in [-1, 1], got {up:g}")
        object.__setattr__(self, "up", up)

    def __call__(self, task: SpatialTask, rng: np.random.Generator, accept: Any = None) -> Contacts3D:
        """A start on ``task``'s object; ``accept`` (a compiled decision of one try's
        directions, given by a kernel) makes the same decisions, so the stream is the same."""
        h, n = task.hand3d._h, task.model.n_contacts
        for _ in range(self.max_tries):
            d = rng.standard_normal((n, 3))
            if accept is not None:
                got = accept(d)
                if got is not None:
                    return got  # type: ignore[no-any-return]
                continue
            if np.any(np.linalg.norm(d, axis=1) == 0.0):
                continue
            hits = [surface_point(task.solid, di) for di in d]
            if any(hit is None for hit in hits):
                continue
            cfg = config3d([contact3d(*hit) for hit in hits])  # type: ignore[misc]
            all_on_top = all(dot(c.n, h) <= -self.up for c in cfg)
            if not all_on_top and task.acceptable(cfg):
                return cfg
        raise CrmgraspError(f"no feasible surface start found in {self.max_tries} tries")


@dataclass(frozen=True)
class SpatialTask(Task):
    """A task in the spatial model. Fields as [`Task`][crmgrasp.tasks.Task], with ``obj`` a
    solid ([`Solid`][crmgrasp.model.solids.Solid]), ``hand`` a [`Hand3D`][], ``actions``
    [`CRM3D`][], ``starts`` a [`SurfaceStarts`][], ``family`` a
    [`SolidFamily`][crmgrasp.model.solid_families.SolidFamily], and ``table`` the height of the
    table plane (metres; ``None``: no table). Success: ``min_friction_3d <= mu_goal``
    (two point contacts never close a spatial grasp; the squeeze is what they hold)."""

    starts: Any = field(default_factory=SurfaceStarts)
    table: float | None = 0.0

    def __post_init__(self) -> None:
        check_solid(self.obj)
        if not isinstance(self.hand, Hand3D):
            raise CrmgraspError(f"a spatial task's hand must be a Hand3D, got {self.hand!r}")
        self._set_model(SpatialModel(self.hand, self.noise, self.table))
        self._check_common()
        if self.family is not None:
            if not isinstance(self.family, SolidFamily):
                raise CrmgraspError(f"a spatial task's family must be a SolidFamily, got {self.family!r}")
            self._check_family_width()

    @property
    def solid(self) -> Solid:
        """The object (typed as a solid)."""
        return self.obj  # type: ignore[return-value]

    @property
    def hand3d(self) -> Hand3D:
        """The hand (typed as a [`Hand3D`][])."""
        return self.hand  # type: ignore[return-value]

    def acceptable(self, config: Contacts3D) -> bool:
        """The start rule: feasible (with the table) and not already a grasp."""
        return self.feasible(config) is Error.NONE and not self.is_success(config)

    def sample_start(self, rng: np.random.Generator, accept: Any = None) -> Any:
        """A start on the object ([`SurfaceStarts`][]; ``accept``: a kernel's compiled
        decision, the same start either way)."""
        self._one_object()
        return self.starts(self, rng, accept)

    def sample_starts(self, rng: np.random.Generator, n: int, accept: Any = None) -> np.ndarray:
        """``n`` starts as rows ``[x_a, n_a, x_b, n_b, ...]`` (``(n, 12)`` for two contacts)."""
        self._one_object()
        return self.model.rows_of([self.sample_start(rng) for _ in range(n)])


def spatial_symmetry(actions: tuple[CRM3D, ...], hand: Hand3D = SPATIAL_HAND) -> Symmetry:
    """The mirror symmetry of a spatial CRM set closed under
    [`mirror_crm`][crmgrasp.model.spatial_model.SpatialModel.mirror_crm] for ``hand``
    (two contacts by default; ``TRIPOD_HAND`` for three).

    A reflection ``M`` in a vertical plane that contains the hand's forward axis ``g``
    (``y -> -y`` for the default axes) maps each tangent frame's ``t_1`` to ``-M t_1`` and
    ``t_2`` to ``M t_2`` (a reflection reverses cross products), the palm side to its
    mirror once the labels are reversed, and leaves ``rho`` and the set of moment
    magnitudes unchanged (``|m_a|`` and ``|m_b|`` swapped; with three contacts ``|m_a|``
    and ``|m_c|``). A task whose object and start distributions are
    invariant under it (``box-3d``, ``cup-3d`` and their tripods: any yaw, offsets
    symmetric about 0) may declare the symmetry; ``tests/test_spatial_tasks.py`` checks the
    equivariance on sampled worlds, for two and three contacts. The registered tasks do not
    declare it: model-vi on the mirror quotient did worse on ``cup-3d`` (10.4% above the
    optimum after 6,000 episodes against 4.8% without) and about the same on ``box-3d``
    (40.8% against 42%); the families preset on it gains 2-4 points on the tripods and
    nothing on ``box-3d`` (docs/model-3d.md); and a declared symmetry makes ``--preset
    fastest`` use it."""
    return symmetry_of(actions, SpatialModel(hand).mirror_crm)


MIRROR_INVARIANT = ("box-3d", "cup-3d", "box-3d-3f", "cup-3d-3f")
"""The registered spatial tasks whose worlds have the mirror symmetry of [`spatial_symmetry`][]
without declaring it (``tests/test_spatial_tasks.py`` checks the equivariance on their sampled
worlds)."""


def mirrored(task: Task) -> Task:
    """``task`` on which learners may use the mirror quotient: unchanged where it declares a
    symmetry; for a task of [`MIRROR_INVARIANT`][], the same task with
    ``spatial_symmetry(task.actions, task.hand)`` declared; an error otherwise. For
    measuring what the quotient buys on those tasks (``benchmarks/family_learning.py
    --mirror``; docs/model-3d.md)."""
    if task.symmetry is not None:
        return task
    if task.name not in MIRROR_INVARIANT:
        raise CrmgraspError(
            f"{task.name} has no mirror symmetry known to hold; the tasks that have one undeclared: "
            + ", ".join(MIRROR_INVARIANT)
        )
    return replace(task, symmetry=spatial_symmetry(task.actions, task.hand))  # type: ignore[arg-type]


def _spatial_task(
    name: str, family: SolidFamily, description: str, reference: float | None, fingers: int = 2
) -> SpatialTask:
    tripod = fingers == 3
    return SpatialTask(
        name=name,
        obj=family.nominal(),  # type: ignore[arg-type]
        hand=TRIPOD_HAND if tripod else SPATIAL_HAND,  # type: ignore[arg-type]
        actions=tripod_crms() if tripod else spatial_crms(),  # type: ignore[arg-type]
        discretizer=TRIPOD_BINS if tripod else PAPER_BINS,
        mu_goal=0.05,
        max_steps=10,
        reference_mean_steps=reference,
        description=description,
        family=family,  # type: ignore[arg-type]
    )


def box_3d() -> SpatialTask:
    """``box-3d``: boxes 0.15-0.30 x 0.06-0.12 x 0.06-0.20 m on the table, any yaw."""
    return _spatial_task("box-3d", BoxOnTable(), "boxes 0.15-0.30 x 0.06-0.12 x 0.06-0.20 m on a table, any yaw", None)


def cup_3d() -> SpatialTask:
    """``cup-3d``: closed cylinders of radius 0.03-0.07 m and height 0.06-0.20 m, upright
    or lying (even odds), any yaw."""
    return _spatial_task(
        "cup-3d", CylinderOnTable(), "cylinders r 0.03-0.07 m, h 0.06-0.20 m, upright or lying, any yaw", None
    )


def open_cup_3d() -> SpatialTask:
    """``open-cup-3d``: open cups ([`OpenCupOnTable`][crmgrasp.model.solid_families.OpenCupOnTable])
    of radius 0.03-0.07 m and height 0.06-0.20 m, walls 5 mm thick, upright or lying (even
    odds), any yaw: ``cup-3d`` with the top open, so that a goal line through the opening
    reaches the inner wall and two contacts may pinch the wall. A mesh (the compiled
    spatial kernel steps it, as it steps ``cup-3d``)."""
    text = "open cups r 0.03-0.07 m, h 0.06-0.20 m, wall 5 mm, upright or lying, any yaw (a mesh)"
    return _spatial_task("open-cup-3d", OpenCupOnTable(), text, None)


def box_3d_3f() -> SpatialTask:
    """``box-3d-3f``: ``box-3d``'s boxes held by three fingers."""
    text = "boxes 0.15-0.30 x 0.06-0.12 x 0.06-0.20 m on a table, any yaw; success at friction 0.05"
    return _spatial_task("box-3d-3f", BoxOnTable(), text, None, fingers=3)


def cup_3d_3f() -> SpatialTask:
    """``cup-3d-3f``: ``cup-3d``'s cylinders held by three fingers."""
    text = "cylinders r 0.03-0.07 m, h 0.06-0.20 m, upright or lying, any yaw; success at friction 0.05"
    return _spatial_task("cup-3d-3f", CylinderOnTable(), text, None, fingers=3)


SPATIAL_TASKS = {
    "box-3d": box_3d,
    "cup-3d": cup_3d,
    "open-cup-3d": open_cup_3d,
    "box-3d-3f": box_3d_3f,
    "cup-3d-3f": cup_3d_3f,
}
"""The registered spatial tasks."""

for _name, _factory in SPATIAL_TASKS.items():
    register_task(_name, _factory, overwrite=True)

"""The contact model: one object that states what a hand's contacts are, do and sense.

A task holds its contact model (``Task.model``) the way a POMDP problem holds its
transition and observation models: everything above the model layer (the episode loop,
the kernels' seam, the environments, the runner, the command line) reads the number of
contacts, the batched row layout, the action parameterization and the observation's
names and bounds from it, and applies the model's rules through it. Nothing above the
model writes a contact count, a row width or an observation name of its own.

`ContactModel` is the protocol. Two models implement it from the rules that live
in their own modules:

* [`PlanarModel`][crmgrasp.model.planar_model.PlanarModel]: two or more contacts in the plane
  ([`crmgrasp.model.hand`][], [`crmgrasp.model.sensing`][], [`crmgrasp.model.quality`][]);
* [`SpatialModel`][crmgrasp.model.spatial_model.SpatialModel]: two contacts on a solid on a
  table ([`crmgrasp.model.spatial`][], [`crmgrasp.model.quality3d`][]).

A new model is one new module implementing this protocol and, for speed, one kernel
behind [`crmgrasp.kernels.kernel_for`][]'s table. The number of contacts is the hand's
(``Hand.contacts``): the planar rules are written for any number, so a three-finger hand
is the planar model with ``contacts = 3``.

Layout
------
A configuration of ``n`` contacts in ``d`` dimensions is one row of ``2 n d`` floats:
per contact in label order, its position then its inward unit normal
(``[ax, ay, anx, any, bx, by, bnx, bny]`` in the plane). A CRM ``(c, f, r)`` is the
index of the moving contact, the index of the frame contact and ``offset_dim`` offset
coordinates (metres).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, ClassVar, Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from crmgrasp._validation import CrmgraspError
from crmgrasp.model.actions import CRMRange, full_ranges
from crmgrasp.model.hand import Error
from crmgrasp.model.sensing import Observation, SensorNoise

__all__ = [
    "ContactModel",
    "LabelledContacts",
    "OBSERVATION_NAMES",
    "observation_names",
    "row_width",
    "contact_columns",
]

OBSERVATION_NAMES: tuple[str, ...] = Observation._fields
"""The continuous observation of a two-contact model, in order: the squared frictionless
force residual and the two frictionless moments ([docs/model.md section 4][model-4])."""


def observation_names(labels: Sequence[str]) -> tuple[str, ...]:
    """The observation of contacts ``labels``: ``rho``, then the moment ``m_<label>`` about
    each contact in label order.

    >>> observation_names("abc")
    ('rho', 'm_a', 'm_b', 'm_c')
    """
    return ("rho", *(f"m_{lab}" for lab in labels))


def row_width(n_contacts: int, dim: int) -> int:
    """Floats in one configuration row: a position and a normal of ``dim`` each per contact.

    >>> row_width(2, 2), row_width(2, 3), row_width(3, 3)
    (8, 12, 18)
    """
    return 2 * n_contacts * dim


def contact_columns(labels: Sequence[str], axes: str) -> tuple[str, ...]:
    """The names of a row's columns: per contact its position ``<label><axis>`` then its
    normal ``<label>n<axis>``.

    >>> contact_columns("ab", "xy")
    ('ax', 'ay', 'anx', 'any', 'bx', 'by', 'bnx', 'bny')
    """
    return tuple(f"{lab}{p}{q}" for lab in labels for p in ("", "n") for q in axes)


class ContactModel(Protocol):
    """What a task's contact model states and does.

    A model states its sizes (read-only attributes, class constants in the two built-in
    models), applies its rules, and holds the hand and the sensing noise they use.
    """

    @property
    def kind(self) -> str:
        """The model's name (``"planar"``, ``"spatial"``): the key of the kernel seam's table."""
        ...

    @property
    def labels(self) -> tuple[str, ...]:
        """The contacts' labels in index order (``("a", "b")``)."""
        ...

    @property
    def dim(self) -> int:
        """Coordinates of a contact's position (2 in the plane, 3 in space)."""
        ...

    @property
    def offset_dim(self) -> int:
        """Coordinates of a CRM's offset ``r`` (1 in the plane, 2 in space)."""
        ...

    @property
    def observation_names(self) -> tuple[str, ...]:
        """The continuous observation's names, in order ([`observation_names`][])."""
        ...

    @property
    def hand(self) -> Any:
        """The hand whose limits the rules apply (aperture, palm, reach)."""
        ...

    @property
    def noise(self) -> SensorNoise:
        """The sensing noise of every reading ([`SensorNoise`][crmgrasp.model.sensing.SensorNoise])."""
        ...

    @property
    def n_contacts(self) -> int:
        """The number of contacts."""
        ...

    @property
    def row_width(self) -> int:
        """Floats in one configuration row ([`row_width`][])."""
        ...

    @property
    def columns(self) -> tuple[str, ...]:
        """The names of a row's columns ([`contact_columns`][])."""
        ...

    def observation_bounds(self) -> dict[str, tuple[float, float]]:
        """Each observation's ``(low, high)``: the box an environment clips into."""
        ...

    # -- configurations and CRMs
    def config_of(self, row: Sequence[float]) -> Any:
        """The configuration of one row of plain floats (no checks)."""
        ...

    def row_of(self, config: Any) -> list[float]:
        """The row of a configuration."""
        ...

    def rows_of(self, configs: Sequence[Any]) -> NDArray[np.float64]:
        """Configurations stacked as ``(N, row_width)`` rows."""
        ...

    def crm(self, c: int, f: int, r: Any) -> Any:
        """The CRM moving contact index ``c`` relative to contact index ``f`` by offset ``r``."""
        ...

    def is_crm(self, action: object) -> bool:
        """Whether ``action`` is a CRM of this model (rather than an action index)."""
        ...

    def check_crm(self, crm: object) -> Any:
        """``crm`` if it is a CRM of this model within the hand's reach, else a one-line error."""
        ...

    def parse_crm(self, text: str) -> Any:
        """The CRM written as ``c,f,r`` (``c,f,r1,r2`` in space), checked (one-line errors)."""
        ...

    def offset_data(self, r: Any) -> Any:
        """A CRM offset as JSON data (a number, or a list)."""
        ...

    def mirror_crm(self, crm: Any) -> Any:
        """The CRM a mirror symmetry maps ``crm`` to (labels swapped)."""
        ...

    def full_ranges(self) -> tuple[CRMRange, ...]:
        """The whole continuous action space: every ordered contact pair over the offsets
        within the hand's reach ([`crmgrasp.model.actions.full_ranges`][])."""
        ...

    def check_range(self, rng: object) -> CRMRange:
        """``rng`` if it is a [`CRMRange`][crmgrasp.model.actions.CRMRange] of this model's
        contacts and offset coordinates whose every offset is within reach, else a one-line
        error."""
        ...

    def range_crm(self, rng: CRMRange, r: Any) -> Any:
        """The CRM of range ``rng`` at offset ``r`` (a sequence of ``offset_dim`` numbers)."""
        ...

    def moment_index(self, label: str) -> int:
        """The position in the observation of the moment about contact ``label``."""
        ...

    @property
    def mirror_axes(self) -> tuple[int, ...]:
        """Where a mirror symmetry sends each observation quantity: quantity ``i`` of the
        mirror image is quantity ``mirror_axes[i]`` of the original, up to sign."""
        ...

    # -- the rules
    def execute(self, obj: Any, config: Any, crm: Any, sensed: Any) -> Any:
        """The CRM transition from ``config``, goal line from ``sensed``: an outcome with
        ``config`` (unchanged on an error) and ``error``."""
        ...

    def read(self, config: Any, rng: np.random.Generator) -> Any:
        """One sensed reading of ``config`` (the model's sensing noise)."""
        ...

    def read_rows(self, rows: NDArray[np.float64], rng: np.random.Generator) -> NDArray[np.float64]:
        """One sensed reading per row, as [`read`][] row after row."""
        ...

    def observe(self, sensed: Any) -> tuple[float, ...]:
        """The observation of a reading (its values in the order of ``observation_names``)."""
        ...

    def quality(self, config: Any) -> float:
        """The least friction coefficient at which ``config`` is force closure."""
        ...

    def feasible(self, obj: Any, config: Any) -> Error:
        """``Error.NONE`` if ``config`` is feasible on ``obj``, else the violated limit."""
        ...

    def check_config(self, obj: Any, config: object, name: str = "configuration") -> Any:
        """``config`` if it is a valid configuration on ``obj``, else a one-line error."""
        ...

    def check_reading(self, config: object, name: str = "reading") -> Any:
        """``config`` if it is a configuration of this model (its type, one contact per finger,
        finite numbers, unit normals) wherever it lies (a sensed one: the object is unknown),
        else a one-line error: ``check_config`` without the test against the object."""
        ...

    def place(self, obj: Any, points: Sequence[ArrayLike]) -> Any:
        """The configuration a user's points name on ``obj`` (one point per contact)."""
        ...

    def numbers(self, config: Any) -> list[float]:
        """A configuration's contacts as one flat list (the row's order)."""
        ...


class LabelledContacts:
    """What the contact models share, from their contacts' ``labels``: the observation
    ``(rho, m_a, m_b, ...)`` and its bounds, the mirror, and the row layout over the
    model's ``axes``. A model states ``labels`` (a class constant, or its hand's)."""

    labels: tuple[str, ...]
    axes: ClassVar[str]
    """The names of a position's coordinates (``"xy"``, ``"xyz"``)."""
    kind: ClassVar[str]
    offset_dim: ClassVar[int]
    hand: Any

    @property
    def observation_names(self) -> tuple[str, ...]:
        return observation_names(self.labels)

    @property
    def mirror_axes(self) -> tuple[int, ...]:
        """A mirror reverses the labels (``a <-> z``): ``rho`` stays and the moment about
        contact ``j`` becomes minus the moment about its mirror contact; for two contacts
        ``(m_a, m_b)`` becomes ``(-m_b, -m_a)``: ``(0, 2, 1)``."""
        n = len(self.labels)
        return (0, *(n - i for i in range(n)))

    def mirror_label(self, label: str) -> str:
        """The label a mirror gives contact ``label`` (the labels reversed)."""
        if label not in self.labels:
            raise CrmgraspError(f"contact {label!r} is not one of the hand's contacts {', '.join(self.labels)}")
        return self.labels[len(self.labels) - 1 - self.labels.index(label)]

    @property
    def dim(self) -> int:
        return len(self.axes)

    @property
    def n_contacts(self) -> int:
        return len(self.labels)

    @property
    def row_width(self) -> int:
        return row_width(self.n_contacts, self.dim)

    @property
    def columns(self) -> tuple[str, ...]:
        return contact_columns(self.labels, self.axes)

    def full_ranges(self) -> tuple[CRMRange, ...]:
        return full_ranges(self.labels, self.offset_dim, self.hand.reach)

    def range_crm(self, rng: CRMRange, r: Any) -> Any:
        index = self.labels.index
        return self.crm(index(rng.c), index(rng.f), r[0] if self.offset_dim == 1 else (r[0], r[1]))  # type: ignore[attr-defined]

    def check_range(self, rng: object) -> CRMRange:
        if not isinstance(rng, CRMRange):
            raise CrmgraspError(f"expected a CRMRange, got {rng!r}")
        for label in (rng.c, rng.f):
            if label not in self.labels:
                raise CrmgraspError(
                    f"CRM range {rng} names contact {label!r}, but the hand has contacts {', '.join(self.labels)}"
                )
        if rng.dim != self.offset_dim:
            raise CrmgraspError(
                f"CRM range {rng} has {rng.dim} offset coordinates; the {self.kind} model takes {self.offset_dim}"
            )  # type: ignore[attr-defined]
        for corner in rng.corners():
            try:
                self.check_crm(self.range_crm(rng, corner))  # type: ignore[attr-defined]
            except CrmgraspError as exc:
                raise CrmgraspError(f"CRM range {rng} reaches beyond the hand: {exc}") from None
        return rng

    def moment_index(self, label: str) -> int:
        """The observation is ``rho`` then the moment about each contact in label order:
        ``m_a`` is quantity 1, ``m_b`` quantity 2, ..."""
        return 1 + self.labels.index(label)

    def observation_bounds(self) -> dict[str, tuple[float, float]]:
        """``rho = |sum_i n_i|^2`` in ``[0, n^2]``; each moment, a sum of ``n - 1`` terms of at
        most ``A`` (contacts at most ``A`` apart, metres), within ``2 (n - 1) A`` (doubled to
        leave room for sensing noise). For two contacts: ``[0, 4]`` and ``2 A``."""
        n = len(self.labels)
        b = 2.0 * (n - 1) * self.hand.aperture
        names = self.observation_names
        return {names[0]: (0.0, float(n * n)), **{m: (-b, b) for m in names[1:]}}

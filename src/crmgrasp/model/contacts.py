"""Contact configurations of the planar hand ([docs/model.md section 2][model-2]).

A [`Contact`][] is a position and the object's inward unit normal there; a
[`Config`][] is the pair of contacts labelled ``a`` and ``b`` of a two-finger hand and a
[`Grip`][] the contacts ``a, b, c, ...`` of a hand with more fingers. All are immutable,
hashable tuples of plain floats; the rules index them by position, so one rule serves
every number of contacts. The batched layout of a configuration is one row of ``4 n``
floats, per contact ``x, y, nx, ny`` (``[ax, ay, anx, any, bx, by, bnx, bny]`` for two;
``np.asarray(config).reshape(4 * n)``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from numbers import Real
from typing import NamedTuple, Self, TypeVar, cast

import numpy as np
from numpy.typing import ArrayLike, NDArray

from crmgrasp._validation import CrmgraspError, as_point, shown

__all__ = [
    "LABELS",
    "ALL_LABELS",
    "MAX_CONTACTS",
    "labels_of",
    "Contact",
    "Config",
    "Grip",
    "Labelled",
    "make_config",
    "replaced",
    "two_contacts",
    "label_index",
    "other",
    "config_from_row",
    "contacts_from_row",
    "configs_to_array",
    "array_to_configs",
    "check_contacts",
    "UNIT_TOL",
]

LABELS = ("a", "b")
"""The two-finger hand's contact labels, in index order."""

MAX_CONTACTS = 4
"""The most contacts a planar hand may have."""

ALL_LABELS = ("a", "b", "c", "d")
"""Every contact label, in index order (a hand with ``n`` contacts uses the first ``n``)."""


def labels_of(n: int) -> tuple[str, ...]:
    """The labels of a hand with ``n`` contacts (``2 <= n <= MAX_CONTACTS``).

    >>> labels_of(3)
    ('a', 'b', 'c')
    """
    if isinstance(n, bool) or not isinstance(n, int) or not 2 <= n <= MAX_CONTACTS:
        raise CrmgraspError(f"a hand has 2 to {MAX_CONTACTS} contacts, got {n!r}")
    return ALL_LABELS[:n]


def label_index(label: str) -> int:
    """Index of a contact label (0 for ``'a'``, 1 for ``'b'``, ...); raises on anything
    else. Whether a given hand has that contact is the hand's check
    ([`Hand.check_crm`][crmgrasp.model.hand.Hand.check_crm])."""
    if label == "a":  # the two-finger labels first: the common case
        return 0
    if label == "b":
        return 1
    if label in ALL_LABELS:
        return ALL_LABELS.index(label)
    raise CrmgraspError(f"unknown contact label {shown(label)}; expected one of {', '.join(ALL_LABELS)}")


def other(label: str) -> str:
    """The other contact's label."""
    return LABELS[1 - label_index(label)]


class Contact(NamedTuple):
    """A contact: position ``(x, y)`` in metres and inward unit normal ``(nx, ny)``."""

    x: float
    y: float
    nx: float
    ny: float

    @property
    def point(self) -> tuple[float, float]:
        """Position ``(x, y)``."""
        return (self.x, self.y)

    @property
    def normal(self) -> tuple[float, float]:
        """Inward unit normal."""
        return (self.nx, self.ny)

    @property
    def tangent(self) -> tuple[float, float]:
        """Frame tangent ``tau = n x z = (n_y, -n_x)``."""
        return (self.ny, -self.nx)

    @classmethod
    def make(cls, point: ArrayLike, normal: ArrayLike) -> Contact:
        """Validated constructor: finite point, unit normal (normalised if within 1e-6)."""
        x, y = as_point(point, "contact point")
        nx, ny = as_point(normal, "contact normal")
        norm = math.sqrt(nx * nx + ny * ny)
        if abs(norm - 1.0) > 1e-6:
            raise CrmgraspError(f"contact normal must be a unit vector, got length {norm:g}")
        return cls(x, y, nx / norm, ny / norm)


class Config(NamedTuple):
    """Configuration of the two-contact hand: contacts ``a`` and ``b``."""

    a: Contact
    b: Contact

    def __getitem__(self, key: int | str) -> Contact:  # type: ignore[override]
        if isinstance(key, str):
            key = label_index(key)
        return tuple.__getitem__(self, key)  # type: ignore[return-value]

    def replace(self, label: str, contact: Contact) -> Config:
        """A copy with contact ``label`` replaced."""
        return Config(contact, self.b) if label_index(label) == 0 else Config(self.a, contact)

    def swapped(self) -> Config:
        """The same contacts with labels ``a`` and ``b`` exchanged."""
        return Config(self.b, self.a)

    @property
    def separation(self) -> float:
        """Distance ``|x_a - x_b|`` in metres."""
        dx, dy = self.b.x - self.a.x, self.b.y - self.a.y
        return math.sqrt(dx * dx + dy * dy)

    def to_dict(self) -> dict[str, dict[str, list[float]]]:
        """JSON-friendly form ``{"a": {"point": [x, y], "normal": [nx, ny]}, "b": ...}``."""
        return {lab: {"point": list(c.point), "normal": list(c.normal)} for lab, c in zip(LABELS, self)}


C = TypeVar("C")


class Labelled(tuple[C, ...]):
    """Contacts ``a, b, c, ...`` in label order, indexed by position or by label: what the
    planar [`Grip`][] and the spatial [`Grip3D`][crmgrasp.model.spatial.Grip3D] share."""

    __slots__ = ()

    def __new__(cls, *contacts: C) -> Self:
        return tuple.__new__(cls, contacts)

    def __getnewargs__(self) -> tuple[C, ...]:  # pickling and copying
        return tuple(self)

    def __getitem__(self, key: int | str) -> C:  # type: ignore[override]
        return tuple.__getitem__(self, label_index(key) if isinstance(key, str) else key)  # type: ignore[return-value]

    def __repr__(self) -> str:
        return f"{type(self).__name__}({', '.join(map(repr, self))})"


class Grip(Labelled[Contact]):
    """Configuration of a hand with three or more contacts: ``a, b, c, ...`` in order.

    Examples
    --------
    >>> g = Grip(Contact(0, 0, 1, 0), Contact(1, 0, -1, 0), Contact(0.5, 1, 0, -1))
    >>> g["c"].y, len(g)
    (1, 3)
    """

    __slots__ = ()

    def replace(self, label: str, contact: Contact) -> Grip:
        """A copy with contact ``label`` replaced."""
        return cast(Grip, replaced(self, label_index(label), contact))

    def to_dict(self) -> dict[str, dict[str, list[float]]]:
        """JSON-friendly form, as [`Config.to_dict`][]."""
        return {lab: {"point": list(c.point), "normal": list(c.normal)} for lab, c in zip(ALL_LABELS, self)}


def make_config(contacts: Sequence[Contact]) -> Config | Grip:
    """The configuration of contacts in label order: a [`Config`][] for two, a
    [`Grip`][] for more (the one place that picks the type)."""
    if len(contacts) == 2:
        return Config(contacts[0], contacts[1])
    return Grip(*contacts)


def two_contacts(config: Config | Grip, what: str) -> Config:
    """``config`` if it has two contacts, else a one-line error: ``what`` takes a two-finger
    hand."""
    if isinstance(config, Config):
        return config
    raise CrmgraspError(f"{what} takes a two-finger hand; this configuration has {len(config)} contacts")


def replaced(config: Config | Grip, index: int, contact: Contact) -> Config | Grip:
    """A copy of ``config`` with the contact at ``index`` replaced (the same type)."""
    if len(config) == 2:
        return Config(config[0], contact) if index else Config(contact, config[1])
    return Grip(*(contact if i == index else c for i, c in enumerate(config)))


def config_from_row(row: Sequence[float]) -> Config:
    """The two-contact configuration of one row ``[ax, ay, anx, any, bx, by, bnx, bny]`` of
    plain floats (no checks: for rows the package made itself)."""
    new = tuple.__new__  # the NamedTuples' own construction, without their Python-level __new__ (a hot path)
    return new(Config, (new(Contact, (row[0], row[1], row[2], row[3])), new(Contact, (row[4], row[5], row[6], row[7]))))


def contacts_from_row(row: Sequence[float]) -> Config | Grip:
    """The configuration of one row of ``4 n`` plain floats, per contact ``x, y, nx, ny``:
    [`config_from_row`][] for two contacts, a [`Grip`][] for more (no checks)."""
    if len(row) == 8:
        return config_from_row(row)
    new = tuple.__new__  # the NamedTuples' own construction, without their Python-level __new__ (a hot path)
    return new(Grip, [new(Contact, row[i : i + 4]) for i in range(0, len(row), 4)])


ROW_WIDTH = 4 * len(LABELS)
"""Floats in the batched row of a [`Config`][]: per contact ``x, y, nx, ny`` (8)."""


def configs_to_array(configs: Sequence[Config]) -> NDArray[np.float64]:
    """Stack configurations into the batched ``(N, ROW_WIDTH)`` layout."""
    return np.asarray(configs, dtype=np.float64).reshape(len(configs), ROW_WIDTH)


def array_to_configs(arr: ArrayLike) -> list[Config]:
    """Inverse of [`configs_to_array`][]."""
    a = np.asarray(arr, dtype=np.float64)
    if a.ndim != 2 or a.shape[1] != ROW_WIDTH:
        raise CrmgraspError(f"configuration array must have shape (N, {ROW_WIDTH}), got {a.shape}")
    return [config_from_row(r) for r in a.tolist()]


UNIT_TOL = 1e-6
"""How far a contact normal's length may be from 1 before [`check_contacts`][] refuses it."""


_NORM2_TOL = 2.0 * UNIT_TOL  # on the squared length


def check_contacts(config: object, name: str = "configuration", contacts: int | None = None) -> Config | Grip:
    """``config`` if it is a [`Config`][] (or a [`Grip`][]) of [`Contact`][] with finite
    coordinates and unit normals (within [`UNIT_TOL`][]), and ``contacts`` of them if given;
    else a one-line `CrmgraspError`. The public functions taking a
    configuration call it; the compiled kernels do not (their inputs come from the model).

    Examples
    --------
    >>> check_contacts(Config(Contact(0, 0, 1, 0), Contact(1, 0, -1, 0))).b.nx
    -1
    >>> check_contacts(Config(Contact(0, 0, 2, 0), Contact(1, 0, -1, 0)))
    Traceback (most recent call last):
    ...
    crmgrasp._validation.CrmgraspError: configuration: contact a's normal must be a unit vector, got (2, 0)
    """
    if contacts is not None and isinstance(config, (Config, Grip)) and len(config) != contacts:
        raise CrmgraspError(f"{name} has {len(config)} contacts; the hand has {contacts}")
    if type(config) is not Config or type(config.a) is not Contact or type(config.b) is not Contact:
        if not isinstance(config, (Config, Grip)) or not all(isinstance(c, Contact) for c in config):
            raise CrmgraspError(f"{name} must be a Config of two Contacts (or a Grip of more), got {config!r:.80}")
        if len(config) > 2:
            if not _fine(config):
                _check_each(config, name)
            return config
    (ax, ay, anx, any_), (bx, by, bnx, bny) = config
    try:
        fine = math.isfinite(ax + ay + anx + any_ + bx + by + bnx + bny) and (  # a NaN or inf (or an overflow)
            abs(anx * anx + any_ * any_ - 1.0) <= _NORM2_TOL and abs(bnx * bnx + bny * bny - 1.0) <= _NORM2_TOL
        )
    except TypeError:  # a value that is no number: named below
        fine = False
    if not fine:
        _check_each(config, name)
    return config


def _fine(config: Config | Grip) -> bool:
    """Whether every contact is finite with a unit normal (within [`UNIT_TOL`][]): the quick
    test of a hand with more than two contacts, as the two-contact one above."""
    total = 0.0
    try:
        for x, y, nx, ny in config:
            total += x + y + nx + ny
            if not abs(nx * nx + ny * ny - 1.0) <= _NORM2_TOL:
                return False
    except TypeError:  # a value that is no number: named by _check_each
        return False
    return math.isfinite(total)


def _check_each(config: Config | Grip, name: str) -> None:
    """The one-line error of the first contact with a value that is not a real number, else of
    the first that is not finite, else of the first whose normal is not a unit vector (within
    [`UNIT_TOL`][])."""
    for label, c in zip(ALL_LABELS, config):
        if not all(isinstance(v, Real) for v in c):
            got = shown(tuple(c), 120)
            raise CrmgraspError(f"{name}: contact {label} must be four numbers (x, y, nx, ny), got {got}")
    for label, c in zip(ALL_LABELS, config):
        if not all(math.isfinite(v) for v in c):
            raise CrmgraspError(f"{name}: contact {label} must be finite, got {tuple(c)}")
    for label, c in zip(ALL_LABELS, config):
        if abs(c.nx * c.nx + c.ny * c.ny - 1.0) > _NORM2_TOL:
            raise CrmgraspError(f"{name}: contact {label}'s normal must be a unit vector, got ({c.nx:g}, {c.ny:g})")

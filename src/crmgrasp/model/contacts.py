"""Contact configurations of the two-contact planar hand (docs/model.md section 2).

A [`Contact`][] is a position and the object's inward unit normal there; a
[`Config`][] is the pair of contacts labelled ``a`` and ``b``. Both are
immutable, hashable named tuples of plain floats. The batched layout of a
configuration is one row of 8 floats, ``[ax, ay, anx, any, bx, by, bnx, bny]``
(``np.asarray(config).reshape(8)``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from crmgrasp._validation import CrmgraspError, as_point

__all__ = [
    "LABELS",
    "Contact",
    "Config",
    "label_index",
    "other",
    "config_from_row",
    "configs_to_array",
    "array_to_configs",
    "check_contacts",
    "UNIT_TOL",
]

LABELS = ("a", "b")
"""Contact labels, in index order."""


def label_index(label: str) -> int:
    """Index (0 or 1) of a contact label; raises on anything but ``'a'`` or ``'b'``."""
    if label == "a":
        return 0
    if label == "b":
        return 1
    raise CrmgraspError(f"unknown contact label {label!r}; expected 'a' or 'b'")


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


def config_from_row(row: Sequence[float]) -> Config:
    """The configuration of one row ``[ax, ay, anx, any, bx, by, bnx, bny]`` of plain floats
    (no checks: for rows the package made itself)."""
    return Config(Contact(row[0], row[1], row[2], row[3]), Contact(row[4], row[5], row[6], row[7]))


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


def check_contacts(config: object, name: str = "configuration") -> Config:
    """``config`` if it is a [`Config`][] of two [`Contact`][] with finite
    coordinates and unit normals (within [`UNIT_TOL`][]); else a one-line
    `CrmgraspError`. The public functions taking a
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
    if type(config) is not Config or type(config.a) is not Contact or type(config.b) is not Contact:
        if not isinstance(config, Config) or not all(isinstance(c, Contact) for c in config):
            raise CrmgraspError(f"{name} must be a Config of two Contacts, got {config!r:.80}")
    (ax, ay, anx, any_), (bx, by, bnx, bny) = config
    if not math.isfinite(ax + ay + anx + any_ + bx + by + bnx + bny):  # a NaN or inf (or an overflow)
        for label, c in zip("ab", config):
            if not all(math.isfinite(v) for v in c):
                raise CrmgraspError(f"{name}: contact {label} must be finite, got {tuple(c)}")
    if abs(anx * anx + any_ * any_ - 1.0) > _NORM2_TOL or abs(bnx * bnx + bny * bny - 1.0) > _NORM2_TOL:
        for label, nx, ny in (("a", anx, any_), ("b", bnx, bny)):
            if abs(nx * nx + ny * ny - 1.0) > _NORM2_TOL:
                raise CrmgraspError(f"{name}: contact {label}'s normal must be a unit vector, got ({nx:g}, {ny:g})")
    return config

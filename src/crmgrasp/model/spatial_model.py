"""The spatial model of two or more contacts (docs/model-3d.md) as a `ContactModel`.

[`SpatialModel`][] holds the 3-D hand, the sensing noise and the table, and applies
the rules of [`crmgrasp.model.spatial`][] (CRM transition, feasibility with the table,
readings, observation) and [`crmgrasp.model.quality3d`][] (min friction of two contacts'
squeeze, least friction of three or more). What the agent sees is the planar model's
observation: ``rho``, ``|m_a|``, ``|m_b|`` (and ``|m_c|``, ... for more contacts).
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from crmgrasp._validation import CrmgraspError, finite, shown
from crmgrasp.model.contact_model import LabelledContacts
from crmgrasp.model.hand import Error
from crmgrasp.model.quality3d import least_friction_3d, min_friction_3d
from crmgrasp.model.sensing import Observation, SensorNoise
from crmgrasp.model.solids import surface_point
from crmgrasp.model.spatial import (
    CRM3D,
    Config3D,
    Contact3D,
    Contacts3D,
    Grip3D,
    Hand3D,
    Outcome3D,
    check_contacts3d,
    config3d,
    execute_crm3d,
    feasible3d,
    observe3d,
    sense3d,
)

__all__ = ["SpatialModel", "contact3d"]

SURFACE_TOL = 1e-6
"""How far (m) a given contact may lie from the solid's surface before
[`SpatialModel.check_config`][] refuses it (and its normal's length from 1:
[`crmgrasp.model.spatial.UNIT_TOL`][], the same)."""


def contact3d(point: ArrayLike, normal: ArrayLike) -> Contact3D:
    """A [`Contact3D`][crmgrasp.model.spatial.Contact3D] of plain floats."""
    return Contact3D(tuple(np.asarray(point).tolist()), tuple(np.asarray(normal).tolist()))  # type: ignore[arg-type]


@functools.lru_cache(maxsize=1 << 14)
def _least_friction(config: Grip3D) -> float:
    """[`least_friction_3d`][crmgrasp.model.quality3d.least_friction_3d] of a configuration,
    cached (a configuration is a hashable tuple; the least recently used of ``2**14`` go
    first): about 12 linear programs each."""
    return least_friction_3d([c.x for c in config], [c.n for c in config])


@dataclass(frozen=True)
class SpatialModel(LabelledContacts):
    """The hand's contacts ``a, b, ...`` on a solid: rows ``[x_a, n_a, x_b, n_b, ...]`` (six
    floats per contact, 12 for two), CRMs ``(c, f, (r_1, r_2))`` with the offset in ``f``'s
    tangent frame, observation ``(rho, |m_a|, |m_b|, ...)``.

    Parameters
    ----------
    hand
        The 3-D hand (aperture, palm, axes, reach).
    noise
        Sensing noise of every reading ([`sense3d`][crmgrasp.model.spatial.sense3d]).
    table
        Height of the table plane, metres (``None``: no table).
    least_friction
        Three or more contacts' least friction: ``None`` for the readable rule
        ([`least_friction_3d`][crmgrasp.model.quality3d.least_friction_3d], cached); a kernel
        may give a compiled copy that returns the same values bit for bit.
    """

    hand: Hand3D
    noise: SensorNoise = field(default_factory=SensorNoise)
    table: float | None = 0.0
    least_friction: Callable[[Grip3D], float] | None = field(default=None, compare=False, repr=False)

    kind: ClassVar[str] = "spatial"
    axes: ClassVar[str] = "xyz"
    offset_dim: ClassVar[int] = 2

    @property
    def labels(self) -> tuple[str, ...]:  # type: ignore[override]
        """The hand's contact labels (``('a', 'b')`` for two)."""
        return self.hand.labels

    # -- configurations and CRMs
    def config_of(self, row: Sequence[float]) -> Contacts3D:
        """The configuration of the first six floats per contact of ``row`` (a kernel's row
        may carry more after them)."""
        new = tuple.__new__  # the NamedTuples' own construction, without their Python-level __new__ (a hot path)
        parts = [
            new(Contact3D, ((row[i], row[i + 1], row[i + 2]), (row[i + 3], row[i + 4], row[i + 5])))
            for i in range(0, 6 * self.n_contacts, 6)
        ]
        return new(Config3D if self.n_contacts == 2 else Grip3D, parts)  # type: ignore[return-value]

    def row_of(self, config: Contacts3D) -> list[float]:
        return [v for c in config for part in c for v in part]

    def rows_of(self, configs: Sequence[Contacts3D]) -> NDArray[np.float64]:
        return np.array([self.row_of(c) for c in configs], dtype=np.float64).reshape(len(configs), self.row_width)

    def crm(self, c: int, f: int, r: Any) -> CRM3D:
        return CRM3D(self.labels[c], self.labels[f], (r[0], r[1]))

    def is_crm(self, action: object) -> bool:
        return isinstance(action, CRM3D)

    def check_crm(self, crm: object) -> CRM3D:
        return self.hand.check_crm(crm)

    def parse_crm(self, text: str) -> CRM3D:
        parts = [p.strip() for p in str(text).split(",")]
        if len(parts) != 4:
            raise CrmgraspError(f"a spatial CRM is c,f,r1,r2 (e.g. a,a,0.05,0), got {text!r:.60}")
        return self.hand.check_crm(CRM3D(parts[0], parts[1], (finite(parts[2], "r1"), finite(parts[3], "r2"))))

    def offset_data(self, r: Any) -> list[float]:
        return [float(v) for v in r]

    def mirror_crm(self, crm: CRM3D) -> CRM3D:
        """Labels reversed (``a <-> b`` for two contacts, ``a <-> c`` for three), ``(r_1, r_2)
        -> (-r_1, r_2)``: a reflection in a vertical plane through the hand's forward axis
        maps ``t_1`` to ``-M t_1`` and ``t_2`` to ``M t_2`` (docs/model-3d.md)."""
        return CRM3D(self.mirror_label(crm.c), self.mirror_label(crm.f), (-crm.r[0], crm.r[1]))

    # -- the rules
    def execute(self, obj: Any, config: Contacts3D, crm: CRM3D, sensed: Contacts3D | None) -> Outcome3D:
        """[`execute_crm3d`][crmgrasp.model.spatial.execute_crm3d] with the table."""
        return execute_crm3d(obj, self.hand, config, crm, sensed, self.table)

    def read(self, config: Contacts3D, rng: np.random.Generator) -> Contacts3D:
        """[`sense3d`][crmgrasp.model.spatial.sense3d]."""
        return sense3d(config, self.noise.sigma_n, self.noise.sigma_p, rng, self.hand)

    def read_rows(self, rows: NDArray[np.float64], rng: np.random.Generator) -> NDArray[np.float64]:
        """[`read`][] row after row (the same draws in the same order)."""
        if not self.noise.active:
            return rows.copy()
        return self.rows_of([self.read(self.config_of(r), rng) for r in rows.tolist()])

    def observe(self, sensed: Contacts3D) -> tuple[float, ...]:
        """[`observe3d`][crmgrasp.model.spatial.observe3d]: an [`Observation`][crmgrasp.model.sensing.Observation]
        for two contacts, ``(rho, |m_a|, |m_b|, |m_c|, ...)`` for more."""
        values = observe3d(sensed)
        return Observation(*values) if len(values) == 3 else values

    def quality(self, config: Contacts3D) -> float:
        """Two contacts: [`min_friction_3d`][crmgrasp.model.quality3d.min_friction_3d], the
        friction their squeeze needs; three or more: the least friction at which they are
        force closure ([`least_friction_3d`][crmgrasp.model.quality3d.least_friction_3d], cached)."""
        if len(config) == 2:
            a, b = config
            return min_friction_3d([a.x, b.x], [a.n, b.n])
        return (self.least_friction or _least_friction)(config)  # type: ignore[arg-type]

    def feasible(self, obj: Any, config: Contacts3D) -> Error:
        """[`feasible3d`][crmgrasp.model.spatial.feasible3d] with the table."""
        return feasible3d(obj, self.hand, config, self.table)

    def check_config(self, obj: Any, config: object, name: str = "configuration") -> Contacts3D:
        """``config`` if it is a [`Config3D`][] (two contacts) or a [`Grip3D`][] (more) of
        one finite contact per finger with unit normals on the solid's surface (within
        [`SURFACE_TOL`][]), else a one-line error."""
        config = self.check_reading(config, name)
        for label, c in zip(self.labels, config):
            off = abs(obj.gap(np.asarray(c.x, dtype=float)))
            if off > SURFACE_TOL:
                raise CrmgraspError(f"{name}: contact {label} at {c.x} is {off:.3g} m off the object")
        return config

    def check_reading(self, config: object, name: str = "reading") -> Contacts3D:
        """``config`` if it is a [`Config3D`][] (two contacts) or a [`Grip3D`][] (more) of
        one finite contact per finger with unit normals (within [`SURFACE_TOL`][]), wherever it
        lies; else a one-line error ([`check_contacts3d`][crmgrasp.model.spatial.check_contacts3d])."""
        return check_contacts3d(config, name, self.n_contacts)

    def place(self, obj: Any, points: Sequence[ArrayLike]) -> Contacts3D:
        """Each contact where the ray from the solid's centre toward its point (finite
        ``(x, y, z)``, metres) leaves the solid."""
        if len(points) != self.n_contacts:
            raise CrmgraspError(f"the spatial model takes {self.n_contacts} points, got {len(points)}")
        out = []
        for label, p in zip(self.labels, points):
            try:
                v = np.asarray(p, dtype=np.float64)
            except (TypeError, ValueError):
                v = np.full(1, np.nan)
            if v.shape != (3,) or not np.all(np.isfinite(v)):
                raise CrmgraspError(f"contact {label} on a spatial task takes a finite X,Y,Z, got {shown(p)}")
            if np.allclose(v, obj.centre, atol=1e-12):
                raise CrmgraspError(f"contact {label}'s point is the object's centre: it gives no direction")
            hit = surface_point(obj, v - obj.centre)
            if hit is None:
                raise CrmgraspError(f"the ray from the object's centre toward contact {label}'s point misses it")
            out.append(contact3d(*hit))
        return config3d(out)

    def numbers(self, config: Contacts3D) -> list[float]:
        return [v for c in config for part in c for v in part]

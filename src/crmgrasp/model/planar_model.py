"""The planar model of two or more contacts ([docs/model.md sections 2-5 and 8][model-2]) as a
`ContactModel`.

[`PlanarModel`][] holds the hand and the sensing noise and applies the rules that live
in their own modules: the CRM transition and feasibility ([`crmgrasp.model.hand`][]),
readings and observations ([`crmgrasp.model.sensing`][]), min friction
([`crmgrasp.model.quality`][]). It adds no rule of its own.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from crmgrasp._validation import CrmgraspError
from crmgrasp.model.contact_model import LabelledContacts
from crmgrasp.model.contacts import LABELS, Config, Grip, check_contacts, contacts_from_row
from crmgrasp.model.hand import CRM, Error, Hand, Outcome, check_config, execute_crm, feasible
from crmgrasp.model.quality import min_friction
from crmgrasp.model.sensing import SensorNoise, observe

__all__ = ["PlanarModel", "SWAP", "mirror_crm"]

SWAP = {"a": "b", "b": "a"}
"""The labels a mirror exchanges on a two-contact hand."""


def mirror_crm(crm: CRM, labels: tuple[str, ...] = LABELS) -> CRM:
    """The planar mirror of a CRM: labels reversed (``a <-> b`` for two contacts, ``a <-> c``
    for three), ``r -> -r``.

    >>> mirror_crm(CRM("a", "a", 0.08))
    CRM('b', 'b', -0.08)
    >>> mirror_crm(CRM("b", "a", 0.0), ("a", "b", "c"))
    CRM('b', 'c', -0)
    """
    last = len(labels) - 1
    return CRM(labels[last - labels.index(crm.c)], labels[last - labels.index(crm.f)], -crm.r)


@dataclass(frozen=True)
class PlanarModel(LabelledContacts):
    """The hand's contacts ``a, b, ...`` in the plane: rows of ``x, y, nx, ny`` per contact
    (``[ax, ay, anx, any, bx, by, bnx, bny]`` for two), CRMs ``(c, f, r)`` with a scalar
    offset, observation ``(rho, m_a, m_b, ...)``.

    Parameters
    ----------
    hand
        The planar hand (contacts, aperture, palm, reach).
    noise
        Sensing noise of every reading (off by default).
    least_friction
        The least friction of three or more contacts, if not the readable
        [`least_friction`][crmgrasp.model.quality.least_friction]: a kernel hands in its
        compiled copy (`crmgrasp.kernels.compiled_rules`), equal to it bit for bit; the
        configurations are then taken as the rules made them (no checks).
    """

    hand: Hand
    noise: SensorNoise = field(default_factory=SensorNoise)
    least_friction: Callable[[Grip], float] | None = field(default=None, compare=False, repr=False)

    kind: ClassVar[str] = "planar"
    axes: ClassVar[str] = "xy"
    offset_dim: ClassVar[int] = 1

    @property
    def labels(self) -> tuple[str, ...]:  # type: ignore[override]
        """The hand's contact labels (``('a', 'b')`` for the paper's hand)."""
        return self.hand.labels

    # -- configurations and CRMs
    def config_of(self, row: Sequence[float]) -> Config | Grip:
        return contacts_from_row(row)

    def row_of(self, config: Config | Grip) -> list[float]:
        return [v for c in config for v in c]

    def rows_of(self, configs: Sequence[Config | Grip]) -> NDArray[np.float64]:
        return np.asarray(configs, dtype=np.float64).reshape(len(configs), self.row_width)

    def crm(self, c: int, f: int, r: Any) -> CRM:
        return CRM(self.labels[c], self.labels[f], r)

    def is_crm(self, action: object) -> bool:
        return isinstance(action, CRM)

    def check_crm(self, crm: object) -> CRM:
        return self.hand.check_crm(crm)  # type: ignore[arg-type]

    def parse_crm(self, text: str) -> CRM:
        return self.hand.check_crm(CRM.parse(text))

    def offset_data(self, r: Any) -> float:
        return float(r)

    def mirror_crm(self, crm: CRM) -> CRM:
        return mirror_crm(crm, self.labels)

    # -- the rules
    def execute(self, obj: Any, config: Config | Grip, crm: CRM, sensed: Config | Grip | None) -> Outcome:
        """[`execute_crm`][crmgrasp.model.hand.execute_crm]."""
        return execute_crm(obj, self.hand, config, crm, sensed)

    def read(self, config: Config | Grip, rng: np.random.Generator) -> Config | Grip:
        """[`sense`][crmgrasp.model.sensing.SensorNoise.sense]."""
        return self.noise.sense(config, rng)

    def read_rows(self, rows: NDArray[np.float64], rng: np.random.Generator) -> NDArray[np.float64]:
        """[`sense_batch`][crmgrasp.model.sensing.SensorNoise.sense_batch]."""
        return self.noise.sense_batch(rows, rng)

    def observe(self, sensed: Config | Grip) -> tuple[float, ...]:
        """[`observe`][crmgrasp.model.sensing.observe]."""
        return observe(sensed)

    def quality(self, config: Config | Grip) -> float:
        """[`min_friction`][crmgrasp.model.quality.min_friction] (``least_friction`` where
        given, for three or more contacts)."""
        if self.least_friction is not None and len(config) > 2:
            return self.least_friction(config)  # type: ignore[arg-type]
        return min_friction(config)

    def feasible(self, obj: Any, config: Config | Grip) -> Error:
        """[`feasible`][crmgrasp.model.hand.feasible]."""
        return feasible(obj, self.hand, config)

    def check_config(self, obj: Any, config: object, name: str = "configuration") -> Config | Grip:
        """[`check_config`][crmgrasp.model.hand.check_config], with one contact per finger."""
        return check_config(obj, config, name, contacts=self.n_contacts)

    def check_reading(self, config: object, name: str = "reading") -> Config | Grip:
        """[`check_contacts`][crmgrasp.model.contacts.check_contacts], with one contact per finger."""
        return check_contacts(config, name, self.n_contacts)

    def place(self, obj: Any, points: Sequence[ArrayLike]) -> Config | Grip:
        """Each contact at the boundary point nearest its point (finite ``(x, y)``, metres;
        [`contact`][crmgrasp.model.hand.Hand.contact])."""
        if len(points) != self.n_contacts:
            raise CrmgraspError(f"the planar model takes {self.n_contacts} points, got {len(points)}")
        return self.hand.contact(obj, *points)

    def numbers(self, config: Config | Grip) -> list[float]:
        return [v for c in config for v in c]

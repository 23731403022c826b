"""Force-derived observations, sensing noise and observation discretizers ([docs/model.md section 4][model-4]).

Observation (paper Eq. 2-3), computed from *sensed* contacts ``i = a, b, ...``:

* ``rho = |sum_i n_i|^2`` in ``[0, n^2]``: squared frictionless force residual;
* ``m_j = sum_{i != j} (x_i - x_j) x n_i`` (z components, metres), one per contact: the
  frictionless moment about contact ``j``. For two contacts ``m_a = (x_b - x_a) x n_b``
  and ``m_b = (x_a - x_b) x n_a``.

Noise: sensed normal = true normal rotated by ``N(0, sigma_n)`` radians; sensed
position = true position + ``N(0, sigma_p^2 I)`` metres. Each sensing draws three
standard normals per contact in the order ``[angle_a, x_a, y_a, angle_b, x_b, y_b,
...]``, so a batch of ``N`` sensings draws exactly the stream of ``N`` scalar ones.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from crmgrasp._validation import CrmgraspError, boolean, finite, non_negative, shown
from crmgrasp.model.contacts import Config, Contact, Grip, check_contacts, make_config
from crmgrasp.model.hand import Error
from crmgrasp.model.history import MAX_SYMBOLS

__all__ = [
    "Error",
    "Observation",
    "observe",
    "SensorNoise",
    "MAX_SIGMA_N",
    "MAX_SIGMA_P",
    "Discretizer",
    "DEFAULT_RHO",
    "DEFAULT_MOMENT",
]


class Observation(NamedTuple):
    """Continuous force-derived observation: ``rho`` (unitless), ``m_a``, ``m_b`` (m)."""

    rho: float
    m_a: float
    m_b: float


def observe(config: Config | Grip) -> tuple[float, ...]:
    """Frictionless force residual and moments of a (sensed) configuration: an
    [`Observation`][] for two contacts, ``(rho, m_a, m_b, m_c, ...)`` for more.

    Sums run in label order from the first term, so that two contacts give the
    two-contact formulas bit for bit.

    Examples
    --------
    >>> from crmgrasp.model.contacts import Config, Contact
    >>> cfg = Config(Contact(-0.15, -0.02, 1.0, 0.0), Contact(-0.10, -0.05, 0.0, 1.0))
    >>> [round(v, 12) for v in observe(cfg)]
    [2.0, 0.05, -0.03]

    A configuration with a non-finite coordinate or a normal that is not a unit vector is
    refused ([`check_contacts`][crmgrasp.model.contacts.check_contacts]).
    """
    contacts = list(check_contacts(config, "observe"))  # a list: [] without a Config's label lookup
    sx, sy = contacts[0].nx, contacts[0].ny
    for c in contacts[1:]:
        sx += c.nx
        sy += c.ny
    moments = [_moment(contacts, j) for j in range(len(contacts))]
    if len(contacts) == 2:
        return Observation(sx * sx + sy * sy, moments[0], moments[1])
    return (sx * sx + sy * sy, *moments)


def _moment(contacts: list[Contact], j: int) -> float:
    """``m_j = sum_{i != j} (x_i - x_j) x n_i``, summed in label order from the first term."""
    p = contacts[j]
    total: float | None = None
    for i, c in enumerate(contacts):
        if i != j:
            term = (c.x - p.x) * c.ny - (c.y - p.y) * c.nx
            total = term if total is None else total + term
    assert total is not None
    return total


MAX_SIGMA_N = math.pi / 4
"""Largest normal noise, radians (45 degrees): beyond it a sensed normal is as likely to
point along the surface as into it, and a goal line says little about the object."""

MAX_SIGMA_P = 0.1
"""Largest position noise, metres (10 cm, far beyond any fingertip sensor)."""


@dataclass(frozen=True)
class SensorNoise:
    """Gaussian sensing noise on contact normals and positions.

    Parameters
    ----------
    sigma_n
        Standard deviation of the normal's rotation, radians, in ``[0, MAX_SIGMA_N]``
        (45 degrees).
    sigma_p
        Standard deviation of each position coordinate, metres, in ``[0, MAX_SIGMA_P]``
        (0.1 m).
    """

    sigma_n: float = 0.0
    sigma_p: float = 0.0

    def __post_init__(self) -> None:
        sigma_n = non_negative(self.sigma_n, "sigma_n")
        sigma_p = non_negative(self.sigma_p, "sigma_p")
        if sigma_n > MAX_SIGMA_N or sigma_p > MAX_SIGMA_P:
            raise CrmgraspError(
                f"sensing noise (sigma_n {sigma_n:g} rad, sigma_p {sigma_p:g} m) is beyond the valid range "
                f"(sigma_n <= {MAX_SIGMA_N:.4g} rad = 45 degrees, sigma_p <= {MAX_SIGMA_P:g} m)"
            )
        object.__setattr__(self, "sigma_n", sigma_n)
        object.__setattr__(self, "sigma_p", sigma_p)

    @property
    def active(self) -> bool:
        """False when both deviations are zero (sensing is exact and draws nothing)."""
        return self.sigma_n > 0.0 or self.sigma_p > 0.0

    def sense(self, config: Config | Grip, rng: np.random.Generator) -> Config | Grip:
        """A noisy reading of ``config`` (returns ``config`` itself when inactive)."""
        if not self.active:
            return config
        z = rng.standard_normal(3 * len(config))
        return make_config([self._perturb(c, z[k], z[k + 1], z[k + 2]) for c, k in zip(config, range(0, len(z), 3))])

    def _perturb(self, c: Contact, za: float, zx: float, zy: float) -> Contact:
        ang = self.sigma_n * float(za)
        co, si = math.cos(ang), math.sin(ang)
        return Contact(
            c.x + self.sigma_p * float(zx),
            c.y + self.sigma_p * float(zy),
            co * c.nx - si * c.ny,
            si * c.nx + co * c.ny,
        )

    def sense_batch(self, configs: NDArray[np.float64], rng: np.random.Generator) -> NDArray[np.float64]:
        """[`sense`][] of each row of ``(N, 4 n)`` configurations (``n`` contacts): one
        ``standard_normal((N, 3 n))`` draw (the stream of ``N`` scalar readings), each row
        perturbed by the scalar rule. Returns ``configs`` itself when inactive."""
        if not self.active:
            return configs
        n = configs.shape[1] // 4
        z = rng.standard_normal((len(configs), 3 * n)).tolist()
        out = np.empty_like(configs)
        for i, (row, zi) in enumerate(zip(configs.tolist(), z)):
            for k in range(n):
                out[i, 4 * k : 4 * k + 4] = self._perturb(Contact(*row[4 * k : 4 * k + 4]), *zi[3 * k : 3 * k + 3])
        return out


def _thresholds(value: object, name: str) -> tuple[float, ...]:
    try:
        items: tuple[object, ...] = tuple(value)  # type: ignore[call-overload, arg-type]
    except TypeError:
        items = (value,)
    out = tuple(finite(v, f"{name} threshold") for v in items)
    if any(b <= a for a, b in itertools.pairwise(out)):
        raise CrmgraspError(f"{name} thresholds must be strictly increasing, got {out}")
    return out


DEFAULT_RHO = (1.0,)
"""The force residual's default threshold (the paper's bins: ``rho >= 1``)."""

DEFAULT_MOMENT = (0.10,)
"""Each moment's default threshold, metres (the paper's bins: ``|m| >= 0.10``)."""


@dataclass(frozen=True, init=False, repr=False)
class Discretizer:
    """Threshold bins per observed quantity, combined with the error flag.

    The quantities are a contact model's observation, in its order: the squared force
    residual first (``rho``), then one frictionless moment per contact (``m_a``,
    ``m_b``, ... for the two-contact models: [`Observation`][]'s names, the default).
    Thresholds are given per name as keywords; a name left out takes its default
    ([`DEFAULT_RHO`][] for the first, [`DEFAULT_MOMENT`][] for the moments).

    A value ``v`` falls in bin ``k`` = the number of thresholds ``t`` with
    ``v >= t`` (so each quantity has ``len(thresholds) + 1`` bins). Moments are
    binned by magnitude when ``abs_moments`` is true ([docs/model.md section 7][model-7]). The index
    is mixed-radix over the quantities in order, error fastest; for two contacts
    ``((rho_bin * n_ma + ma_bin) * n_mb + mb_bin) * 3 + error``.

    Examples
    --------
    >>> d = Discretizer()               # the paper-box bins: 2 x 2 x 2 x 3
    >>> d.size
    24
    >>> d.index(Observation(2.0, 0.05, -0.12), Error.NONE)
    15
    >>> d.label(15)
    'rho>=1 |m_a|<0.1 |m_b|>=0.1 error=none'
    >>> d.decode(15)
    ((1, 0, 1), <Error.NONE: 0>)
    >>> Discretizer(m_c=(0.1,))
    Traceback (most recent call last):
    ...
    crmgrasp._validation.CrmgraspError: unknown observation 'm_c' in the bins; known: rho, m_a, m_b
    >>> Discretizer(names=("rho", "m_a", "m_b", "m_c")).size     # three contacts' moments
    48
    """

    names: tuple[str, ...]
    """The quantities binned, in the index's order (the model's observation names)."""
    thresholds: tuple[tuple[float, ...], ...]
    """Each quantity's thresholds, strictly increasing, in the order of [`names`][]."""
    abs_moments: bool
    """Whether the moments (every quantity but the first) are binned by magnitude."""
    _strides: tuple[int, ...] = field(repr=False, compare=False)

    def __init__(
        self, *, names: Sequence[str] = Observation._fields, abs_moments: bool = True, **thresholds: object
    ) -> None:
        if isinstance(names, (str, bytes)) or not isinstance(names, Sequence):
            raise CrmgraspError(f"bins need a sequence of observation names, got {shown(names)}")
        names = tuple(names)
        if len(names) < 1 or not all(isinstance(n, str) for n in names) or len(set(names)) != len(names):
            raise CrmgraspError(f"bins need distinct observation names, got {names!r}")
        for key in thresholds:
            if key not in names:
                raise CrmgraspError(f"unknown observation {key!r} in the bins; known: {', '.join(names)}")
        boolean(abs_moments, "abs_moments")
        th = tuple(_thresholds(thresholds.get(n, DEFAULT_MOMENT if i else DEFAULT_RHO), n) for i, n in enumerate(names))
        strides = [len(Error)]
        for t in reversed(th[1:]):
            strides.insert(0, strides[0] * (len(t) + 1))
        size = strides[0] * (len(th[0]) + 1)
        if size > MAX_SYMBOLS:
            raise CrmgraspError(
                f"the bins make {size:,} discrete observations "
                f"({' x '.join(str(len(t) + 1) for t in th)} bins x {len(Error)} error flags); "
                f"a history takes at most {MAX_SYMBOLS:,}"
            )
        object.__setattr__(self, "names", names)
        object.__setattr__(self, "thresholds", th)
        object.__setattr__(self, "abs_moments", abs_moments)
        object.__setattr__(self, "_strides", tuple(strides))

    def __repr__(self) -> str:
        parts = ", ".join(f"{n}={t!r}" for n, t in zip(self.names, self.thresholds))
        return f"Discretizer({parts}, abs_moments={self.abs_moments!r})"

    @property
    def sizes(self) -> tuple[int, ...]:
        """Bins per quantity, in the order of [`names`][]."""
        return tuple(len(t) + 1 for t in self.thresholds)

    @property
    def size(self) -> int:
        """Number of discrete observations (including the error flag)."""
        return self._strides[0] * (len(self.thresholds[0]) + 1)

    def bins(self, values: Sequence[float]) -> tuple[int, ...]:
        """Bin of each quantity (an [`Observation`][], or its values in order): the
        number of thresholds ``t`` with ``value >= t`` (NaN is in bin 0)."""
        absolute = self.abs_moments
        return tuple(_bin(abs(v) if absolute and i else v, t) for i, (v, t) in enumerate(zip(values, self.thresholds)))

    def index(self, values: Sequence[float], error: Error | int) -> int:
        """Integer in ``[0, size)`` for an observation (its values in order) and error flag:
        ``compose(bins(values), error)``, written as one loop (the reference step's hot path)."""
        out, absolute, first = int(error), self.abs_moments, True
        for v, thresholds, stride in zip(values, self.thresholds, self._strides):
            if absolute and not first:
                v = abs(v)
            first = False
            for t in thresholds:
                if v >= t:
                    out += stride
        return out

    def compose(self, bins: Sequence[int], error: int) -> int:
        """The index of the bins and error flag (mixed radix, error fastest); inverse of
        [`decode`][]."""
        return sum(b * s for b, s in zip(bins, self._strides)) + int(error)

    def decode(self, index: int) -> tuple[tuple[int, ...], Error]:
        """Inverse of [`index`][]: the bins of the quantities, and the error flag."""
        if not 0 <= int(index) < self.size:
            raise CrmgraspError(f"observation index {index} is outside [0, {self.size})")
        rest, err = divmod(int(index), len(Error))
        out = []
        for n in reversed(self.sizes[1:]):
            rest, b = divmod(rest, n)
            out.append(b)
        return (rest, *reversed(out)), Error(err)

    def label(self, index: int) -> str:
        """Readable form of an index, e.g. ``'rho>=1 |m_a|<0.1 |m_b|>=0.1 error=none'``."""
        bins, err = self.decode(index)
        parts = [
            _bin_text(f"|{n}|" if self.abs_moments and i else n, t, b)
            for i, (n, t, b) in enumerate(zip(self.names, self.thresholds, bins))
        ]
        return " ".join(parts) + f" error={err.name.lower()}"

    def to_dict(self) -> dict[str, object]:
        """JSON-friendly form (round-trips through ``Discretizer(names=..., **d)``)."""
        return {**{n: list(t) for n, t in zip(self.names, self.thresholds)}, "abs_moments": self.abs_moments}


def _bin(value: float, thresholds: tuple[float, ...]) -> int:
    """The bin of ``value``: how many thresholds ``t`` satisfy ``value >= t``."""
    k = 0
    for t in thresholds:
        if value >= t:
            k += 1
    return k


def _bin_text(name: str, thresholds: tuple[float, ...], k: int) -> str:
    if not thresholds:
        return f"{name}:any"
    if k == 0:
        return f"{name}<{thresholds[0]:g}"
    if k == len(thresholds):
        return f"{name}>={thresholds[-1]:g}"
    return f"{thresholds[k - 1]:g}<={name}<{thresholds[k]:g}"

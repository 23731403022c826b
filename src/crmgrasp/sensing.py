"""Force-derived observations, sensing noise and observation discretizers (SPEC section 4).

Observation (paper Eq. 2-3), computed from *sensed* contacts:

* ``rho = |n_a + n_b|^2`` in ``[0, 4]``: squared frictionless force residual;
* ``m_a = (x_b - x_a) x n_b`` and ``m_b = (x_a - x_b) x n_a`` (z components, metres):
  the frictionless moments about contact a and contact b.

Noise: sensed normal = true normal rotated by ``N(0, sigma_n)`` radians; sensed
position = true position + ``N(0, sigma_p^2 I)`` metres. Each sensing draws six
standard normals in the order ``[angle_a, x_a, y_a, angle_b, x_b, y_b]``, so a
batch of ``N`` sensings draws exactly the stream of ``N`` scalar ones.
"""

from __future__ import annotations

import itertools
import math
from bisect import bisect_right
from dataclasses import dataclass, field
from enum import IntEnum
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from ._validation import CrmgraspError, finite, non_negative
from .contacts import Config, Contact

__all__ = [
    "Error",
    "Observation",
    "observe",
    "observe_batch",
    "SensorNoise",
    "Discretizer",
]


class Error(IntEnum):
    """Error flag observed after a CRM (paper's epsilon_0, epsilon_1, epsilon_2)."""

    NONE = 0
    APERTURE = 1
    PALM = 2


class Observation(NamedTuple):
    """Continuous force-derived observation: ``rho`` (unitless), ``m_a``, ``m_b`` (m)."""

    rho: float
    m_a: float
    m_b: float


def observe(config: Config) -> Observation:
    """Frictionless force residual and moments of a (sensed) configuration.

    Examples
    --------
    >>> from crmgrasp.contacts import Config, Contact
    >>> cfg = Config(Contact(-0.15, -0.02, 1.0, 0.0), Contact(-0.10, -0.05, 0.0, 1.0))
    >>> [round(v, 12) for v in observe(cfg)]
    [2.0, 0.05, -0.03]
    """
    a, b = config
    sx, sy = a.nx + b.nx, a.ny + b.ny
    dx, dy = b.x - a.x, b.y - a.y
    return Observation(sx * sx + sy * sy, dx * b.ny - dy * b.nx, -dx * a.ny + dy * a.nx)


def observe_batch(configs: NDArray[np.float64]) -> NDArray[np.float64]:
    """Vectorised :func:`observe`: ``(N, 8)`` configurations to ``(N, 3)`` ``[rho, m_a, m_b]``."""
    c = configs
    sx, sy = c[:, 2] + c[:, 6], c[:, 3] + c[:, 7]
    dx, dy = c[:, 4] - c[:, 0], c[:, 5] - c[:, 1]
    return np.stack([sx * sx + sy * sy, dx * c[:, 7] - dy * c[:, 6], -dx * c[:, 3] + dy * c[:, 2]], axis=1)


@dataclass(frozen=True)
class SensorNoise:
    """Gaussian sensing noise on contact normals and positions.

    Parameters
    ----------
    sigma_n
        Standard deviation of the normal's rotation, radians (>= 0).
    sigma_p
        Standard deviation of each position coordinate, metres (>= 0).
    """

    sigma_n: float = 0.0
    sigma_p: float = 0.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "sigma_n", non_negative(self.sigma_n, "sigma_n"))
        object.__setattr__(self, "sigma_p", non_negative(self.sigma_p, "sigma_p"))

    @property
    def active(self) -> bool:
        """False when both deviations are zero (sensing is exact and draws nothing)."""
        return self.sigma_n > 0.0 or self.sigma_p > 0.0

    def sense(self, config: Config, rng: np.random.Generator) -> Config:
        """A noisy reading of ``config`` (returns ``config`` itself when inactive)."""
        if not self.active:
            return config
        z = rng.standard_normal(6)
        return Config(self._perturb(config.a, z[0], z[1], z[2]), self._perturb(config.b, z[3], z[4], z[5]))

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
        """Vectorised :meth:`sense` over ``(N, 8)`` configurations (same draws, same order)."""
        if not self.active:
            return configs
        z = rng.standard_normal((len(configs), 6))
        out = np.empty_like(configs)
        for k, zk in ((0, 0), (4, 3)):
            ang = self.sigma_n * z[:, zk]
            co, si = np.cos(ang), np.sin(ang)
            nx, ny = configs[:, k + 2], configs[:, k + 3]
            out[:, k] = configs[:, k] + self.sigma_p * z[:, zk + 1]
            out[:, k + 1] = configs[:, k + 1] + self.sigma_p * z[:, zk + 2]
            out[:, k + 2] = co * nx - si * ny
            out[:, k + 3] = si * nx + co * ny
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


@dataclass(frozen=True)
class Discretizer:
    """Threshold bins per observed quantity, combined with the error flag.

    A value ``v`` falls in bin ``k`` = the number of thresholds ``t`` with
    ``v >= t`` (so each quantity has ``len(thresholds) + 1`` bins). Moments are
    binned by magnitude when ``abs_moments`` is true (SPEC section 7). The index
    is mixed-radix, error fastest:
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
    """

    rho: tuple[float, ...] = (1.0,)
    m_a: tuple[float, ...] = (0.10,)
    m_b: tuple[float, ...] = (0.10,)
    abs_moments: bool = True
    _sizes: tuple[int, int, int] = field(init=False, repr=False, compare=False)
    _codes: NDArray[np.int64] = field(init=False, repr=False, compare=False)  # bin code -> index of error none

    def __post_init__(self) -> None:
        for name in ("rho", "m_a", "m_b"):
            object.__setattr__(self, name, _thresholds(getattr(self, name), name))
        object.__setattr__(self, "_sizes", (len(self.rho) + 1, len(self.m_a) + 1, len(self.m_b) + 1))
        object.__setattr__(self, "_codes", np.arange(self.size // len(Error), dtype=np.int64) * len(Error))

    @property
    def size(self) -> int:
        """Number of discrete observations (including the error flag)."""
        r, a, b = self._sizes
        return r * a * b * len(Error)

    def bins(self, obs: Observation) -> tuple[int, int, int]:
        """Bin of each of ``rho``, ``m_a``, ``m_b``."""
        ma, mb = (abs(obs.m_a), abs(obs.m_b)) if self.abs_moments else (obs.m_a, obs.m_b)
        return (bisect_right(self.rho, obs.rho), bisect_right(self.m_a, ma), bisect_right(self.m_b, mb))

    def index(self, obs: Observation, error: Error | int) -> int:
        """Integer in ``[0, size)`` for an observation and error flag."""
        return self.index_of(obs.rho, obs.m_a, obs.m_b, int(error))

    def index_of(self, rho: float, m_a: float, m_b: float, error: int) -> int:
        """:meth:`index` from plain numbers (the environments' hot path)."""
        if self.abs_moments:
            m_a, m_b = abs(m_a), abs(m_b)
        _, na, nb = self._sizes
        r, a, b = bisect_right(self.rho, rho), bisect_right(self.m_a, m_a), bisect_right(self.m_b, m_b)
        return ((r * na + a) * nb + b) * 3 + error

    def index_batch(self, obs: NDArray[np.float64], error: NDArray[np.integer]) -> NDArray[np.int64]:
        """Vectorised :meth:`index`: ``obs`` of shape ``(N, 3)``, ``error`` of shape ``(N,)``."""
        return self.index_columns(obs[:, 0], obs[:, 1], obs[:, 2], error)

    def index_columns(
        self, rho: NDArray[np.float64], m_a: NDArray[np.float64], m_b: NDArray[np.float64], error: NDArray[np.integer]
    ) -> NDArray[np.int64]:
        """:meth:`index_batch` on columns: the bins' mixed-radix code (in bytes when
        it fits), times 3 by table look-up, plus the error."""
        if self.abs_moments:
            m_a, m_b = np.abs(m_a), np.abs(m_b)
        nr, na, nb = self._sizes
        small = nr * na * nb <= 256  # the bin code fits a byte
        code = _bins(rho, self.rho)
        for values, thresholds, n in ((m_a, self.m_a, na), (m_b, self.m_b, nb)):
            code = code * (np.uint8(n) if small else np.int64(n)) + _bins(values, thresholds)
        return self._codes.take(code) + np.asarray(error)

    def decode(self, index: int) -> tuple[int, int, int, Error]:
        """Inverse of :meth:`index`: ``(rho_bin, ma_bin, mb_bin, error)``."""
        if not 0 <= int(index) < self.size:
            raise CrmgraspError(f"observation index {index} is outside [0, {self.size})")
        rest, err = divmod(int(index), len(Error))
        _, na, nb = self._sizes
        rest, b = divmod(rest, nb)
        r, a = divmod(rest, na)
        return (r, a, b, Error(err))

    def label(self, index: int) -> str:
        """Readable form of an index, e.g. ``'rho>=1 |m_a|<0.1 |m_b|>=0.1 error=none'``."""
        r, a, b, err = self.decode(index)
        fmt = "|{}|" if self.abs_moments else "{}"
        parts = [
            _bin_text("rho", self.rho, r),
            _bin_text(fmt.format("m_a"), self.m_a, a),
            _bin_text(fmt.format("m_b"), self.m_b, b),
        ]
        return " ".join(parts) + f" error={err.name.lower()}"

    def to_dict(self) -> dict[str, object]:
        """JSON-friendly form (round-trips through ``Discretizer(**d)``)."""
        return {"rho": list(self.rho), "m_a": list(self.m_a), "m_b": list(self.m_b), "abs_moments": self.abs_moments}


def _bins(values: NDArray[np.float64], thresholds: tuple[float, ...]) -> NDArray[np.integer]:
    """Per value, its bin: the number of thresholds ``t`` with ``value >= t``."""
    if len(thresholds) == 1:
        return (values >= thresholds[0]).view(np.uint8)
    if len(thresholds) <= 3:  # a few comparisons beat searchsorted's overhead
        out = np.zeros(len(values), dtype=np.uint8)
        for t in thresholds:
            out += values >= t
        return out
    return np.searchsorted(np.asarray(thresholds), values, side="right")


def _bin_text(name: str, thresholds: tuple[float, ...], k: int) -> str:
    if not thresholds:
        return f"{name}:any"
    if k == 0:
        return f"{name}<{thresholds[0]:g}"
    if k == len(thresholds):
        return f"{name}>={thresholds[-1]:g}"
    return f"{thresholds[k - 1]:g}<={name}<{thresholds[k]:g}"

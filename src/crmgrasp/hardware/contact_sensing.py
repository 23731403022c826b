"""Intrinsic contact sensing from a fingertip force/torque sensor (Bicchi, Salisbury
and Brock, IJRR 1993), and the signal conditioning the paper's load cells needed.

For a pure-force contact (a frictional point contact transmits no moment), the
measured force ``f`` and torque ``m`` about the sensor origin satisfy
``m = x x f``: the contact point ``x`` lies on the line of action
``x(l) = (f x m) / |f|^2 + l f``. Intersecting that line with the known fingertip
surface gives the contact: the first crossing along ``f`` (there the force, which
the object exerts on the finger, points into the fingertip). The object's inward
surface normal at the contact is the fingertip's outward normal there. Readings
with ``|f|`` below a threshold are "no contact".

Planar case (vectors in the sensor's x-y plane, torque about z): the line is
``x(l) = m_z (f_y, -f_x) / |f|^2 + l f``. Fingertips: [`Circle`][] (a sphere in
the plane) or [`Flat`][] (a pad ``{x : n . x = d}`` with outward unit normal
``n``); [`Sphere`][] for the spatial case.

The paper's strain gauges drifted with temperature, so forces were high-pass
filtered and contact was detected on the filtered change in force:
[`HighPass`][] (first order, ``y_k = a (y_{k-1} + x_k - x_{k-1})``,
``a = tau / (tau + dt)``) and [`ContactDetector`][].
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from crmgrasp._validation import CrmgraspError, as_numbers, as_point, finite, float_array, positive, shown

__all__ = [
    "Circle",
    "Flat",
    "Sphere",
    "SensedContact",
    "NoContact",
    "contact_from_wrench",
    "HighPass",
    "ContactDetector",
    "MAX_READING",
]

MAX_READING = 1e9
"""The largest force (N) or torque (N m) component a reading may hold: far past any sensor,
and small enough that the line-of-action arithmetic cannot overflow."""


def _reading(value: object, name: str) -> np.ndarray:
    """``value`` (a number or a vector of them) as a float array whose components are finite
    and at most [`MAX_READING`][] in size, or a one-line error naming ``name``."""
    x = float_array(value, name)
    if not np.all(np.isfinite(x)):
        raise CrmgraspError(f"{name} must be finite, got {shown(value)}")
    if np.any(np.abs(x) > MAX_READING):
        raise CrmgraspError(f"{name} must be at most {MAX_READING:g} in size, got {shown(value)}")
    return x


class SensedContact(NamedTuple):
    """A contact estimated from a wrench: point and object-inward normal (sensor frame), force magnitude."""

    point: tuple[float, ...]
    normal: tuple[float, ...]
    force: float


class NoContact(NamedTuple):
    """A reading that does not establish a contact, and why."""

    reason: str


@dataclass(frozen=True)
class Circle:
    """A round fingertip in the plane: centre ``(x, y)`` and radius, metres."""

    radius: float
    center: tuple[float, float] = (0.0, 0.0)

    def __post_init__(self) -> None:
        object.__setattr__(self, "radius", positive(self.radius, "fingertip radius"))
        object.__setattr__(self, "center", as_point(self.center, "fingertip center"))


@dataclass(frozen=True)
class Flat:
    """A flat fingertip pad in the plane ``{x : n . x = offset}``, ``n`` its outward unit normal."""

    normal: tuple[float, float]
    offset: float = 0.0

    def __post_init__(self) -> None:
        nx, ny = as_point(self.normal, "pad normal")
        norm = math.hypot(nx, ny)
        if norm == 0.0:
            raise CrmgraspError("pad normal must be non-zero")
        object.__setattr__(self, "normal", (nx / norm, ny / norm))
        object.__setattr__(self, "offset", finite(self.offset, "pad offset"))


@dataclass(frozen=True)
class Sphere:
    """A spherical fingertip in space: centre ``(x, y, z)`` and radius, metres."""

    radius: float
    center: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        object.__setattr__(self, "radius", positive(self.radius, "fingertip radius"))
        object.__setattr__(self, "center", as_numbers(self.center, "sphere center", 3))


def contact_from_wrench(
    tip: Circle | Flat | Sphere, force: ArrayLike, torque: ArrayLike | float, threshold: float = 0.05
) -> SensedContact | NoContact:
    """Contact point, object normal and force magnitude from a force/torque reading.

    Parameters
    ----------
    tip
        The fingertip surface in the sensor frame.
    force
        Force on the fingertip, newtons: 2 components (planar) or 3 (spatial).
    torque
        Torque about the sensor origin, newton-metres: a scalar ``m_z`` (planar) or 3 components.
    threshold
        Smallest force magnitude that counts as contact, newtons.

    Examples
    --------
    >>> contact_from_wrench(Circle(0.01), (0.0, 2.0), 0.0)
    SensedContact(point=(0.0, -0.01), normal=(0.0, -1.0), force=2.0)
    >>> contact_from_wrench(Circle(0.01), (0.0, 0.01), 0.0)
    NoContact(reason='force 0.01 N below the 0.05 N contact threshold')
    """
    if not isinstance(tip, (Circle, Flat, Sphere)):
        raise CrmgraspError(f"the fingertip must be a Circle, Flat or Sphere, got {shown(tip)}")
    f, m = _reading(force, "force reading"), _reading(torque, "torque reading")
    threshold = positive(threshold, "contact threshold (N)")  # at 0 a zero force would divide by zero
    planar = isinstance(tip, (Circle, Flat))
    if planar and (f.shape != (2,) or m.ndim != 0):
        raise CrmgraspError(f"a planar fingertip needs a 2-vector force and a scalar torque, got {f.shape}, {m.shape}")
    if not planar and (f.shape != (3,) or m.shape != (3,)):
        raise CrmgraspError(f"a spherical fingertip needs 3-vector force and torque, got {f.shape}, {m.shape}")
    mag = float(np.linalg.norm(f))
    if mag < threshold:
        return NoContact(f"force {mag:.3g} N below the {threshold:.3g} N contact threshold")
    if planar:
        base = float(m) * np.array([f[1], -f[0]]) / (mag * mag)
    else:
        base = np.cross(f, m) / (mag * mag)
    if isinstance(tip, Flat):
        n = np.array(tip.normal)
        along = float(n @ f)
        if along >= 0.0:
            return NoContact("force does not press into the pad")
        lam = (tip.offset - float(n @ base)) / along
        point = base + lam * f
        return SensedContact(_tuple(point), _tuple(n), mag)
    c = np.array(tip.center)
    w = base - c
    qa = mag * mag
    qb = float(w @ f)
    qc = float(w @ w) - tip.radius**2
    disc = qb * qb - qa * qc
    if disc < 0.0:
        return NoContact("the line of action misses the fingertip (inconsistent wrench)")
    lam = (-qb - math.sqrt(disc)) / qa
    point = base + lam * f
    normal = (point - c) / tip.radius
    return SensedContact(_tuple(point), _tuple(normal / np.linalg.norm(normal)), mag)


def _tuple(v: np.ndarray) -> tuple[float, ...]:
    return tuple(float(x) + 0.0 for x in v)


class HighPass:
    """First-order high-pass filter over one or more channels.

    ``y_k = a (y_{k-1} + x_k - x_{k-1})`` with ``a = tau / (tau + dt)``: a constant
    offset decays with time constant ``tau`` (seconds); a slow drift of slope
    ``s`` leaves a residual of about ``s tau``; a step passes, then decays.
    """

    def __init__(self, tau: float, dt: float) -> None:
        self.a = positive(tau, "filter time constant tau") / (tau + positive(dt, "sample period dt"))
        self._x: np.ndarray | None = None
        self._y: np.ndarray | None = None

    def __call__(self, x: ArrayLike) -> np.ndarray:
        """Filter one sample (a scalar or a vector of channels, as many as the first sample's)."""
        x = _reading(x, "filter sample")
        if self._x is not None and x.shape != self._x.shape:
            raise CrmgraspError(f"filter sample has shape {x.shape}; the earlier samples had {self._x.shape}")
        if self._x is None:
            self._x, self._y = x.copy(), np.zeros_like(x)
            return self._y.copy()
        self._y = self.a * (self._y + x - self._x)
        self._x = x.copy()
        return self._y.copy()

    def reset(self) -> None:
        """Forget the history (the next sample becomes the new baseline)."""
        self._x = self._y = None


class ContactDetector:
    """Detects contact onsets on the high-pass filtered change in force.

    A constant contact force fades from the filtered signal with time constant
    ``tau`` and a release is a step of the opposite sign, so the detector reports
    events, not a level: it returns True on the sample where the filtered force
    gains more than ``on`` newtons along the direction of the raw force (a new or
    harder push), and re-arms once the filtered magnitude has settled below ``off``.
    """

    def __init__(self, tau: float, dt: float, on: float = 0.2, off: float = 0.1) -> None:
        on, off = finite(on, "onset threshold on (N)"), finite(off, "re-arm threshold off (N)")
        if not 0.0 < off <= on:
            raise CrmgraspError(f"need 0 < off <= on thresholds, got on={on}, off={off}")
        self.filter = HighPass(tau, dt)
        self.on, self.off = on, off
        self._armed = True

    def __call__(self, force: ArrayLike) -> bool:
        """Feed one raw force sample; True exactly at a contact onset."""
        raw = _reading(force, "force sample")
        if raw.ndim != 1:
            raise CrmgraspError(f"a force sample must be a vector of components, got shape {raw.shape}")
        filtered = self.filter(raw)
        size = float(np.linalg.norm(raw))
        gain = float(filtered @ raw) / size if size > 0 else 0.0  # filtered change along the push
        if not self._armed:
            if float(np.linalg.norm(filtered)) < self.off:
                self._armed = True
            return False
        if gain > self.on:
            self._armed = False
            return True
        return False

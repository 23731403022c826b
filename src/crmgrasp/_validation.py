"""Input validation shared by every module: one clear error type, one-line messages."""

from __future__ import annotations

import math

__all__ = ["CrmgraspError", "as_point", "finite", "positive", "non_negative"]


class CrmgraspError(ValueError):
    """Invalid user input: a malformed shape, hand, CRM, task, option or file.

    The message is a single line that names the offending value; the CLI prints it
    as ``crmgrasp: error: <message>`` and exits with status 2.
    """


def finite(value: object, name: str) -> float:
    """Return ``value`` as a finite float, or raise :class:`CrmgraspError`."""
    try:
        x = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise CrmgraspError(f"{name} must be a number, got {value!r}") from None
    if not math.isfinite(x):
        raise CrmgraspError(f"{name} must be finite, got {x}")
    return x


def positive(value: object, name: str) -> float:
    """Return ``value`` as a finite float > 0, or raise :class:`CrmgraspError`."""
    x = finite(value, name)
    if x <= 0.0:
        raise CrmgraspError(f"{name} must be > 0, got {x}")
    return x


def non_negative(value: object, name: str) -> float:
    """Return ``value`` as a finite float >= 0, or raise :class:`CrmgraspError`."""
    x = finite(value, name)
    if x < 0.0:
        raise CrmgraspError(f"{name} must be >= 0, got {x}")
    return x


def as_point(value: object, name: str) -> tuple[float, float]:
    """Return ``value`` as a finite 2-tuple of floats, or raise :class:`CrmgraspError`."""
    if isinstance(value, (str, bytes)):
        raise CrmgraspError(f"{name} must be a pair (x, y), got {value!r}")
    try:
        items = list(value)  # type: ignore[call-overload]
    except TypeError:
        raise CrmgraspError(f"{name} must be a pair (x, y), got {value!r}") from None
    if len(items) != 2:
        raise CrmgraspError(f"{name} must have 2 coordinates, got {len(items)}")
    return (finite(items[0], f"{name}[0]"), finite(items[1], f"{name}[1]"))

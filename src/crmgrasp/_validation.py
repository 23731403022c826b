"""Input validation shared by every module: one clear error type, one-line messages."""

from __future__ import annotations

import math
import re
from numbers import Real
from typing import Any

import numpy as np

__all__ = [
    "CrmgraspError",
    "as_numbers",
    "as_point",
    "generator",
    "is_real",
    "finite",
    "positive",
    "non_negative",
    "integer",
    "shown",
    "tries",
    "setting",
    "SEED_MAX",
    "MAX_TRIES",
]

SEED_MAX = 2**63 - 1
"""Largest seed accepted anywhere (seeds are non-negative and fit a signed 64-bit integer)."""

MAX_TRIES = 1_000_000
"""The most attempts a sampler may be given (``max_tries``) before it gives up."""

_MAX_DIGITS = 30  # longer integers are refused before conversion (no run needs more)


class CrmgraspError(ValueError):
    """Invalid user input: a malformed shape, hand, CRM, task, option or file.

    The message is a single line that names the offending value; the CLI prints it
    as ``crmgrasp: error: <message>`` and exits with status 2.
    """


def shown(value: object, limit: int = 40) -> str:
    """``repr(value)``, cut to ``limit`` characters for a one-line message.

    Examples
    --------
    >>> shown("x" * 100, 10)
    "'xxxxxxxx..."
    """
    text = repr(value)
    return text if len(text) <= limit else text[: limit - 1] + "..."


def finite(value: object, name: str) -> float:
    """Return ``value`` as a finite float, or raise `CrmgraspError`. Text must be
    plain ASCII (Python would also read other scripts' digits)."""
    if isinstance(value, str) and not value.isascii():
        raise CrmgraspError(f"{name} must be a number written with ASCII digits, got {shown(value)}")
    try:
        x = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise CrmgraspError(f"{name} must be a number, got {shown(value)}") from None
    if not math.isfinite(x):
        raise CrmgraspError(f"{name} must be finite, got {x}")
    return x


def is_finite_number(value: object) -> bool:
    """Whether ``value`` is a finite real number as JSON data holds one: an ``int`` or ``float``,
    not a ``bool``, not text (what a saved record's numbers must be; [`finite`][] reads text too).

    Examples
    --------
    >>> is_finite_number(2.5), is_finite_number(True), is_finite_number("1"), is_finite_number(float("nan"))
    (True, False, False, False)
    """
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def is_real(value: object) -> bool:
    """Whether ``value`` is a real number (a Python or NumPy one), not a ``bool``: what a
    user's object (a hand's reading, a raw sensor value) must hold where a number is due.

    >>> is_real(2), is_real(True), is_real("1")
    (True, False, False)
    """
    return isinstance(value, Real) and not isinstance(value, bool)


def positive(value: object, name: str) -> float:
    """Return ``value`` as a finite float > 0, or raise `CrmgraspError`."""
    x = finite(value, name)
    if x <= 0.0:
        raise CrmgraspError(f"{name} must be > 0, got {x}")
    return x


def non_negative(value: object, name: str) -> float:
    """Return ``value`` as a finite float >= 0, or raise `CrmgraspError`."""
    x = finite(value, name)
    if x < 0.0:
        raise CrmgraspError(f"{name} must be >= 0, got {x}")
    return x


def boolean(value: object, name: str) -> bool:
    """Return ``value`` if it is a bool (true or false, not a number or text), or raise
    `CrmgraspError`."""
    if not isinstance(value, bool):
        raise CrmgraspError(f"{name} must be true or false, got {shown(value)}")
    return value


def as_numbers(value: object, name: str, count: int, what: str = "") -> tuple[float, ...]:
    """Return ``value`` (a sequence) as ``count`` finite floats, or raise `CrmgraspError`
    (``what`` names the expected form in the message; default ``"<count> numbers"``).

    >>> as_numbers((0, 1.5, "2"), "pose", 3)
    (0.0, 1.5, 2.0)
    """
    what = what or f"{count} numbers"
    if isinstance(value, (str, bytes)):
        raise CrmgraspError(f"{name} must be {what}, got {shown(value)}")
    try:
        items = list(value)  # type: ignore[call-overload]
    except TypeError:
        raise CrmgraspError(f"{name} must be {what}, got {shown(value)}") from None
    if len(items) != count:
        raise CrmgraspError(f"{name} must have {count} coordinates, got {len(items)}")
    return tuple(finite(v, f"{name}[{i}]") for i, v in enumerate(items))


def float_array(value: object, name: str) -> Any:
    """``value`` (a number, or nested sequences of numbers) as a float64 numpy array, or a
    one-line error naming ``name``: text, bytes, mappings, ragged lists and other objects are not
    numbers. Its shape and values are the caller's to check.

    >>> float_array([(0, 1), (2, 3)], "points").shape
    (2, 2)
    """
    if not isinstance(value, (str, bytes, dict)):
        try:
            return np.asarray(value, dtype=np.float64)
        except (TypeError, ValueError, OverflowError):
            pass
    raise CrmgraspError(f"{name} must be numbers, got {shown(value)}")


def known(name: object, table: Any, what: str) -> str:
    """``name`` if it is text and a key of ``table`` (a registry); otherwise a one-line error
    naming ``what`` and the known names.

    >>> known("sarsa", {"sarsa": 1}, "agent")
    'sarsa'
    """
    if not isinstance(name, str) or name not in table:
        raise CrmgraspError(f"unknown {what} {shown(name)}; known: {', '.join(table)}")
    return name


def listed(value: object, name: str, what: str = "a list") -> tuple[Any, ...]:
    """``value`` as a tuple if it is an ordered collection (a list, tuple, range or 1-D array;
    not text, a mapping or a set), or a one-line error naming ``name``.

    >>> listed([0.04, 0.08], "offsets")
    (0.04, 0.08)
    """
    ordered = not isinstance(value, (str, bytes, dict, set, frozenset)) and hasattr(value, "__len__")
    try:
        if ordered:
            return tuple(value)  # type: ignore[arg-type]
    except TypeError:  # a 0-d array
        pass
    raise CrmgraspError(f"{name} must be {what}, got {shown(value)}")


def as_point(value: object, name: str) -> tuple[float, float]:
    """Return ``value`` as a finite 2-tuple of floats, or raise `CrmgraspError`."""
    return as_numbers(value, name, 2, "a pair (x, y)")  # type: ignore[return-value]


def generator(value: object, name: str = "rng") -> Any:
    """Return ``value`` if it is a ``numpy.random.Generator`` (every random draw of the
    package comes from one), or raise `CrmgraspError`."""
    if not isinstance(value, np.random.Generator):
        raise CrmgraspError(f"{name} must be a numpy.random.Generator, got {shown(value)}")
    return value


def integer(value: object, name: str, low: int, high: int) -> int:
    """Return ``value`` as an ``int`` in ``[low, high]``, or raise `CrmgraspError`.

    Accepts an ``int`` (not a ``bool``) or decimal ASCII text such as ``"12"``; refuses
    floats, other scripts' digits and overlong text before converting it.

    Examples
    --------
    >>> integer("7", "trials", 1, 10)
    7
    """
    if isinstance(value, str):
        text = value.strip()
        if not (text.isascii() and text.lstrip("+-").isdigit() and len(text) <= _MAX_DIGITS):
            raise CrmgraspError(f"{name} must be an integer in [{low}, {high}], got {shown(value)}")
        value = int(text)
    if isinstance(value, bool) or not isinstance(value, int):
        raise CrmgraspError(f"{name} must be an integer in [{low}, {high}], got {shown(value)}")
    if not low <= value <= high:
        raise CrmgraspError(f"{name} must be an integer in [{low}, {high}], got {value}")
    return value


def seed_value(value: object, name: str = "seed") -> int:
    """``value`` as a seed: an integer (Python's or NumPy's) in ``[0, SEED_MAX]``, or text of
    one (one-line error otherwise).

    >>> seed_value(3)
    3
    """
    if isinstance(value, np.integer):
        value = int(value)
    return integer(value, name, 0, SEED_MAX)


def optional_seed(value: object) -> int | None:
    """``None``, or [`seed_value`][]'s ``value``.

    >>> optional_seed(3), optional_seed(None)
    (3, None)
    """
    return None if value is None else seed_value(value)


def setting(text: str) -> tuple[str, bool | int | float]:
    """``"KEY=VALUE"`` as ``(KEY, value)``: ``true``/``false`` (any case) as a ``bool``, a
    decimal integer as an ``int``, anything else as a finite ``float``; a one-line
    `CrmgraspError` names a malformed item.

    Examples
    --------
    >>> setting("plan_every=5"), setting("beta=0.5"), setting("sample=False")
    (('plan_every', 5), ('beta', 0.5), ('sample', False))
    """
    key, sep, raw = text.partition("=")
    if not sep or not key.strip() or not raw.strip():
        raise CrmgraspError(f"a setting must read KEY=VALUE, got {shown(text)}")
    word = raw.strip()
    if word.lower() in ("true", "false"):
        return key.strip(), word.lower() == "true"
    if re.fullmatch(f"[+-]?[0-9]{{1,{_MAX_DIGITS}}}", word):
        return key.strip(), int(word)
    return key.strip(), finite(word, key.strip())


def tries(value: object) -> int:
    """A sampler's ``max_tries``: an integer in ``[1, MAX_TRIES]``.

    >>> tries(10)
    10
    """
    return integer(value, "max_tries", 1, MAX_TRIES)


def require_extra(extra: str, what: str, *modules: str) -> tuple[Any, ...]:
    """Import ``modules`` and return them, or raise a one-line error: ``what`` needs the
    optional extra ``crmgrasp[extra]``, with pip's command to install it."""
    import importlib

    try:
        return tuple(importlib.import_module(name) for name in modules)
    except ImportError as exc:
        raise CrmgraspError(f"{what} needs the optional extra: pip install 'crmgrasp[{extra}]' ({exc})") from None

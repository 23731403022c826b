"""The one check of an experiment's parameters: each field of its config against its type.

Every experiment takes a frozen dataclass of parameters (``Figure7Config``, ...). The
command line builds them from checked options, but a user may build one in Python
(``GeneralizationConfig(families=(...))``). [`CheckedConfig`][] checks every field against
its annotation on construction, so that a wrong value is one line naming the field, not an
error from deep inside a run that has already written files:

* ``int``: an integer (not a bool) in ``[0, SEED_MAX]``: every count and seed here is one;
* ``float``: a finite number; ``bool``: true or false; ``str``: text;
* ``X | None``: ``None`` or an ``X``;
* ``tuple[X, ...]`` and ``tuple[X, Y]``: a list or tuple of such values (of that length),
  stored as a tuple;
* any other class (a learner's spec, a deep learner's config): an instance of it.

Bounds beyond these (at least one trial, a known task) are the experiment's to check, where
it states them.
"""

from __future__ import annotations

import dataclasses
import functools
import types
import typing
from typing import Any, TypeVar

from crmgrasp._validation import SEED_MAX, CrmgraspError, boolean, finite, integer, shown

__all__ = ["CheckedConfig", "checked_config", "checked_value"]

C = TypeVar("C")


class CheckedConfig:
    """Base of an experiment's frozen config dataclass: [`checked_value`][] of every field
    on construction (a subclass with its own ``__post_init__`` calls this one first)."""

    def __post_init__(self) -> None:
        hints = _hints(type(self))  # type: ignore[arg-type]  # a class is hashable
        for f in dataclasses.fields(self):  # type: ignore[arg-type]
            value = checked_value(getattr(self, f.name), hints[f.name], f"{type(self).__name__}.{f.name}")
            object.__setattr__(self, f.name, value)


def checked_config(config: object, cls: type[C]) -> C:
    """``config`` if it is a ``cls`` (an experiment's parameters); a one-line error otherwise."""
    if not isinstance(config, cls):
        raise CrmgraspError(f"the experiment's parameters must be a {cls.__name__}, got {shown(config)}")
    return config


@functools.cache
def _hints(cls: type) -> dict[str, Any]:
    return typing.get_type_hints(cls)


def checked_value(value: Any, hint: Any, name: str) -> Any:
    """``value`` checked against the annotation ``hint`` (module docstring), tuples as
    tuples; a one-line error naming ``name`` otherwise.

    >>> checked_value([1, 2], tuple[int, ...], "seeds")
    (1, 2)
    """
    args = typing.get_args(hint)
    if isinstance(hint, types.UnionType) or typing.get_origin(hint) is typing.Union:
        (inner,) = (a for a in args if a is not type(None))
        return None if value is None else checked_value(value, inner, name)
    if typing.get_origin(hint) is tuple:
        return _checked_tuple(value, args, name)
    if hint is int:
        return integer(value, name, 0, SEED_MAX) if not isinstance(value, str) else _wrong(value, "an integer", name)
    if hint is float:
        return finite(value, name) if not isinstance(value, (str, bytes)) else _wrong(value, "a number", name)
    if hint is bool:
        return boolean(value, name)
    if hint is str:
        return value if isinstance(value, str) else _wrong(value, "text", name)
    if isinstance(hint, type) and not isinstance(value, hint):
        _wrong(value, f"a {hint.__name__}", name)
    return value


def _checked_tuple(value: Any, args: tuple[Any, ...], name: str) -> tuple[Any, ...]:
    if not isinstance(value, (tuple, list)):
        _wrong(value, "a list", name)
    if args[-1] is Ellipsis:
        return tuple(checked_value(v, args[0], f"{name}[{i}]") for i, v in enumerate(value))
    if len(value) != len(args):
        raise CrmgraspError(f"{name} must have {len(args)} items, got {len(value)}")
    return tuple(checked_value(v, a, f"{name}[{i}]") for i, (v, a) in enumerate(zip(value, args)))


def _wrong(value: Any, what: str, name: str) -> typing.NoReturn:
    raise CrmgraspError(f"{name} must be {what}, got {shown(value)}")

"""The readers that every task-file section shares, planar and spatial.

Each reader checks one kind of value (a table's keys, a finite number, a list of numbers,
the ``[[crm]]`` tables, the bins, a task name) and answers bad input with a one-line
`CrmgraspError` that names the key. [`common_keys`][]
reads the keys both task-file models take (bins, noise, goal, rewards, length,
reference, description, symmetry). [`crmgrasp.tasks.files`][] (planar) and
`crmgrasp.tasks.spatial_files` (spatial) build on them; neither imports the other's
readers.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import types
import typing
from collections.abc import Callable, Collection, Sequence
from typing import Any

from crmgrasp._validation import CrmgraspError, shown
from crmgrasp.model.actions import CRMRange
from crmgrasp.model.contact_model import observation_names
from crmgrasp.model.contacts import LABELS
from crmgrasp.model.hand import CRM
from crmgrasp.model.sensing import Discretizer, SensorNoise
from crmgrasp.tasks.core import Task
from crmgrasp.tasks.symmetry import Symmetry

__all__ = [
    "init_keys",
    "read_fields",
    "write_fields",
    "field_rows",
    "SCALAR_KEYS",
    "COMMON_SECTIONS",
    "TOP_ONLY",
    "check_top_level",
    "common_dict",
    "table_keys",
    "number",
    "numbers",
    "crm_tables",
    "range_entries",
    "typed",
    "DEFAULT_GRID",
    "bins_table",
    "section",
    "common_keys",
]


def init_keys(cls: type) -> tuple[set[str], set[str]]:
    """The keys a table for the dataclass ``cls`` takes (its constructor's fields) and the
    ones it needs (those without a default): the class owns its schema, the readers ask it."""
    fields = [f for f in dataclasses.fields(cls) if f.init]
    required = {f.name for f in fields if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING}
    return {f.name for f in fields}, required


@functools.cache
def _hints(cls: type) -> dict[str, Any]:
    return typing.get_type_hints(cls)


def typed(value: Any, hint: Any, key: str) -> Any:
    """``value`` checked against a field's type: a float is a finite number, an int an
    integer (not a boolean), a bool true or false, a str a string, ``X | None`` an ``X``
    (or absent), a tuple of floats a list of numbers (of the tuple's length when it
    states one)."""
    if isinstance(hint, types.UnionType) or typing.get_origin(hint) is typing.Union:
        (inner,) = (a for a in typing.get_args(hint) if a is not type(None))
        return None if value is None else typed(value, inner, key)
    if hint is float:
        return number(value, key)
    if hint is bool or hint is int or hint is str:
        if not isinstance(value, hint) or (hint is int and isinstance(value, bool)):
            what = {bool: "true or false", int: "an integer", str: "a string"}[hint]
            raise CrmgraspError(f"{key} must be {what}, got {shown(value)}")
        return value
    args = typing.get_args(hint)
    if typing.get_origin(hint) is tuple and args:
        out = numbers(value, key)
        if args[-1] is not Ellipsis and len(out) != len(args):
            raise CrmgraspError(f"{key} must have {len(args)} numbers, got {len(out)}")
        return out
    raise TypeError(f"{key}: a field of type {hint} has no task-file form")  # a bug, not bad input


def read_fields(cls: type, table: Any, where: str, prefix: str, skip: Collection[str] = ()) -> dict[str, Any]:
    """The keyword arguments that ``table`` states for the dataclass ``cls``.

    Its keys are the class's constructor fields (less ``skip``); each value is checked
    against the field's type ([`typed`][]; errors name the key as ``prefix + key``); a
    key left out takes the class's default, and the class itself checks the bounds. The
    class owns its schema: defaults, types and bounds are stated once, there."""
    allowed, required = init_keys(cls)
    t = table_keys(table, where, allowed - set(skip), required - set(skip))
    hints = _hints(cls)
    return {k: typed(v, hints[k], f"{prefix}{k}") for k, v in t.items()}


def write_fields(obj: Any, skip: Collection[str] = ()) -> dict[str, Any]:
    """A dataclass as the table [`read_fields`][] reads back: every constructor field
    (less ``skip``) in declaration order, tuples as lists; a field that is ``None`` or
    infinite is left out, which reads back as its default (``None`` or infinity)."""
    out: dict[str, Any] = {}
    for f in dataclasses.fields(obj):
        v = getattr(obj, f.name)
        if not f.init or f.name in skip or v is None or (isinstance(v, float) and math.isinf(v)):
            continue
        out[f.name] = list(v) if isinstance(v, tuple) else v
    return out


def _type_text(hint: Any) -> str:
    """A field's type in a task file's words (``number``, ``integer``, ``2 numbers``)."""
    if isinstance(hint, types.UnionType) or typing.get_origin(hint) is typing.Union:
        (inner,) = (a for a in typing.get_args(hint) if a is not type(None))
        return f"{_type_text(inner)} (optional)"
    args = typing.get_args(hint)
    if typing.get_origin(hint) is tuple:
        return "list of numbers" if args[-1] is Ellipsis else f"{len(args)} numbers"
    return {float: "number", int: "integer", bool: "true or false", str: "string"}[hint]


def _value_text(value: Any) -> str:
    """A default as a task file writes it (``true``, ``"incoming"``, ``[0.005, 0.05]``)."""
    if value is None or (isinstance(value, float) and math.isinf(value)):
        return "none" if value is None else "no bound"
    if isinstance(value, bool):
        return str(value).lower()
    if isinstance(value, str):
        return f'"{value}"'
    return repr(list(value)) if isinstance(value, tuple) else repr(value)


def field_rows(cls: type, skip: Collection[str] = ()) -> list[tuple[str, str, str]]:
    """``(key, type, default)`` of each key a table for ``cls`` takes, in the task file's
    words, for the docs (``crmgrasp task-template --keys``)."""
    rows = []
    for f in dataclasses.fields(cls):
        if f.init and f.name not in skip:
            default = "required" if f.default is dataclasses.MISSING else _value_text(f.default)
            rows.append((f.name, _type_text(_hints(cls)[f.name]), default))
    return rows


def table_keys(table: Any, where: str, allowed: set[str], required: set[str] = frozenset()) -> dict[str, Any]:  # type: ignore[assignment]
    if not isinstance(table, dict):
        raise CrmgraspError(f"{where} must be a table, got {shown(table)}")
    for key in table:
        if key not in allowed:
            raise CrmgraspError(f"unknown key {key!r} in {where}; known: {', '.join(sorted(allowed))}")
    for key in sorted(required):
        if key not in table:
            raise CrmgraspError(f"{where} needs the key {key!r}")
    return table


def number(value: Any, key: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise CrmgraspError(f"{key} must be a finite number, got {shown(value)}")
    return float(value)


def numbers(value: Any, key: str) -> tuple[float, ...]:
    if not isinstance(value, list):
        raise CrmgraspError(f"{key} must be a list of numbers, got {shown(value)}")
    return tuple(number(v, f"{key}[{i}]") for i, v in enumerate(value))


DEFAULT_GRID = 5
"""Offsets per coordinate that an ``[[crm]]`` offset range gives the discrete actions
unless its ``grid`` says otherwise (5 over ``[-r, r]``: ``-r, -r/2, 0, r/2, r``)."""


def _offset_range(c: str, f: str, r: Any, dim: int, key: str) -> CRMRange | None:
    """The range an ``[[crm]]`` entry's ``r`` states, or ``None`` for a fixed offset:
    ``[low, high]`` in the plane (``dim = 1``), ``[[low_1, high_1], [low_2, high_2]]`` in space."""
    if not isinstance(r, list) or (dim > 1 and not all(isinstance(v, list) for v in r)):
        return None
    spans = [r] if dim == 1 else r
    if len(spans) != dim:
        raise CrmgraspError(f"{key} must be a range [low, high] per offset coordinate ({dim}), got {shown(r)}")
    pairs = [numbers(span, key) for span in spans]
    if any(len(p) != 2 for p in pairs):
        raise CrmgraspError(f"{key} must be a range [low, high] per offset coordinate, got {shown(r)}")
    return CRMRange(c, f, tuple(p[0] for p in pairs), tuple(p[1] for p in pairs))


def crm_tables(
    value: Any, make: Callable[[str, str, Any, str], Any] | None = None, labels: Sequence[str] = LABELS, dim: int = 1
) -> tuple[tuple[Any, ...], tuple[CRMRange, ...]]:
    """The ``[[crm]]`` tables: the fixed CRMs (the discrete actions) and the offset ranges
    (the continuous action space, ``Task.ranges``), ``c`` and ``f`` among the hand's
    contact ``labels``. ``make(c, f, r, where)`` builds a CRM (default: planar, ``r`` a
    number, 0 when absent); an entry whose ``r`` is a range (``[low, high]``; in space one
    per coordinate) adds its
    range and ``grid`` (default [`DEFAULT_GRID`][]; 0 for none) evenly spaced CRMs of it to
    the discrete actions."""
    if not isinstance(value, list) or not value:
        raise CrmgraspError("the task needs at least one [[crm]] table")
    build = make or (lambda c, f, r, where: CRM(c, f, number(0.0 if r is None else r, f"{where} r")))
    actions: list[Any] = []
    ranges: list[CRMRange] = []
    for i, t in enumerate(value):
        where = f"[[crm]] number {i + 1}"
        t = table_keys(t, where, {"c", "f", "r", "grid"}, {"c", "f"})
        if t["c"] not in labels or t["f"] not in labels:
            quoted = [f'"{lab}"' for lab in labels]
            names = ", ".join(quoted[:-1]) + " or " + quoted[-1]
            raise CrmgraspError(f"{where}: c and f must be {names}, got {shown(t['c'])}, {shown(t['f'])}")
        rg = _offset_range(t["c"], t["f"], t.get("r"), dim, f"{where} r")
        if rg is None:
            if "grid" in t:
                raise CrmgraspError(f"{where}: grid applies to an offset range (r = [low, high]), not to a fixed r")
            actions.append(build(t["c"], t["f"], t.get("r"), where))
            continue
        grid = t.get("grid", DEFAULT_GRID)
        if isinstance(grid, bool) or not isinstance(grid, int) or not 0 <= grid <= 1000:
            raise CrmgraspError(f"{where} grid must be an integer in [0, 1000], got {shown(grid)}")
        ranges.append(rg)
        points = [] if grid == 0 else ([rg.low] if rg.fixed else rg.grid(grid))
        actions += [build(t["c"], t["f"], p[0] if dim == 1 else list(p), where) for p in points]
    return tuple(actions), tuple(ranges)


def range_entries(ranges: Sequence[CRMRange]) -> list[dict[str, Any]]:
    """Offset ranges as ``[[crm]]`` entries that add no discrete action (``grid = 0``)."""
    out = []
    for rg in ranges:
        spans = [[lo, hi] for lo, hi in zip(rg.low, rg.high, strict=True)]
        out.append({"c": rg.c, "f": rg.f, "r": spans[0] if rg.dim == 1 else spans, "grid": 0})
    return out


def bins_table(table: Any, names: tuple[str, ...] = Discretizer().names) -> Discretizer:
    """The ``[bins]`` table: thresholds per observation name of the model (``names``;
    each a list of numbers, its default [`Discretizer`][crmgrasp.model.sensing.Discretizer]'s when
    left out) and ``abs_moments``."""
    t = table_keys(table, "[bins]", {*names, "abs_moments"})
    abs_m = t.get("abs_moments", True)
    if not isinstance(abs_m, bool):
        raise CrmgraspError(f"bins.abs_moments must be true or false, got {shown(abs_m)}")
    kw = {q: numbers(t[q], f"bins.{q}") for q in names if q in t}
    return Discretizer(names=names, abs_moments=abs_m, **kw)


def section(key: str, build: Callable[[Any], Any], value: Any) -> Any:
    """``build(value)`` with the key named in any error."""
    try:
        return build(value)
    except CrmgraspError as exc:
        text = str(exc)
        raise CrmgraspError(text if key in text else f"{key}: {text}") from None
    except (TypeError, ValueError) as exc:
        raise CrmgraspError(f"{key}: {exc}") from None


SCALAR_KEYS = ("description", "mu_goal", "max_steps", "grasp_reward", "error_cost", "reference_mean_steps")
"""The top-level keys of every task file that are fields of [`Task`][crmgrasp.tasks.core.Task]
itself: read by their field types, bounded by the Task."""

COMMON_SECTIONS = ("name", "hand", "crm", "bins", "starts", "noise", "family", "symmetry", *SCALAR_KEYS)
"""The keys planar and spatial task files share."""


TOP_ONLY = ("symmetry", *SCALAR_KEYS)
"""Top-level keys that no table of a task file takes."""


def check_top_level(doc: Any) -> None:
    """A one-line error naming the table when a key of [`TOP_ONLY`][] sits inside one: TOML
    puts every key written after a ``[table]`` header into that table, so a top-level key
    must come before the first header."""
    if not isinstance(doc, dict):
        return
    for name, value in doc.items():
        for table in value if isinstance(value, list) else [value]:
            stray = [k for k in table if k in TOP_ONLY] if isinstance(table, dict) else []
            if stray:
                raise CrmgraspError(
                    f"{stray[0]!r} sits in [{name}] but is a top-level key: TOML puts every key after a "
                    "[table] header into that table, so write it before the first [table]"
                )


def common_keys(d: dict[str, Any], kw: dict[str, Any]) -> None:
    """The keys planar and spatial task files share (bins, noise, [`SCALAR_KEYS`][],
    symmetry), checked into the task's keyword arguments ``kw``."""
    if "bins" in d:
        names = observation_names(kw["hand"].labels)
        kw["discretizer"] = section("bins", lambda t: bins_table(t, names), d["bins"])
    if "noise" in d:
        noise = section("noise", lambda t: read_fields(SensorNoise, t, "[noise]", "noise."), d["noise"])
        kw["noise"] = section("noise", lambda kw: SensorNoise(**kw), noise)
    hints = _hints(Task)
    for key in SCALAR_KEYS:
        if d.get(key) is not None:
            kw[key] = typed(d[key], hints[key], key)
    if d.get("symmetry") is not None:
        sym = d["symmetry"]
        if not isinstance(sym, list) or any(isinstance(i, bool) or not isinstance(i, int) for i in sym):
            raise CrmgraspError(f"symmetry must be a list of action indices, got {shown(sym)}")
        kw["symmetry"] = Symmetry(tuple(sym))


def common_dict(task: Task, hand: Any) -> dict[str, Any]:
    """What planar and spatial task files share, written from ``task`` (its ``hand``:
    the planar or the spatial one): the inverse of [`common_keys`][] with the name,
    the hand and the bins."""
    doc: dict[str, Any] = {"name": task.name, **{k: getattr(task, k) for k in SCALAR_KEYS}}
    if task.reference_mean_steps is None:
        del doc["reference_mean_steps"]
    doc["hand"] = write_fields(hand)
    doc["bins"] = task.discretizer.to_dict()
    doc["noise"] = write_fields(task.noise)
    if task.symmetry is not None:
        doc["symmetry"] = list(task.symmetry.actions)
    return doc

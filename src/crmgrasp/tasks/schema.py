"""The readers that every task-file section shares, planar and spatial.

Each reader checks one kind of value (a table's keys, a finite number, a list of numbers,
the ``[[crm]]`` tables, the bins, a task name) and answers bad input with a one-line
:class:`~crmgrasp._validation.CrmgraspError` that names the key. :func:`common_keys`
reads the keys both task-file models take (bins, noise, goal, rewards, length,
reference, description, symmetry). :mod:`crmgrasp.tasks.files` (planar) and
:mod:`crmgrasp.tasks.spatial_files` (spatial) build on them; neither imports the other's
readers.
"""

from __future__ import annotations

import dataclasses
import math
import re
from collections.abc import Callable
from typing import Any

from crmgrasp._validation import CrmgraspError, shown
from crmgrasp.model.hand import CRM
from crmgrasp.model.sensing import Discretizer, SensorNoise
from crmgrasp.tasks.core import Symmetry

__all__ = [
    "init_keys",
    "table_keys",
    "number",
    "numbers",
    "crm_tables",
    "bins_table",
    "section",
    "checked_name",
    "common_keys",
]

_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9._-]{0,63}")


def init_keys(cls: type) -> tuple[set[str], set[str]]:
    """The keys a table for the dataclass ``cls`` takes (its constructor's fields) and the
    ones it needs (those without a default): the class owns its schema, the readers ask it."""
    fields = [f for f in dataclasses.fields(cls) if f.init]
    required = {f.name for f in fields if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING}
    return {f.name for f in fields}, required


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


def crm_tables(value: Any, make: Callable[[str, str, Any, str], Any] | None = None) -> tuple[Any, ...]:
    """The ``[[crm]]`` tables; ``make(c, f, r, where)`` builds each (default: a planar CRM,
    ``r`` a number, 0 when absent)."""
    if not isinstance(value, list) or not value:
        raise CrmgraspError("the task needs at least one [[crm]] table")
    out = []
    for i, t in enumerate(value):
        where = f"[[crm]] number {i + 1}"
        t = table_keys(t, where, {"c", "f", "r"}, {"c", "f"})
        if t["c"] not in ("a", "b") or t["f"] not in ("a", "b"):
            raise CrmgraspError(f'{where}: c and f must be "a" or "b", got {shown(t["c"])}, {shown(t["f"])}')
        if make is None:
            out.append(CRM(t["c"], t["f"], number(t.get("r", 0.0), f"{where} r")))
        else:
            out.append(make(t["c"], t["f"], t.get("r"), where))
    return tuple(out)


def bins_table(table: Any) -> Discretizer:
    t = table_keys(table, "[bins]", {"rho", "m_a", "m_b", "abs_moments"})
    abs_m = t.get("abs_moments", True)
    if not isinstance(abs_m, bool):
        raise CrmgraspError(f"bins.abs_moments must be true or false, got {shown(abs_m)}")
    kw = {q: numbers(t[q], f"bins.{q}") for q in ("rho", "m_a", "m_b") if q in t}
    return Discretizer(**kw, abs_moments=abs_m)  # type: ignore[arg-type]


def section(key: str, build: Callable[[Any], Any], value: Any) -> Any:
    """``build(value)`` with the key named in any error."""
    try:
        return build(value)
    except CrmgraspError as exc:
        text = str(exc)
        raise CrmgraspError(text if key in text else f"{key}: {text}") from None
    except (TypeError, ValueError) as exc:
        raise CrmgraspError(f"{key}: {exc}") from None


def checked_name(name: Any) -> str:
    """``name`` if it is a valid task name (one-line error otherwise)."""
    if not isinstance(name, str) or not _NAME.fullmatch(name):
        raise CrmgraspError(
            f"name must be 1-64 letters, digits, '.', '_' or '-' (first a letter or digit), got {shown(name)}"
        )
    return name


def common_keys(d: dict[str, Any], kw: dict[str, Any]) -> None:
    """The keys planar and spatial task files share (bins, noise, goal, rewards, length,
    reference, description, symmetry), checked into the task's keyword arguments ``kw``."""
    if "bins" in d:
        kw["discretizer"] = section("bins", bins_table, d["bins"])
    if "noise" in d:
        t = section("noise", lambda v: table_keys(v, "[noise]", {"sigma_n", "sigma_p"}), d["noise"])
        kw["noise"] = section("noise", lambda t: SensorNoise(**{k: number(v, f"noise.{k}") for k, v in t.items()}), t)
    if "mu_goal" in d:
        kw["mu_goal"] = number(d["mu_goal"], "mu_goal")
    if "grasp_reward" in d:
        kw["grasp_reward"] = number(d["grasp_reward"], "grasp_reward")
    if "error_cost" in d:
        kw["error_cost"] = number(d["error_cost"], "error_cost")
    if "max_steps" in d:
        m = d["max_steps"]
        if isinstance(m, bool) or not isinstance(m, int):
            raise CrmgraspError(f"max_steps must be an integer, got {shown(m)}")
        kw["max_steps"] = m  # its bounds: Task's (MAX_STEPS)
    if d.get("reference_mean_steps") is not None:
        kw["reference_mean_steps"] = number(d["reference_mean_steps"], "reference_mean_steps")
    if "description" in d:
        if not isinstance(d["description"], str):
            raise CrmgraspError(f"description must be a string, got {shown(d['description'])}")
        kw["description"] = d["description"]
    if d.get("symmetry") is not None:
        sym = d["symmetry"]
        if not isinstance(sym, list) or any(isinstance(i, bool) or not isinstance(i, int) for i in sym):
            raise CrmgraspError(f"symmetry must be a list of action indices, got {shown(sym)}")
        kw["symmetry"] = Symmetry(tuple(sym))

"""Study files: the cells and seeds of a sweep, parsed and checked.

A study file is TOML::

    name = "alpha-study"
    trials = 20
    episodes = 500
    eval_episodes = 200        # optional (default 200)
    seeds = [0, 1, 2]
    [grid]                     # every combination of these values is a cell ...
    task = ["paper-box"]
    agent = ["sarsa", "dyna-q"]
    alpha = [0.1, 0.3, 0.6]
    # [[cell]]                 # ... and/or cells listed one by one
    # agent = "q"
    # epsilon = 0.1

Cell keys: ``task`` (a name, a .toml file, read beside the study file when its path is
relative, or ``package.module:factory``), ``start_preset``, ``grasp_reward``, ``agent``,
``k``, ``symmetric`` and every registered agent's scalar keyword parameters
([`agent_params`][]: ``alpha``, ``beta``, ``mean_after``, ...), each typed as its
constructor's default. A cell may set only the parameters its agent takes. Every error is
one line naming the file, the cell and the key.
"""

from __future__ import annotations

import dataclasses
import difflib
import hashlib
import itertools
import json
import math
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from crmgrasp._io import read_bounded
from crmgrasp._validation import CrmgraspError, integer, seed_value, shown
from crmgrasp.tasks.core import checked_name
from crmgrasp.tasks.schema import typed

__all__ = [
    "Study",
    "load_study",
    "study_from_dict",
    "cell_id",
    "cell_keys",
    "table_keys",
    "agent_params",
    "BASE_KEYS",
    "TABLE_PARAMS",
]

BASE_KEYS = ("task", "start_preset", "grasp_reward", "agent", "k", "symmetric")
"""The cell keys that are not an agent's parameters."""

TABLE_PARAMS = ("alpha", "gamma", "epsilon", "q0", "lam", "trace", "n_planning", "planning", "q_act", "unknown")
"""The agent parameters every study's tables carry as columns (the parameters of the first
learners); a study's other parameters follow them where a cell sets them."""

_DEFAULT_CELL = {"task": "paper-box", "agent": "sarsa", "k": 2}


def agent_params() -> tuple[str, ...]:
    """Every registered agent's keyword parameters whose defaults are scalars (booleans,
    integers, floats, strings), in the registry's order: what a cell may set besides
    [`BASE_KEYS`][]. Read from the registry at each call, so an agent registered later
    counts."""
    from crmgrasp.agents.training import AGENTS, agent_parameters, parameter_defaults

    names = dict.fromkeys(p for agent in AGENTS for p in agent_parameters(agent))
    scalar = (bool, int, float, str)
    return tuple(p for p in names if all(type(d) in scalar for d in parameter_defaults(p).values()))


def cell_keys() -> tuple[str, ...]:
    """The keys a cell may set: [`BASE_KEYS`][] and [`agent_params`][]."""
    return (*BASE_KEYS, *agent_params())


def table_keys(study: Study) -> list[str]:
    """The cell keys ``study``'s tables carry as columns: [`BASE_KEYS`][], [`TABLE_PARAMS`][],
    then the other agent parameters its cells set, in [`agent_params`][]' order."""
    extra = [k for k in agent_params() if k not in TABLE_PARAMS and any(k in c for c in study.cells)]
    return [*BASE_KEYS, *TABLE_PARAMS, *extra]


@dataclass(frozen=True)
class Study:
    """A parsed study: budgets, seeds and the cells (each a dict of cell keys)."""

    name: str
    trials: int
    episodes: int
    eval_episodes: int
    seeds: tuple[int, ...]
    cells: tuple[dict[str, Any], ...]

    def to_dict(self) -> dict[str, Any]:
        """Plain data (what ``run.json`` records and ``--resume`` compares)."""
        return {
            "name": self.name,
            "trials": self.trials,
            "episodes": self.episodes,
            "eval_episodes": self.eval_episodes,
            "seeds": list(self.seeds),
            "cells": [dict(c) for c in self.cells],
        }


def cell_id(cell: dict[str, Any]) -> str:
    """A short stable name of a cell: agent, k and a digest of its settings."""
    digest = hashlib.sha256(json.dumps(cell, sort_keys=True).encode()).hexdigest()[:8]
    return f"{cell.get('agent', 'sarsa')}-k{cell.get('k', 2)}-{digest}"


def _scalar(key: str, value: Any, where: str) -> Any:
    if isinstance(value, (dict, list)):
        raise CrmgraspError(f"{where}: {key} must be a single value, got {shown(value)}")
    if isinstance(value, float) and not math.isfinite(value):
        raise CrmgraspError(f"{where}: {key} must be finite, got {value}")
    return value


_CELL_TYPES: dict[str, type] = {
    "task": str,
    "start_preset": str,
    "grasp_reward": float,
    "agent": str,
    "k": int,
    "symmetric": bool,
}
"""The types of the cell keys that are not an agent's parameters (those take their
constructor default's type)."""


def _typed(key: str, value: Any, want: type | None, where: str) -> Any:
    """``value`` checked as a task file checks a field of type ``want``
    ([`crmgrasp.tasks.schema.typed`][]: a boolean is not a number, a number is finite, a
    string not a number), the cell named in the error; any scalar when ``want`` is None."""
    if want is None:
        return value
    try:
        return typed(value, want, key)
    except CrmgraspError as exc:
        raise CrmgraspError(f"{where}: {exc}") from None


def _cell(raw: dict[str, Any], where: str) -> dict[str, Any]:
    from crmgrasp.agents.training import AGENTS, agent_parameters, parameter_defaults

    keys = cell_keys()
    for key in raw:
        if key not in keys:
            raise CrmgraspError(f"{where}: {_unknown(key, raw.get('agent', _DEFAULT_CELL['agent']))}")
    cell = {**_DEFAULT_CELL, **{k: _scalar(k, v, where) for k, v in raw.items()}}
    agent = _typed("agent", cell["agent"], str, where)
    if agent not in AGENTS:
        raise CrmgraspError(f"{where}: unknown agent {shown(agent)}; known agents: {', '.join(AGENTS)}")
    extra = [k for k in agent_params() if k in cell and k not in agent_parameters(agent)]
    if extra:
        takes = ", ".join(agent_parameters(agent)) or "none"
        raise CrmgraspError(f"{where}: agent {agent!r} takes no {', '.join(extra)} (it takes {takes})")
    for key, value in cell.items():
        default = parameter_defaults(key).get(agent) if key not in BASE_KEYS else None
        want = _CELL_TYPES.get(key) or (type(default) if type(default) in (bool, int, float, str) else None)
        _typed(key, value, want, where)
    return cell


def _unknown(key: str, agent: Any) -> str:
    """The message for an unknown cell key: the nearest key, the keys every cell takes and
    those of the cell's agent (where it names a registered one), not every agent's."""
    from crmgrasp.agents.training import AGENTS, agent_parameters

    near = difflib.get_close_matches(str(key), cell_keys(), n=1)
    hint = f" (did you mean {near[0]!r}?)" if near else ""
    scalar = set(agent_params())
    own = [p for p in agent_parameters(agent) if p in scalar] if isinstance(agent, str) and agent in AGENTS else []
    takes = f"; agent {agent!r} takes {', '.join(own)}" if own else ""
    return f"unknown key {shown(key)}{hint}; every cell takes {', '.join(BASE_KEYS)}{takes}"


def study_from_dict(doc: Any) -> Study:
    """The [`Study`][] a parsed study file states (one-line errors naming the key)."""
    if not isinstance(doc, dict):
        raise CrmgraspError("a study must be a table")
    known = {"name", "trials", "episodes", "eval_episodes", "seeds", "grid", "cell"}
    for key in doc:
        if key not in known:
            raise CrmgraspError(f"unknown key {key!r}; study keys: {', '.join(sorted(known))}")
    name = checked_name(doc.get("name", "study"))  # it names the run folder: a task name's rule
    trials = integer(doc.get("trials", 20), "trials", 1, 100_000)
    episodes = integer(doc.get("episodes", 500), "episodes", 1, 10_000_000)
    eval_episodes = integer(doc.get("eval_episodes", 200), "eval_episodes", 1, 10_000_000)  # what its tables compare
    seeds = doc.get("seeds", [0])
    if not isinstance(seeds, list) or not seeds or any(isinstance(s, bool) or not isinstance(s, int) for s in seeds):
        raise CrmgraspError(f"seeds must be a non-empty list of integers, got {shown(seeds)}")
    seeds = tuple(seed_value(s) for s in seeds)
    if len(set(seeds)) != len(seeds):
        raise CrmgraspError("seeds must not repeat")
    cells: list[dict[str, Any]] = []
    grid = doc.get("grid")
    if grid is not None:
        if not isinstance(grid, dict) or not grid:
            raise CrmgraspError("[grid] must be a table of lists")
        keys = list(grid)
        values = []
        for key in keys:
            v = grid[key]
            if not isinstance(v, list) or not v:
                raise CrmgraspError(f"[grid] {key} must be a non-empty list, got {shown(v)}")
            values.append(v)
        cells += [_cell(dict(zip(keys, combo)), "[grid]") for combo in itertools.product(*values)]
    listed = doc.get("cell", [])
    if not isinstance(listed, list):
        raise CrmgraspError("[[cell]] must be an array of tables")
    for i, c in enumerate(listed):
        if not isinstance(c, dict):
            raise CrmgraspError(f"[[cell]] number {i + 1} must be a table of cell keys, got {shown(c)}")
        cells.append(_cell(c, f"[[cell]] number {i + 1}"))
    if not cells:
        raise CrmgraspError("a study needs a [grid] or at least one [[cell]]")
    if len(cells) * len(seeds) > 100_000:
        raise CrmgraspError(f"{len(cells) * len(seeds):,} runs exceed the 100,000 one study may hold")
    ids = [cell_id(c) for c in cells]
    if len(set(ids)) != len(ids):
        raise CrmgraspError("two cells of the study are the same")
    return Study(name, trials, episodes, eval_episodes, seeds, tuple(cells))


def load_study(path: str | Path) -> Study:
    """Read a study file (1 MiB at most; one-line errors naming the file and the key). A
    cell's task given as a relative ``.toml`` path is the file beside the study file (not
    in the working directory): it becomes that file's absolute path."""
    p = Path(path)
    data = read_bounded(p, 1 << 20, "study file")
    try:
        study = study_from_dict(tomllib.loads(data.decode("utf-8")))
    except (UnicodeDecodeError, tomllib.TOMLDecodeError) as exc:
        raise CrmgraspError(f"study file {str(p)!r} is not valid TOML ({exc})") from None
    except CrmgraspError as exc:
        raise CrmgraspError(f"study file {str(p)!r}: {exc}") from None
    here = p.resolve().parent
    cells = tuple({**c, "task": _beside(here, c["task"])} for c in study.cells)
    try:
        _check_tasks(cells)
    except CrmgraspError as exc:
        raise CrmgraspError(f"study file {str(p)!r}: {exc}") from None
    return dataclasses.replace(study, cells=cells)


def _check_tasks(cells: tuple[dict[str, Any], ...]) -> None:
    """Build each distinct task of the cells (with its start preset and grasp reward) once,
    so that a task name, file or preset that does not resolve is a one-line error before any
    run starts, not a failed run per cell and seed."""
    from crmgrasp.tasks.files import resolve_reading

    for task, starts, reward in dict.fromkeys((c["task"], c.get("start_preset"), c.get("grasp_reward")) for c in cells):
        try:
            resolve_reading(task, starts=starts, grasp_reward=reward)
        except CrmgraspError as exc:
            raise CrmgraspError(f"cell task {task!r}: {exc}") from None


def _beside(folder: Path, task: str) -> str:
    """``task`` as the absolute path of the file beside the study file, for a relative
    ``.toml`` path; unchanged otherwise (a task name, ``package.module:factory``, an
    absolute path)."""
    return str(folder / task) if task.endswith(".toml") and not Path(task).is_absolute() else task

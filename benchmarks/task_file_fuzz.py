"""Hostile task files, at scale: every key of a task document set to every value of a hostile list.

For each task named (the built-in ones by default) it takes the task's own document
(`crmgrasp.tasks.files.task_to_dict`: what a task file holds), and for every leaf of it (a
key, or an item of a list) and every value of [`HOSTILE`][] (wrong types, NaN and
infinities, zero, negative and huge numbers, unknown contact labels, empty tables) plus
deleting the leaf, it builds the task (`task_from_dict`, as `--task file.toml` does), draws five starts as
`crmgrasp references` does (`sample_starts`) and runs three episodes of up to four random
CRMs on it through the readable rules, with Python's
warnings raised as errors. A variant passes if it runs or if it fails with a
`CrmgraspError` of one line under 400 characters (the message a user sees); anything else
(another exception, a warning such as NaN arithmetic, a message of several lines) is
reported with the leaf and value that caused it. It prints one JSON object and exits 1 if a
variant failed.

The tests of bad input check chosen cases; this runs every leaf. Measured 2026-12-07 (after
commit c011f46): `python benchmarks/task_file_fuzz.py` on the 21 built-in tasks, 54,763 variants
in 294 s on one core, none failed. At the commit before, `--task cup-3d` failed 1 of its 2,645:
the family's pose offset set to ``[-0.02, 1e9]`` gave NaN normals (a RuntimeWarning; without the
warnings raised, episodes on garbage), now a one-line error.

Usage: ``python benchmarks/task_file_fuzz.py [--task NAME ...] [--seed S]``.
"""

from __future__ import annotations

import argparse
import copy
import json
import sys
import time
import warnings
from collections.abc import Callable, Iterator
from typing import Any

import numpy as np

from crmgrasp import sim
from crmgrasp._validation import CrmgraspError
from crmgrasp.planners.references import sample_starts
from crmgrasp.tasks import make_task, task_names
from crmgrasp.tasks.files import task_from_dict, task_to_dict

HOSTILE: tuple[Any, ...] = (
    -1,
    0,
    3,
    0.5,
    -1e-12,
    1e9,
    float("nan"),
    float("inf"),
    True,
    "x",
    "a",
    "z",
    [],
    [1],
    [[1, 2]],
    [0.1, 0.05],
    [0.5, 0.1],
    [-1, 1],
    [1, -1],
    [0.0, 0.0],
    {},
    {"a": 1},
)
"""The values every leaf is set to, in turn (and then the leaf is deleted)."""

DELETE = object()


def leaves(doc: Any, path: tuple[Any, ...] = ()) -> Iterator[tuple[Any, ...]]:
    """The path of every key and list item below ``doc``, depth first."""
    if isinstance(doc, dict):
        for key, value in doc.items():
            yield (*path, key)
            yield from leaves(value, (*path, key))
    elif isinstance(doc, list):
        for i, value in enumerate(doc):
            yield (*path, i)
            yield from leaves(value, (*path, i))


def mutated(doc: Any, path: tuple[Any, ...], value: Any) -> Any:
    """A copy of ``doc`` with the leaf at ``path`` set to ``value`` (deleted for [`DELETE`][])."""
    out = copy.deepcopy(doc)
    parent = out
    for key in path[:-1]:
        parent = parent[key]
    if value is DELETE:
        del parent[path[-1]]
    else:
        parent[path[-1]] = value
    return out


def attempt(call: Callable[[], Any], limit: int = 400) -> str | None:
    """Run ``call()`` with Python's warnings raised as errors: ``None`` if it works or raises a
    ``CrmgraspError`` of one line under ``limit`` characters (the message a user sees), else
    what went wrong (also ``benchmarks/env_fuzz.py``'s rule)."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            call()
    except CrmgraspError as exc:
        text = str(exc)
        return None if "\n" not in text and len(text) < limit else f"CrmgraspError of {len(text)} chars: {text[:200]!r}"
    except Exception as exc:  # what this script looks for
        return f"{type(exc).__name__}: {str(exc)[:200]}"
    return None


def run_variant(doc: Any, rng: np.random.Generator) -> str | None:
    """Build the task of ``doc`` and run three short episodes of random CRMs; ``None`` if that
    runs or fails in one line, else what went wrong ([`attempt`][])."""
    return attempt(lambda: _exercise(doc, rng))


def _exercise(doc: Any, rng: np.random.Generator) -> None:
    task = task_from_dict(doc)
    sample_starts(task, 5, int(rng.integers(2**31)))  # the references' starts
    for _ in range(3):
        now = sim.reset(task, rng)
        for _ in range(4):
            now = sim.step(task, now.state, int(rng.integers(len(task.actions))), rng)
            if now.terminated or now.truncated:
                break


def fuzz(name: str, seed: int) -> dict[str, Any]:
    """Every variant of task ``name``'s document: the count and the failures."""
    doc = task_to_dict(make_task(name))
    rng = np.random.default_rng(seed)
    count, failures = 0, []
    for path in leaves(doc):
        for value in (*HOSTILE, DELETE):
            count += 1
            problem = run_variant(mutated(doc, path, value), rng)
            if problem is not None:
                shown = "delete" if value is DELETE else repr(value)
                failures.append({"leaf": ".".join(map(str, path)), "value": shown, "problem": problem})
    return {"task": name, "variants": count, "failed": len(failures), "failures": failures[:20]}


def main(argv: list[str] | None = None) -> dict[str, Any]:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--task", action="append", choices=task_names(), help="(default: every built-in task)")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    t0 = time.perf_counter()
    rows = []
    for name in args.task or task_names():
        rows.append(fuzz(name, args.seed))
        print(f"{name}: {rows[-1]['variants']} variants, {rows[-1]['failed']} failed", file=sys.stderr, flush=True)
    out = {
        "variants": sum(r["variants"] for r in rows),
        "failed": sum(r["failed"] for r in rows),
        "seconds": round(time.perf_counter() - t0, 1),
        "tasks": rows,
    }
    print(json.dumps(out, indent=1))
    return out


if __name__ == "__main__":
    sys.exit(1 if main()["failed"] else 0)

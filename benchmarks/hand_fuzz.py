"""Hostile hands, at scale: a saved policy run on a hand whose answers, one at a time, are hostile.

A user's hand implements [`HandInterface`][crmgrasp.hardware.runner.HandInterface]:
``sense()`` returns the sensed contacts (or ``NoContact``) and ``execute(crm)`` the CRM's error
flag; it may also offer ``raw_reading()`` (the raw sensor values of the step log), ``time``
(its clock, s) and ``object_pose()`` (the MCAP record's object pose). This script takes the
kinematic hand of each task of [`TASKS`][] (two fingers and three in the plane, two and a
tripod in space) and, for each of those answers ([`SLOTS`][]) and each hostile value of that
answer's list, replaces the answer with the value and runs
[`PolicyRunner.run`][crmgrasp.hardware.runner.PolicyRunner.run] once with a CSV step log and,
with the extra ``crmgrasp[mcap]``, once with an MCAP log. The readings are the hand's true
readings made malformed (a NaN, an infinity, a string or a huge coordinate; a normal that is
not a unit vector; a contact too few or too many; a reading of the other space) or not
readings at all.

A run passes if it completes and writes its log, or raises a ``CrmgraspError`` of one line
under 400 characters and leaves no log file behind (Python's warnings raised as errors;
``benchmarks/task_file_fuzz.py``'s rule). Anything else (another exception, a warning, a
message of several lines, a half-written log) is reported with the task, answer and value. It
prints one JSON object and exits 1 if a run failed.

Measured 2026-12-07 on the 2-core machine: 640 runs (4 tasks x 80 hostile answers x 2 logs) in
0.4 s, none failed; on the code before the runner checked its hand's answers (29015ed,
``PYTHONPATH`` of a worktree), 346 failed (docs/hardware.md). Usage: ``python
benchmarks/hand_fuzz.py [--task paper-box ...]``.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import tempfile
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import task_file_fuzz
from crmgrasp.agents.policy import GreedyPolicy
from crmgrasp.hardware.contact_sensing import NoContact
from crmgrasp.hardware.runner import KinematicHand, PolicyRunner
from crmgrasp.model.contacts import Contact, Grip, make_config
from crmgrasp.model.spatial import Contact3D, config3d
from crmgrasp.tasks import Task, make_task

TASKS = ("paper-box", "triangles-3f", "cup-3d", "box-3d-3f")
"""Two fingers and three in the plane, two and a tripod in space."""

SLOTS = ("first reading", "second reading", "execute", "raw_reading", "time", "object_pose")
"""The hand's answers replaced, one at a time: ``sense()`` before the first CRM and after it,
``execute``'s error flag, and the optional ``raw_reading()``, ``time`` and ``object_pose()``."""

NOT_READINGS: tuple[Any, ...] = (None, "x", 3, (), (0.1, 0.2), {"a": 1}, np.zeros(4), NoContact(5), [])
"""Values that are not readings at all."""

ERRORS: tuple[Any, ...] = (None, "none", "PALM", 7, -1, 1.5, True, np.int64(0), np.int64(9), math.nan, object(), [0])
"""Values ``execute`` returns instead of an error flag."""

RAWS: tuple[Any, ...] = (5, None, "x", [1, 2], {"v": math.nan}, {"v": object()}, {1: 2}, {"v": math.inf}, {"b": b"x"})
"""Values ``raw_reading()`` returns."""

TIMES: tuple[Any, ...] = ("x", None, math.nan, math.inf, -1.0, True, [1.0], 1e300)
"""Values of the hand's ``time``."""

POSES: tuple[Any, ...] = (
    None,
    (1.0, 2.0),
    "x",
    (math.nan,) * 3,
    (math.nan,) * 7,
    np.zeros(7),
    {"p": 1},
    object(),
    (1e300,) * 3,
)
"""Values ``object_pose()`` returns."""


def malformed(reading: Any, other: Any) -> Iterator[tuple[str, Any]]:
    """The hand's true ``reading`` made malformed, named; ``other`` is a reading of the other
    space (planar for a spatial task and the reverse)."""
    contacts = list(reading)
    planar = isinstance(contacts[0], Contact)
    make = make_config if planar else config3d

    def with_field(value: Any) -> Any:
        c = contacts[0]
        first = c._replace(x=value) if planar else c._replace(x=(value, *c.x[1:]))
        return make([first, *contacts[1:]])

    for name, value in (("NaN", math.nan), ("infinity", math.inf), ("string", "0.1"), ("huge", 1e308), ("None", None)):
        yield f"a coordinate {name}", with_field(value)
    c = contacts[0]
    yield (
        "a zero normal",
        make([c._replace(nx=0.0, ny=0.0) if planar else c._replace(n=(0.0, 0.0, 0.0)), *contacts[1:]]),
    )
    doubled = c._replace(nx=2 * c.nx, ny=2 * c.ny) if planar else c._replace(n=tuple(2 * v for v in c.n))
    yield "a normal of length 2", make([doubled, *contacts[1:]])
    yield "a contact too few", Grip(*contacts[:-1]) if planar and len(contacts) == 2 else make(contacts[:-1])
    yield "a contact too many", make([*contacts, contacts[-1]])
    yield "the other space's reading", other
    yield "a list of its contacts", contacts
    yield "its contacts as floats", tuple(float(v) for v in np.ravel([list(_flat(c)) for c in contacts]))


def _flat(c: Contact | Contact3D) -> Iterator[float]:
    """A contact's numbers."""
    if isinstance(c, Contact):
        yield from c
    else:
        yield from (*c.x, *c.n)


class HostileHand:
    """A kinematic hand that answers one slot with ``value`` (the first reading's slot: only
    the reading before the first CRM; the second: only the one after it)."""

    def __init__(self, hand: KinematicHand, slot: str, value: Any) -> None:
        self.hand, self.slot, self.value, self.readings = hand, slot, value, 0

    def sense(self) -> Any:
        real = self.hand.sense()
        self.readings += 1
        target = {"first reading": 1, "second reading": 2}.get(self.slot)
        return self.value if self.readings == target else real

    def execute(self, crm: Any) -> Any:
        real = self.hand.execute(crm)
        return self.value if self.slot == "execute" else real

    def raw_reading(self) -> Any:
        return self.value if self.slot == "raw_reading" else {"v": 1.0}

    @property
    def time(self) -> Any:
        return self.value if self.slot == "time" else float(self.readings)

    def object_pose(self) -> Any:
        return self.value if self.slot == "object_pose" else None


def cases(task: Task, other: Any, rng: np.random.Generator) -> Iterator[tuple[str, str, Callable[[], KinematicHand]]]:
    """Per slot and hostile value: ``(slot, value's name, a fresh kinematic hand)``."""

    def fresh() -> KinematicHand:
        world = task.sample_world(np.random.default_rng(0))
        return KinematicHand(world.task, world.config, np.random.default_rng(0))

    first = fresh().sense()
    values = {
        "first reading": [*((repr(v)[:30], v) for v in NOT_READINGS), *malformed(first, other)],
        "execute": [(repr(v)[:30], v) for v in ERRORS],
        "raw_reading": [(repr(v)[:30], v) for v in RAWS],
        "time": [(repr(v)[:30], v) for v in TIMES],
        "object_pose": [(repr(v)[:30], v) for v in POSES],
    }
    values["second reading"] = values["first reading"]
    for slot in SLOTS:
        for name, value in values[slot]:
            yield slot, name, lambda value=value, slot=slot: HostileHand(fresh(), slot, value)  # type: ignore[misc]


def run_case(policy: GreedyPolicy, make_hand: Callable[[], Any], log: Path) -> str | None:
    """One run with a step log at ``log``: ``None`` if it passes (see the module docstring)."""
    outcome: dict[str, Any] = {}

    def call() -> None:
        outcome["result"] = PolicyRunner(policy).run(make_hand(), np.random.default_rng(1), log)

    problem = task_file_fuzz.attempt(call)
    if problem is not None:
        return problem
    if "result" in outcome:
        return None if log.exists() and log.stat().st_size > 0 else "ran but wrote no log"
    return f"refused but left a {log.suffix} log behind" if log.exists() else None


def fuzz(name: str, other: Any, folder: Path, logs: tuple[str, ...]) -> tuple[int, list[dict[str, str]]]:
    """Every slot and value on task ``name``: the count and the failures."""
    task = make_task(name)
    policy = GreedyPolicy(task, 1, {})  # uniform: every CRM in turn
    count, failures = 0, []
    for slot, value, make_hand in cases(task, other, np.random.default_rng(0)):
        for suffix in logs:
            count += 1
            log = folder / f"run{count}{suffix}"
            problem = run_case(policy, make_hand, log)
            if problem is not None:
                failures.append({"task": name, "slot": slot, "value": value, "log": suffix, "problem": problem})
    return count, failures


def main(argv: list[str] | None = None) -> dict[str, Any]:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--task", action="append", dest="tasks", choices=TASKS)
    args = ap.parse_args(argv)
    try:
        import mcap  # noqa: F401

        logs: tuple[str, ...] = (".csv", ".mcap")
    except ImportError:
        logs = (".csv",)
    readings = {}
    for n in ("paper-box", "cup-3d"):
        world = make_task(n).sample_world(np.random.default_rng(0))
        readings[n] = KinematicHand(world.task, world.config, np.random.default_rng(0)).sense()
    t0, count, failures = time.perf_counter(), 0, []
    with tempfile.TemporaryDirectory() as tmp:
        for name in args.tasks or TASKS:
            other = readings["paper-box" if "3d" in name else "cup-3d"]
            folder = Path(tmp) / name
            folder.mkdir()
            n, bad = fuzz(name, other, folder, logs)
            print(f"{name}: {n} runs, {len(bad)} failed", file=sys.stderr, flush=True)
            count, failures = count + n, failures + bad
    out = {
        "runs": count,
        "failed": len(failures),
        "logs": list(logs),
        "seconds": round(time.perf_counter() - t0, 1),
        "failed_by_slot": {s: sum(f["slot"] == s for f in failures) for s in SLOTS},
        "failures": failures[:60],
    }
    print(json.dumps(out, indent=1))
    return out


if __name__ == "__main__":
    sys.exit(1 if main()["failed"] else 0)

"""A conformance test for hands: what a real (or simulated) hand must do to run CRM policies.

[`check_hand`][] takes a factory ``make_hand(task, start, rng)`` (a real hand ignores
``start`` and ``rng`` and stays where it is put) and checks, on worlds drawn from the task:

1. ``sense``: returns [`NoContact`][crmgrasp.hardware.contact_sensing.NoContact] or a
   configuration of the task's contact model: one finite row of the model's layout
   (``task.model.columns``), taken by the model as a reading, whose observation
   (``task.observe``) is finite;
2. ``execute``: each of the task's CRMs returns an [`Error`][crmgrasp.model.hand.Error]
   member, and the hand senses again afterwards;
3. ``refuse``: a CRM naming a contact the hand does not have is refused with a one-line
   `CrmgraspError` (the model's ``check_crm``), not an exception from deep inside;
4. ``raw_reading`` (optional): a dict with string keys that serialises to JSON;
5. ``runner``: [`PolicyRunner`][crmgrasp.hardware.runner.PolicyRunner] runs an episode on it
   and writes a step log with one row per reading.

Checks 1, 2 and 4 are those the runner makes of every answer while it runs
([`crmgrasp.hardware.answers`][]). The kinematic hand
([`KinematicHand`][crmgrasp.hardware.runner.KinematicHand]) and both
MuJoCo hands pass it (``tests/test_conformance.py``); ``docs/hardware.md`` walks through the
methods.
"""

from __future__ import annotations

import csv
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from crmgrasp._validation import CrmgraspError, integer, seed_value, shown
from crmgrasp.hardware.answers import checked_error, checked_raw, checked_reading
from crmgrasp.hardware.runner import HandInterface, PolicyRunner
from crmgrasp.model.contacts import ALL_LABELS
from crmgrasp.tasks import Task, checked_task

__all__ = ["check_hand", "CHECKS"]

MAX_WORLDS = 1000
"""The most worlds [`check_hand`][] runs a hand in (each runs every CRM of the task)."""

CHECKS = ("sense", "execute", "refuse", "raw_reading", "runner")
"""The checks of [`check_hand`][], in order."""

MakeHand = Callable[[Task, Any, np.random.Generator], HandInterface]


class _Cycle:
    """A saved-policy stand-in that takes the task's actions in turn (``predict``)."""

    def __init__(self, task: Task) -> None:
        self.task = task

    def predict(self, observations: list[Any], actions: list[Any], rng: np.random.Generator) -> int:
        return len(actions) % len(self.task.actions)


def _fail(check: str, what: str) -> CrmgraspError:
    return CrmgraspError(f"hand conformance: {check}: {what}")


def _checked(check: str, answer_check: Callable[..., Any], *args: Any) -> Any:
    """``answer_check(*args)`` (a check of [`crmgrasp.hardware.answers`][]), its one-line
    error named by the conformance check that failed."""
    try:
        return answer_check(*args)
    except CrmgraspError as exc:
        raise _fail(check, str(exc)) from None


def _refuses(task: Task, hand: HandInterface) -> None:
    crm = task.actions[0]
    extra = next(label for label in ALL_LABELS if label not in task.model.labels)
    try:
        bad = type(crm)(crm.c, extra, crm.r)
    except CrmgraspError:
        return  # the CRM type itself refuses the label
    try:
        hand.execute(bad)
    except CrmgraspError as exc:
        if "\n" in str(exc):
            raise _fail("refuse", f"the error for {bad} spans lines: {exc!r}") from None
        return
    except Exception as exc:
        raise _fail("refuse", f"{bad} raised {type(exc).__name__} ({exc}), not a one-line CrmgraspError") from None
    raise _fail("refuse", f"{bad} names contact {extra!r}, which the hand lacks, but was executed")


def check_hand(make_hand: MakeHand, task: Task, seed: int = 0, worlds: int = 2) -> list[str]:
    """Run the checks of the module docstring on hands from ``make_hand`` over ``worlds``
    worlds of ``task`` (one hand per world and CRM); return the names of the checks passed
    ([`CHECKS`][]; ``raw_reading`` only where the hand has it). The first failure raises a
    one-line `CrmgraspError` naming its check."""
    if not callable(make_hand):
        raise CrmgraspError(f"make_hand must make a hand from (task, start, rng), got {shown(make_hand)}")
    task, worlds = checked_task(task, "check_hand"), integer(worlds, "worlds", 1, MAX_WORLDS)
    rng = np.random.default_rng(seed_value(seed))
    passed: list[str] = []
    has_raw = False
    for w in range(worlds):
        world = task.sample_world(rng)
        for i, _ in enumerate(task.actions):
            hand, crm = make_hand(world.task, world.config, rng), task.actions[i]
            _checked("sense", checked_reading, task, hand.sense(), f"in world {w} before CRM {i}")
            _checked("execute", checked_error, hand.execute(crm), crm)
            _checked("sense", checked_reading, task, hand.sense(), f"in world {w} after CRM {i}")
            raw = getattr(hand, "raw_reading", None)
            if raw is not None:
                has_raw = True
                _checked("raw_reading", checked_raw, raw())
    passed += ["sense", "execute"]
    _refuses(task, make_hand(world.task, world.config, rng))
    passed.append("refuse")
    if has_raw:
        passed.append("raw_reading")
    with tempfile.TemporaryDirectory() as tmp:
        log = Path(tmp) / "run.csv"
        result = PolicyRunner(_Cycle(task), task).run(make_hand(world.task, world.config, rng), rng, log=log)
        with open(log, newline="") as fh:
            rows = list(csv.reader(fh))
        if len(rows) != 1 + len(result.rows) or result.crms > task.max_steps:
            raise _fail("runner", f"a run of {result.crms} CRMs logged {len(rows) - 1} rows")
    passed.append("runner")
    return passed

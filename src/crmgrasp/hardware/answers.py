"""What a hand's answers must be, checked where they arrive.

A hand ([`HandInterface`][crmgrasp.hardware.runner.HandInterface]) is the user's code, so
everything it returns is input: [`HandSteps`][crmgrasp.hardware.runner.HandSteps] checks each
answer as the runner receives it, and the conformance test
([`check_hand`][crmgrasp.hardware.conformance.check_hand]) checks the same answers with the
same functions. A malformed answer is a one-line `CrmgraspError` naming the method and what
it returned, before anything is logged:

* ``sense()``: [`NoContact`][crmgrasp.hardware.contact_sensing.NoContact], or a configuration
  of the task's contact model: its row (``task.model.numbers``) has one real, finite number
  per column of ``task.model.columns``, the model takes it as a reading (``check_reading``:
  its configuration type, one contact per finger, unit normals) and its observation is finite;
* ``execute(crm)``: an [`Error`][crmgrasp.model.hand.Error] member;
* ``raw_reading()`` (optional): a dict with string keys that serialises to JSON (a non-finite
  number is written as ``null``);
* ``time`` (optional): a real number of seconds in ``[0, MAX_TIME]`` (an MCAP record's clock);
* ``object_pose()`` (optional): ``None``, or real finite numbers: ``x, y, yaw`` in the plane
  (m, rad), ``x, y, z, qw, qx, qy, qz`` in space (m, and a unit quaternion).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from crmgrasp._io import dumps_json
from crmgrasp._validation import CrmgraspError, is_real, shown
from crmgrasp.hardware.contact_sensing import NoContact
from crmgrasp.model.hand import Error
from crmgrasp.tasks import Task

__all__ = [
    "MAX_TIME",
    "POSE_WIDTH",
    "QUATERNION_TOL",
    "checked_error",
    "checked_pose",
    "checked_raw",
    "raw_problem",
    "checked_reading",
    "checked_time",
    "is_clock",
]

MAX_TIME = 1e9
"""The latest clock reading a hand may report, s (about 32 years; an MCAP record stamps each
message in integer nanoseconds)."""

POSE_WIDTH = {"planar": 3, "spatial": 7}
"""Numbers in an object pose, per contact model kind."""

QUATERNION_TOL = 1e-6
"""How far from 1 the norm of a spatial pose's quaternion ``qw, qx, qy, qz`` may be."""


def checked_reading(task: Task, reading: Any, where: str = "") -> tuple[Any, tuple[float, ...] | None]:
    """``(reading, its observation)`` if ``reading`` (what ``sense()`` returned, ``where`` says
    when) is a configuration of ``task``'s contact model with finite numbers and a finite
    observation, ``(reading, None)`` if it is ``NoContact``; else a one-line error."""
    if isinstance(reading, NoContact):
        return reading, None
    model, at = task.model, f" {where}" if where else ""
    width = len(model.columns)
    what = f"a {model.kind} configuration of {model.n_contacts} contacts ({width} finite numbers)"
    try:
        row = list(model.numbers(reading))
    except Exception:  # the user's object: any failure to read it is the same refusal
        row = []
    if len(row) != width or not all(map(is_real, row)):
        raise CrmgraspError(f"the hand's sense(){at} returned {shown(reading, 80)}, not {what}")
    if not all(math.isfinite(float(v)) for v in row):
        raise CrmgraspError(f"the hand's sense(){at} returned a reading that is not finite: {shown(reading, 120)}")
    model.check_reading(reading, f"the hand's sense(){at}")
    with np.errstate(over="ignore", invalid="ignore"):  # a huge coordinate: refused below, not warned of
        obs = task.observe(reading)
    if not all(math.isfinite(v) for v in obs):
        raise CrmgraspError(f"the hand's sense(){at}: the observation {obs} is not finite")
    return reading, obs


def checked_error(value: Any, crm: Any) -> Error:
    """``value`` (what ``execute(crm)`` returned) if it is an `Error` member, else a one-line error."""
    if isinstance(value, Error):
        return value
    names = ", ".join(e.name for e in Error)
    raise CrmgraspError(f"the hand's execute({crm}) returned {shown(value)}, not an Error ({names})")


def raw_problem(value: Any) -> str | None:
    """What keeps ``value`` from being a raw reading (a dict with string keys that serialises to
    JSON: what ``raw_reading()`` returns and a step record holds), or ``None``."""
    if not isinstance(value, dict) or not all(isinstance(k, str) for k in value):
        return f"{shown(value)}, not a dict with string keys"
    try:
        dumps_json(value, indent=None)
    except (TypeError, ValueError, RecursionError) as exc:
        return f"a dict that JSON cannot hold ({shown(str(exc), 80)})"
    return None


def checked_raw(value: Any) -> dict[str, Any]:
    """``value`` (what ``raw_reading()`` returned) if it is a raw reading ([`raw_problem`][]),
    else a one-line error."""
    problem = raw_problem(value)
    if problem is not None:
        raise CrmgraspError(f"the hand's raw_reading() returned {problem}")
    return value


def is_clock(value: Any) -> bool:
    """Whether ``value`` is a clock reading: a real number of seconds in ``[0, MAX_TIME]`` (a
    hand's ``time``, a step record's)."""
    return is_real(value) and 0.0 <= float(value) <= MAX_TIME


def checked_time(value: Any) -> float:
    """``value`` (the hand's ``time``) as a float if it is a clock reading ([`is_clock`][]),
    else a one-line error."""
    if not is_clock(value):
        raise CrmgraspError(f"the hand's time is {shown(value)}, not a number of seconds in [0, {MAX_TIME:g}]")
    return float(value)


def checked_pose(task: Task, value: Any) -> tuple[float, ...] | None:
    """``value`` (what ``object_pose()`` returned) as a tuple of floats, or None; else a
    one-line error ([`POSE_WIDTH`][] numbers per model kind, real and finite; in space the
    quaternion's norm within [`QUATERNION_TOL`][] of 1)."""
    if value is None:
        return None
    width = POSE_WIDTH[task.model.kind]
    try:
        numbers = list(value)
    except TypeError:
        numbers = []
    if len(numbers) != width or not all(is_real(v) and math.isfinite(float(v)) for v in numbers):
        raise CrmgraspError(f"the hand's object_pose() returned {shown(value, 80)}, not None or {width} finite numbers")
    pose = tuple(float(v) for v in numbers)
    if width == 7 and abs(math.hypot(*pose[3:]) - 1.0) > QUATERNION_TOL:
        raise CrmgraspError(f"the hand's object_pose() returned the quaternion {pose[3:]}, not a unit one")
    return pose

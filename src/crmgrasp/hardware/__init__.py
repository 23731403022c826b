"""The hardware half: intrinsic contact sensing from fingertip wrenches
([`crmgrasp.hardware.contact_sensing`][]), the hand interface and the policy runner
([`crmgrasp.hardware.runner`][]), and a MuJoCo stand-in for Robonaut
([`crmgrasp.hardware.mujoco`][], extra ``crmgrasp[mujoco]``)."""

from __future__ import annotations

import importlib
from collections.abc import Callable
from typing import Any

from crmgrasp._validation import CrmgraspError

__all__ = ["HANDS", "hand_steps"]

HANDS = {
    "kinematic": "the kinematic model (the task's own rules; default)",
    "mujoco": "the MuJoCo stand-in (extra crmgrasp[mujoco]; fingertip palm tolerance 10 degrees, its own sensors)",
}
"""The hands that episodes can run on: name -> what it is."""

_STEPPERS = {"mujoco": ("crmgrasp.hardware.mujoco.steps", "MujocoSteps")}


def hand_steps(hand: str) -> Callable[[Any], Any] | None:
    """The stepper class that runs episodes on ``hand`` ([`HANDS`][]; ``None`` for the
    kinematic model, whose kernels the caller picks), imported only when asked for; a
    one-line error naming the extra if the hand's simulator is not installed."""
    if hand not in HANDS:
        raise CrmgraspError(f"unknown hand {hand!r}; choose one of {', '.join(HANDS)}")
    if hand not in _STEPPERS:
        return None
    module, name = _STEPPERS[hand]
    steps = getattr(importlib.import_module(module), name)
    steps.require()
    return steps  # type: ignore[no-any-return]

"""A physics-simulated stand-in for Robonaut: a MuJoCo two-fingertip hand.

Needs the optional extra ``crmgrasp[mujoco]`` (``mujoco>=3.2,<5``). The modules
import MuJoCo lazily, so ``import crmgrasp.hardware.mujoco`` works without it and the
first use raises a one-line `CrmgraspError`.
Rendering is headless: ``MUJOCO_GL`` defaults to ``egl`` here (set it to
``osmesa`` where EGL is missing).
"""

from __future__ import annotations

import dataclasses
import math
import os
from types import ModuleType

from crmgrasp._validation import CrmgraspError, non_negative, require_extra
from crmgrasp.tasks import Task, checked_task

__all__ = ["require_mujoco", "mujoco_available", "hardware_task"]


def hardware_task(task: Task, palm_tolerance_deg: float = 10.0, mu_goal: float | None = None) -> Task:
    """``task`` as a real (or MuJoCo) hand runs it: a fingertip palm tolerance
    (``hand.palm_normal_tol = sin(palm_tolerance_deg)``; the default 1e-9 would turn
    every sensed contact a hair off into a palm error; degrees in ``[0, 90)``) and,
    optionally, another goal."""
    checked_task(task, "hardware_task")
    tolerance = non_negative(palm_tolerance_deg, "palm tolerance (degrees)")
    if tolerance >= 90.0:
        raise CrmgraspError(f"palm tolerance (degrees) must be below 90, got {tolerance:g}")
    hand = dataclasses.replace(task.hand, palm_normal_tol=math.sin(math.radians(tolerance)))
    out = dataclasses.replace(task, hand=hand)
    return out if mu_goal is None else dataclasses.replace(out, mu_goal=mu_goal)


def mujoco_available() -> bool:
    """True if the ``mujoco`` package can be imported."""
    try:
        require_mujoco()
    except CrmgraspError:
        return False
    return True


def require_mujoco() -> ModuleType:
    """Import and return ``mujoco``, or raise a one-line error naming the extra."""
    os.environ.setdefault("MUJOCO_GL", "egl")
    return require_extra("mujoco", "the MuJoCo stand-in", "mujoco")[0]  # type: ignore[no-any-return]

"""Run a saved policy on a hand: the kinematic simulator or a real (or physics) hand.

A hand implements :class:`HandInterface`: ``sense()`` returns the sensed contact
configuration (or :class:`~crmgrasp.hardware.contact_sensing.NoContact`), ``execute(crm)``
performs a CRM and returns its error flag. :class:`KinematicHand` is the
simulator behind that interface. :class:`PolicyRunner` senses, discretizes,
builds the k-order history, picks the policy's action, executes it, and logs every
step (readings, observation, action, error) to a CSV file. It stops when the
*sensed* configuration is a grasp (``min_friction(sensed) <= mu_goal``: all a real
robot can check), when contact is lost, or after ``task.max_steps`` CRMs.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Any, Protocol, runtime_checkable

import numpy as np

from crmgrasp._io import dumps_json, write_csv
from crmgrasp._validation import CrmgraspError
from crmgrasp.agents.policy import GreedyPolicy
from crmgrasp.hardware.contact_sensing import NoContact
from crmgrasp.model.contacts import Config
from crmgrasp.model.hand import CRM, Error, execute_crm
from crmgrasp.model.sensing import SensorNoise, observe
from crmgrasp.tasks import Task

__all__ = ["HandInterface", "KinematicHand", "PolicyRunner", "RunResult"]

LOG_COLUMNS = [
    "step",
    "ax",
    "ay",
    "anx",
    "any",
    "bx",
    "by",
    "bnx",
    "bny",
    "rho",
    "m_a",
    "m_b",
    "obs_index",
    "observation",
    "action",
    "crm",
    "error",
    "raw",
]


@runtime_checkable
class HandInterface(Protocol):
    """What a hand must offer to run CRM policies."""

    def sense(self) -> Config | NoContact: ...

    def execute(self, crm: CRM) -> Error: ...


class KinematicHand:
    """The kinematic simulator as a hand: true state hidden, readings through ``noise``."""

    def __init__(self, task: Task, start: Config, rng: np.random.Generator, noise: SensorNoise | None = None):
        self.task, self.config, self.rng = task, start, rng
        self.noise = task.noise if noise is None else noise
        self._reading: Config | None = None

    def sense(self) -> Config:
        """One noisy reading of the current configuration."""
        self._reading = self.noise.sense(self.config, self.rng)
        return self._reading

    def execute(self, crm: CRM) -> Error:
        """Execute ``crm``; its goal line comes from the last reading."""
        t = self.task
        out = execute_crm(t.obj, t.hand, self.config, t.hand.check_crm(crm), self._reading or self.config)
        self.config = out.config
        return out.error

    def raw_reading(self) -> dict[str, Any]:
        """Raw sensor values behind the last reading (none beyond the reading here)."""
        return {}


@dataclass
class RunResult:
    """Outcome of one policy run."""

    crms: int
    grasped: bool
    stopped: str
    rows: list[list[Any]] = field(default_factory=list)


class PolicyRunner:
    """Drives a saved policy (a tabular :class:`~crmgrasp.agents.policy.GreedyPolicy` or a
    deep :class:`~crmgrasp.agents.deep.RecurrentPolicy`: anything with ``task`` and
    ``predict(observations, actions, rng)``) on a :class:`HandInterface`."""

    def __init__(self, policy: GreedyPolicy | Any, task: Task | None = None) -> None:
        """``task`` (default: the policy's) may be a variant, e.g. with noise or another
        palm tolerance, but must keep the policy's name, CRM set and bins."""
        self.policy = policy
        self.task = policy.task if task is None else task
        p = policy.task
        if (self.task.name, self.task.actions, self.task.discretizer) != (p.name, p.actions, p.discretizer):
            raise CrmgraspError(f"the policy was made for {p.name!r} with other CRMs or bins than this task")

    def run(
        self, hand: HandInterface, rng: np.random.Generator, log: str | os.PathLike[str] | None = None
    ) -> RunResult:
        """Run one episode; write the step log to ``log`` (CSV) if given."""
        t = self.task
        rows: list[list[Any]] = []
        error = Error.NONE
        seen: list[tuple[float, float, float, int]] = []
        taken: list[int] = []
        result = None
        for step in range(t.max_steps + 1):
            reading = hand.sense()
            if isinstance(reading, NoContact):
                result = RunResult(step, False, f"no contact: {reading.reason}")
                break
            obs = observe(reading)
            index = t.discretizer.index(obs, error)
            seen.append((obs.rho, obs.m_a, obs.m_b, int(error)))
            raw: dict[str, Any] = getattr(hand, "raw_reading", dict)()
            row = [step, *reading.a, *reading.b, *obs, index, t.discretizer.label(index)]
            if t.is_success(reading):
                rows.append([*row, "", "", "", dumps_json(raw, indent=None)])
                result = RunResult(step, True, "grasp sensed")
                break
            if step == t.max_steps:
                rows.append([*row, "", "", "", dumps_json(raw, indent=None)])
                result = RunResult(step, False, "step limit")
                break
            action = self.policy.predict(seen, taken, rng)
            taken.append(action)
            crm = t.actions[action]
            error = hand.execute(crm)
            rows.append([*row, action, str(crm), error.name.lower(), dumps_json(raw, indent=None)])
        assert result is not None
        result.rows = rows
        if log is not None:
            write_csv(log, LOG_COLUMNS, rows)
        return result

"""Run a saved policy on a hand: the kinematic simulator or a real (or physics) hand.

A hand implements :class:`HandInterface`: ``sense()`` returns the sensed contact
configuration (or :class:`~crmgrasp.hardware.contact_sensing.NoContact`), ``execute(crm)``
performs a CRM and returns its error flag. :class:`KinematicHand` is the
simulator behind that interface, in the plane or in space (it steps the task's own
rules: ``task.execute``, ``task.read``). :class:`PolicyRunner` senses, discretizes,
builds the k-order history, picks the policy's action, executes it, and logs every
step (readings, observation, action, error) to a CSV file. It stops when the
*sensed* configuration is a grasp (``min_friction(sensed) <= mu_goal``: all a real
robot can check), when contact is lost, or after ``task.max_steps`` CRMs.
"""

from __future__ import annotations

import dataclasses
import os
from dataclasses import dataclass, field
from typing import Any, Protocol, runtime_checkable

import numpy as np

from crmgrasp._io import dumps_json, write_csv
from crmgrasp._validation import CrmgraspError
from crmgrasp.agents.policy import GreedyPolicy
from crmgrasp.hardware.contact_sensing import NoContact
from crmgrasp.model.contacts import Config
from crmgrasp.model.hand import CRM, Error
from crmgrasp.model.sensing import SensorNoise
from crmgrasp.model.spatial import CRM3D, Config3D
from crmgrasp.tasks import Task

__all__ = ["HandInterface", "KinematicHand", "PolicyRunner", "RunResult", "log_columns"]

RUN_COLUMNS = ["obs_index", "observation", "action", "crm", "error", "raw"]
"""The columns of a step log after the contacts and the observation: the observation's bin
and label, the action taken, its CRM and error flag, and the raw sensor values."""


def log_columns(task: Task) -> list[str]:
    """The step-log columns of a run on ``task``: ``step``, the reading's contacts in the
    contact model's row order (``ax, ay, anx, any, ...`` in the plane; ``ax, ay, az, anx,
    any, anz, ...`` in space), the model's observation (``rho, m_a, m_b``), then
    :data:`RUN_COLUMNS`."""
    return ["step", *task.model.columns, *task.model.observation_names, *RUN_COLUMNS]


@runtime_checkable
class HandInterface(Protocol):
    """What a hand must offer to run CRM policies."""

    def sense(self) -> Config | Config3D | NoContact: ...

    def execute(self, crm: Any) -> Error:
        """Perform ``crm`` (a :class:`~crmgrasp.model.hand.CRM`, or a
        :class:`~crmgrasp.model.spatial.CRM3D` on a spatial hand); return its error flag."""
        ...


class KinematicHand:
    """The kinematic simulator as a hand (planar or spatial task): true state hidden,
    readings through ``noise`` (default: the task's)."""

    def __init__(
        self, task: Task, start: Config | Config3D, rng: np.random.Generator, noise: SensorNoise | None = None
    ):
        self.task = task if noise is None else dataclasses.replace(task, noise=noise)
        self.config, self.rng = task.check_config(start, "start"), rng
        self._reading: Config | Config3D | None = None

    def sense(self) -> Config | Config3D:
        """One noisy reading of the current configuration."""
        self._reading = self.task.read(self.config, self.rng)
        return self._reading

    def execute(self, crm: CRM | CRM3D) -> Error:
        """Execute ``crm``; its goal line comes from the last reading."""
        t = self.task
        out = t.execute(self.config, t.crm(crm), self._reading or self.config)
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
            obs = t.observe(reading)
            index = t.discretizer.index(obs, error)
            seen.append((obs.rho, obs.m_a, obs.m_b, int(error)))
            raw: dict[str, Any] = getattr(hand, "raw_reading", dict)()
            row = [step, *t.model.numbers(reading), *obs, index, t.discretizer.label(index)]
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
            write_csv(log, log_columns(t), rows)
        return result

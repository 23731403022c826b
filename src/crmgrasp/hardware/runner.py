"""Run a saved policy on a hand: the kinematic simulator or a real (or physics) hand.

A hand implements [`HandInterface`][]: ``sense()`` returns the sensed contact
configuration (or [`NoContact`][crmgrasp.hardware.contact_sensing.NoContact]), ``execute(crm)``
performs a CRM and returns its error flag. [`KinematicHand`][] is the
simulator behind that interface, in the plane or in space (it steps the task's own
rules: ``task.execute``, ``task.read``). [`PolicyRunner`][] senses, discretizes,
builds the k-order history, picks the policy's action, executes it, and logs every
step (readings, observation, action, error) to a CSV file. It stops when the
*sensed* configuration is a grasp (``min_friction(sensed) <= mu_goal``: all a real
robot can check), when contact is lost, or after ``task.max_steps`` CRMs.
"""

from __future__ import annotations

import dataclasses
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol, runtime_checkable

import numpy as np

from crmgrasp._io import dumps_json, write_csv
from crmgrasp._validation import CrmgraspError, generator
from crmgrasp.agents.policy import GreedyPolicy
from crmgrasp.hardware.answers import checked_error, checked_pose, checked_raw, checked_reading, checked_time
from crmgrasp.hardware.contact_sensing import NoContact
from crmgrasp.model.contacts import Config, Grip
from crmgrasp.model.hand import CRM, Error
from crmgrasp.model.sensing import SensorNoise
from crmgrasp.model.spatial import CRM3D, Contacts3D
from crmgrasp.sim import OneStep, Percept, SimState, run_episode, step_reward
from crmgrasp.tasks import Task, checked_task

__all__ = ["HandInterface", "HandSteps", "KinematicHand", "PolicyRunner", "RunResult", "log_columns"]

RUN_COLUMNS = ["obs_index", "observation", "action", "crm", "error", "raw"]
"""The columns of a step log after the contacts and the observation: the observation's bin
and label, the action taken, its CRM and error flag, and the raw sensor values."""


def log_columns(task: Task) -> list[str]:
    """The step-log columns of a run on ``task``: ``step``, the reading's contacts in the
    contact model's row order (``ax, ay, anx, any, ...`` in the plane; ``ax, ay, az, anx,
    any, anz, ...`` in space), the model's observation (``rho, m_a, m_b``), then
    [`RUN_COLUMNS`][]."""
    task = checked_task(task, "log_columns")
    return ["step", *task.model.columns, *task.model.observation_names, *RUN_COLUMNS]


@runtime_checkable
class HandInterface(Protocol):
    """What a hand must offer to run CRM policies."""

    def sense(self) -> Config | Grip | Contacts3D | NoContact: ...

    def execute(self, crm: Any) -> Error:
        """Perform ``crm`` (a [`CRM`][crmgrasp.model.hand.CRM], or a
        [`CRM3D`][crmgrasp.model.spatial.CRM3D] on a spatial hand); return its error flag."""
        ...


class KinematicHand:
    """The kinematic simulator as a hand (planar or spatial task): true state hidden,
    readings through ``noise`` (default: the task's)."""

    def __init__(
        self, task: Task, start: Config | Grip | Contacts3D, rng: np.random.Generator, noise: SensorNoise | None = None
    ):
        task = checked_task(task, "KinematicHand")
        self.task = task if noise is None else dataclasses.replace(task, noise=noise)
        self.config, self.rng = task.check_config(start, "start"), generator(rng)
        self._reading: Config | Grip | Contacts3D | None = None

    def sense(self) -> Config | Grip | Contacts3D:
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
    readings: list[tuple[Any, str, str]] = field(default_factory=list)
    """Per reading with contact, in order: the sensed configuration, the CRM taken after it (its
    text as in the step log) and that CRM's error (both ``""`` after the last reading)."""


class PolicyRunner:
    """Drives a saved policy (a tabular [`GreedyPolicy`][crmgrasp.agents.policy.GreedyPolicy] or a
    deep [`RecurrentPolicy`][crmgrasp.agents.deep.RecurrentPolicy]: anything with ``task`` and
    ``predict(observations, actions, rng)``) on a [`HandInterface`][]."""

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
        """Run one episode through the one episode loop ([`crmgrasp.sim.run_episode`][],
        with the hand as its stepper); write the step log to ``log`` if given: CSV, or an
        MCAP record in Foxglove's schemas for a name ending in ``.mcap``
        ([`crmgrasp.hardware.records`][], extra ``crmgrasp[mcap]``)."""
        t = self.task
        steps = HandSteps(t, hand)
        episode = run_episode(t, _Predicting(self.policy, rng), rng, trace=True, kernel=steps)
        rows = [steps.row(tr.before, tr.action, tr.after.error) for tr in episode.trace]  # type: ignore[arg-type]
        last = episode.trace[-1].after if episode.trace else steps.first
        if steps.lost is None:
            rows.append(steps.row(last))
        if steps.lost is not None:
            result = RunResult(last.state.steps, False, f"no contact: {steps.lost}")
        elif episode.success:
            result = RunResult(last.state.steps, True, "grasp sensed")
        else:
            result = RunResult(last.state.steps, False, "step limit")
        result.rows = rows
        result.readings = [
            (tr.before.state.sensed, str(t.crm(tr.action)), tr.after.error.name.lower())  # type: ignore[arg-type]
            for tr in episode.trace
        ]
        if steps.lost is None:
            result.readings.append((last.state.sensed, "", ""))
        if log is not None and str(log).endswith(".mcap"):
            from crmgrasp.hardware.records import write_mcap

            trace: list[tuple[OneStep, Any, Error | None]] = [
                (tr.before, tr.action, tr.after.error) for tr in episode.trace
            ]
            if steps.lost is None:
                trace.append((last, None, None))
            write_mcap(Path(log), [steps.record(*item) for item in trace], t.name)
        elif log is not None:
            write_csv(log, log_columns(t), rows)
        return result


_HERE = object()
"""The start of a run on a hand: wherever the hand is."""


class HandSteps:
    """A hand as the episode loop's stepper: each step executes the CRM on the hand, then
    senses once. The episode ends when the *sensed* configuration is a grasp (all a real
    robot can check), when contact is lost, or after ``max_steps`` CRMs. It keeps what the
    step log needs beside the steps: the raw sensor values of every reading. Each answer of
    the hand is checked as it arrives ([`crmgrasp.hardware.answers`][]): a malformed one is a
    one-line error naming the method, before anything is logged.

    ``min_friction`` of a step is that of the sensed configuration ([`score`][] may
    override it: a simulated hand can report the truth)."""

    def __init__(self, task: Task, hand: HandInterface | None = None) -> None:
        self.task = task
        self.hand: HandInterface = hand  # type: ignore[assignment]  # set by begin where None
        self.raws: list[dict[str, Any]] = []
        self.clock: list[tuple[float, Any]] = []  # per reading: the hand's time (s) and the object's pose
        self.lost: str | None = None
        self.first: OneStep

    def score(self, reading: Config | Grip | Contacts3D, sensed: float) -> float:
        """The ``min_friction`` a step reports, given the sensed configuration's
        (``sensed``): that one."""
        return sensed

    def _sense(self, steps: int, error: Error) -> OneStep:
        when = "before the first CRM" if steps == 0 else f"after CRM {steps}"
        t, (reading, obs) = self.task, checked_reading(self.task, self.hand.sense(), when)
        if obs is None:  # NoContact
            self.lost = str(reading.reason)
            nan = float("nan")
            lost = (nan,) * len(t.model.observation_names)
            return OneStep(SimState(None, None, steps), lost, error, -1, nan, -1.0, False, True)  # type: ignore[arg-type]
        self.raws.append(checked_raw(getattr(self.hand, "raw_reading", dict)()))
        pose = getattr(self.hand, "object_pose", None)
        clock = checked_time(getattr(self.hand, "time", steps))
        self.clock.append((clock, None if pose is None else checked_pose(t, pose())))
        mu = float(t.quality(reading))
        grasped = bool(t.grasped(mu))
        index = t.discretizer.index(obs, error)
        end = steps >= t.max_steps and not grasped
        state = SimState(reading, reading, steps)  # type: ignore[arg-type]
        reward = step_reward(t, grasped, error)
        return OneStep(state, obs, error, index, self.score(reading, mu), reward, grasped, end)

    def begin(self, config: Any, rng: np.random.Generator) -> OneStep:
        self.raws, self.clock, self.lost = [], [], None
        self.first = self._sense(0, Error.NONE)
        return self.first

    def step_one(self, state: SimState, action: Any, rng: np.random.Generator) -> OneStep:
        crm = self.task.crm(action)
        return self._sense(state.steps + 1, checked_error(self.hand.execute(crm), crm))

    def sample_start(self, rng: np.random.Generator) -> Any:
        return _HERE

    def use(self, instance: Task) -> None:
        raise CrmgraspError("a hand runs where it is: it takes no world")

    def row(self, now: OneStep, action: Any = None, error: Error | None = None) -> list[Any]:
        """The step log's row of a reading: contacts, observation, its bin and label, then
        the action, its CRM and error (blank after the last reading), and the raw values."""
        t = self.task
        row: list[Any] = [now.state.steps, *t.model.numbers(now.state.sensed), *now.observation]
        row += [now.obs_index, t.discretizer.label(now.obs_index)]
        if action is None or error is None:
            row += ["", "", ""]
        else:
            index = "" if t.model.is_crm(action) else action  # a CRM of the continuous space has no index
            row += [index, str(t.crm(action)), error.name.lower()]
        return [*row, dumps_json(self.raws[now.state.steps], indent=None)]

    def record(self, now: OneStep, action: Any = None, error: Error | None = None) -> Any:
        """The MCAP record ([`StepRecord`][crmgrasp.hardware.records.StepRecord]) of a
        reading and the CRM taken after it."""
        from crmgrasp.hardware.records import StepRecord, contact_frames

        t, k = self.task, now.state.steps
        time, pose = self.clock[k]
        rec = StepRecord(
            time=time,
            step=k,
            contacts=contact_frames(t.model, now.state.sensed),
            observation={name: float(v) for name, v in zip(t.model.observation_names, now.observation)},
            obs_index=now.obs_index,
            label=t.discretizer.label(now.obs_index),
            raw=self.raws[k],
            pose=pose,
        )
        if action is not None and error is not None:
            rec.action = None if t.model.is_crm(action) else int(action)
            rec.crm, rec.error = str(t.crm(action)), error.name.lower()
        return rec


class _Predicting:
    """A saved policy (``predict(observations, actions, rng)``) as the episode loop's
    [`Policy`][crmgrasp.sim.Policy]: it keeps the history of readings and actions."""

    def __init__(self, policy: Any, rng: np.random.Generator) -> None:
        self.policy, self.rng = policy, rng
        self.seen: list[tuple[float, ...]] = []  # each: the observation, then the error flag
        self.taken: list[Any] = []

    def begin(self, first: Percept) -> None:
        self.seen, self.taken = [(*first.observation, int(first.error))], []

    def act(self) -> Any:
        action = self.policy.predict(self.seen, self.taken, self.rng)
        if not self.policy.task.model.is_crm(action):  # a continuous policy's CRM goes as it is
            action = int(action)
        self.taken.append(action)
        return action

    def tell(self, percept: Percept) -> None:
        self.seen.append((*percept.observation, int(percept.error)))

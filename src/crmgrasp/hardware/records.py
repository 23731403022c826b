"""MCAP records of runs on a hand, in Foxglove's message schemas.

``crmgrasp run --log run.mcap`` (and the physics-learning experiment) write one MCAP file
per run (extra ``crmgrasp[mcap]``: the ``mcap`` reader and the Foxglove SDK, whose
``foxglove.*`` schemas Foxglove Studio and other robotics tools display without setup).
Topics, one message per reading (before the first CRM and after each), stamped with the
hand's clock (MuJoCo's simulated time; the kinematic hand: one second per CRM):

* ``/contacts`` (``foxglove.SceneUpdate``): per sensed contact a sphere at its point and an
  arrow along its inward normal (metres, world frame; planar contacts at z = 0);
* ``/object`` (``foxglove.PoseInFrame``): the object's pose (a hand that reports it: the
  MuJoCo stand-in);
* ``/wrench/<contact>`` (``crmgrasp.Wrench``, JSON): the tared fingertip wrench behind the
  reading, ``force`` (N) and ``torque`` (N m): each entry of the hand's ``raw_reading()`` named
  by a contact label whose value is 3 (planar) or 6 (spatial) numbers;
* ``/raw`` (``crmgrasp.RawReading``, JSON): the rest of the hand's ``raw_reading()`` (the
  entries that are not a contact's wrench), if any;
* ``/crm`` (``crmgrasp.CRMStep``, JSON): the step, the model's observation, its bin and
  label; the CRM taken after the reading, its action index and the error flag it returned;
* ``/log`` (``foxglove.Log``): the same step as one line of text.

The file is written to a temporary name and renamed at the end: a run cut short leaves
no half-written record.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType
from typing import Any

from crmgrasp._io import atomic_path, check_output, json_safe
from crmgrasp._validation import CrmgraspError, is_real, require_extra, shown
from crmgrasp.hardware.answers import MAX_TIME, is_clock, raw_problem

__all__ = ["StepRecord", "write_mcap", "require_mcap", "contact_frames", "check_records", "TOPICS"]

TOPICS = ("/contacts", "/object", "/wrench/<contact>", "/raw", "/crm", "/log")
"""The topics of a record (``<contact>``: each contact's label)."""

_WRENCH = {
    "type": "object",
    "title": "crmgrasp.Wrench",
    "properties": {
        name: {"type": "object", "properties": {k: {"type": "number"} for k in "xyz"}} for name in ("force", "torque")
    },
}
_RAW = {"type": "object", "title": "crmgrasp.RawReading"}
_STEP = {
    "type": "object",
    "title": "crmgrasp.CRMStep",
    "properties": {
        "step": {"type": "integer"},
        "observation": {"type": "object", "additionalProperties": {"type": "number"}},
        "obs_index": {"type": "integer"},
        "label": {"type": "string"},
        "action": {"type": ["integer", "null"]},
        "crm": {"type": ["string", "null"]},
        "error": {"type": ["string", "null"]},
    },
}


@dataclass
class StepRecord:
    """One reading of a run and the CRM taken after it (``None`` after the last)."""

    time: float
    """The hand's clock at the reading, s."""
    step: int
    contacts: dict[str, tuple[tuple[float, ...], tuple[float, ...]]]
    """Label -> (point, inward unit normal), metres, world frame."""
    observation: dict[str, float]
    obs_index: int
    label: str
    raw: dict[str, list[float]] = field(default_factory=dict)
    """Label -> the tared wrench: ``f_x, f_y, m_z`` (planar) or ``f, m`` (spatial)."""
    pose: tuple[float, ...] | None = None
    """The object's position and orientation: ``(x, y, yaw)`` or ``(x, y, z, qw, qx, qy, qz)``."""
    action: int | None = None
    crm: str | None = None
    error: str | None = None


def contact_frames(model: Any, config: Any) -> dict[str, tuple[tuple[float, ...], tuple[float, ...]]]:
    """Each contact's ``(point, inward normal)`` as 3-vectors, read off the contact model's
    row (its ``columns``: ``ax, ay[, az], anx, any[, anz], ...``; a planar contact at z = 0)."""
    values = dict(zip(model.columns, (float(v) for v in model.numbers(config))))
    return {
        label: (
            tuple(values.get(f"{label}{k}", 0.0) for k in "xyz"),
            tuple(values.get(f"{label}n{k}", 0.0) for k in "xyz"),
        )
        for label in model.labels
    }


def require_mcap() -> ModuleType:
    """Import and return the Foxglove SDK, or raise a one-line error naming the extra."""
    return require_extra("mcap", "an MCAP record", "mcap", "foxglove")[1]  # type: ignore[no-any-return]


def _is_wrench(values: object) -> bool:
    """A planar ``f_x, f_y, m_z`` or a spatial ``f, m`` reading: 3 or 6 finite real numbers."""
    return _numbers(values, (3, 6))


def _wrench(values: Sequence[float]) -> dict[str, dict[str, float]]:
    """``{force, torque}`` of a planar ``f_x, f_y, m_z`` or a spatial ``f, m`` reading."""
    v = [float(x) for x in values]
    f, m = ((v[0], v[1], 0.0), (0.0, 0.0, v[2])) if len(v) == 3 else (tuple(v[:3]), tuple(v[3:6]))
    return {"force": dict(zip("xyz", f)), "torque": dict(zip("xyz", m))}


def _pose(fg: Any, pose: tuple[float, ...]) -> Any:
    msgs = fg.messages
    if len(pose) == 3:  # planar: x, y, yaw
        x, y, yaw = pose
        q = msgs.Quaternion(x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2))
        return msgs.Pose(position=msgs.Vector3(x=x, y=y, z=0.0), orientation=q)
    x, y, z, qw, qx, qy, qz = pose
    return msgs.Pose(position=msgs.Vector3(x=x, y=y, z=z), orientation=msgs.Quaternion(x=qx, y=qy, z=qz, w=qw))


def _arrow_pose(fg: Any, point: Sequence[float], normal: Sequence[float]) -> Any:
    """A pose at ``point`` whose x axis is ``normal`` (Foxglove's arrows point along x)."""
    msgs = fg.messages
    nx, ny, nz = normal
    # the rotation taking (1, 0, 0) to n: axis (0, -nz, ny), angle acos(nx)
    w = math.sqrt(max(0.0, (1.0 + nx) / 2.0))
    if w < 1e-9:  # n = -x: half a turn about z
        q = msgs.Quaternion(x=0.0, y=0.0, z=1.0, w=0.0)
    else:
        q = msgs.Quaternion(x=0.0, y=-nz / (2 * w), z=ny / (2 * w), w=w)
    return msgs.Pose(position=msgs.Vector3(x=point[0], y=point[1], z=point[2]), orientation=q)


def _sphere(msgs: Any, at: Any) -> Any:
    """The 8 mm red sphere that marks a contact point."""
    return msgs.SpherePrimitive(pose=at, size=msgs.Vector3(x=0.008, y=0.008, z=0.008), color=msgs.Color(r=0.9, a=1))


def _scene(fg: Any, rec: StepRecord, stamp: Any) -> Any:
    msgs = fg.messages
    entities = []
    for label, (point, normal) in rec.contacts.items():
        at = _arrow_pose(fg, point, normal)
        entities.append(
            msgs.SceneEntity(
                timestamp=stamp,
                frame_id="world",
                id=f"contact-{label}",
                spheres=[
                    msgs.SpherePrimitive(
                        pose=at,
                        size=msgs.Vector3(x=0.008, y=0.008, z=0.008),
                        color=msgs.Color(r=0.9, g=0.2, b=0.2, a=1),
                    )
                ],
                arrows=[
                    msgs.ArrowPrimitive(
                        pose=at,
                        shaft_length=0.02,
                        shaft_diameter=0.002,
                        head_length=0.006,
                        head_diameter=0.005,
                        color=msgs.Color(r=0.2, g=0.4, b=0.9, a=1),
                    )
                ],
            )
        )
    return msgs.SceneUpdate(entities=entities)


def _numbers(values: Any, sizes: tuple[int, ...]) -> bool:
    """Whether ``values`` is a list or tuple of one of ``sizes`` real, finite numbers."""
    return isinstance(values, (list, tuple)) and len(values) in sizes and all(map(_finite, values))


def _finite(value: Any) -> bool:
    return is_real(value) and math.isfinite(value)


def _count(value: Any) -> bool:
    """Whether ``value`` is an integer >= 0 (not a bool)."""
    return isinstance(value, int) and not isinstance(value, bool) and value >= 0


def _text_keys(value: Any) -> bool:
    return isinstance(value, dict) and all(isinstance(k, str) for k in value)


def _frame(value: Any) -> bool:
    """Whether ``value`` is a contact's ``(point, normal)``: two 3-vectors of finite numbers."""
    return isinstance(value, (list, tuple)) and len(value) == 2 and all(_numbers(v, (3,)) for v in value)


def _problem(rec: StepRecord) -> str | None:
    """What is wrong with ``rec``'s fields (``None`` if nothing): the form the module writes."""
    checks = (
        ("time", is_clock(rec.time), f"seconds in [0, {MAX_TIME:g}]"),
        ("step", _count(rec.step), "an integer >= 0"),
        (
            "contacts",
            _text_keys(rec.contacts) and all(map(_frame, rec.contacts.values())),
            "label -> (point, normal), each 3 finite numbers",
        ),
        ("observation", _text_keys(rec.observation) and all(map(_finite, rec.observation.values())), "name -> number"),
        ("obs_index", _count(rec.obs_index), "an integer >= 0"),
        ("label", isinstance(rec.label, str), "text"),
        ("raw", raw_problem(rec.raw) is None, "a dict with text keys that JSON holds"),
        ("pose", rec.pose is None or _numbers(rec.pose, (3, 7)), "None, or 3 or 7 finite numbers"),
        ("action", rec.action is None or _count(rec.action), "None or an integer >= 0"),
        ("crm", rec.crm is None or isinstance(rec.crm, str), "None or text"),
        ("error", rec.error is None or isinstance(rec.error, str), "None or text"),
    )
    for name, ok, want in checks:
        if not ok:
            return f"its {name} is {shown(getattr(rec, name))}, not {want}"
    return None


def check_records(records: Any) -> list[StepRecord]:
    """``records`` as a list if it is a list or tuple of [`StepRecord`][]s whose fields have
    the form the module writes, else a one-line error naming the first record that does not."""
    if not isinstance(records, (list, tuple)):
        raise CrmgraspError(f"records must be a list of StepRecord, got {shown(records)}")
    for i, rec in enumerate(records):
        problem = _problem(rec) if isinstance(rec, StepRecord) else "it is no StepRecord"
        if problem:
            raise CrmgraspError(f"record {i} cannot be written: {problem}")
    return list(records)


def write_mcap(path: str | Path, records: Sequence[StepRecord], task_name: str) -> Path:
    """Write ``records`` (one per reading) to the MCAP file ``path`` (see the module
    docstring); return the path. The records are checked first ([`check_records`][]), so a
    malformed one leaves nothing written."""
    records = check_records(records)
    if not isinstance(task_name, str):
        raise CrmgraspError(f"the task name must be text, got {shown(task_name)}")
    path = check_output(path, "MCAP record")
    fg = require_mcap()
    with atomic_path(path) as tmp:
        ctx = fg.Context()
        writer = fg.open_mcap(str(tmp), allow_overwrite=True, context=ctx)
        try:
            _log_all(fg, ctx, records, task_name)
        finally:
            writer.close()
    return path


def _json_channel(fg: Any, ctx: Any, topic: str, schema: dict[str, Any]) -> Any:
    data = json.dumps(schema).encode()
    schema_ = fg.Schema(name=schema["title"], encoding="jsonschema", data=data)
    return fg.Channel(topic, schema=schema_, message_encoding="json", context=ctx)


def _log_all(fg: Any, ctx: Any, records: Sequence[StepRecord], task_name: str) -> None:
    msgs, ch = fg.messages, fg.channels
    scene = ch.SceneUpdateChannel("/contacts", context=ctx)
    pose = ch.PoseInFrameChannel("/object", context=ctx)
    log = ch.LogChannel("/log", context=ctx)
    step = _json_channel(fg, ctx, "/crm", _STEP)
    wrenches: dict[str, Any] = {}
    raw = None
    for rec in records:
        ns = round(rec.time * 1e9)
        stamp = msgs.Timestamp(sec=ns // 1_000_000_000, nsec=ns % 1_000_000_000)
        scene.log(_scene(fg, rec, stamp), log_time=ns)
        if rec.pose is not None:
            pose.log(msgs.PoseInFrame(timestamp=stamp, frame_id="world", pose=_pose(fg, rec.pose)), log_time=ns)
        other = {}
        for label, values in rec.raw.items():
            if label not in rec.contacts or not _is_wrench(values):
                other[label] = values
                continue
            if label not in wrenches:
                wrenches[label] = _json_channel(fg, ctx, f"/wrench/{label}", _WRENCH)
            wrenches[label].log(_wrench(values), log_time=ns)
        if other:
            raw = raw or _json_channel(fg, ctx, "/raw", _RAW)
            raw.log(json_safe(other), log_time=ns)
        body = {
            "step": rec.step,
            "observation": rec.observation,
            "obs_index": rec.obs_index,
            "label": rec.label,
            "action": rec.action,
            "crm": rec.crm,
            "error": rec.error,
        }
        step.log(body, log_time=ns)
        text = f"step {rec.step}: {rec.label}" + (f"; CRM {rec.crm} -> {rec.error}" if rec.crm else "; end")
        log.log(
            msgs.Log(timestamp=stamp, level=msgs.LogLevel.Info, message=text, name=task_name, file="", line=0),
            log_time=ns,
        )

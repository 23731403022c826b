"""Reading policy files: bounded, strict standard JSON, the checksum, and the task a file
carries or names.

A policy file is read from a regular file of at most [`MAX_BYTES`][] bytes and parsed as strict
standard JSON: no duplicate keys, no NaN or infinities, integers of at most 20 digits, bounded
nesting; every refusal is a one-line `CrmgraspError` naming the file. [`policy_digest`][] is
the checksum a saved policy carries (SHA-256 of the document without it, sorted keys, no
spaces), so an edited file is refused. [`GreedyPolicy`][crmgrasp.agents.policy.GreedyPolicy]
and the deep policies read their files through this module.
"""

from __future__ import annotations

import hashlib
import json
import os
from typing import Any

from crmgrasp._io import as_path, read_bounded
from crmgrasp._validation import CrmgraspError, shown
from crmgrasp.tasks import Task, make_task, task_from_dict, task_names, task_to_dict

__all__ = [
    "MAX_BYTES",
    "MAX_INT_DIGITS",
    "read_policy_document",
    "policy_digest",
    "policy_task",
    "first_difference",
    "crm_difference",
    "written_spec",
]

MAX_BYTES = 64 * 2**20
"""Largest policy file read (64 MiB; a paper-box table is a few kB)."""

MAX_INT_DIGITS = 20
"""The most digits an integer in a policy file may have (state codes included)."""


def _no_duplicates(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key, value in pairs:
        if key in out:
            raise CrmgraspError(f"key {shown(key)} appears more than once")
        out[key] = value
    return out


def _int(text: str) -> int:
    if len(text.lstrip("-")) > MAX_INT_DIGITS:
        raise CrmgraspError(f"integer {shown(text)} has more than {MAX_INT_DIGITS} digits")
    return int(text)


def _no_constant(text: str) -> Any:
    raise CrmgraspError(f"{text} is not standard JSON")


def policy_digest(doc: dict[str, Any]) -> str:
    """SHA-256 hex digest of a policy document without its ``sha256`` field (sorted
    keys, no spaces)."""
    body = {k: v for k, v in doc.items() if k != "sha256"}
    return hashlib.sha256(json.dumps(body, sort_keys=True, separators=(",", ":")).encode()).hexdigest()


def read_policy_document(path: str | os.PathLike[str]) -> Any:
    """The parsed JSON of a policy file, read with the bounds above (one-line errors)."""
    p = as_path(path, "policy file")
    data = read_bounded(p, MAX_BYTES, "policy file")
    try:
        return json.loads(
            data.decode("utf-8"),
            object_pairs_hook=_no_duplicates,
            parse_int=_int,
            parse_constant=_no_constant,
        )
    except CrmgraspError as exc:
        raise CrmgraspError(f"policy file {str(p)!r}: {exc}") from None
    except RecursionError:
        raise CrmgraspError(f"policy file {str(p)!r} is nested too deeply") from None
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise CrmgraspError(f"policy file {str(p)!r} is not valid JSON ({exc})") from None


def written_spec(spec: Any) -> Any:
    """A stored task spec as today's writer states it (read, then written back), so that a
    file saved before a key was added or left out by default still matches its task; the
    spec as stored when it does not read."""
    try:
        return task_to_dict(task_from_dict(spec))
    except CrmgraspError:
        return spec


def first_difference(a: Any, b: Any, where: str = "") -> str | None:
    """The first key path at which two JSON values differ (``None`` if equal)."""
    if isinstance(a, dict) and isinstance(b, dict):
        for key in sorted(set(a) | set(b), key=str):
            sub = first_difference(a.get(key), b.get(key), f"{where}.{key}" if where else str(key))
            if sub is not None:
                return sub
        return None
    if isinstance(a, list) and isinstance(b, list) and len(a) == len(b):
        for i, (x, y) in enumerate(zip(a, b)):
            sub = first_difference(x, y, f"{where}[{i}]")
            if sub is not None:
                return sub
        return None
    return None if a == b else (where or "the task")


def crm_difference(got: Any, expected: list[Any]) -> str:
    """How a policy's CRM set ``got`` differs from the task's ``expected``, in a few words: its
    type, its count, or its first CRM that differs (a grid's set has hundreds)."""
    if not isinstance(got, list):
        return f"is {shown(got)}, not a list of the task's {len(expected)} CRMs"
    if len(got) != len(expected):
        return f"has {len(got)} CRMs, the task's {len(expected)}"
    i = next(i for i, (x, y) in enumerate(zip(got, expected, strict=True)) if x != y)
    return f"differs from the task's at CRM {i + 1}: {shown(got[i])} in the policy, {shown(expected[i])} in the task"


def policy_task(doc: Any, source: str = "policy") -> Task:
    """The task a policy document carries (``task_spec``) or names (a registered task)."""
    if not isinstance(doc, dict):
        raise CrmgraspError(f"{source}: not a crmgrasp policy")
    spec, name = doc.get("task_spec"), doc.get("task")
    if spec is not None:
        if isinstance(spec, dict) and isinstance(spec.get("starts"), dict) and spec["starts"].get("kind") == "custom":
            if isinstance(name, str) and name in task_names():
                return make_task(name)
            raise CrmgraspError(f"{source}: its task {name!r} has Python-defined starts; give the task (--task)")
        try:
            return task_from_dict(spec)
        except CrmgraspError as exc:
            raise CrmgraspError(f"{source}: bad task_spec: {exc}") from None
    if not isinstance(name, str):
        raise CrmgraspError(f"{source} names no task")
    return make_task(name)

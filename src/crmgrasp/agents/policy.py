"""Greedy policies and their JSON file format (no pickle).

File layout (``format`` ``"crmgrasp-policy"``, ``version`` 1)::

    {
      "format": "crmgrasp-policy", "version": 1,
      "task": "paper-box", "k": 2,
      "actions": [["a", "b", 0.0], ...],          # the task's CRM set, in order
      "bins": {"rho": [1.0], "m_a": [0.1], "m_b": [0.1], "abs_moments": true},
      "agent": "sarsa",
      "greedy": {"<state code>": [best actions], ...}   # visited states only
    }

A state code is the k-order history code of :mod:`crmgrasp.model.history`; its
``"greedy"`` entry lists the actions tied for the best value (usually one). In a
state the file does not list, the policy picks uniformly among all actions.
Loading checks every field and refuses a policy made for another task, history
order, CRM set or bins.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from crmgrasp._io import write_json
from crmgrasp._validation import CrmgraspError
from crmgrasp.agents.tabular import TabularAgent
from crmgrasp.model.history import KOrderEncoder
from crmgrasp.tasks import Task

if TYPE_CHECKING:
    from crmgrasp.agents.symmetric import SymmetricAgent

__all__ = ["GreedyPolicy", "FORMAT", "VERSION"]

FORMAT = "crmgrasp-policy"
VERSION = 1


class GreedyPolicy:
    """A fixed state -> action table, usable wherever an agent's ``greedy`` is."""

    name = "policy"

    def __init__(self, task: Task, k: int, table: dict[int, tuple[int, ...]], agent: str = "unknown") -> None:
        self.task = task
        self.encoder = KOrderEncoder(task.discretizer.size, len(task.actions), k)
        self.k = k
        self.n_actions = len(task.actions)
        self.table = table
        self.agent = agent

    @classmethod
    def from_agent(cls, task: Task, k: int, agent: TabularAgent | SymmetricAgent) -> GreedyPolicy:
        """The greedy policy of a tabular agent over the states it has visited: in
        each, the best of the actions it has tried (all ties kept)."""
        table = {}
        for s, row in agent.q.items():
            acts = sorted(agent.tried.get(s) or range(len(row)))
            best = max(row[a] for a in acts)
            table[s] = tuple(a for a in acts if row[a] == best)
        return cls(task, k, table, agent.name)

    def begin_episode(self) -> None:
        """Stateless."""

    def greedy(self, state: int, rng: np.random.Generator) -> int:
        """The listed action (uniform among ties); uniform over all actions if unlisted."""
        acts = self.table.get(state)
        if acts is None:
            return int(rng.integers(self.n_actions))
        return acts[0] if len(acts) == 1 else acts[int(rng.integers(len(acts)))]

    act = greedy

    def update(self, *args: Any) -> None:
        """A saved policy does not learn."""

    def to_dict(self) -> dict[str, Any]:
        """The JSON document."""
        return {
            "format": FORMAT,
            "version": VERSION,
            "task": self.task.name,
            "k": self.k,
            "actions": [[c.c, c.f, c.r] for c in self.task.actions],
            "bins": self.task.discretizer.to_dict(),
            "agent": self.agent,
            "greedy": {str(s): list(a) for s, a in sorted(self.table.items())},
        }

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write the policy atomically."""
        return write_json(path, self.to_dict())

    @classmethod
    def load(cls, path: str | os.PathLike[str], task: Task) -> GreedyPolicy:
        """Read and validate a policy file for ``task``."""
        p = Path(path)
        try:
            doc = json.loads(p.read_text(encoding="utf-8"))
        except FileNotFoundError:
            raise CrmgraspError(f"policy file {str(p)!r} does not exist") from None
        except (UnicodeDecodeError, json.JSONDecodeError) as exc:
            raise CrmgraspError(f"policy file {str(p)!r} is not valid JSON ({exc})") from None
        return cls.from_dict(doc, task, source=str(p))

    @classmethod
    def from_dict(cls, doc: Any, task: Task, source: str = "policy") -> GreedyPolicy:
        """Validate a policy document against ``task``."""

        def bad(msg: str) -> CrmgraspError:
            return CrmgraspError(f"{source}: {msg}")

        if not isinstance(doc, dict) or doc.get("format") != FORMAT:
            raise bad(f'not a crmgrasp policy (expected "format": "{FORMAT}")')
        if doc.get("version") != VERSION:
            raise bad(f"unsupported policy version {doc.get('version')!r} (expected {VERSION})")
        missing = {"task", "k", "actions", "bins", "greedy"} - set(doc)
        if missing:
            raise bad(f"missing field(s) {', '.join(sorted(missing))}")
        if doc["task"] != task.name:
            raise bad(f"policy is for task {doc['task']!r}, not {task.name!r}")
        k = doc["k"]
        if isinstance(k, bool) or not isinstance(k, int) or k < 0:
            raise bad(f"k must be an integer >= 0, got {k!r}")
        expected = [[c.c, c.f, c.r] for c in task.actions]
        if doc["actions"] != expected:
            raise bad(f"policy's CRM set {doc['actions']} differs from the task's {expected}")
        if doc["bins"] != task.discretizer.to_dict():
            raise bad(f"policy's observation bins {doc['bins']} differ from the task's")
        encoder = KOrderEncoder(task.discretizer.size, len(task.actions), k)
        if not isinstance(doc["greedy"], dict):
            raise bad('"greedy" must be an object mapping state codes to action lists')
        table: dict[int, tuple[int, ...]] = {}
        for key, acts in doc["greedy"].items():
            try:
                s = int(key)
            except ValueError:
                raise bad(f"state code {key!r} is not an integer") from None
            if not 0 <= s < encoder.size:
                raise bad(f"state code {s} is outside [0, {encoder.size}) for k = {k}")
            if (
                not isinstance(acts, list)
                or not acts
                or any(isinstance(a, bool) or not isinstance(a, int) or not 0 <= a < len(task.actions) for a in acts)
            ):
                raise bad(f"state {s}: actions must be a non-empty list of integers in [0, {len(task.actions)})")
            table[s] = tuple(acts)
        return cls(task, k, table, str(doc.get("agent", "unknown")))

"""Greedy policies and their JSON file format (no pickle).

File layout (``format`` ``"crmgrasp-policy"``, ``version`` 2)::

    {
      "format": "crmgrasp-policy", "version": 2,
      "task": "paper-box", "k": 2,
      "task_spec": {...},                          # the task itself (task-file schema)
      "actions": [["a", "b", 0.0], ...],          # the task's CRM set, in order
      "bins": {"rho": [1.0], "m_a": [0.1], "m_b": [0.1], "abs_moments": true},
      "agent": "sarsa",
      "greedy": {"<state code>": [best actions], ...},  # visited states only
      "sha256": "<hex digest of the rest of the document>"
    }

A learner that backs off to shorter histories
([`BackoffVI`][crmgrasp.agents.backoff.BackoffVI]) writes version 3, which adds
``"backoff": {"k": 1, "greedy": {...}}``: a history the ``"greedy"`` table does not list
acts from its last ``k`` CRMs' code in that table (``k`` below the file's).

A learner with ``skip_errored`` (a policy that never repeats a CRM that erred since the
contacts last moved, [`crmgrasp.agents.base`][]) writes version 4: version 3 (or 2) with
``"skip_errored": true`` and a ``"ranked"`` table beside each ``"greedy"`` one, listing per
state every action the policy chooses among, best first, in groups of equal value
(``{"<state code>": [[best actions], [next], ...]}``; the first group is the ``"greedy"``
entry). After an error the policy takes the first group with an action not known to err
there.

``task_spec`` ([`crmgrasp.tasks.task_to_dict`][]) makes the file stand alone: it
loads without naming a task, also for a task from a TOML file; given a task, the
file is refused unless the task is the one it was made for (the first differing key is
named). Files without ``task_spec`` (written before it existed) name a registered task.

A state code is the k-order history code of [`crmgrasp.model.history`][], written
in canonical decimal; its ``"greedy"`` entry lists the actions tied for the best value
(usually one). In a state the file does not list (nor its back-off table), the policy
picks uniformly among all actions. ``sha256`` is the digest of the document without it, serialised with
sorted keys and no spaces, so an edited file (a changed ``k``, table or header) is
refused. Loading reads at most [`MAX_BYTES`][crmgrasp.agents.policy_file.MAX_BYTES] from a regular file, parses strict
standard JSON (no duplicate keys, no NaN, integers of at most 20 digits, bounded
nesting), checks every field and refuses a policy made for another task, history
order, CRM set or bins.
"""

from __future__ import annotations

import os
from collections.abc import Collection, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from crmgrasp._io import write_json
from crmgrasp._validation import CrmgraspError, generator, shown
from crmgrasp.agents.base import allowed_choice, erred_here
from crmgrasp.agents.policy_file import (
    MAX_BYTES,
    MAX_INT_DIGITS,
    crm_difference,
    first_difference,
    policy_digest,
    policy_task,
    read_policy_document,
    written_spec,
)
from crmgrasp.agents.tabular import TabularAgent
from crmgrasp.model.hand import Error
from crmgrasp.model.history import MAX_K, KOrderEncoder
from crmgrasp.tasks import Task, checked_task, task_to_dict

if TYPE_CHECKING:
    from crmgrasp.agents.symmetric import SymmetricAgent

__all__ = [
    "GreedyPolicy",
    "FORMAT",
    "VERSION",
    "MAX_BYTES",
    "read_policy_document",
    "policy_digest",
    "policy_task",
    "observation_indices",
]

FORMAT = "crmgrasp-policy"
VERSION = 2
VERSIONS = (2, 3, 4)
"""Versions read: 2, 3 (2 with a back-off table, written only with one) and 4 (either with
``skip_errored`` and ranked tables)."""
ObservationLike = int | Sequence[float]
"""A discrete observation index, or the model's observation values then the error flag
(``(rho, m_a, m_b, error)`` for two contacts)."""


def observation_indices(task: Task, observations: Sequence[ObservationLike], actions: Sequence[int]) -> list[int]:
    """Check a history (``len(observations) == len(actions) + 1``, indices in range) and
    turn every observation into its discrete index (one-line errors)."""
    try:
        observations, actions = list(observations), list(actions)
    except TypeError:
        got = f"{shown(observations)} and {shown(actions)}"
        raise CrmgraspError(f"a history is a sequence of observations and one of actions, got {got}") from None
    if len(observations) < 1 or len(observations) != len(actions) + 1:
        raise CrmgraspError(
            f"a history needs one more observation than actions, got {len(observations)} and {len(actions)}"
        )
    n = len(task.actions)
    for a in actions:
        if isinstance(a, bool) or not isinstance(a, (int, np.integer)) or not 0 <= a < n:
            raise CrmgraspError(f"action {shown(a)} is not an integer in [0, {n})")
    out = []
    for o in observations:
        if isinstance(o, (int, np.integer)) and not isinstance(o, bool):
            if not 0 <= o < task.discretizer.size:
                raise CrmgraspError(f"observation index {o} is outside [0, {task.discretizer.size})")
            out.append(int(o))
            continue
        names = task.model.observation_names
        try:
            *raw, err = o  # type: ignore[misc]
            values = [float(v) for v in raw]
        except (TypeError, ValueError):
            values, err = [], None
        if len(values) != len(names):
            raise CrmgraspError(f"an observation is an index or ({', '.join(names)}, error), got {shown(o)}")
        if not all(np.isfinite(values)) or err not in range(len(Error)):
            raise CrmgraspError(f"observation {shown(o)} is not finite or has an unknown error flag")
        out.append(task.discretizer.index(values, int(err)))  # type: ignore[arg-type]
    return out


def crm_rows(task: Task) -> list[list[Any]]:
    """The task's CRM set as JSON data: ``[c, f, r]`` per action (``r`` a list in 3-D)."""
    return [[c.c, c.f, list(c.r) if isinstance(c.r, tuple) else c.r] for c in task.actions]


class GreedyPolicy:
    """A fixed state -> action table, usable wherever an agent's ``greedy`` is."""

    name = "policy"
    file_name = "policy.json"
    """What a run folder calls the file of a saved policy of this kind."""

    def __init__(
        self,
        task: Task,
        k: int,
        table: dict[int, tuple[int, ...]],
        agent: str = "unknown",
        backoff: GreedyPolicy | None = None,
        ranked: dict[int, tuple[tuple[int, ...], ...]] | None = None,
    ) -> None:
        self.task = task
        self.encoder = KOrderEncoder(task.discretizer.size, len(task.actions), k)
        self.k = k
        self.n_actions = len(task.actions)
        self.table = table
        self.agent = agent
        if backoff is not None and not 0 <= backoff.k < k:
            raise CrmgraspError(f"a back-off table needs an order below {k}, got {backoff.k}")
        self.backoff = backoff
        """The table of shorter histories that an unlisted history acts from, or None."""
        self.ranked = ranked
        """Per state, the actions chosen among, best first in groups of equal value; given,
        the policy skips CRMs that erred since the contacts last moved (``skip_errored``)."""
        self.skip_errored = ranked is not None

    @classmethod
    def from_agent(cls, task: Task, k: int, agent: TabularAgent | SymmetricAgent) -> GreedyPolicy:
        """The greedy policy of a tabular agent over the states it has visited: in
        each, the best of the actions its greedy policy chooses among (``greedy_tried``: the tried
        ones; all ties kept); with the back-off table of an agent that has one
        (``backoff_tables()``)."""
        checked_task(task, "a policy")
        if not all(hasattr(agent, name) for name in ("greedy_table", "greedy_tried", "n_actions")):
            raise CrmgraspError(f"a greedy policy is made from a tabular agent, got {shown(agent)}")
        skip = bool(getattr(agent, "skip_errored", False))
        values, choices = agent.greedy_table, agent.greedy_tried
        _check_fits(task, k, agent.n_actions, values)
        tables = getattr(getattr(agent, "inner", agent), "backoff_tables", None)
        backoff = None
        if tables is not None:
            k1, rows, tried = tables()
            ranked1 = _ranked(rows, tried)
            backoff = cls(task, k1, _best_actions(ranked1), agent.name, None, ranked1 if skip else None)
        ranked = _ranked(values, choices)
        return cls(task, k, _best_actions(ranked), agent.name, backoff, ranked if skip else None)

    def begin_episode(self) -> None:
        """Stateless."""

    def greedy(self, state: int, rng: np.random.Generator, banned: Collection[int] = ()) -> int:
        """The listed action (uniform among ties); else the back-off table's for the
        history's last CRMs; uniform over all actions if neither lists it. With ``banned``
        (a policy with ``skip_errored``), the first ranked group with an action outside it,
        as [`allowed_choice`][crmgrasp.agents.base.allowed_choice] chooses."""
        acts = self.table.get(state)
        if acts is None:
            if self.backoff is not None:
                h = self.encoder.decode(state)
                return self.backoff.greedy(self.backoff.encoder.encode(h[: max(2 * self.backoff.k, 1)]), rng, banned)
            if banned:
                return allowed_choice([], [], self.n_actions, banned, rng)
            return int(rng.integers(self.n_actions))
        if banned and self.ranked is not None:  # the groups' order as values: -1 for the second group, ...
            row = [0.0] * self.n_actions
            for i, group in enumerate(self.ranked[state]):
                for a in group:
                    row[a] = -float(i)
            return allowed_choice(row, sorted(a for g in self.ranked[state] for a in g), self.n_actions, banned, rng)
        return acts[0] if len(acts) == 1 else acts[int(rng.integers(len(acts)))]

    act = greedy

    def predict(
        self,
        observations: Sequence[ObservationLike],
        actions: Sequence[int] = (),
        rng: np.random.Generator | None = None,
    ) -> int:
        """The action after an episode's history: ``observations`` ``o_0 .. o_t`` and the
        ``actions`` ``a_0 .. a_{t-1}`` taken between them (one fewer).

        Each observation is a discrete index of the task's bins, or a tuple of the
        model's observation values and the error flag (``(rho, m_a, m_b, error)`` for two
        contacts; binned here). Ties and unlisted states draw from
        ``rng`` (default: a generator seeded with 0, so a call is repeatable)."""
        codes = observation_indices(self.task, observations, actions)
        hist = self.encoder.start(codes[0])
        for a, o in zip(actions, codes[1:]):
            hist = self.encoder.push(hist, int(a), o)
        banned: frozenset[int] = frozenset()
        if self.skip_errored:
            for a, o in zip(actions, codes[1:]):
                banned = erred_here(banned, int(a), Error(self.task.discretizer.decode(o)[1]))
        ties = np.random.default_rng(0) if rng is None else generator(rng)
        return self.greedy(self.encoder.encode(hist), ties, banned)

    def update(self, *args: Any) -> None:
        """A saved policy does not learn."""

    def to_dict(self) -> dict[str, Any]:
        """The JSON document, with its checksum."""
        doc: dict[str, Any] = {
            "format": FORMAT,
            "version": VERSION,
            "task": self.task.name,
            "task_spec": task_to_dict(self.task),
            "k": self.k,
            "actions": crm_rows(self.task),
            "bins": self.task.discretizer.to_dict(),
            "agent": self.agent,
            "greedy": _table_json(self.table),
        }
        if self.backoff is not None:
            doc["version"] = 3
            doc["backoff"] = {"k": self.backoff.k, "greedy": _table_json(self.backoff.table)}
        if self.ranked is not None:
            doc["version"] = 4
            doc["skip_errored"] = True
            doc["ranked"] = _ranked_json(self.ranked)
            if self.backoff is not None and self.backoff.ranked is not None:
                doc["backoff"]["ranked"] = _ranked_json(self.backoff.ranked)
        doc["sha256"] = policy_digest(doc)
        return doc

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write the policy atomically."""
        return write_json(path, self.to_dict())

    @classmethod
    def load(cls, path: str | os.PathLike[str], task: Task | None = None) -> GreedyPolicy:
        """Read ([`read_policy_document`][]) and validate a policy file for ``task``
        (default: the registered task the file names)."""
        doc = read_policy_document(path)
        if task is not None:
            task = checked_task(task, "GreedyPolicy.load")
        if task is None:
            task = policy_task(doc, source=f"policy file {str(path)!r}")
        return cls.from_dict(doc, task, source=repr(str(path)))

    @classmethod
    def from_dict(cls, doc: Any, task: Task, source: str = "policy") -> GreedyPolicy:
        """Validate a policy document against ``task``."""

        def bad(msg: str) -> CrmgraspError:
            return CrmgraspError(f"{source}: {msg}")

        if not isinstance(doc, dict) or doc.get("format") != FORMAT:
            raise bad(f'not a crmgrasp policy (expected "format": "{FORMAT}")')
        if doc.get("version") not in VERSIONS:
            raise bad(f"unsupported policy version {shown(doc.get('version'))} (expected {VERSION}; re-save it)")
        missing = {"task", "k", "actions", "bins", "greedy", "sha256"} - set(doc)
        if missing:
            raise bad(f"missing field(s) {', '.join(sorted(missing))}")
        if doc["sha256"] != policy_digest(doc):
            raise bad("the checksum does not match: the file was edited or damaged")
        if doc["task"] != task.name:
            raise bad(f"policy is for task {doc['task']!r}, not {task.name!r}")
        if "task_spec" in doc:
            where = first_difference(written_spec(doc["task_spec"]), task_to_dict(task))
            if where is not None:
                raise bad(f"policy was made for another version of task {task.name!r} (it differs in {where})")
        agent = doc.get("agent", "unknown")
        if not isinstance(agent, str):
            raise bad(f'"agent" must be the learner\'s name (a string), got {shown(agent)}')
        k = doc["k"]
        if isinstance(k, bool) or not isinstance(k, int) or not 0 <= k <= MAX_K:
            raise bad(f"k must be an integer in [0, {MAX_K}], got {shown(k)}")
        expected, bins = crm_rows(task), task.discretizer.to_dict()
        if doc["actions"] != expected:
            raise bad(f"policy's CRM set {crm_difference(doc['actions'], expected)}")
        if doc["bins"] != bins:
            where = first_difference(doc["bins"], bins)
            raise bad(f"policy's observation bins differ from the task's (in {where}): {shown(doc['bins'])}")
        encoder = KOrderEncoder(task.discretizer.size, len(task.actions), k)
        table = _read_table(doc["greedy"], encoder, bad)
        if (doc["version"] == 4) != (doc.get("skip_errored") is True and "ranked" in doc):
            raise bad('a version 4 policy, and only one, has "skip_errored": true and a "ranked" table')
        ranked = _read_ranked(doc["ranked"], table, encoder, bad) if doc["version"] == 4 else None
        backoff = None
        if doc["version"] == 3 or "backoff" in doc:
            backoff = _read_backoff(doc, task, k, bad)
        return cls(task, k, table, agent, backoff, ranked)


def _check_fits(task: Task, k: int, n_actions: int, values: dict[int, list[float]]) -> None:
    """A one-line error unless an agent of ``n_actions`` whose greedy table is ``values`` can
    be a policy of ``task`` over k-order histories: the same number of CRMs, every state
    code a k-order history code of the task."""
    if n_actions != len(task.actions):
        raise CrmgraspError(f"the agent chooses among {n_actions} CRMs; task {task.name!r} has {len(task.actions)}")
    size = KOrderEncoder(task.discretizer.size, len(task.actions), k).size
    if values and max(values) >= size:
        raise CrmgraspError(
            f"the agent's states are not k = {k} histories of task {task.name!r} (it learned another k or task)"
        )


def _best_actions(ranked: dict[int, tuple[tuple[int, ...], ...]]) -> dict[int, tuple[int, ...]]:
    """Per state, the best of the actions chosen among, ties kept: the first group of `_ranked`."""
    return {s: groups[0] for s, groups in ranked.items()}


def _ranked(values: dict[int, list[float]], tried: dict[int, set[int]]) -> dict[int, tuple[tuple[int, ...], ...]]:
    """Per state, the actions chosen among (all where none is listed), best first, in
    groups of equal value (increasing within a group)."""
    out = {}
    for s, row in values.items():
        acts = sorted(tried.get(s) or range(len(row)))
        levels = sorted({row[a] for a in acts}, reverse=True)
        out[s] = tuple(tuple(a for a in acts if row[a] == v) for v in levels)
    return out


def _table_json(table: dict[int, tuple[int, ...]]) -> dict[str, list[int]]:
    return {str(s): list(a) for s, a in sorted(table.items())}


def _ranked_json(ranked: dict[int, tuple[tuple[int, ...], ...]]) -> dict[str, list[list[int]]]:
    return {str(s): [list(g) for g in groups] for s, groups in sorted(ranked.items())}


def _read_ranked(
    ranked: Any, table: dict[int, tuple[int, ...]], encoder: KOrderEncoder, bad: Any
) -> dict[int, tuple[tuple[int, ...], ...]]:
    """A ``"ranked"`` table: exactly the states of its ``"greedy"`` table, each a non-empty
    list of disjoint action groups whose first is that state's ``"greedy"`` entry."""
    if not isinstance(ranked, dict):
        raise bad('"ranked" must be an object mapping state codes to lists of action groups')
    out: dict[int, tuple[tuple[int, ...], ...]] = {}
    for key, groups in ranked.items():
        if not isinstance(groups, list) or not groups:
            raise bad(f"ranked state {shown(key)}: expected a non-empty list of action groups")
        rows = [_read_table({key: g}, encoder, bad) for g in groups]
        s = next(iter(rows[0]))
        acts = tuple(r[s] for r in rows)
        flat = [a for g in acts for a in g]
        if len(set(flat)) != len(flat) or acts[0] != table.get(s):
            raise bad(f"ranked state {s}: its groups must be disjoint and the first must be its greedy entry")
        out[s] = acts
    if set(out) != set(table):
        raise bad('"ranked" must list exactly the states of "greedy"')
    return out


def _read_backoff(doc: dict[str, Any], task: Task, k: int, bad: Any) -> GreedyPolicy:
    """The back-off table of a version 3 document (its order below ``k``)."""
    part = doc.get("backoff")
    if doc["version"] == 4:
        keys, text = {"k", "greedy", "ranked"}, 'a version 4 policy\'s "backoff" object has "k", "greedy" and "ranked"'
    else:
        keys = {"k", "greedy"}
        text = 'a version 3 policy has a "backoff" object with "k" and "greedy" (and only version 3 has one)'
    if doc["version"] == 2 or not isinstance(part, dict) or set(part) != keys:
        raise bad(text)
    k1 = part["k"]
    if isinstance(k1, bool) or not isinstance(k1, int) or not 0 <= k1 < k:
        raise bad(f"backoff k must be an integer in [0, {k}), got {shown(k1)}")
    encoder = KOrderEncoder(task.discretizer.size, len(task.actions), k1)
    table = _read_table(part["greedy"], encoder, bad)
    ranked = _read_ranked(part["ranked"], table, encoder, bad) if "ranked" in part else None
    return GreedyPolicy(task, k1, table, doc.get("agent", "unknown"), None, ranked)


def _read_table(greedy: Any, encoder: KOrderEncoder, bad: Any) -> dict[int, tuple[int, ...]]:
    """A ``"greedy"`` table, every code and action list checked against ``encoder``."""
    n, k = encoder.n_actions, encoder.k
    if not isinstance(greedy, dict):
        raise bad('"greedy" must be an object mapping state codes to action lists')
    table: dict[int, tuple[int, ...]] = {}
    for key, acts in greedy.items():
        if not (key.isascii() and key.isdigit() and len(key) <= MAX_INT_DIGITS and key == str(int(key))):
            raise bad(f"state code {shown(key)} is not a canonical non-negative integer")
        s = int(key)
        if not 0 <= s < encoder.size:
            raise bad(f"state code {s} is outside [0, {encoder.size}) for k = {k}")
        if (
            not isinstance(acts, list)
            or not acts
            or any(isinstance(a, bool) or not isinstance(a, int) or not 0 <= a < n for a in acts)
        ):
            raise bad(f"state {s}: actions must be a non-empty list of integers in [0, {n})")
        table[s] = tuple(acts)
    return table

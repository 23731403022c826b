"""The fast path of model-based planning: [`value_iteration`][] runs
`ModelVI`'s sweeps in compiled code
(`crmgrasp.kernels._vi_jit`) on arrays built from the agent's model and values,
then writes the values back; the agent's readable sweeps are the definition.

A learner that plans after every real step changes little between two plans: one pair's
counts, now and then a new pair, outcome or state. Its outcome arrays are kept between plans
(`_Outcomes`) while the model and the value table are the same objects, which only grow: the
changed pairs' probabilities are written again by the same division (``agent.changed``, kept by
``ModelVI.update``), new pairs are appended in the model's order, and an outcome that led outside
the table points to its state's row once the state has one. A pair that gained an outcome has
them all copied afresh. The arrays are those a copy of the whole model would give (tested)."""

from __future__ import annotations

import weakref
from itertools import chain, islice, repeat
from typing import Any

import numpy as np

__all__ = ["value_iteration"]


class _Outcomes:
    """The outcome arrays of one agent's model (``_vi_jit``'s layout, as `_outcomes` makes
    them) and what keeps them in step with it: the model and value-table objects they were made
    from, the table's size and last state, each pair's position and number of outcomes, and the
    positions of the outcomes whose next state had no row, by state."""

    def __init__(self, agent: Any, states: list[Any], row: dict[Any, int]) -> None:
        self.model, self.q = agent.model, agent.q
        self.n_states, self.last = len(states), states[-1] if states else None
        self.index = {key: i for i, key in enumerate(agent.model)}
        *self.arrays, nexts = _outcomes(agent.model, row)
        self.sizes: list[int] = np.diff(self.arrays[2]).tolist()
        self.unresolved: dict[Any, list[int]] = {}
        for j in np.flatnonzero(self.arrays[5] < 0).tolist():
            self.unresolved.setdefault(nexts[j], []).append(j)

    def refresh(self, agent: Any, states: list[Any], row: dict[Any, int], changed: set[Any]) -> bool:
        """Bring the arrays in step with the model and say True, or say False (and change
        nothing) where they cannot be kept: another model or table object, a table that did
        not only grow, a pair that gained an outcome."""
        model, old = agent.model, self.n_states
        if model is not self.model or agent.q is not self.q or len(states) < old:
            return False
        if old and states[old - 1] != self.last:
            return False
        recount = []
        for key in changed:
            i = self.index.get(key)
            if i is None:
                continue  # a new pair: appended below
            if len(model[key]) != self.sizes[i]:
                return False
            recount.append((key, i))
        for s in states[old:]:
            for j in self.unresolved.pop(s, ()):
                self.arrays[5][j] = row[s]
        self.n_states, self.last = len(states), states[-1] if states else None
        if len(model) > len(self.sizes):
            self._append(model, row)
        first, p = self.arrays[2], self.arrays[3]
        for key, i in recount:
            counts = list(model[key].values())
            p[first[i] : first[i + 1]] = np.array(counts, dtype=np.float64) / sum(counts)
        return True

    def _append(self, model: Any, row: dict[Any, int]) -> None:
        """Append the pairs the model gained (its last ones, in its order)."""
        base, start = len(self.sizes), int(self.arrays[2][-1])
        new = dict(islice(model.items(), base, None))
        rows, cols, first, p, r, nxt, t, nexts = _outcomes(new, row)
        for i, key in enumerate(new):
            self.index[key] = base + i
        self.sizes += np.diff(first).tolist()
        for j in np.flatnonzero(nxt < 0).tolist():
            self.unresolved.setdefault(nexts[j], []).append(start + j)
        old = self.arrays
        self.arrays = [
            np.concatenate((old[0], rows)),
            np.concatenate((old[1], cols)),
            np.concatenate((old[2], first[1:] + start)),
            *(np.concatenate((a, b)) for a, b in zip(old[3:], (p, r, nxt, t), strict=True)),
        ]


_KEPT: weakref.WeakKeyDictionary[Any, _Outcomes] = weakref.WeakKeyDictionary()
"""Per agent that keeps its arrays between plans (``keeps_arrays``), the last ones."""


def value_iteration(agent: Any, tol: float) -> int:
    """Solve ``agent``'s model in place (its ``q`` and ``q_greedy`` rows); returns the sweeps."""
    import crmgrasp.kernels._vi_jit as _vi_jit

    n = agent.n_actions
    states = list(agent.q)
    row = {s: i for i, s in enumerate(states)}
    qa = _table(agent.q.values(), len(states), n)
    blank = [agent.unknown] * n  # a row outside the model (never a pair's source) has no greedy values
    qg = _table(map(agent.q_greedy.get, states, repeat(blank)), len(states), n)
    tried = np.zeros(qa.shape, dtype=np.bool_)
    tried.flat[[i * n + a for s, acts in agent.tried.items() if (i := row.get(s)) is not None for a in acts]] = True
    rows, cols, first, p, r, nxt, t = _model_arrays(agent, states, row)
    done = _vi_jit.sweeps(
        qa,
        qg,
        tried,
        rows,
        cols,
        first,
        p,
        r,
        nxt,
        t,
        float(agent.q_act),
        float(agent.unknown),
        float(agent.gamma),
        int(agent.sweeps),
        float(tol),
        np.empty(len(states)),
        np.empty(len(states), dtype=np.bool_),
        np.empty(len(states)),
        np.empty(len(states), dtype=np.bool_),
    )
    greedy = agent.q_greedy
    for (s, a), va, vg in zip(agent.model, qa[rows, cols].tolist(), qg[rows, cols].tolist(), strict=True):
        agent.q[s][a] = va  # the sweeps write only the model's pairs: the rest of each row stands
        if s in greedy:
            greedy[s][a] = vg
    return int(done)


def _model_arrays(agent: Any, states: list[Any], row: dict[Any, int]) -> list[np.ndarray]:
    """The outcome arrays of ``agent``'s model: the kept ones, brought in step, where they can
    be kept (see the module docstring), else made afresh (and kept if the agent keeps its
    arrays)."""
    changed = getattr(agent, "changed", None)
    kept = _KEPT.get(agent)
    if kept is None or changed is None or not kept.refresh(agent, states, row, changed):
        if not getattr(agent, "keeps_arrays", False):
            return list(_outcomes(agent.model, row, nexts=False)[:-1])
        kept = _KEPT[agent] = _Outcomes(agent, states, row)
        agent.changed = set()
    agent.changed.clear()
    return kept.arrays


def _table(rows: Any, size: int, n: int) -> np.ndarray:
    """``size`` rows of ``n`` floats (lists) as a ``(size, n)`` array."""
    return np.fromiter(chain.from_iterable(rows), dtype=np.float64, count=size * n).reshape(size, n)


def _outcomes(model: Any, row: dict[Any, int], nexts: bool = True) -> tuple[Any, ...]:
    """The model's pairs and outcomes as the sweeps' arrays (``_vi_jit``'s layout): each pair's
    row and action, the offsets of its outcomes, and per outcome ``p = count / total`` (the
    pair's total summed in insertion order, as the readable sweeps do), reward, the next
    state's row (-1 outside ``row``) and whether it is terminal; last, the next states
    themselves (None with ``nexts=False``). Built with whole-list operations, not a Python step
    per outcome. Pairs that hold one entry object (``backoff-vi``'s and ``pooled-vi``'s shared
    entries for untried CRMs) have it flattened once and its outcomes gathered for each: the
    same numbers, by the same divisions."""
    sources, tables = list(model), list(model.values())
    ids = list(map(id, tables))
    by_id = dict(zip(ids, tables, strict=True))  # each distinct entry, in order of first use
    pairs = (
        np.array([row[s] for s, _ in sources], dtype=np.int64),
        np.array([a for _, a in sources], dtype=np.int64),
    )
    if len(by_id) == len(tables):
        sizes, p, r, nxt, t, ahead = _flat(tables, row)
        first = np.zeros(len(tables) + 1, dtype=np.int64)
        np.cumsum(sizes, out=first[1:])
        return (*pairs, first, p, r, nxt, t, list(ahead) if nexts else None)
    position = dict(zip(by_id, range(len(by_id))))
    which = np.fromiter(map(position.__getitem__, ids), dtype=np.int64, count=len(ids))
    u_sizes, u_p, u_r, u_nxt, u_t, u_ahead = _flat(list(by_id.values()), row)
    u_first = np.zeros(len(by_id) + 1, dtype=np.int64)
    np.cumsum(u_sizes, out=u_first[1:])
    sizes = u_sizes[which]
    first = np.zeros(len(tables) + 1, dtype=np.int64)
    np.cumsum(sizes, out=first[1:])
    at = np.arange(first[-1], dtype=np.int64) + np.repeat(u_first[:-1][which] - first[:-1], sizes)
    ahead = np.fromiter(u_ahead, dtype=object, count=len(u_ahead))[at].tolist() if nexts else None
    return (*pairs, first, u_p[at], u_r[at], u_nxt[at], u_t[at], ahead)


def _flat(tables: list[Any], row: dict[Any, int]) -> tuple[Any, ...]:
    """Per entry of ``tables`` its number of outcomes; per outcome, in order, ``p``, reward,
    next row (-1 outside ``row``), terminal flag, and the next states (a tuple)."""
    totals = [sum(cs.values()) for cs in tables]
    sizes = np.fromiter(map(len, tables), dtype=np.int64, count=len(tables))
    keys = list(chain.from_iterable(tables))
    counts = np.fromiter(chain.from_iterable(map(dict.values, tables)), dtype=np.float64, count=len(keys))
    rewards, ahead, ends = zip(*keys, strict=True) if keys else ((), (), ())
    p = counts / np.repeat(np.array(totals, dtype=np.float64), sizes)
    return (
        sizes,
        p,
        np.array(rewards, dtype=np.float64),
        np.fromiter(map(row.get, ahead, repeat(-1)), dtype=np.int64, count=len(ahead)),
        np.array(ends, dtype=np.bool_),
        ahead,
    )

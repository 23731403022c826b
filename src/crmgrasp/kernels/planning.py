"""The fast path of model-based planning: [`value_iteration`][] runs
`ModelVI`'s sweeps in compiled code
(`crmgrasp.kernels._vi_jit`) on arrays built from the agent's model and values,
then writes the values back; the agent's readable sweeps are the definition."""

from __future__ import annotations

from itertools import chain, repeat
from typing import Any

import numpy as np

__all__ = ["value_iteration"]


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
    rows, cols, first, p, r, nxt, t = _outcomes(agent.model, row)
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
    )
    greedy = agent.q_greedy
    for (s, a), va, vg in zip(agent.model, qa[rows, cols].tolist(), qg[rows, cols].tolist(), strict=True):
        agent.q[s][a] = va  # the sweeps write only the model's pairs: the rest of each row stands
        if s in greedy:
            greedy[s][a] = vg
    return int(done)


def _table(rows: Any, size: int, n: int) -> np.ndarray:
    """``size`` rows of ``n`` floats (lists) as a ``(size, n)`` array."""
    return np.fromiter(chain.from_iterable(rows), dtype=np.float64, count=size * n).reshape(size, n)


def _outcomes(model: Any, row: dict[Any, int]) -> tuple[np.ndarray, ...]:
    """The model's pairs and outcomes as the sweeps' arrays (``_vi_jit``'s layout): each pair's
    row and action, the offsets of its outcomes, and per outcome ``p = count / total`` (the
    pair's total summed in insertion order, as the readable sweeps do), reward, the next
    state's row (-1 outside ``row``) and whether it is terminal. Built with whole-list
    operations, not a Python step per outcome: this runs after every real step."""
    sources, tables = list(model), list(model.values())
    totals = [sum(cs.values()) for cs in tables]
    sizes = np.fromiter(map(len, tables), dtype=np.int64, count=len(tables))
    first = np.zeros(len(tables) + 1, dtype=np.int64)
    np.cumsum(sizes, out=first[1:])
    keys = list(chain.from_iterable(tables))
    counts = np.fromiter(chain.from_iterable(map(dict.values, tables)), dtype=np.float64, count=len(keys))
    rewards, nexts, ends = zip(*keys, strict=True) if keys else ((), (), ())
    p = counts / np.repeat(np.array(totals, dtype=np.float64), sizes)
    return (
        np.array([row[s] for s, _ in sources], dtype=np.int64),
        np.array([a for _, a in sources], dtype=np.int64),
        first,
        p,
        np.array(rewards, dtype=np.float64),
        np.fromiter(map(row.get, nexts, repeat(-1)), dtype=np.int64, count=len(nexts)),
        np.array(ends, dtype=np.bool_),
    )

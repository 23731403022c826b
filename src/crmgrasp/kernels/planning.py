"""The fast path of model-based planning: [`value_iteration`][] runs
`ModelVI`'s sweeps in compiled code
(`crmgrasp.kernels._vi_jit`) on arrays built from the agent's model and values,
then writes the values back; the agent's readable sweeps are the definition."""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["value_iteration"]


def value_iteration(agent: Any, tol: float) -> int:
    """Solve ``agent``'s model in place (its ``q`` and ``q_greedy`` rows); returns the sweeps."""
    import crmgrasp.kernels._vi_jit as _vi_jit

    n = agent.n_actions
    states = list(agent.q)
    row = {s: i for i, s in enumerate(states)}
    qa = np.array([agent.q[s] for s in states], dtype=np.float64).reshape(-1, n)
    blank = [agent.unknown] * n  # a row outside the model (never a pair's source) has no greedy values
    qg = np.array([agent.q_greedy.get(s, blank) for s in states], dtype=np.float64).reshape(-1, n)
    tried = np.zeros(qa.shape, dtype=np.bool_)
    for s, acts in agent.tried.items():
        i = row.get(s)
        if i is not None:
            tried[i, list(acts)] = True
    pair_row, pair_a, first = [], [], [0]
    out_p: list[float] = []
    out_r: list[float] = []
    out_row: list[int] = []
    out_t: list[bool] = []
    add_p, add_r, add_row, add_t, index = out_p.append, out_r.append, out_row.append, out_t.append, row.get
    for (s, a), cs in agent.model.items():
        total = sum(cs.values())
        pair_row.append(row[s])
        pair_a.append(a)
        for (r, s2, t), c in cs.items():
            add_p(c / total)
            add_r(r)
            add_row(index(s2, -1))
            add_t(t)
        first.append(len(out_p))
    rows, cols = np.array(pair_row, dtype=np.int64), np.array(pair_a, dtype=np.int64)
    done = _vi_jit.sweeps(
        qa,
        qg,
        tried,
        rows,
        cols,
        np.array(first, dtype=np.int64),
        np.array(out_p, dtype=np.float64),
        np.array(out_r, dtype=np.float64),
        np.array(out_row, dtype=np.int64),
        np.array(out_t, dtype=np.bool_),
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

"""Compiled value-iteration sweeps of `crmgrasp.agents.model_based.ModelVI`.

[`sweeps`][] evaluates exactly the expressions of ``ModelVI._sweeps_reference`` in the
same order (Gauss-Seidel, pairs in the model's insertion order, outcomes in each pair's
insertion order, Python's ``max`` keeping the first of equal values), so the values are
equal bit for bit (the tests check whole training runs). No constant of the learner is
written here: ``q_act``, ``unknown``, ``gamma``, the sweep limit and the tolerance are
arguments.

Layout: ``qa``, ``qg`` the ``(S, n)`` acting and greedy values (rows: the model's source
states); ``tried`` the ``(S, n)`` tried mask; pair ``k`` is ``(pair_row[k], pair_a[k])``
with outcomes ``first[k] .. first[k + 1] - 1``: probability, reward, the next state's row
(``-1``: a state that is no pair's source) and whether it is terminal.
"""

from __future__ import annotations

from crmgrasp.kernels._compile import compiled


@compiled
def _v_act(qa, row, q_act):  # type: ignore[no-untyped-def]
    if row < 0:
        return q_act
    best = qa[row, 0]
    for b in range(1, qa.shape[1]):
        if qa[row, b] > best:
            best = qa[row, b]
    return best


@compiled
def _v_greedy(qg, tried, row, unknown):  # type: ignore[no-untyped-def]
    if row < 0:
        return unknown
    found = False
    best = 0.0
    for b in range(qg.shape[1]):
        if tried[row, b] and (not found or qg[row, b] > best):
            best, found = qg[row, b], True
    return best if found else unknown


@compiled
def sweeps(qa, qg, tried, pair_row, pair_a, first, out_p, out_r, out_row, out_t, q_act, unknown, gamma, limit, tol):  # type: ignore[no-untyped-def]
    """Value iteration of both value functions in place until the largest change is below
    ``tol`` or ``limit`` sweeps; returns the sweeps done."""
    for sweep in range(limit):
        change = 0.0
        for k in range(pair_row.shape[0]):
            s, a = pair_row[k], pair_a[k]
            new_a = 0.0
            new_g = 0.0
            for j in range(first[k], first[k + 1]):
                p, r = out_p[j], out_r[j]
                if out_t[j]:
                    new_a += p * r
                    new_g += p * r
                else:
                    new_a += p * (r + gamma * _v_act(qa, out_row[j], q_act))
                    new_g += p * (r + gamma * _v_greedy(qg, tried, out_row[j], unknown))
            d_a, d_g = abs(new_a - qa[s, a]), abs(new_g - qg[s, a])
            if d_a > change:
                change = d_a
            if d_g > change:
                change = d_g
            qa[s, a], qg[s, a] = new_a, new_g
        if change < tol:
            return sweep + 1
    return limit


# compiled sources: a78b1798ed42b00d3c3012670c6ebfb1e10d5b1c1f6c8507d77f9621c39c6947

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
def _row_max(q, tried, row, use_tried):  # type: ignore[no-untyped-def]
    """The largest of row ``row`` of ``q`` (of its tried actions with ``use_tried``; 0.0 and
    False where none is tried), and whether one was found."""
    found = False
    best = 0.0
    for b in range(q.shape[1]):
        if (not use_tried or tried[row, b]) and (not found or q[row, b] > best):
            best, found = q[row, b], True
    return best, found


@compiled
def _values(v, has, q, tried, use_tried, empty):  # type: ignore[no-untyped-def]
    """Write per row its largest value into ``v`` (of its tried actions with ``use_tried``;
    ``empty`` where none is tried) and into ``has`` whether the row has one to keep up to date."""
    for row in range(q.shape[0]):
        best, found = _row_max(q, tried, row, use_tried)
        v[row] = best if found else empty
        has[row] = found


@compiled
def _keep(v, has, q, tried, row, a, old, new, use_tried):  # type: ignore[no-untyped-def]
    """Keep ``v[row]`` the largest of its row after ``q[row, a]`` went from ``old`` to ``new``
    (already written): larger, it is the new largest; smaller and it was the largest, the row
    is searched again. ``max`` is exact, so this is the value a search of the row gives (up to
    the sign of a zero, which ``new += p * (r + gamma * v)`` from 0.0 cannot show)."""
    if not has[row] or (use_tried and not tried[row, a]):
        return
    if new > v[row]:
        v[row] = new
    elif new < old and old == v[row]:
        v[row] = _row_max(q, tried, row, use_tried)[0]


@compiled
def sweeps(  # type: ignore[no-untyped-def]
    qa,
    qg,
    tried,
    pair_row,
    pair_a,
    first,
    out_p,
    out_r,
    out_row,
    out_t,
    q_act,
    unknown,
    gamma,
    limit,
    tol,
    va,
    has_a,
    vg,
    has_g,
):
    """Value iteration of both value functions in place until the largest change is below
    ``tol`` or ``limit`` sweeps; returns the sweeps done. A next state's value (the largest of
    its acting values; of its greedy values over tried actions, ``unknown`` where none is
    tried; ``q_act`` and ``unknown`` for a row of -1) is kept per row as the sweep writes the
    values (`_keep`), not searched for at every outcome: the same numbers. ``va``, ``vg``
    (floats) and ``has_a``, ``has_g`` (booleans), one per row, are the caller's work arrays."""
    _values(va, has_a, qa, tried, False, q_act)
    _values(vg, has_g, qg, tried, True, unknown)
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
                    row = out_row[j]
                    new_a += p * (r + gamma * (va[row] if row >= 0 else q_act))
                    new_g += p * (r + gamma * (vg[row] if row >= 0 else unknown))
            old_a, old_g = qa[s, a], qg[s, a]
            d_a, d_g = abs(new_a - old_a), abs(new_g - old_g)
            if d_a > change:
                change = d_a
            if d_g > change:
                change = d_g
            qa[s, a], qg[s, a] = new_a, new_g
            _keep(va, has_a, qa, tried, s, a, old_a, new_a, False)
            _keep(vg, has_g, qg, tried, s, a, old_g, new_g, True)
        if change < tol:
            return sweep + 1
    return limit


# compiled sources: 558933e4e9fd694b1d93f83c8874066d0040613a9f2d6aa5735db199130e247f

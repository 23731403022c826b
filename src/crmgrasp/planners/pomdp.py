"""Explicit discrete POMDPs: belief update, point-based value iteration, Cassandra files.

A [`POMDP`][] has states ``S``, actions ``A``, observations ``O``, sparse
transitions ``T[a][s, s'] = Pr(s' | s, a)``, observations
``Z[a][s', o] = Pr(o | s', a)``, a start belief ``b0`` and a set of absorbing goal
states. Every action costs 1 in a non-goal state and 0 in a goal state (reward
-1 and 0), over a finite horizon: the value is minus the expected number of CRMs.

Belief update (pomdp_py's notation): ``b'(s') = eta Z(o | s', a) sum_s T(s' | s, a) b(s)``.

[`solve_pbvi`][] runs finite-horizon point-based value iteration (Pineau, Gordon
and Thrun 2003) over a set of reachable beliefs: ``Gamma_t`` holds one alpha vector
per belief point, with its action; ``alpha_{a}(s) = r_a(s) + sum_o argmax_{alpha in
Gamma_{t-1}} b . g_{a,o}^alpha``, ``g_{a,o}^alpha = T_a (Z_a[:, o] * alpha)``.

[`write_cassandra`][] and [`read_cassandra`][] handle Tony Cassandra's
``.pomdp`` format (the subset written here: explicit ``T``, ``O`` entries, ``R``
with wildcards), so external solvers (pomdp-solve, SARSOP) can cross-check.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy import sparse

from crmgrasp._io import as_path, atomic_write_text
from crmgrasp._validation import CrmgraspError, float_array, generator, integer, shown

__all__ = ["POMDP", "PBVIPolicy", "belief_update", "solve_pbvi", "collect_beliefs", "write_cassandra", "read_cassandra"]


@dataclass
class POMDP:
    """A finite POMDP with unit action cost outside the goal states."""

    n_states: int
    n_actions: int
    n_obs: int
    T: list[sparse.csr_matrix]
    Z: np.ndarray  # (A, S, O)
    b0: np.ndarray
    goal: np.ndarray  # bool (S,)
    goal_obs: int | None = None
    """Observation emitted only in goal states (the episode ends there), if any."""
    counts: dict[str, int] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if len(self.T) != self.n_actions or self.Z.shape != (self.n_actions, self.n_states, self.n_obs):
            raise CrmgraspError("POMDP: T and Z must match the numbers of actions, states and observations")
        if self.b0.shape != (self.n_states,) or not np.isclose(self.b0.sum(), 1.0):
            raise CrmgraspError("POMDP: the start belief must be a distribution over the states")

    def reward(self) -> np.ndarray:
        """``r(s)``: -1 outside the goal, 0 in it (the same for every action)."""
        return np.where(self.goal, 0.0, -1.0)


MAX_HORIZON = 1000
"""The longest horizon [`collect_beliefs`][] and [`solve_pbvi`][] take, in steps (a task's
longest episode)."""


def _checked(m: object, who: str) -> POMDP:
    """``m`` if it is a [`POMDP`][]; one-line error otherwise, naming ``who``."""
    if not isinstance(m, POMDP):
        raise CrmgraspError(f"{who} needs a POMDP, got {shown(m)}")
    return m


def belief_update(m: POMDP, b: np.ndarray, a: int, o: int) -> np.ndarray | None:
    """``b'(s') = eta Z(o | s', a) sum_s T(s' | s, a) b(s)``; ``None`` if ``o`` has
    probability 0 under ``b`` and ``a``. Checks its arguments (a one-line error for a belief
    that is no distribution over ``m``'s states, or an action or observation out of range)."""
    m = _checked(m, "belief_update")
    belief = float_array(b, "belief")
    if belief.shape != (m.n_states,) or not np.all(belief >= 0.0) or not np.isclose(belief.sum(), 1.0):
        raise CrmgraspError(f"belief must be a distribution over the {m.n_states} states, got {shown(b)}")
    a, o = (int(v) if isinstance(v, np.integer) else v for v in (a, o))
    return belief_step(m, belief, integer(a, "action", 0, m.n_actions - 1), integer(o, "observation", 0, m.n_obs - 1))


def belief_step(m: POMDP, b: np.ndarray, a: int, o: int) -> np.ndarray | None:
    """[`belief_update`][]'s rule, unchecked: for the planners' own beliefs, actions and observations."""
    pred = m.T[a].T @ b
    post = pred * m.Z[a][:, o]
    total = post.sum()
    return None if total <= 0.0 else post / total


def collect_beliefs(m: POMDP, n: int, horizon: int, rng: np.random.Generator) -> np.ndarray:
    """Up to ``n`` (1 to 100,000) distinct beliefs reachable from ``b0`` under random
    actions, each run at most ``horizon`` steps (0 to [`MAX_HORIZON`][])."""
    m = _checked(m, "collect_beliefs")
    n = integer(n, "number of beliefs", 1, 100_000)
    horizon = integer(horizon, "horizon", 0, MAX_HORIZON)
    rng = generator(rng)
    points = [m.b0]
    seen = {m.b0.round(9).tobytes()}
    for _ in range(50 * n):
        if len(points) >= n:
            break
        b = m.b0
        for _ in range(horizon):
            a = int(rng.integers(m.n_actions))
            pred = m.T[a].T @ b
            p_obs = pred @ m.Z[a]
            if m.goal_obs is not None:
                p_obs[m.goal_obs] = 0.0  # the episode would end: nothing to plan for
            if p_obs.sum() <= 0:
                break
            o = int(rng.choice(m.n_obs, p=p_obs / p_obs.sum()))
            nb = belief_step(m, b, a, o)
            if nb is None or nb[~m.goal].sum() <= 0:
                break
            nb = np.where(m.goal, 0.0, nb)
            nb /= nb.sum()
            key = nb.round(9).tobytes()
            if key not in seen:
                seen.add(key)
                points.append(nb)
            b = nb
    return np.array(points)


@dataclass
class PBVIPolicy:
    """Alpha vectors per steps-to-go ``t`` (``alphas[t]`` of shape ``(k, S)``) with
    their actions."""

    alphas: list[np.ndarray]
    actions: list[np.ndarray]

    def value(self, b: np.ndarray, t: int) -> float:
        """``max_alpha b . alpha`` with ``t`` steps to go (minus expected CRMs)."""
        return float(np.max(self.alphas[t] @ b))

    def action(self, b: np.ndarray, t: int) -> int:
        """The action of the best alpha vector at ``b`` with ``t`` steps to go."""
        return int(self.actions[t][int(np.argmax(self.alphas[t] @ b))])


def solve_pbvi(m: POMDP, beliefs: np.ndarray, horizon: int) -> PBVIPolicy:
    """Finite-horizon point-based value iteration over ``beliefs`` (rows: distributions over
    the states) with ``horizon`` steps to go (0 to [`MAX_HORIZON`][])."""
    m = _checked(m, "solve_pbvi")
    beliefs = _beliefs(m, beliefs)
    horizon = integer(horizon, "horizon", 0, MAX_HORIZON)
    r = m.reward()
    alphas = [np.zeros((1, m.n_states))]
    acts = [np.zeros(1, dtype=np.int64)]
    for _ in range(horizon):
        prev = alphas[-1]  # (k, S)
        best_vals = np.full(len(beliefs), -np.inf)
        new_alpha = np.zeros((len(beliefs), m.n_states))
        new_act = np.zeros(len(beliefs), dtype=np.int64)
        for a in range(m.n_actions):
            alpha_a = np.tile(r, (len(beliefs), 1))
            for o in range(m.n_obs):
                zo = m.Z[a][:, o]
                if not zo.any():
                    continue
                g = (m.T[a] @ (zo[:, None] * prev.T)).T  # (k, S): g_{a,o}^alpha
                pick = np.argmax(beliefs @ g.T, axis=1)  # best alpha per belief
                alpha_a += g[pick]
            vals = np.einsum("ij,ij->i", beliefs, alpha_a)
            better = vals > best_vals
            best_vals[better] = vals[better]
            new_alpha[better] = alpha_a[better]
            new_act[better] = a
        keep = np.unique(new_alpha.round(12), axis=0, return_index=True)[1]
        alphas.append(new_alpha[np.sort(keep)])
        acts.append(new_act[np.sort(keep)])
    return PBVIPolicy(alphas, acts)


def _beliefs(m: POMDP, beliefs: object) -> np.ndarray:
    """``beliefs`` as a float array of rows that are distributions over ``m``'s states."""
    try:
        b = np.array(beliefs, dtype=np.float64)
    except (TypeError, ValueError):
        b = np.empty(0)
    if b.ndim != 2 or b.shape[1] != m.n_states or not len(b) or not np.all(b >= 0.0):  # also NaN
        raise CrmgraspError(f"beliefs must be rows of {m.n_states} non-negative numbers, got {shown(beliefs)}")
    if not np.allclose(b.sum(axis=1), 1.0):
        raise CrmgraspError("beliefs must be distributions: each row sums to 1")
    return b


def write_cassandra(m: POMDP, path: str | os.PathLike[str]) -> Path:
    """Write ``m`` in Cassandra's ``.pomdp`` format (discount 1, values reward)."""
    m = _checked(m, "write_cassandra")
    lines = [
        "# crmgrasp POMDP: reward -1 per CRM outside the goal states",
        "discount: 1.0",
        "values: reward",
        f"states: {m.n_states}",
        f"actions: {m.n_actions}",
        f"observations: {m.n_obs}",
        "start: " + " ".join(repr(float(p)) for p in m.b0),
        "",
    ]
    for a in range(m.n_actions):
        coo = m.T[a].tocoo()
        lines += [
            f"T: {a} : {s} : {s2} {float(p)!r}"
            for s, s2, p in zip(coo.row.tolist(), coo.col.tolist(), coo.data.tolist())
        ]
    for a in range(m.n_actions):
        s2s, os_ = np.nonzero(m.Z[a])
        lines += [f"O: {a} : {s2} : {o} {float(m.Z[a][s2, o])!r}" for s2, o in zip(s2s.tolist(), os_.tolist())]
    lines += [f"R: * : {s} : * : * {'0.0' if m.goal[s] else '-1.0'}" for s in range(m.n_states)]
    return atomic_write_text(path, "\n".join(lines) + "\n")


MAX_ENTRIES = 100_000_000
"""The most numbers a POMDP read from a file may hold in its dense observation array
(``actions x states x observations``; 800 MB)."""

_Row = tuple[int, int, int, float]


def read_cassandra(path: str | os.PathLike[str]) -> POMDP:
    """Read a file written by [`write_cassandra`][] (that subset of the format); a file that
    is not one, or whose sizes, indices or probabilities are out of range, is a one-line
    error naming it."""
    path = as_path(path, "POMDP file")
    try:
        head, t_rows, o_rows, goal_states = _parse(path.read_text(encoding="utf-8"))
        n_s, n_a, n_o = (integer(head[k], k, 1, MAX_ENTRIES) for k in ("states", "actions", "observations"))
        b0 = np.array([float(x) for x in head["start"].split()])
        _check_rows(n_s, n_a, n_o, t_rows, o_rows, goal_states)
    except (KeyError, ValueError, IndexError, OSError, CrmgraspError) as exc:
        raise CrmgraspError(f"cannot read POMDP file {str(path)!r}: {exc}") from None
    trans = []
    for a in range(n_a):
        entries = [(s0, s1, pr) for aa, s0, s1, pr in t_rows if aa == a]
        r, c, d = zip(*entries) if entries else ((), (), ())
        trans.append(sparse.csr_matrix((d, (r, c)), shape=(n_s, n_s)))
    obs = np.zeros((n_a, n_s, n_o))
    for a, s1, o, pr in o_rows:
        obs[a, s1, o] = pr
    goal = np.zeros(n_s, dtype=bool)
    goal[goal_states] = True
    return POMDP(n_s, n_a, n_o, trans, obs, b0, goal)


def _parse(text: str) -> tuple[dict[str, str], list[_Row], list[_Row], list[int]]:
    """The header entries, the ``T`` and ``O`` rows and the goal states of a ``.pomdp`` text."""
    head: dict[str, str] = {}
    t_rows: list[_Row] = []
    o_rows: list[_Row] = []
    goal_states: list[int] = []
    for line in text.splitlines():
        line = line.split("#", 1)[0].strip()
        if not line:
            continue
        key, _, rest = line.partition(":")
        if key in ("T", "O"):
            act, src, tail = (x.strip() for x in rest.split(":"))
            dst, prob = tail.split()
            (t_rows if key == "T" else o_rows).append((int(act), int(src), int(dst), float(prob)))
        elif key == "R":
            parts = [x.strip() for x in rest.split(":")]
            if float(parts[3].split()[-1]) == 0.0:
                goal_states.append(int(parts[1]))
        else:
            head[key.strip()] = rest.strip()
    return head, t_rows, o_rows, goal_states


def _check_rows(n_s: int, n_a: int, n_o: int, t_rows: list[_Row], o_rows: list[_Row], goal: list[int]) -> None:
    """A one-line error unless the sizes fit [`MAX_ENTRIES`][] and every row's indices and
    probability are in range."""
    if n_a * n_s * n_o > MAX_ENTRIES:
        raise CrmgraspError(f"{n_a} actions x {n_s} states x {n_o} observations exceed {MAX_ENTRIES:,} entries")
    for key, rows, n_to in (("T", t_rows, n_s), ("O", o_rows, n_o)):
        for a, s0, s1, pr in rows:
            if not (0 <= a < n_a and 0 <= s0 < n_s and 0 <= s1 < n_to and 0.0 <= pr <= 1.0):
                raise CrmgraspError(f"entry '{key}: {a} : {s0} : {s1} {pr}' is out of range")
    if any(not 0 <= s < n_s for s in goal):
        raise CrmgraspError(f"a reward names a state outside 0..{n_s - 1}")

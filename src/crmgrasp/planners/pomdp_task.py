"""An explicit POMDP of a polygonal task, built by sampling the simulator.

Hidden states are cells of contact configurations: contact a on edge ``i`` at an
arclength fraction in bin ``k`` (bins of at most ``cell`` metres), contact b
likewise, plus one absorbing goal state. Starting from the cells of ``n_starts``
task starts, every reachable cell is expanded: ``samples`` configurations drawn
uniformly inside the cell (feasible ones only) execute each CRM; the counts of
next cells (or the goal) and of discretized observations give ``T`` and ``Z``
(maximum-likelihood estimates; the counts are reported in ``model.counts``). The
goal emits its own observation (index ``n_obs - 1``).

[`POMDPAgent`][] runs the point-based policy in the real simulator by belief
tracking; when an observation has probability 0 under the model, the belief falls
back to the prediction without that observation.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod

import numpy as np
from scipy import sparse

from crmgrasp._validation import CrmgraspError, integer, positive, seed_value
from crmgrasp.model.contacts import Config, Contact, Grip
from crmgrasp.model.geometry import Polygon
from crmgrasp.model.hand import Error, execute_crm
from crmgrasp.model.sensing import observe
from crmgrasp.planners.pomdp import POMDP, PBVIPolicy, belief_step, collect_beliefs, solve_pbvi
from crmgrasp.sim import Percept, run_episode
from crmgrasp.tasks import Task, acceptable, checked_task
from crmgrasp.tasks.core import MAX_SAMPLED

__all__ = ["TaskPOMDP", "build_task_pomdp", "BeliefTracker", "POMDPAgent"]

Cell = tuple[int, int, int, int]


class TaskPOMDP:
    """A sampled POMDP of a task, with its cell index and initial-observation table."""

    def __init__(self, task: Task, model: POMDP, cells: list[Cell], z0: np.ndarray, bins: list[int]) -> None:
        self.task, self.model, self.cells, self.z0, self.bins = task, model, cells, z0, bins
        self.index = {c: i for i, c in enumerate(cells)}

    def cell_of(self, cfg: Config) -> Cell:
        """The cell of a configuration."""
        obj = self.task.obj
        assert isinstance(obj, Polygon)
        return _cell(obj, self.bins, cfg)


def _cell(obj: Polygon, bins: list[int], cfg: Config | Grip) -> Cell:
    out = []
    for c in cfg:
        e = obj.edge_index(c.point)
        ax, ay, ex, ey, l2 = obj.edges[e][:5]
        frac = ((c.x - ax) * ex + (c.y - ay) * ey) / l2
        out += [e, min(bins[e] - 1, max(0, int(frac * bins[e])))]
    return (out[0], out[1], out[2], out[3])


def _sample_in(obj: Polygon, bins: list[int], cell: Cell, rng: np.random.Generator) -> Config:
    contacts = []
    for e, k in ((cell[0], cell[1]), (cell[2], cell[3])):
        ax, ay, ex, ey, _, nx, ny = obj.edges[e]
        frac = (k + rng.uniform(0.05, 0.95)) / bins[e]
        contacts.append(Contact(ax + frac * ex, ay + frac * ey, nx, ny))
    return Config(contacts[0], contacts[1])


def build_task_pomdp(
    task: Task,
    *,
    cell: float = 0.01,
    samples: int = 20,
    n_starts: int = 2000,
    seed: int = 0,
    max_states: int = 20000,
) -> TaskPOMDP:
    """Build the sampled POMDP of ``task`` (noise-free dynamics).

    The hidden states are the cells reached from ``n_starts`` sampled starts (seed ``seed``)
    and, breadth first, from ``samples`` acceptable configurations drawn in each reached cell
    and moved by every CRM; a grasp leads to one absorbing goal state. Transition and
    observation probabilities are the counted frequencies."""
    task = checked_task(task, "build_task_pomdp")
    samples = integer(samples, "samples per cell", 1, 10_000)
    n_starts = integer(n_starts, "n_starts", 1, MAX_SAMPLED)
    seed, max_states = seed_value(seed), integer(max_states, "max_states", 1, 10_000_000)
    obj = task.obj
    if not isinstance(obj, Polygon):
        raise CrmgraspError(f"the sampled POMDP needs a polygonal object, got {type(obj).__name__}")
    if task.model.n_contacts != 2:
        raise CrmgraspError(f"the sampled POMDP grids two contacts; {task.name!r} has {task.model.n_contacts}")
    cell = positive(cell, "cell")
    lengths = [math.sqrt(e[4]) for e in obj.edges]
    per_edge = [length / cell for length in lengths]  # cells along each edge
    if max(per_edge) > max_states:
        raise CrmgraspError(
            f"cell {cell:g} m cuts an edge of {max(lengths):.3g} m into more than {max_states:,} cells, "
            "the most states the POMDP may have; use a larger cell size"
        )
    rng = np.random.default_rng(seed)
    grid = _CellIndex(obj, [max(1, math.ceil(n)) for n in per_edge], max_states)
    start_counts: dict[int, int] = {}
    z0_counts: dict[tuple[int, int], int] = {}
    for _ in range(n_starts):
        cfg = task.sample_start(rng)
        s = grid.state(cfg)
        start_counts[s] = start_counts.get(s, 0) + 1
        o = task.discretizer.index(observe(cfg), Error.NONE)
        z0_counts[(s, o)] = z0_counts.get((s, o), 0) + 1
    t_counts, z_counts, executed = _explore(task, grid, samples, rng)
    n, n_obs = len(grid.cells) + 1, task.discretizer.size + 1  # the last state is the goal, the last observation its
    trans = _transitions(t_counts, len(task.actions), n)
    obs_p = _observations(z_counts, len(task.actions), n, n_obs)
    b0 = np.zeros(n)
    for s, k in start_counts.items():
        b0[s] = k / n_starts
    z0 = np.zeros((n, n_obs))
    for (s, o), k in z0_counts.items():
        z0[s, o] += k
    rows = z0.sum(axis=1, keepdims=True)
    z0 = np.divide(z0, rows, out=np.zeros_like(z0), where=rows > 0)  # Pr(first observation | start cell)
    goal = np.zeros(n, dtype=bool)
    goal[n - 1] = True
    counts = {"states": n, "start_samples": n_starts, "crm_samples": executed, "samples_per_cell": samples}
    model = POMDP(n, len(task.actions), n_obs, trans, obs_p, b0, goal, n_obs - 1, counts)
    return TaskPOMDP(task, model, [*grid.cells, (-1, -1, -1, -1)], z0, grid.bins)


class _CellIndex:
    """The cells met so far, numbered in the order first met (at most ``max_states``)."""

    def __init__(self, obj: Polygon, bins: list[int], max_states: int) -> None:
        self.obj, self.bins, self.max_states = obj, bins, max_states
        self.cells: list[Cell] = []
        self.index: dict[Cell, int] = {}

    def state(self, cfg: Config | Grip) -> int:
        """The number of the cell of configuration ``cfg``, numbering it if it is new."""
        c = _cell(self.obj, self.bins, cfg)
        if c not in self.index:
            if len(self.cells) >= self.max_states:
                raise CrmgraspError(f"more than {self.max_states} reachable cells; use a larger cell size")
            self.index[c] = len(self.cells)
            self.cells.append(c)
        return self.index[c]


def _explore(
    task: Task, grid: _CellIndex, samples: int, rng: np.random.Generator
) -> tuple[dict[tuple[int, int, int], int], dict[tuple[int, int, int], int], int]:
    """Expand every cell met, in order, newly met cells included: up to ``samples`` acceptable
    configurations drawn in it (of ``5 samples`` tries), each moved by every CRM. Returns the
    counts of ``(a, s, s2)`` (``s2 = -1``: a grasp) and of ``(a, s2, o)``, and the CRMs executed."""
    obj, goal_obs = grid.obj, task.discretizer.size
    t_counts: dict[tuple[int, int, int], int] = {}
    z_counts: dict[tuple[int, int, int], int] = {}
    done = executed = 0
    while done < len(grid.cells):
        c = grid.cells[done]
        configs = []
        for _ in range(samples * 5):
            cfg = _sample_in(obj, grid.bins, c, rng)
            if acceptable(obj, task.hand, task.mu_goal, cfg):
                configs.append(cfg)
                if len(configs) == samples:
                    break
        if not configs:  # a cell only touched at its feasible edge: keep it, treat it as the sample seen
            configs = [_sample_in(obj, grid.bins, c, rng)]
        for a, crm in enumerate(task.actions):
            for cfg in configs:
                out = execute_crm(obj, task.hand, cfg, crm, cfg)
                executed += 1
                if task.is_success(out.config):
                    s2, o = -1, goal_obs
                else:
                    s2 = grid.state(out.config)
                    o = task.discretizer.index(observe(out.config), out.error)
                t_counts[(a, done, s2)] = t_counts.get((a, done, s2), 0) + 1
                z_counts[(a, s2, o)] = z_counts.get((a, s2, o), 0) + 1
        done += 1
    return t_counts, z_counts, executed


def _transitions(t_counts: dict[tuple[int, int, int], int], n_actions: int, n: int) -> list[sparse.csr_matrix]:
    """Per action, the ``n x n`` matrix of ``Pr(s2 | s, a)`` (counted frequencies; the goal,
    state ``n - 1``, absorbing)."""
    g = n - 1
    totals: dict[tuple[int, int], int] = {}
    for (a, s, _), k in t_counts.items():
        totals[(a, s)] = totals.get((a, s), 0) + k
    trans = []
    for a in range(n_actions):
        rows, cols, vals = [g], [g], [1.0]
        for (aa, s, s2), k in t_counts.items():
            if aa == a:
                rows.append(s)
                cols.append(g if s2 == -1 else s2)
                vals.append(k / totals[(a, s)])
        trans.append(sparse.csr_matrix((vals, (rows, cols)), shape=(n, n)))
    return trans


def _observations(z_counts: dict[tuple[int, int, int], int], n_actions: int, n: int, n_obs: int) -> np.ndarray:
    """``Pr(o | s2, a)`` of shape ``(n_actions, n, n_obs)``: counted frequencies, the goal's
    own observation at the goal, uniform where a state was never reached by ``a``."""
    g, goal_obs = n - 1, n_obs - 1
    obs_p = np.zeros((n_actions, n, n_obs))
    for (a, s2, o), k in z_counts.items():
        obs_p[a, g if s2 == -1 else s2, o] += k
    for a in range(n_actions):
        obs_p[a, g, :] = 0.0
        obs_p[a, g, goal_obs] = 1.0
        seen = obs_p[a].sum(axis=1, keepdims=True)
        obs_p[a] = np.divide(obs_p[a], seen, out=np.full_like(obs_p[a], 1.0 / n_obs), where=seen > 0)
    return obs_p


class BeliefTracker(ABC):
    """Acts in the simulator on a [`TaskPOMDP`][]'s belief, kept by Bayes' rule: the prior
    conditioned on the first observation, then ``b'(s') = eta Z(o | s', a) sum_s T(s' | s, a) b(s)``
    after each CRM. What chooses the CRM (``act``) is the subclass's: [`POMDPAgent`][]'s PBVI
    policy, or pomdp_py's POUCT on the model ([`crmgrasp.planners.pouct.ModelPOUCTPolicy`][])."""

    def __init__(self, tp: TaskPOMDP) -> None:
        self.tp = tp
        self._b, self._left, self._a = tp.model.b0, tp.task.max_steps, 0

    def _initial(self, o: int) -> np.ndarray | None:
        b = self.tp.model.b0 * self.tp.z0[:, o]
        return None if b.sum() <= 0 else b / b.sum()

    @abstractmethod
    def act(self) -> int:
        """The CRM to take from the current belief (``self._b``, with ``self._left`` CRMs left),
        recorded in ``self._a`` for the belief update: the subclass's."""

    # -- the Policy interface (crmgrasp.sim.run_episode)
    def begin(self, first: Percept) -> None:
        """Belief: the prior conditioned on the first observation."""
        b = self._initial(first.obs_index)
        self._b = self.tp.model.b0 if b is None else b
        self._left = self.tp.task.max_steps

    def tell(self, percept: Percept) -> None:
        """Bayes update of the belief on the observation (the prediction alone where
        the model gives it probability 0), conditioned on no grasp yet."""
        if percept.terminated:
            return
        m, b, a = self.tp.model, self._b, self._a
        nb = belief_step(m, b, a, percept.obs_index)
        if nb is None or nb[~m.goal].sum() <= 0:
            nb = m.T[a].T @ b
        nb = np.where(m.goal, 0.0, nb)
        self._b = nb / nb.sum() if nb.sum() > 0 else m.b0
        self._left -= 1

    def run(self, config: Config) -> tuple[int, bool]:
        """Execute from ``config`` (noise-free; [`crmgrasp.sim.run_episode`][]); return
        (CRMs, success)."""
        ep = run_episode(self.tp.task, self, np.random.default_rng(0), start=config)
        return ep.steps, ep.success


class POMDPAgent(BeliefTracker):
    """Executes a PBVI policy of a [`TaskPOMDP`][] in the simulator."""

    def __init__(self, tp: TaskPOMDP, n_beliefs: int = 300, seed: int = 0) -> None:
        super().__init__(tp)
        h = tp.task.max_steps
        pts = collect_beliefs(tp.model, n_beliefs, h, np.random.default_rng(seed))
        extra = [self._initial(o) for o in range(tp.model.n_obs)]
        pts = np.vstack([pts] + [b[None] for b in extra if b is not None])
        self.policy: PBVIPolicy = solve_pbvi(tp.model, pts, h)

    def model_value(self) -> float:
        """Expected CRMs predicted by the model: ``sum_o Pr(o_0) V(b0 | o_0)``."""
        h = self.tp.task.max_steps
        total = 0.0
        for o in range(self.tp.model.n_obs):
            p = float(self.tp.model.b0 @ self.tp.z0[:, o])
            b = self._initial(o)
            if p > 0 and b is not None:
                total -= p * self.policy.value(b, h)
        return total

    # -- the Policy interface (crmgrasp.sim.run_episode)
    def act(self) -> int:
        """The PBVI policy's action for the belief and the CRMs left."""
        self._a = self.policy.action(self._b, self._left)
        return self._a

"""Four ways to get more from the families preset's episodes at decision time, measured (none kept).

The families preset (`backoff-vi`, k = 2, ``skip_errored``, ``mean_after`` = 2000) learns for
EPISODES episodes per seed; its training episodes are recorded (a stepper that wraps the task's
kernel and keeps every reading: the same episodes, bit for bit). Each variant then makes a
greedy policy from the same agent and runs on the same W worlds as the preset's own greedy
policy (``preset``), against the belief-space optimum over ``--pool`` worlds (the W first), as
``benchmarks/family_learning.py`` scores (graspable gap, graspable worlds never grasped):

* ``loop-break``: never take again a CRM already taken in the same two-CRM history of the
  episode (the greedy policy is deterministic, so a history met twice with the contacts where
  they were repeats a cycle);
* ``lcb``: plan the greedy policy with each long pair's reward lowered by
  ``LCB / sqrt(n + 1)`` (``n`` its own outcomes): prefer CRMs the history has seen work;
* ``trie``: a policy search on the empirical tree of the recorded episodes. Each node is a whole
  history; a two-CRM history's CRM is changed where that raises the discounted value of the
  tree's episodes, a node's value being ``(sum_o n_o (r_o + gamma V(child_o)) + beta Q(h, a)) /
  (n + beta)``, with ``Q`` the agent's greedy model value (its value where the tree has no
  data). Unlike the k = 2 model, the tree keeps which worlds lie behind a history under the
  policy searched (its observation frequencies do not depend on the policy);
* ``reweight``: re-plan the greedy policy on long counts where a transition counts 1 if every
  earlier CRM of its episode is the greedy policy's choice (the worlds behind it are then the
  greedy policy's own) and ``LAM`` otherwise.

Measured (docs/results.md, "Tried and not kept at decision time"). Usage: ``python
benchmarks/greedy_variants.py [--task u-handle] [--seeds 10] [--first 0] [--episodes 3000]
[--worlds 300] [--pool 3200] [--lcb 1.0] [--beta 1.0] [--lam 0.3]``. Prints one JSON object;
progress on stderr.
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
import sys
import types
from typing import Any

import numpy as np

from crmgrasp.agents.base import LearnerPolicy
from crmgrasp.agents.training import encoder_for, train_trials
from crmgrasp.experiments._episodes import episode_records
from crmgrasp.kernels import kernel_for
from crmgrasp.model.hand import Error
from crmgrasp.planners.references import BeliefPolicy, graspable_starts, sample_starts
from crmgrasp.tasks import make_task

PRESET = {"skip_errored": True, "mean_after": 2000}
VARIANTS = ("preset", "loop-break", "lcb", "trie", "reweight")


class Recording:
    """The task's kernel as a stepper that records each episode: its first observation and per
    CRM ``(action, observation, erred, reward, grasped: terminated)``."""

    def __init__(self, task: Any) -> None:
        self.kernel, self.episodes = kernel_for(task), []

    def sample_start(self, rng: np.random.Generator) -> Any:
        return self.kernel.sample_start(rng)

    def use(self, instance: Any) -> None:
        self.kernel.use(instance)

    def begin(self, config: Any, rng: np.random.Generator) -> Any:
        out = self.kernel.begin(config, rng)
        self.episodes.append((out.obs_index, []))
        return out

    def step_one(self, state: Any, action: Any, rng: np.random.Generator) -> Any:
        out = self.kernel.step_one(state, action, rng)
        self.episodes[-1][1].append((int(action), out.obs_index, out.error != Error.NONE, out.reward, out.terminated))
        return out


class LoopBreak(LearnerPolicy):
    """The greedy policy, banning in each two-CRM history the CRMs it took there this episode."""

    def begin(self, first: Any) -> None:
        self._taken: dict[int, set[int]] = {}
        super().begin(first)

    def _choose(self, s: int) -> int:
        taken = self._taken.setdefault(s, set())
        banned = self._banned | taken
        a = self._pick(s, self.rng, banned) if banned else self._pick(s, self.rng)  # type: ignore[call-arg]
        taken.add(a)
        return a


class Overridden(LearnerPolicy):
    """The greedy policy with the trie search's CRMs where it changed them (``choice``)."""

    def __init__(self, agent: Any, encoder: Any, rng: np.random.Generator, choice: Any) -> None:
        super().__init__(agent, encoder, rng, learn=False)
        self.choice = choice

    def _choose(self, s: int) -> int:
        a = self.choice(s, self._banned)
        return super()._choose(s) if a is None else a


class TreeSearch:
    """Coordinate ascent over two-CRM histories (representatives of the mirror quotient) on the
    tree of recorded episodes; see the module docstring."""

    def __init__(self, agent: Any, task: Any, encoder: Any, episodes: list, beta: float) -> None:
        self.agent, self.inner, self.enc, self.beta = agent, agent.inner, encoder, beta
        self.amap, self.n, self.horizon = list(task.symmetry.actions), agent.n_actions, task.max_steps
        self.judge, self.gamma = self.inner._planned(), self.inner.gamma
        self.roots: dict[int, int] = {}
        self.kids: dict[tuple, dict[int, dict[int, list]]] = {}
        for first, steps in episodes:
            self.roots[first] = self.roots.get(first, 0) + 1
            h: tuple = (first,)
            for a, o, err, r, grasped in steps:
                cell = self.kids.setdefault(h, {}).setdefault(a, {}).setdefault(o, [0, r, grasped, err])
                cell[0] += 1
                h += (a, o)
        self.changed: dict[int, int] = {}
        self._rows: dict[int, list[float]] = {}

    def model_row(self, s: int) -> list[float]:
        """The agent's greedy values of history ``s``, per CRM in ``s``'s own frame."""
        row = self._rows.get(s)
        if row is None:
            c, flip = self.agent.representative(s)
            node, flip2 = self.inner._node(c, self.judge.tried)
            q = self.judge.q_greedy[node] if node is not None else [self.judge.unknown] * self.n
            row = self._rows[s] = [q[self._map(self._map(a, flip), flip2)] for a in range(self.n)]
        return row

    def _map(self, a: int, flip: bool) -> int:
        return self.amap[a] if flip else a

    def choice(self, s: int, banned: Any) -> int | None:
        """The changed CRM of ``s`` (None where unchanged or banned)."""
        c, flip = self.agent.representative(s)
        a = self.changed.get(c)
        return None if a is None or self._map(a, flip) in banned else self._map(a, flip)

    def act(self, s: int, banned: Any) -> int:
        a = self.choice(s, banned)
        if a is not None:
            return a
        row = self.model_row(s)
        return max((b for b in range(self.n) if b not in banned), key=row.__getitem__, default=0)

    def value(self, h: tuple, win: tuple, banned: frozenset, depth: int) -> float:
        if depth >= self.horizon:
            return 0.0
        s = self.enc.encode(win)
        a = self.act(s, banned)
        q = self.model_row(s)[a]
        cells = self.kids.get(h, {}).get(a)
        if not cells:
            return q
        total, n = self.beta * q, self.beta
        for o, (count, r, grasped, err) in cells.items():
            n += count
            if grasped:
                total += count * r
                continue
            after = banned | {a} if err else frozenset()
            total += count * (r + self.gamma * self.value((*h, a, o), self.enc.push(win, a, o), after, depth + 1))
        return total / n

    def objective(self) -> float:
        """The tree's value of the current policy: its episodes' first observations weighted by
        their counts (the discounted return the search raises)."""
        total = sum(self.roots.values())
        return sum(c / total * self.value((f,), self.enc.start(f), frozenset(), 0) for f, c in self.roots.items())

    def _reached(self) -> dict[int, list]:
        """Per representative, the tree's topmost nodes of its histories the policy reaches, with
        their discounted reach weights."""
        out: dict[int, list] = {}
        total = sum(self.roots.values())
        stack = [((f,), self.enc.start(f), frozenset(), 0, c / total, frozenset()) for f, c in self.roots.items()]
        while stack:
            h, win, banned, depth, mass, above = stack.pop()
            if depth >= self.horizon:
                continue
            s = self.enc.encode(win)
            c, _ = self.agent.representative(s)
            if c not in above:
                out.setdefault(c, []).append((mass, h, win, banned, depth))
            a = self.act(s, banned)
            cells = self.kids.get(h, {}).get(a) or {}
            n = self.beta + sum(v[0] for v in cells.values())
            for o, (count, _, grasped, err) in cells.items():
                if not grasped:
                    after = banned | {a} if err else frozenset()
                    nxt = ((*h, a, o), self.enc.push(win, a, o), after, depth + 1, mass * self.gamma * count / n)
                    stack.append((*nxt, above | {c}))
        return out

    def search(self, passes: int = 3) -> int:
        """Coordinate ascent, most reached histories first; returns the changes kept."""
        kept = 0
        for _ in range(passes):
            reached = self._reached()
            moved = False
            for c in sorted(reached, key=lambda c: -sum(x[0] for x in reached[c])):
                nodes = self._reached().get(c) if moved else reached[c]
                if not nodes:
                    continue
                before = self.changed.get(c)
                best, best_a = sum(m * self.value(*x) for m, *x in nodes), None
                tried = {
                    self._map(a, self.agent.representative(self.enc.encode(win))[1])
                    for _, h, win, _, _ in nodes
                    for a in self.kids.get(h, {})
                }
                for a in tried - {before}:
                    self.changed[c] = a
                    v = sum(m * self.value(*x) for m, *x in nodes)
                    if v > best + 1e-9:
                        best, best_a = v, a
                if best_a is None and before is None:
                    self.changed.pop(c, None)
                elif best_a is None:
                    self.changed[c] = before
                else:
                    self.changed[c], moved, kept = best_a, True, kept + 1
            if not moved:
                break
        return kept


def reweighted(agent: Any, encoder: Any, episodes: list, lam: float) -> None:
    """Replace the long counts by the reweighted ones of the module docstring (``reweight``)."""
    rng, inner, amap, counts = np.random.default_rng(0), agent.inner, agent._amap, {}
    for first, steps in episodes:
        hist = encoder.start(first)
        s, agree, banned = encoder.encode(hist), True, frozenset()
        for a, o, err, r, grasped in steps:
            w = 1.0 if agree else lam
            agree = agree and (agent.greedy(s, rng, banned) if banned else agent.greedy(s, rng)) == a
            hist = encoder.push(hist, a, o)
            s2 = encoder.encode(hist)
            c, flip = agent.representative(s)
            pairs = [(amap[a] if flip else a, agent.representative(s2)[0])]
            if agent._tie_start and agent._is_mirror_start(c) and amap[pairs[0][0]] != pairs[0][0]:
                pairs.append((amap[pairs[0][0]], agent.representative(agent.mirror(s2))[0]))
            for b, c2 in pairs:
                row = counts.setdefault((c, b), {})
                row[(r, c2, grasped)] = row.get((r, c2, grasped), 0.0) + w
            banned, s = (banned | {a} if err else frozenset()), s2
    inner.counts, inner._solved = counts, False


def lowered(agent: Any, lcb: float) -> None:
    """Plan the greedy model with each long pair's rewards lowered by ``lcb / sqrt(n + 1)``."""
    inner = agent.inner
    plain = type(inner)._long_entries

    def entries(self: Any, longs: list[int], rng: Any) -> list:
        out = plain(self, longs, rng)
        if rng is not None:
            return out
        cut = [lcb / math.sqrt(sum((self.counts.get((node[1], b)) or {}).values()) + 1.0) for node, b, _ in out]
        return [(node, b, {(r - d, nd, t): p for (r, nd, t), p in e.items()}) for (node, b, e), d in zip(out, cut)]

    inner._long_entries, inner._solved = types.MethodType(entries, inner), False


def _score(task: Any, make: Any, worlds: list, graspable: np.ndarray, optimum: np.ndarray) -> tuple[float, int]:
    """The graspable gap to the optimum and the graspable worlds never grasped of ``make()``'s policy."""
    records = episode_records(task, make, worlds, 0)
    steps = np.array([len(r.actions) for r in records], dtype=float)
    won = np.array([r.success for r in records])
    return round(float(steps[graspable].mean() / optimum[graspable].mean() - 1.0), 4), int((graspable & ~won).sum())


def one_seed(task: Any, seed: int, args: argparse.Namespace, worlds: list, graspable: Any, optimum: Any) -> dict:
    """Every variant's score for one seed's agent (module docstring)."""
    enc, made = encoder_for(task, 2), []

    def stepper(t: Any) -> Recording:
        made.append(Recording(t))
        return made[-1]

    params = {"symmetric": True, **PRESET}
    res = train_trials(task, "backoff-vi", trials=1, episodes=args.episodes, seed=seed, k=2, eval_episodes=0,
                       params=params, stepper=stepper)  # fmt: skip
    agent, episodes = res.agents[0], made[-1].episodes

    def policy(kind: type = LearnerPolicy, **extra: Any) -> Any:
        """A maker of ``kind``'s greedy policy, each with a fresh tie-breaking generator (as
        ``greedy_records`` makes them)."""
        return lambda: kind(agent, enc, np.random.default_rng([seed, 0]), **(extra or {"learn": False}))

    out = {"preset": _score(task, policy(), worlds, graspable, optimum)}
    out["loop-break"] = _score(task, policy(LoopBreak), worlds, graspable, optimum)
    tree = TreeSearch(agent, task, enc, episodes, args.beta)
    before = tree.objective()
    changes = tree.search()
    out["trie"] = _score(task, policy(Overridden, choice=tree.choice), worlds, graspable, optimum)
    out["trie_tree_value"] = (round(before, 4), round(tree.objective(), 4), changes)
    counts = agent.inner.counts
    reweighted(agent, enc, episodes, args.lam)
    out["reweight"] = _score(task, policy(), worlds, graspable, optimum)
    agent.inner.counts, agent.inner._solved = counts, False
    lowered(agent, args.lcb)
    out["lcb"] = _score(task, policy(), worlds, graspable, optimum)
    return out


def main(argv: list[str] | None = None) -> dict:
    """Parse ``argv``, run every seed, print and return the summary (module docstring)."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--task", default="u-handle")
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--first", type=int, default=0)
    ap.add_argument("--episodes", type=int, default=3000)
    ap.add_argument("--worlds", type=int, default=300)
    ap.add_argument("--pool", type=int, default=3200)
    ap.add_argument("--lcb", type=float, default=1.0)
    ap.add_argument("--beta", type=float, default=1.0)
    ap.add_argument("--lam", type=float, default=0.3)
    args = ap.parse_args(argv)
    task = make_task(args.task)
    if task.symmetry is None:
        raise SystemExit(f"{args.task}: this benchmark runs the mirror quotient; the task declares no mirror symmetry")
    planned = sample_starts(task, max(args.pool, args.worlds), 10_000)
    worlds = planned[: args.worlds]
    graspable = graspable_starts(task, worlds)
    optimum = np.array([len(r.actions) for r in episode_records(task, _belief(task, planned), worlds, 0)], dtype=float)
    rows: dict[str, list] = {v: [] for v in VARIANTS}
    for seed in range(args.first, args.first + args.seeds):
        for v, score in one_seed(task, seed, args, worlds, graspable, optimum).items():
            rows.setdefault(v, []).append(score)
        print(f"{args.task} seed {seed}: " + ", ".join(f"{v} {rows[v][-1]}" for v in rows), file=sys.stderr)
    out: dict = {"task": args.task, "episodes": args.episodes, "seeds": [args.first, args.first + args.seeds - 1]}
    out.update(worlds=args.worlds, pool=len(planned), lcb=args.lcb, beta=args.beta, lam=args.lam)
    for v in VARIANTS:
        gaps = [g for g, _ in rows[v]]
        out[v] = {
            "gap_graspable": gaps,
            "median_gap_graspable": statistics.median(gaps),
            "seeds_within_10pct": sum(g <= 0.10 for g in gaps),
            "fails_graspable": [f for _, f in rows[v]],
        }
    out["trie_tree_value"] = rows["trie_tree_value"]  # per seed: before, after the search, CRMs changed
    print(json.dumps(out, indent=1))
    return out


def _belief(task: Any, planned: list) -> Any:
    """One belief-space optimal policy over ``planned`` for every world (its memo shared)."""
    planner = BeliefPolicy(task, planned)
    return lambda: planner


if __name__ == "__main__":
    main()

"""What memory a policy needs: the belief-space optimal policy projected onto memory features.

A learner on k-order histories can at best act as a table from its memory to CRMs. Which
memory would let such a table act like the belief-space optimum, and how well does the table
then do on worlds it was not made from? This script answers it for one task without any
learner in the way:

1. W worlds are sampled (``sample_starts(task, W, 10_000)``) and the belief-space optimal
   policy over them ([`BeliefPolicy`][crmgrasp.planners.references.BeliefPolicy]) runs on each
   (noise-free). Its mean CRMs per episode is the optimum over the W worlds.
2. At every decision it took, each memory feature of [`FEATURES`][] is computed from the
   episode so far (CRMs, discretized observations, errors): for instance ``k2``, the last two
   CRMs and observations (what ``backoff-vi`` with k = 2 sees), or ``full``, the whole history.
3. Per feature, the *projected table* takes in each feature value the CRM the optimum took
   there most often (ties: the lowest index). ``agree`` is the share of the optimum's
   decisions that agree with its feature value's CRM: 1 means the optimum is a function of
   that memory on these worlds.
4. The table runs (noise-free, through the one episode loop) on the W worlds and on F fresh
   worlds (``sample_starts(task, F, 20_000)``). A feature value the table does not hold acts
   as the ``k1`` table, then as the ``k0`` table (the current observation alone), then CRM 0.

The table on the W worlds is at least the optimum over them (``full`` equals it); on fresh
worlds every table is a policy that does not know the world, so its cost there is an upper
bound on the family's own optimum (in expectation), as the planner of
``benchmarks/family_learning.py --planner`` is.

5. With ``--learn E`` (repeatable), the families preset (``crmgrasp learn --preset families``:
   ``backoff-vi``, k = 2, ``skip_errored``, acting on the mean for its last third of the
   episodes, ``mean_after = 2E / 3``, which is the preset's 2,000 at E = 3,000) learns E episodes
   from scratch in each of ``--seeds`` seeds, and its greedy policy runs on the same W and F
   worlds: the learner against the table it could at best become, on identical worlds.

6. With ``--teach E`` (repeatable), the same learner is *taught*: it acts on nothing and
   learns from E episodes in which a teacher chooses each CRM, on E worlds of its own per seed
   (``sample_starts(task, E, 30_000 + seed)``). The teacher is the belief-space optimal policy
   over those worlds, replaced by a uniformly drawn CRM with probability ``--epsilon`` (0.2),
   all draws from ``default_rng(seed)``. Its greedy policy then runs on the same W and F worlds.
   This separates where the learner's data come from (its own acting, or the optimum's
   behaviour with exploration) from what it makes of them.

Usage: ``python benchmarks/memory_projection.py [--task triangles-3f] [--worlds 2000] [--fresh 1000]
[--learn 3000 --learn 20000 --seeds 1] [--teach 3000 --epsilon 0.2]``. Prints one JSON object;
progress on stderr.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections import Counter
from collections.abc import Callable
from typing import Any

import numpy as np

from crmgrasp.kernels import kernel_for
from crmgrasp.model.hand import Error
from crmgrasp.planners.references import BeliefPolicy, sample_starts
from crmgrasp.sim import Percept, run_episode
from crmgrasp.tasks import make_task


class Memory:
    """The episode so far: observations ``o_0 .. o_t``, CRMs ``a_1 .. a_t`` and the CRMs
    that erred."""

    def __init__(self, first: int) -> None:
        self.obs: list[int] = [first]
        self.acts: list[int] = []
        self.erred: list[int] = []

    def push(self, action: int, obs: int, error: bool) -> None:
        self.obs.append(obs)
        self.acts.append(action)
        if error:
            self.erred.append(action)

    def last(self, k: int) -> tuple[int, ...]:
        """``(o_t, a_t, o_{t-1}, ..., a_{t-k+1})``, shorter near the start."""
        out = [self.obs[-1]]
        for i in range(1, k + 1):
            if i > len(self.acts):
                break
            out += [self.acts[-i], self.obs[-i - 1]] if i < k else [self.acts[-i]]
        return tuple(out)


FEATURES: dict[str, Callable[[Memory], Any]] = {
    "k0": lambda m: m.last(0),
    "k1": lambda m: m.last(1),
    "k2": lambda m: m.last(2),
    "k3": lambda m: m.last(3),
    "full": lambda m: (tuple(m.obs), tuple(m.acts)),
    "k1+errored": lambda m: (m.last(1), frozenset(m.erred)),
    "k2+errored": lambda m: (m.last(2), frozenset(m.erred)),
    "k1+first": lambda m: (m.last(1), m.obs[0]),
    "k1+step": lambda m: (m.last(1), len(m.acts)),
    "k1+previous_crm": lambda m: (m.last(1), tuple(m.acts[-2:-1])),
    "k1+previous_obs": lambda m: (m.last(1), tuple(m.obs[-2:-1])),
}
"""Memory features of the episode so far, by name: ``kN`` the last N CRMs and observations
(``k0`` the current observation alone); ``full`` the whole history; ``+errored`` with the set of
CRMs that erred in the episode; ``+first`` with the first observation; ``+step`` with the number
of CRMs so far; ``+previous_crm`` and ``+previous_obs`` with one half of what ``k2`` adds to ``k1``
(the CRM before the last, or the observation before the current one)."""


class _Tracked:
    """What both policies below keep of an episode: its memory and its cost (CRMs, plus
    ``error_cost`` per errored CRM); subclasses set ``self.a`` in ``act``."""

    def __init__(self, error_cost: float) -> None:
        self.error_cost, self.cost, self.mem, self.a = error_cost, 0.0, Memory(0), 0

    def begin(self, first: Percept) -> None:
        self.cost, self.mem = 0.0, Memory(first.obs_index)

    def tell(self, percept: Percept) -> None:
        error = percept.error is not Error.NONE
        self.cost += 1.0 + self.error_cost * error
        self.mem.push(self.a, percept.obs_index, error)


class Recorder(_Tracked):
    """A policy that acts as ``policy`` and counts, per feature value, the CRMs it took there."""

    def __init__(self, policy: BeliefPolicy, error_cost: float) -> None:
        super().__init__(error_cost)
        self.policy = policy
        self.votes: dict[str, dict[Any, Counter[int]]] = {name: {} for name in FEATURES}

    def begin(self, first: Percept) -> None:
        self.policy.begin(first)
        super().begin(first)

    def act(self) -> int:
        self.a = self.policy.act()
        for name, f in FEATURES.items():
            self.votes[name].setdefault(f(self.mem), Counter())[self.a] += 1
        return self.a

    def tell(self, percept: Percept) -> None:
        self.policy.tell(percept)
        super().tell(percept)


class Projected(_Tracked):
    """A feature's projected table as a policy: a value it does not hold acts as the ``k1``
    table, then the ``k0`` table, then CRM 0 (module docstring)."""

    def __init__(self, tables: dict[str, dict[Any, int]], name: str, error_cost: float) -> None:
        super().__init__(error_cost)
        self.chain = [(FEATURES[n], tables[n]) for n in (name, "k1", "k0")]

    def act(self) -> int:
        self.a = next((t[f(self.mem)] for f, t in self.chain if f(self.mem) in t), 0)
        return self.a


def _run(task: Any, policy: Any, worlds: list) -> tuple[float, float]:
    """Mean cost and success of ``policy`` from each world (noise-free)."""
    kernel, rng = kernel_for(task), np.random.default_rng(0)
    costs, won = [], []
    for w in worlds:
        ep = run_episode(task, policy, rng, start=w, kernel=kernel)
        costs.append(policy.cost)
        won.append(ep.success)
    return float(np.mean(costs)), float(np.mean(won))


def learned(task: Any, episodes: int, seeds: int, worlds: list, fresh: list) -> dict:
    """Step 5 of the module docstring: per seed, the preset's greedy cost and success on the W
    and F worlds after ``episodes`` episodes, and the training time."""
    from crmgrasp.experiments._episodes import train_preset

    t0 = time.perf_counter()
    agents, k = train_preset(task, "families", seeds, episodes, 0, mean_after=2 * episodes // 3)
    out: dict = {"train_seconds": round(time.perf_counter() - t0, 1)}
    out.update(_greedy(task, agents, k, worlds, fresh))
    return out


class Taught:
    """A policy whose CRMs are a teacher's (the optimum, or with probability ``epsilon`` a
    uniform draw), teaching ``agent`` every transition on its k-order histories."""

    def __init__(self, agent: Any, encoder: Any, teacher: BeliefPolicy, epsilon: float, rng: np.random.Generator):
        self.agent, self.encoder, self.teacher, self.epsilon, self.rng = agent, encoder, teacher, epsilon, rng
        self.n_actions = len(teacher.task.actions)
        self.hist: tuple[int, ...] = ()
        self.s = self.a = 0

    def _choose(self, steps_left: bool) -> int:
        """The next CRM; after the last step (the teacher has no plan there) only a placeholder
        for the update's ``a2``, which the model-based learner does not read."""
        a = self.teacher.act() if steps_left else 0
        return int(self.rng.integers(self.n_actions)) if self.rng.random() < self.epsilon else a

    def begin(self, first: Percept) -> None:
        self.teacher.begin(first)
        self.hist = self.encoder.start(first.obs_index)
        self.s = self.encoder.encode(self.hist)
        self.agent.begin_episode()
        self.a = self._choose(True)

    def act(self) -> int:
        return self.a

    def tell(self, percept: Percept) -> None:
        self.teacher.tell(percept, self.a)
        self.hist = self.encoder.push(self.hist, self.a, percept.obs_index)
        s2 = self.encoder.encode(self.hist)
        if percept.terminated:
            self.agent.update(self.s, self.a, percept.reward, s2, None, True, self.rng)
            return
        a2 = self._choose(not percept.truncated)
        self.agent.update(self.s, self.a, percept.reward, s2, a2, False, self.rng)
        self.s, self.a = s2, a2


def taught(task: Any, episodes: int, seeds: int, epsilon: float, worlds: list, fresh: list) -> dict:
    """Step 6 of the module docstring: per seed, the greedy cost and success on the W and F worlds
    of the families preset's learner taught by the optimum over E worlds of its own."""
    k, make = families_learner(task)
    kernel, agents, t0 = kernel_for(task), [], time.perf_counter()
    for seed in range(seeds):
        agent, encoder = make()
        own = sample_starts(task, episodes, 30_000 + seed)
        rng = np.random.default_rng(seed)
        policy = Taught(agent, encoder, BeliefPolicy(task, own), epsilon, rng)
        for w in own:
            run_episode(task, policy, rng, start=w, kernel=kernel)
        agents.append(agent)
    out: dict = {"epsilon": epsilon, "train_seconds": round(time.perf_counter() - t0, 1)}
    out.update(_greedy(task, agents, k, worlds, fresh))
    return out


def families_learner(task: Any) -> tuple[int, Callable[[], tuple[Any, Any]]]:
    """The families preset's history order, and a maker of a fresh learner of it (its
    agent, on the mirror quotient where the task declares one, and its history encoder)."""
    from crmgrasp.agents.presets import apply_preset
    from crmgrasp.agents.training import build_agent, encoder_for

    choice = apply_preset("families", task)
    encoder = encoder_for(task, choice.k)
    params = {"symmetric": choice.symmetric, **dict(choice.params)}
    return choice.k, lambda: (build_agent(task, encoder, choice.agent, params), encoder)


def _greedy(task: Any, agents: list, k: int, worlds: list, fresh: list) -> dict:
    """Per agent, its greedy policy's mean cost and success on ``worlds`` and on ``fresh``."""
    from crmgrasp.experiments._episodes import greedy_records

    out: dict = {}
    for name, starts in (("worlds", worlds), ("fresh", fresh)):
        recs = greedy_records(task, agents, starts, 0, k=k)
        costs = [float(np.mean([len(r.actions) + task.error_cost * sum(r.errors) for r in t])) for t in recs]
        out[f"cost_on_{name}"] = [round(c, 4) for c in costs]
        out[f"success_on_{name}"] = [round(float(np.mean([r.success for r in t])), 4) for t in recs]
    return out


def main(
    task_name: str = "triangles-3f",
    n_worlds: int = 2000,
    n_fresh: int = 1000,
    learn: tuple[int, ...] = (),
    seeds: int = 1,
    teach: tuple[int, ...] = (),
    epsilon: float = 0.2,
) -> dict:
    """The projection of every feature, and the learner at each budget of ``learn`` (module
    docstring)."""
    task = make_task(task_name)
    t0 = time.perf_counter()
    worlds, fresh = sample_starts(task, n_worlds, 10_000), sample_starts(task, n_fresh, 20_000)
    rec = Recorder(BeliefPolicy(task, worlds), task.error_cost)
    optimum, opt_success = _run(task, rec, worlds)
    print(
        f"{task_name}: optimum over {n_worlds} worlds {optimum:.3f} ({time.perf_counter() - t0:.0f} s)", file=sys.stderr
    )
    tables = {
        name: {f: min(c.items(), key=lambda kv: (-kv[1], kv[0]))[0] for f, c in votes.items()}
        for name, votes in rec.votes.items()
    }
    out: dict = {"task": task_name, "worlds": n_worlds, "fresh": n_fresh, "optimum": round(optimum, 4)}
    out["optimum_success"] = round(opt_success, 4)
    for name, votes in rec.votes.items():
        decisions = sum(sum(c.values()) for c in votes.values())
        agree = sum(max(c.values()) for c in votes.values())
        policy = Projected(tables, name, task.error_cost)
        own, _ = _run(task, policy, worlds)
        new, success = _run(task, policy, fresh)
        out[name] = {
            "values": len(votes),
            "agree": round(agree / decisions, 4),
            "cost_on_worlds": round(own, 4),
            "cost_on_fresh": round(new, 4),
            "success_on_fresh": round(success, 4),
        }
        print(f"{task_name}: {name}: {out[name]}", file=sys.stderr, flush=True)
    for episodes in learn:
        out[f"families_preset_{episodes}"] = learned(task, episodes, seeds, worlds, fresh)
        print(f"{task_name}: {episodes} episodes: {out[f'families_preset_{episodes}']}", file=sys.stderr, flush=True)
    for episodes in teach:
        out[f"taught_{episodes}"] = taught(task, episodes, seeds, epsilon, worlds, fresh)
        print(f"{task_name}: taught {episodes} episodes: {out[f'taught_{episodes}']}", file=sys.stderr, flush=True)
    out["seconds"] = round(time.perf_counter() - t0, 1)
    return out


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--task", default="triangles-3f")
    ap.add_argument("--worlds", type=int, default=2000)
    ap.add_argument("--fresh", type=int, default=1000)
    ap.add_argument("--learn", type=int, action="append", default=[], help="the families preset's episodes")
    ap.add_argument("--seeds", type=int, default=1, help="its seeds, 0 .. SEEDS - 1")
    ap.add_argument("--teach", type=int, action="append", default=[], help="episodes taught by the optimum")
    ap.add_argument("--epsilon", type=float, default=0.2, help="the teacher's share of uniformly drawn CRMs")
    a = ap.parse_args()
    if a.worlds < 1 or a.fresh < 1 or a.seeds < 1 or any(e < 1 for e in a.learn + a.teach):
        ap.error("--worlds, --fresh, --seeds, --learn and --teach must be at least 1")
    if not 0.0 <= a.epsilon <= 1.0:
        ap.error(f"--epsilon must be in [0, 1], got {a.epsilon}")
    res = main(a.task, a.worlds, a.fresh, tuple(a.learn), a.seeds, tuple(a.teach), a.epsilon)
    print(json.dumps(res, indent=1))

"""The cost of ``model-vi``'s planning step: the compiled value iteration against the readable
sweeps, timed inside the same learning runs.

``ModelVI`` solves its model after every real step, from the previous solution. The compiled
path (`crmgrasp.kernels.planning.value_iteration`) copies the agent's tables into arrays, runs
the sweeps in compiled code and writes the values back; the readable path
(``ModelVI._sweeps_reference``) is the definition, and both give the same values bit for bit,
so the two runs of a case take the same steps. Per case, ``model-vi`` learns for
``--episodes`` episodes (seed 0) once with each path, alternating over ``--rounds`` rounds; the
least total time spent planning is kept. The compiled path's time is split into the compiled
sweeps and the copying around them.

Columns: the model's states, pairs and outcomes at the end; plans; microseconds per plan,
compiled and readable, and their ratio (below 1: the compiled path is faster); of the compiled
time, the share spent in the sweeps themselves; the share of compiled plans that kept their
outcome arrays from the plan before (``kernels.planning._Outcomes``) instead of copying the
whole model.

A second table times work that builds large acyclic structures three ways, alternating, least
of the rounds: with the cyclic garbage collector held off and what was built moved to its oldest
generation at the end (`crmgrasp._collector.collector_paused`, what the code does), held off and
what was built left in its youngest generation (the code before 2026-12-07), and left to itself;
with the seconds its young and middle passes and its full passes took in each: whole
``--preset families`` runs (``backoff-vi``, k = 2, on the mirror quotient;
``--families-episodes`` episodes, seed 0), which rebuild their planning model after new data,
and the belief-space optimum over ``--optimum-starts`` sampled starts (seed 0), which memoises
every belief it meets.

A third table times the same ``--preset families`` runs with the entries for CRMs a history
never tried made once per plan for all histories that lead to the same next histories
(``BackoffVI._untried_entry``, ``PooledVI._pooled_entry``: what the code does) and made afresh
for each history (the peer, with ``backoff-vi``'s routed terms of the short level,
``BackoffVI._short_routed``, made afresh as well: the same entries, so the same steps, which
the table checks):
whole-run seconds and the seconds spent rebuilding the planning models (``BackoffVI._rebuilt``
with its short level's ``PooledVI._solve`` inside), least of the rounds.

Usage: ``python benchmarks/bench_planning.py [--episodes 300] [--families-episodes 1000]
[--optimum-starts 4000] [--rounds 3] [--smoke]``. Prints three tables and one JSON object.
"""

from __future__ import annotations

import argparse
import contextlib
import functools
import gc
import importlib
import json
import time
from collections.abc import Callable, Iterator
from typing import Any

from crmgrasp._collector import collector_paused

CASES = (("paper-box", 1), ("u-handle", 1), ("u-handle", 2))
"""(task, history order) of each case."""

FAMILIES = ("u-handle", "triangles-3f")
"""Tasks of the ``--preset families`` runs."""

OPTIMA = ("u-handle",)
"""Tasks of the belief-space optimum runs."""


class _Clock:
    """Seconds spent in ``ModelVI._plan`` and in the compiled sweeps while installed, and how
    many compiled plans found their kept outcome arrays usable (``_Outcomes.refresh``)."""

    def __init__(self) -> None:
        self.plan = self.sweeps = 0.0
        self.plans = self.kept = 0

    def __enter__(self) -> _Clock:
        import crmgrasp.kernels._vi_jit as jit
        import crmgrasp.kernels.planning as planning
        from crmgrasp.agents.model_based import ModelVI

        self._saved = (ModelVI._plan, jit.sweeps, planning._Outcomes.refresh)
        plan, sweeps, refresh = self._saved

        def counted(kept: Any, *args: Any) -> bool:
            ok = refresh(kept, *args)
            self.kept += ok
            return ok

        def timed_plan(agent: Any) -> None:
            t0 = time.perf_counter()
            plan(agent)
            self.plan += time.perf_counter() - t0
            self.plans += 1

        def timed_sweeps(*args: Any) -> Any:
            t0 = time.perf_counter()
            out = sweeps(*args)
            self.sweeps += time.perf_counter() - t0
            return out

        ModelVI._plan, jit.sweeps = timed_plan, timed_sweeps  # type: ignore[method-assign]
        planning._Outcomes.refresh = counted  # type: ignore[method-assign]
        return self

    def __exit__(self, *exc: object) -> None:
        import crmgrasp.kernels._vi_jit as jit
        import crmgrasp.kernels.planning as planning
        from crmgrasp.agents.model_based import ModelVI

        ModelVI._plan, jit.sweeps, planning._Outcomes.refresh = self._saved  # type: ignore[method-assign]


def _run(task: Any, k: int, episodes: int, compiled: bool) -> tuple[_Clock, Any]:
    from crmgrasp.agents.training import train_trials

    with _Clock() as clock:
        result = train_trials(
            task, "model-vi", trials=1, episodes=episodes, seed=0, k=k, eval_episodes=1, params={"compiled": compiled}
        )
    return clock, result.agents[0]


PAUSING = ("crmgrasp.agents.backoff", "crmgrasp.agents.pooled", "crmgrasp.planners.references")
"""The modules that hold the collector off (each imports ``collector_paused``)."""


MODES = ("paused", "resumed_young", "not_paused")
"""How the collector is treated: held off and the build's objects moved to its oldest generation
at the end (what the code does); held off, the build's objects left in its youngest generation
(the code before 2026-12-07); left alone."""


def _timed(work: Callable[[], object], mode: str) -> tuple[float, float, float]:
    """Seconds of ``work()``, of the collector's young and middle passes in it, and of its full
    passes; ``mode`` one of [`MODES`][] (the pause in every module of ``PAUSING`` replaced)."""
    modules = [importlib.import_module(name) for name in PAUSING]
    saved = [m.collector_paused for m in modules]
    spent, began = [0.0, 0.0], [0.0]

    def clock(phase: str, info: dict[str, int]) -> None:
        if phase == "start":
            began[0] = time.perf_counter()
        else:
            spent[info["generation"] == 2] += time.perf_counter() - began[0]

    if mode != "paused":
        for m in modules:
            replaced = contextlib.nullcontext if mode == "not_paused" else functools.partial(collector_paused, False)
            m.collector_paused = replaced  # type: ignore[attr-defined]
    gc.collect()
    gc.callbacks.append(clock)
    try:
        t0 = time.perf_counter()
        work()
        return time.perf_counter() - t0, spent[0], spent[1]
    finally:
        gc.callbacks.remove(clock)
        for m, pause in zip(modules, saved, strict=True):
            m.collector_paused = pause  # type: ignore[attr-defined]


def _families_work(name: str, episodes: int) -> Callable[[], object]:
    """One ``--preset families`` run of ``episodes`` episodes on task ``name``, seed 0."""
    from crmgrasp.agents.presets import apply_preset
    from crmgrasp.agents.training import train_trials
    from crmgrasp.tasks import make_task

    task = make_task(name)
    choice = apply_preset("families", task)
    params = {**dict(choice.params), "symmetric": choice.symmetric}
    return lambda: train_trials(
        task, choice.agent, trials=1, episodes=episodes, seed=0, k=choice.k, eval_episodes=1, params=params
    )


def _optimum_work(name: str, starts: int) -> Callable[[], object]:
    """The belief-space optimum of task ``name`` over ``starts`` sampled starts, seed 0."""
    from crmgrasp.planners.references import belief_optimum, sample_starts
    from crmgrasp.tasks import make_task

    task = make_task(name)
    sampled = sample_starts(task, starts, 0)
    belief_optimum(task, sampled[:2])  # load the compiled kernels before timing
    return lambda: belief_optimum(task, sampled)


def _pause_table(cases: dict[str, Callable[[], object]], rounds: int) -> dict[str, dict[str, float]]:
    """Each case in each of [`MODES`][], alternating, least of ``rounds``."""
    out: dict[str, dict[str, float]] = {}
    head = " | ".join(f"{m} s | young passes s | full passes s" for m in MODES)
    print(f"| case | {head} | paused / resumed_young | paused / not_paused |")
    print("| --- " * (3 + 3 * len(MODES)) + "|")
    for label, work in cases.items():
        best: dict[str, tuple[float, float, float]] = {}
        for _ in range(rounds):
            for mode in MODES:
                got = _timed(work, mode)
                if mode not in best or got[0] < best[mode][0]:
                    best[mode] = got
        row: dict[str, float] = {}
        for mode in MODES:
            total, young, full = best[mode]
            row |= {f"{mode}_s": round(total, 2), f"{mode}_young_s": round(young, 2), f"{mode}_full_s": round(full, 2)}
        row["paused_over_resumed_young"] = round(best["paused"][0] / best["resumed_young"][0], 3)
        row["paused_over_not_paused"] = round(best["paused"][0] / best["not_paused"][0], 3)
        out[label] = row
        print(f"| {label} | " + " | ".join(str(v) for v in row.values()) + " |")
    return out


def _planning_table(episodes: int, rounds: int) -> dict[str, dict[str, float]]:
    """Each case of ``CASES`` learned with the compiled and the readable planning,
    alternating, least planning time of ``rounds``."""
    from crmgrasp.tasks import make_task

    out: dict[str, dict[str, float]] = {}
    print("| task, k | states | pairs | outcomes | plans | compiled us | readable us | ratio | in the sweeps | kept |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for task_name, k in CASES:
        task = make_task(task_name)
        _run(task, k, 2, True)  # load the compiled sweeps before timing
        best: dict[bool, _Clock] = {}
        for _ in range(rounds):
            for compiled in (True, False):
                clock, agent = _run(task, k, episodes, compiled)
                if compiled not in best or clock.plan < best[compiled].plan:
                    best[compiled] = clock
        fast, slow = best[True], best[False]
        row = {
            "states": len(agent.q),
            "pairs": len(agent.model),
            "outcomes": sum(len(cs) for cs in agent.model.values()),
            "plans": fast.plans,
            "compiled_us": round(fast.plan / fast.plans * 1e6, 1),
            "readable_us": round(slow.plan / slow.plans * 1e6, 1),
            "compiled_over_readable": round(fast.plan / slow.plan, 3),
            "sweeps_share": round(fast.sweeps / fast.plan, 3),
            "kept_share": round(fast.kept / fast.plans, 3),
        }
        out[f"{task_name} k={k}"] = row
        print(f"| {task_name}, {k} | " + " | ".join(str(v) for v in row.values()) + " |")
    return out


REBUILDS = (("BackoffVI", "_rebuilt", "_untried_entry"), ("PooledVI", "_solve", "_pooled_entry"))
"""Per learner class: the method that rebuilds its planning model and the one that makes an
untried entry from its per-plan cache (``agent._untried``)."""


@contextlib.contextmanager
def _rebuild_clock(shared: bool) -> Iterator[list[float]]:
    """Seconds spent rebuilding planning models while open (the list's one item; a rebuild
    inside another, the short level's inside ``backoff-vi``'s, counted once); with
    ``shared=False`` every untried entry is made afresh (the cache emptied before each)."""
    from crmgrasp.agents import backoff, pooled

    classes = {"BackoffVI": backoff.BackoffVI, "PooledVI": pooled.PooledVI}
    saved = [(classes[c], name, getattr(classes[c], name)) for c, *names in REBUILDS for name in names]
    spent, depth = [0.0], [0]

    def timed(method: Callable[..., Any]) -> Callable[..., Any]:
        def run(*args: Any) -> Any:
            depth[0] += 1
            t0 = time.perf_counter()
            try:
                return method(*args)
            finally:
                depth[0] -= 1
                if not depth[0]:
                    spent[0] += time.perf_counter() - t0

        return run

    def afresh(method: Callable[..., Any]) -> Callable[..., Any]:
        def run(agent: Any, *args: Any) -> Any:
            agent._untried.clear()
            getattr(agent, "_routed", {}).clear()  # backoff-vi's routed terms, shared the same way
            return method(agent, *args)

        return run

    for c, rebuild, untried in REBUILDS:
        cls = classes[c]
        setattr(cls, rebuild, timed(getattr(cls, rebuild)))
        if not shared:
            setattr(cls, untried, afresh(getattr(cls, untried)))
    try:
        yield spent
    finally:
        for cls, name, method in saved:
            setattr(cls, name, method)


def _sharing_table(cases: dict[str, Callable[[], Any]], rounds: int) -> dict[str, dict[str, float]]:
    """Each families run with the untried entries shared and made afresh, alternating, least
    of ``rounds``; the two must take the same steps."""
    import numpy as np

    out: dict[str, dict[str, float]] = {}
    print("| case | shared s | in rebuilds s | afresh s | in rebuilds s | ratio | rebuilds ratio |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for label, work in cases.items():
        best: dict[bool, tuple[float, float]] = {}
        steps: dict[bool, Any] = {}
        for _ in range(rounds):
            for shared in (True, False):
                with _rebuild_clock(shared) as spent:
                    t0 = time.perf_counter()
                    steps[shared] = work().steps
                    got = (time.perf_counter() - t0, spent[0])
                if shared not in best or got[0] < best[shared][0]:
                    best[shared] = got
        if not np.array_equal(steps[True], steps[False]):
            raise AssertionError(f"{label}: shared and afresh untried entries took different steps")
        (fast, fast_rb), (slow, slow_rb) = best[True], best[False]
        row = {
            "shared_s": round(fast, 2),
            "shared_rebuilds_s": round(fast_rb, 2),
            "afresh_s": round(slow, 2),
            "afresh_rebuilds_s": round(slow_rb, 2),
            "shared_over_afresh": round(fast / slow, 3),
            "rebuilds_shared_over_afresh": round(fast_rb / slow_rb, 3),
        }
        out[label] = row
        print(f"| {label} | " + " | ".join(str(v) for v in row.values()) + " |")
    return out


def main(argv: list[str] | None = None) -> dict[str, dict[str, float]]:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--episodes", type=int, default=300, help="learning episodes per run")
    ap.add_argument("--families-episodes", type=int, default=1000, help="episodes per families-preset run")
    ap.add_argument("--optimum-starts", type=int, default=4000, help="sampled starts of the belief-space optimum")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--smoke", action="store_true", help="tiny sizes (for CI)")
    args = ap.parse_args(argv)
    if args.smoke:
        args.episodes, args.families_episodes, args.optimum_starts, args.rounds = 10, 10, 20, 1
    out = _planning_table(args.episodes, args.rounds)
    print()
    families = {
        f"families {name}, {args.families_episodes} episodes": _families_work(name, args.families_episodes)
        for name in FAMILIES
    }
    cases = families | {
        f"optimum {name}, {args.optimum_starts} starts": _optimum_work(name, args.optimum_starts) for name in OPTIMA
    }
    paused = _pause_table(cases, args.rounds)
    print()
    shared = _sharing_table(families, args.rounds)
    doc = {"episodes": args.episodes, "rounds": args.rounds, "cases": out, "collector": paused, "untried": shared}
    print(json.dumps(doc))
    return {**out, **paused, **{f"untried {label}": row for label, row in shared.items()}}


if __name__ == "__main__":
    main()

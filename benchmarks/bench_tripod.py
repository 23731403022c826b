"""The tripod environments' step time: compiled, compiled deciding the grasp only, least
friction compiled only, readable.

For ``crmgrasp/Box3D3F-v0`` and ``crmgrasp/Cup3D3F-v0`` on the default backend (every rule
compiled: ``FusedFingersSpatialKernel``), the same with ``exact_friction=False`` (``_decided``:
the step decides the grasp and reports no least friction), with only the least friction compiled (the
readable CRMs, starts and observations: ``FingersSpatialKernel``, the path before the fused
kernel and still the one for sensing noise), and on ``backend="reference"`` (the readable
rules), with ``CartPole-v1`` as the peer: random actions through ``gymnasium.make``,
``steps`` per round, the environments alternating round by round, the least round kept.
Every round starts with both least-friction caches empty, so a step pays for each new
configuration's least friction as in a fresh run. Times are per step, counting the resets
(a new solid and a start, whose acceptance needs the start's least friction), and for the
step alone (``env.step`` calls only, each timed on its own in the same pass; CartPole's too).

The least friction alone, as well, on the distinct configurations of ``steps`` random
actions of each task: the compiled rule (``least_friction`` of
``crmgrasp.kernels._closure_jit``, no cache; the least of ``rounds`` passes; three contacts take
the exact rule of ``crmgrasp.model.tripod``) and, as peers, the rules before it ([`PEERS`][]):
the search over the cone's half-angle (the rule of four contacts) and its plain bisection; the
rule and the search stopped once they decide the grasp (``decided_friction``); the readable rule
(``least_friction_3d``, first 50 configurations, once), linear programs per configuration and
pivots per program each way, and how far each peer's answers lie from the rule's.

Prints one JSON object (microseconds and ratios). Usage:
``python benchmarks/bench_tripod.py [STEPS] [ROUNDS]`` (defaults 1000 and 3).
"""

from __future__ import annotations

import json
import sys
import time
from typing import Any

import gymnasium as gym
import numpy as np

import crmgrasp  # noqa: F401  (registers the environments)
from crmgrasp.kernels.closure import FingersSpatialKernel, _cached
from crmgrasp.kernels.family import FamilyKernel
from crmgrasp.model.quality3d import EDGES, least_friction_3d
from crmgrasp.model.spatial_model import _least_friction


def _round(env: Any, actions: list[int]) -> tuple[float, float]:
    """Seconds per step of one pass over ``actions``, caches emptied first: resets included,
    and ``env.step`` alone (the same pass, each call timed on its own)."""
    _least_friction.cache_clear()
    _cached.cache_clear()
    clock = time.perf_counter
    alone = 0.0
    t0 = clock()
    for a in actions:
        t1 = clock()
        _, _, term, trunc, _ = env.step(a)
        alone += clock() - t1
        if term or trunc:
            env.reset()
    return (clock() - t0) / len(actions), alone / len(actions)


def _configurations(env_id: str, steps: int) -> list[tuple[np.ndarray, np.ndarray]]:
    """The distinct configurations of ``steps`` random actions of ``env_id`` (reset seed 0,
    actions drawn with seed 1), in the order first visited."""
    env = gym.make(env_id)
    _, info = env.reset(seed=0)
    configs = [info["config"]]
    for a in np.random.default_rng(1).integers(env.action_space.n, size=steps).tolist():
        _, _, term, trunc, info = env.step(a)
        configs.append(info["config"])
        if term or trunc:
            configs.append(env.reset()[1]["config"])
    return [(np.array([c.x for c in cfg]), np.array([c.n for c in cfg])) for cfg in dict.fromkeys(configs)]


def _apart(pairs: list, new: np.ndarray, old: np.ndarray, goal: float) -> tuple[float, int]:
    """The largest relative gap between two rules' answers above friction 1e-6, and how many
    fall on the other side of ``goal``."""
    gap, crossed = 0.0, 0
    for a, b in zip(new.tolist(), old.tolist(), strict=True):
        crossed += (a <= goal) != (b <= goal)
        if a != b and min(a, b) > 1e-6:
            gap = max(gap, abs(a - b) / b)
    return gap, crossed


PEERS = {
    "search": {"TRIPOD_EXACT": 0},
    "bisection": {"TRIPOD_EXACT": 0, "GUIDE_MAX": 0, "FIRST_PROBE": 0.0},
}
"""Each peer: the rule with constants of ``quality3d`` set otherwise (a rule before): the search
over the friction cone's half-angle with its first probe and secant guesses, and without them
(the plain bisection)."""


def _modules() -> dict[str, Any]:
    from crmgrasp.model import quality3d

    return {"GUIDE_MAX": quality3d, "FIRST_PROBE": quality3d, "TRIPOD_EXACT": quality3d}


def _counted(pairs: list, changes: dict[str, float]) -> tuple[float, float]:
    """Linear programs and simplex pivots per configuration of the readable rule on ``pairs``,
    with the constants in ``changes`` set to their values."""
    from crmgrasp.model import lp

    counts = [0, 0]
    program, pivot = lp.solve, lp._pivot
    modules = _modules()
    before = {name: getattr(modules[name], name) for name in changes}

    def counting(*args: Any) -> Any:
        counts[0] += 1
        return program(*args)

    def pivoting(*args: Any) -> None:
        counts[1] += 1
        pivot(*args)

    lp.solve, lp._pivot = counting, pivoting
    for name, value in changes.items():
        setattr(modules[name], name, type(before[name])(value))
    try:
        for p, n in pairs:
            least_friction_3d(p, n)
    finally:
        lp.solve, lp._pivot = program, pivot
        for name, value in before.items():
            setattr(modules[name], name, value)
    return counts[0] / len(pairs), counts[1] / len(pairs)


def _least_friction_alone(env_id: str, steps: int, rounds: int) -> dict[str, float]:
    """The least friction on the distinct configurations a random-action run of ``env_id``
    visits: microseconds per configuration, compiled (the least of ``rounds`` passes) by the
    rule and by each of [`PEERS`][] and, to decide the grasp only, by the rule and the
    search (``decided_friction`` at the task's ``mu_goal``); readable (the first 50
    configurations, once); linear programs and pivots per configuration, counted on the
    readable rule; and how far each peer's answers lie from the rule's (the largest relative gap
    above friction 1e-6, and how many fall on the other side of the task's ``mu_goal``)."""
    import crmgrasp.kernels._closure_jit as jit
    import crmgrasp.kernels._lp_jit as layout
    from crmgrasp.kernels.closure import closure_params

    pairs = _configurations(env_id, steps)
    goal = gym.make(env_id).unwrapped.task.mu_goal
    tols = {"rule": closure_params()}
    for name, changes in PEERS.items():
        tols[name] = closure_params()
        for key, value in changes.items():
            tols[name][getattr(layout, key)] = value
    jit.least_friction(*pairs[0], EDGES, tols["rule"])  # compiled before timing
    jit.decided_friction(*pairs[0], EDGES, tols["rule"], goal)
    timed = {**{(n, "exact"): t for n, t in tols.items()}, ("rule", "decided"): tols["rule"]}
    timed[("search", "decided")] = tols["search"]
    best = dict.fromkeys(timed, float("inf"))
    for _ in range(rounds):
        for (name, how), tol in timed.items():
            t0 = time.perf_counter()
            for p, n in pairs:
                if how == "exact":
                    jit.least_friction(p, n, EDGES, tol)
                else:
                    jit.decided_friction(p, n, EDGES, tol, goal)
            best[(name, how)] = min(best[(name, how)], (time.perf_counter() - t0) / len(pairs))
    answers = {name: np.array([jit.least_friction(p, n, EDGES, tol) for p, n in pairs]) for name, tol in tols.items()}
    t0 = time.perf_counter()
    for p, n in pairs[:50]:
        least_friction_3d(p, n)
    readable = (time.perf_counter() - t0) / len(pairs[:50])
    programs, pivots = _counted(pairs[:50], {})
    out = {
        "configurations": len(pairs),
        "least_friction_us": round(best[("rule", "exact")] * 1e6, 1),
        "least_friction_readable_us": round(readable * 1e6, 1),
        "programs_per_configuration": round(programs, 1),
        "pivots_per_program": round(pivots / max(programs, 1e-9), 1),
        "least_friction_decided_us": round(best[("rule", "decided")] * 1e6, 1),
        "least_friction_decided_search_us": round(best[("search", "decided")] * 1e6, 1),
    }
    for name, changes in PEERS.items():
        counted = _counted(pairs[:50], changes)
        gap, crossed = _apart(pairs, answers["rule"], answers[name], goal)
        out |= {
            f"least_friction_{name}_us": round(best[(name, "exact")] * 1e6, 1),
            f"{name}_over_rule": round(best[(name, "exact")] / best[("rule", "exact")], 2),
            f"programs_per_configuration_{name}": round(counted[0], 1),
            f"pivots_per_program_{name}": round(counted[1] / counted[0], 1),
            f"largest_relative_gap_to_{name}_above_1e-6": float(f"{gap:.2g}"),
            f"crossing_mu_goal_against_{name}": crossed,
        }
    return out


def main(steps: int = 1000, rounds: int = 3) -> dict[str, Any]:
    envs: dict[str, Any] = {"cartpole": gym.make("CartPole-v1")}
    for env_id in ("crmgrasp/Box3D3F-v0", "crmgrasp/Cup3D3F-v0"):
        name = env_id.split("/")[1].split("-")[0].lower()
        envs[name] = gym.make(env_id)
        envs[f"{name}_decided"] = gym.make(env_id, exact_friction=False)
        envs[f"{name}_lf_only"] = gym.make(env_id)
        envs[f"{name}_lf_only"].unwrapped.kernel = FamilyKernel(envs[name].unwrapped.task, FingersSpatialKernel)
        envs[f"{name}_reference"] = gym.make(env_id, backend="reference")
    actions, best, alone = {}, {}, {}
    for name, env in envs.items():
        env.reset(seed=0)
        actions[name] = np.random.default_rng(0).integers(env.action_space.n, size=steps).tolist()
        best[name] = alone[name] = float("inf")
    for _ in range(rounds):
        for name, env in envs.items():
            with_resets, step_only = _round(env, actions[name])
            best[name], alone[name] = min(best[name], with_resets), min(alone[name], step_only)
    cart, cart_alone = best.pop("cartpole"), alone.pop("cartpole")
    out: dict[str, Any] = {
        "steps": steps,
        "rounds": rounds,
        "cartpole_us": round(cart * 1e6, 2),
        "cartpole_step_alone_us": round(cart_alone * 1e6, 2),
    }
    for name, seconds in best.items():
        out[f"{name}_us"] = round(seconds * 1e6, 1)
        out[f"{name}_over_cartpole"] = round(seconds / cart, 1)
        out[f"{name}_step_alone_us"] = round(alone[name] * 1e6, 1)
        out[f"{name}_step_alone_over_cartpole"] = round(alone[name] / cart_alone, 1)
    for name in ("box3d3f", "cup3d3f"):
        out[f"{name}_reference_over_compiled"] = round(best[f"{name}_reference"] / best[name], 1)
        out[f"{name}_lf_only_over_compiled"] = round(best[f"{name}_lf_only"] / best[name], 2)
    for env_id in ("crmgrasp/Box3D3F-v0", "crmgrasp/Cup3D3F-v0"):
        name = env_id.split("/")[1].split("-")[0].lower()
        for key, value in _least_friction_alone(env_id, steps, rounds).items():
            out[f"{name}_{key}"] = value
    return out


if __name__ == "__main__":
    print(json.dumps(main(*(int(a) for a in sys.argv[1:3])), indent=2))

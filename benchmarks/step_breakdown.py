"""Where a paper-box step spends its time: the numbers behind README "Where the time goes".

Times (``timeit``, minimum of 5 repeats) the parts of one single-environment step
and of one 1,024-env vector step on the compiled kernel, the same parts on the
reference kernel (the readable rules, row by row) as the peer, and the corner-start
sampler's acceptance rate under the uniform and the tighter proposal.

Usage: ``python benchmarks/step_breakdown.py``; prints one JSON object (microseconds).
"""

import json
import timeit

import gymnasium as gym
import numpy as np

from crmgrasp import paper_box
from crmgrasp.kernels import kernel_for
from crmgrasp.tasks import accept_corner_candidates, corner_boxes, corner_proposal


def _us(fn, number: int) -> float:
    return round(min(timeit.repeat(fn, number=number, repeat=5)) / number * 1e6, 3)


def _batches(n: int, count: int, rng: np.random.Generator) -> list:
    """``count`` consecutive batches of a running ``n``-env vector env (rows mid-episode, the
    resets its episodes end in, random actions): timing one batch over and over would let
    the processor learn its branches and understate the pass by about half."""
    env = gym.make_vec("crmgrasp/PaperBox-v0", num_envs=n, vectorization_mode="vector_entry_point")
    env.reset(seed=1)
    out = []
    for _ in range(10 + count):
        acts = rng.integers(4, size=n)
        resets = env._prev_done.copy()
        cfg = env._cfg.copy()
        starts = env._starts(int(resets.sum())).copy()
        env._next -= len(starts)  # the env steps with the same starts
        env.step(acts)
        out.append((cfg, acts, resets, starts))
    return out[10:]


def _parts(task, backend: str, rng: np.random.Generator) -> dict:
    """The single-env and vector-env parts on one backend."""
    k = kernel_for(task, backend)
    row: dict = {"kernel": k.name}
    env = gym.make("crmgrasp/PaperBox-v0", backend=backend)
    env.reset(seed=0)
    state = env.unwrapped._state
    row["single_step_one_us"] = {
        f"C{i + 1}": _us(lambda i=i: k.step_one(state, i, rng), 2000) for i in range(len(task.actions))
    }
    row["single_begin_us"] = _us(lambda: k.begin(state.config, rng), 2000)
    row["single_env_reset_us"] = _us(env.reset, 2000)
    n = 1024 if backend == "numba" else 128
    batches = _batches(n, 20 if backend == "numba" else 3, rng)

    def steps() -> None:
        for cfg, acts, resets, starts in batches:
            k.step_batch(cfg, cfg, acts, resets, starts, rng)

    def executes() -> None:
        for cfg, acts, _, _ in batches:
            k.execute(cfg, cfg, acts)

    row[f"vector_step_batch_{n}_us"] = round(_us(steps, 2) / len(batches), 3)
    row[f"vector_execute_{n}_us"] = round(_us(executes, 2) / len(batches), 3)
    row["starts_2048_us"] = _us(lambda: k.sample_starts(rng, 2048), 5)
    return row


def main() -> dict:
    task = paper_box()
    obj, hand = task.obj, task.hand
    rng = np.random.default_rng(0)
    out: dict = {backend: _parts(task, backend, rng) for backend in ("numba", "reference")}
    cum, c_in, c_out = corner_boxes(obj, hand.aperture)
    raw = rng.random((4, 20_000))
    out["corner_acceptance_uniform_proposal"] = len(accept_corner_candidates(obj, hand, task.mu_goal, raw)) / 2e4
    tight = corner_proposal(raw, cum, c_in, c_out)
    out["corner_acceptance_tight_proposal"] = len(accept_corner_candidates(obj, hand, task.mu_goal, tight)) / 2e4
    print(json.dumps(out, indent=2))
    return out


if __name__ == "__main__":
    main()

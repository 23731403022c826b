"""Where a paper-box step spends its time: the numbers behind README "Where the time goes".

Times (``timeit``, minimum of 5 repeats) the parts of one single-environment step
and of one 1,024-env vector step, the corner-start sampler's acceptance rate, and
the cost of the numpy operations the batched kernel is made of. Run with
``CRMGRASP_NUMBA=0`` for the numpy path.

Usage: ``python benchmarks/step_breakdown.py``; prints one JSON object (microseconds).
"""

import json
import timeit

import gymnasium as gym
import numpy as np

from crmgrasp import _numba, paper_box
from crmgrasp._scalar import crm_step, observe_mu
from crmgrasp.batch import execute_columns
from crmgrasp.tasks import _corner_boxes, _corner_candidates, _corner_proposal


def _us(fn, number: int) -> float:
    return round(min(timeit.repeat(fn, number=number, repeat=5)) / number * 1e6, 3)


def main() -> dict:
    task = paper_box()
    obj, hand = task.obj, task.hand
    out: dict = {"backend": "numba" if _numba.AVAILABLE else "numpy"}
    rng = np.random.default_rng(0)
    cfg = task.sample_start(rng)
    v = (*cfg.a, *cfg.b)
    args = (obj.edges, obj.convex, hand.aperture, hand.palm_depth, hand.palm_normal_tol)
    out["single_crm_step_us"] = {
        f"C{i + 1}": _us(lambda c=c: crm_step(v, c.ci == 1, c.fi == 1, c.r, *args), 20000)
        for i, c in enumerate(task.actions)
    }
    out["single_observe_mu_us"] = _us(lambda: observe_mu(v), 20000)
    env = gym.make("crmgrasp/PaperBox-v0")
    env.reset(seed=0)
    out["single_reset_us"] = _us(env.reset, 20000)

    vec = gym.make_vec("crmgrasp/PaperBox-v0", num_envs=1024, vectorization_mode="vector_entry_point")
    vec.reset(seed=0)
    u = vec.unwrapped
    a = rng.integers(4, size=1024)
    c = u._cfg.copy()
    cb, fb, rr = u._c_is_b[a], u._f_is_b[a], u._r[a]

    def kernel() -> None:
        with np.errstate(all="ignore"):
            execute_columns(obj, hand, c, c, cb, fb, rr)

    actions = rng.integers(4, size=(200, 1024))

    def steps() -> None:
        for row in actions:
            vec.step(row)

    out["vector_step_us"] = round(min(timeit.repeat(steps, number=1, repeat=5)) / 200 * 1e6, 1)
    out["vector_kernel_us"] = _us(kernel, 1000)
    out["vector_observe_and_bins_us"] = _us(lambda: u._observe(np.zeros(1024, dtype=np.int8)), 1000)
    out["vector_240_starts_us"] = _us(lambda: u._starts(240), 1000)
    cum, c_in, c_out = _corner_boxes(obj, hand.aperture)
    raw = rng.random((4, 100_000))
    out["corner_acceptance_uniform_proposal"] = _corner_candidates(obj, hand, task.mu_goal, raw).shape[1] / 1e5
    tight = _corner_proposal(raw, cum, c_in, c_out)
    out["corner_acceptance_tight_proposal"] = _corner_candidates(obj, hand, task.mu_goal, tight).shape[1] / 1e5
    x, y, m = rng.random(1024), rng.random(1024), rng.random(1024) > 0.5
    col, block = rng.random((4, 1)), rng.random((4, 1024))
    out["numpy_1024_multiply_us"] = _us(lambda: x * y, 20000)
    out["numpy_1024_where_us"] = _us(lambda: np.where(m, x, y), 20000)
    out["numpy_4x1_by_1024_broadcast_multiply_us"] = _us(lambda: col * block[0], 20000)
    print(json.dumps(out, indent=2))
    return out


if __name__ == "__main__":
    main()

"""Hostile actions and reset options, at scale: every registered Gymnasium environment and the
vector environments of several tasks, stepped with every value of a hostile list.

For each Gymnasium id that ``import crmgrasp`` registers (``crmgrasp/...``) it makes the
environment, and for each of [`ACTIONS`][] (out-of-range and negative indices, NaN and
infinities, wrong types, shapes and dtypes, a dict, a string, ``None``) resets it and steps
it once; then it resets it with each of [`OPTIONS`][] (a start that is not one, an unknown
key). For the discrete and continuous vector environments of [`VECTOR_TASKS`][] (2 rows) it
does the same with [`BATCHES`][]. Then the one episode loop itself
([`crmgrasp.sim.run_episode`][], the agent interface of learners, planners and a user's own
policy), with a policy that acts each of [`ACTIONS`][] and a CRM beyond the hand's reach, on
each task of [`VECTOR_TASKS`][] through the readable steps and through the task's kernel, and
its batched form ([`crmgrasp.sim.run_batch`][] over the kernel's rows) on the single-object
ones. Everything runs with Python's warnings raised as errors. A step, reset or episode passes
if it works or raises a ``CrmgraspError`` of one line under 300 characters (Gymnasium's
``check_env`` accepts a documented error for an invalid action); another exception, a warning
or a longer message is reported, and so is an episode that runs with an action that is no
index of the task's CRMs (this script's own oracle: an integer, or a 0-d integer array, not a
bool, in range). It prints one JSON object and exits 1 if one failed.

Measured 2026-12-07 on the 2-core machine: 27 ids x 25 cases, 6 tasks x 2 vector environments
x 14 batches and 273 episode-loop cases, 1,116 cases in 2.3 s, none failed. Before the episode
loop took its indices through ``Task.action_index`` (at 7e2c3a2), 214 of the 273 failed: an
``IndexError``, ``TypeError`` or numba ``TypingError`` from deep inside, and episodes that ran
with ``-1`` (Python's last CRM) or ``True``.

Usage: ``python benchmarks/env_fuzz.py``.
"""

from __future__ import annotations

import json
import sys
import time
from collections.abc import Callable
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import task_file_fuzz

ACTIONS: tuple[Any, ...] = (
    -1,
    10**6,
    1.5,
    np.nan,
    np.inf,
    "a",
    None,
    [0, 1],
    np.array([0]),
    np.array(0),
    np.int64(1),
    True,
    np.array([np.nan]),
    np.array([0.0, np.nan]),
    np.array([[0.0]]),
    (0, 0.1),
    {"pair": 0},
    np.array([2.0, 0.0]),
    np.array([0.0, 5.0]),
    np.zeros(7),
)
"""The actions each environment is stepped with (one per reset)."""

OPTIONS: tuple[dict[str, Any], ...] = ({"config": None}, {"config": 3}, {"world": 1}, {"nosuch": 1}, {"config": "x"})
"""The reset options each environment is reset with."""

VECTOR_TASKS = ("paper-box", "box-family", "cup-3d", "triangles-3f", "u-handle", "open-cup-3d")

BATCHES: tuple[Any, ...] = (
    np.array([0, 1, 2]),
    np.array([-1, 0]),
    np.array([0.5, 1.0]),
    np.array([np.nan, 0]),
    np.array(["a", "b"]),
    [0, 1],
    1,
    None,
    np.zeros((2, 2)),
    np.array([10**9, 0]),
    np.array([True, False]),
    np.zeros((2, 3)),
    np.full((2, 3), np.nan),
    np.full((2, 3), 5.0),
)
"""The action batches each two-row vector environment is stepped with."""


def attempt(call: Callable[[], Any]) -> str | None:
    """``None`` if ``call()`` works or raises a one-line ``CrmgraspError`` under 300 characters,
    else what went wrong (``benchmarks/task_file_fuzz.py``'s rule, warnings raised as errors)."""
    return task_file_fuzz.attempt(call, limit=300)


def _stepped(env: Any, action: Any) -> Callable[[], Any]:
    def call() -> Any:
        env.reset(seed=1)
        return env.step(action)

    return call


def fuzz_ids() -> tuple[int, list[dict[str, str]]]:
    """Every registered id with every action and reset option: the count and the failures."""
    import gymnasium as gym

    import crmgrasp  # noqa: F401  (registers the ids)

    count, failures = 0, []
    for env_id in sorted(i for i in gym.registry if i.startswith("crmgrasp/")):
        env = gym.make(env_id)
        env.reset(seed=0)
        cases = [(repr(a)[:40], _stepped(env, a)) for a in ACTIONS]
        cases += [(f"reset options {o}", lambda e=env, o=o: e.reset(seed=0, options=o)) for o in OPTIONS]
        for label, call in cases:
            count += 1
            problem = attempt(call)
            if problem is not None:
                failures.append({"env": env_id, "case": label, "problem": problem})
        env.close()
    return count, failures


def fuzz_vectors() -> tuple[int, list[dict[str, str]]]:
    """The vector environments of ``VECTOR_TASKS`` with every batch: the count and the failures."""
    from crmgrasp.envs.vector import continuous_vector_env, vector_env
    from crmgrasp.tasks import make_task

    count, failures = 0, []
    for name in VECTOR_TASKS:
        for maker in (vector_env, continuous_vector_env):
            env = maker(2, make_task(name))
            env.reset(seed=0)
            for batch in BATCHES:
                count += 1
                problem = attempt(_stepped(env, batch))
                if problem is not None:
                    failures.append({"env": f"{maker.__name__}({name})", "case": repr(batch)[:40], "problem": problem})
    return count, failures


class _Acting:
    """A policy of the one episode loop ([`crmgrasp.sim.run_episode`][]) that acts ``action``."""

    def __init__(self, action: Any) -> None:
        self.action = action

    def begin(self, first: Any) -> None:
        pass

    def act(self) -> Any:
        return self.action

    def tell(self, percept: Any) -> None:
        pass


class _BatchActing(_Acting):
    """The same for [`crmgrasp.sim.run_batch`][]: ``action`` for every row."""

    def begin(self, row: int, first: Any) -> None:  # type: ignore[override]
        pass

    def act(self, rows: list[int]) -> Any:  # type: ignore[override]
        return [self.action] * len(rows)

    def tell(self, row: int, percept: Any) -> None:  # type: ignore[override]
        pass


def _episode(task: Any, action: Any, kernel: Any) -> Any:
    """One episode of a policy that acts ``action``, through ``kernel`` (None: the readable steps)."""
    from crmgrasp.sim import run_episode

    return run_episode(task, _Acting(action), np.random.default_rng(0), kernel=kernel)


def _batch(task: Any, action: Any) -> None:
    """Two rows of episodes through the task's kernel, every row acting ``action``."""
    from crmgrasp.kernels import kernel_for
    from crmgrasp.kernels.rows import KernelRows
    from crmgrasp.sim import run_batch

    rows = KernelRows(task, kernel_for(task), [np.random.default_rng(0)] * 2)
    run_batch(rows, _BatchActing(action), 2, lambda r, last: last is None)


def fuzz_episode_loop() -> tuple[int, list[dict[str, str]]]:
    """The episode loop with a policy acting each of ``ACTIONS`` (and a CRM beyond the hand's
    reach), through the readable steps and the task's kernel, and the batched loop through
    [`KernelRows`][crmgrasp.kernels.rows.KernelRows] (single-object tasks): the count and the
    failures."""
    from crmgrasp.kernels import kernel_for
    from crmgrasp.model.hand import CRM
    from crmgrasp.tasks import make_task

    count, failures = 0, []
    for name in VECTOR_TASKS:
        task = make_task(name)
        for action in (*ACTIONS, CRM("a", "b", 99.0)):
            cases = [("readable steps", partial(_episode, task, action, None))]
            cases.append(("kernel", partial(_episode, task, action, kernel_for(task))))
            if task.family is None:
                cases.append(("batched", partial(_batch, task, action)))
            for where, call in cases:
                count += 1
                ran: list[bool] = []
                problem = attempt(partial(_noting, call, ran))
                if problem is None and ran and not _an_index(action, len(task.actions)):
                    problem = "ran with an action that is no index of the task's CRMs"
                if problem is not None:
                    failures.append({"env": f"{where}({name})", "case": repr(action)[:40], "problem": problem})
    return count, failures


def _noting(call: Callable[[], Any], ran: list[bool]) -> None:
    """``call()``, then a note in ``ran`` that it returned."""
    call()
    ran.append(True)


def _an_index(action: Any, n: int) -> bool:
    """Whether ``action`` is an index of ``n`` CRMs (this script's own oracle: a Python or
    NumPy integer, or a 0-d integer array, not a bool, in ``[0, n)``)."""
    if isinstance(action, np.ndarray):
        if action.ndim != 0 or action.dtype.kind not in "iu":
            return False
        action = action.item()
    return isinstance(action, (int, np.integer)) and not isinstance(action, (bool, np.bool_)) and 0 <= action < n


def main() -> dict[str, Any]:
    t0 = time.perf_counter()
    n_ids, bad_ids = fuzz_ids()
    print(f"registered ids: {n_ids} cases, {len(bad_ids)} failed", file=sys.stderr, flush=True)
    n_vec, bad_vec = fuzz_vectors()
    print(f"vector environments: {n_vec} cases, {len(bad_vec)} failed", file=sys.stderr, flush=True)
    n_loop, bad_loop = fuzz_episode_loop()
    print(f"episode loop: {n_loop} cases, {len(bad_loop)} failed", file=sys.stderr, flush=True)
    failures = bad_ids + bad_vec + bad_loop
    out = {
        "cases": n_ids + n_vec + n_loop,
        "failed": len(failures),
        "seconds": round(time.perf_counter() - t0, 1),
        "failures": failures[:40],
    }
    print(json.dumps(out, indent=1))
    return out


if __name__ == "__main__":
    sys.exit(1 if main()["failed"] else 0)

"""Compile the kernels into numba's on-disk cache before a parallel test run (tests/conftest.py).

With ``-n 2`` both pytest-xdist workers meet the same compiled functions and, on a cold cache
(a fresh clone), each compiles them for itself. Run here as two processes at once, each
compiling its own half, the compilation is done once, on both cores, and the workers load it.

``python tests/numba_warmup.py H`` runs half ``H`` (0: planar tasks, the vector environments and
value iteration; 1: spatial tasks and tripods). A half steps a few CRMs of each of its tasks
on the kernel the seam picks, noise-free and noisy; half 0 also steps the discrete and
continuous vector environments of a planar and a spatial task and plans with value iteration:
the signatures the tests use. Anything it misses is compiled by the workers, as without it.
"""

from __future__ import annotations

import dataclasses
import sys
from typing import Any

import numpy as np

HALVES = (
    ("paper-box", "box-family", "u-handle", "notch-or-box", "triangles-3f", "odd-polygons-3f", "box-family-3f"),
    ("box-3d", "cup-3d", "open-cup-3d", "box-3d-3f", "cup-3d-3f"),
)
"""The tasks of each half: the planar kernels (half 0 also takes the vector environments and
value iteration) and the spatial ones (the tripods alone compile in about 23 s). Cold on the
2-core machine the halves take 18 and 32 s; a few small helpers are compiled in both."""


def noisy(task: Any) -> Any:
    """``task`` with sensing noise of 0.05 rad on the normals and 3 mm on the positions (the
    noisy kernels compile apart from the noise-free ones)."""
    from crmgrasp.model.sensing import SensorNoise

    return dataclasses.replace(task, noise=SensorNoise(sigma_n=0.05, sigma_p=0.003))


def _steps(name: str) -> None:
    """A few CRMs of task ``name`` on its kernel, noise-free and noisy (`noisy`), by index."""
    from crmgrasp.kernels import kernel_for
    from crmgrasp.tasks import make_task

    base = make_task(name)
    for task in (base, noisy(base)):
        rng = np.random.default_rng(0)
        kernel = kernel_for(task, "auto")
        for _ in range(2):
            now = kernel.begin(kernel.sample_start(rng), rng)
            for a in range(3):
                now = kernel.step_one(now.state, a % len(task.actions), rng)


def _vector(name: str) -> None:
    """The discrete and continuous vector environments of task ``name``: a few batched steps."""
    from crmgrasp.envs.vector import continuous_vector_env, vector_env
    from crmgrasp.tasks import make_task

    task = make_task(name)
    for make in (vector_env, continuous_vector_env):
        env = make(4, task)
        env.reset(seed=0)
        for _ in range(3):
            env.step(env.action_space.sample())


def _planning() -> None:
    """Value iteration (model-vi, backoff-vi) on a few episodes."""
    from crmgrasp.agents.training import train_trials
    from crmgrasp.tasks import make_task

    task = make_task("paper-box")
    for agent, k in (("model-vi", 1), ("backoff-vi", 2)):
        train_trials(task, agent, trials=1, episodes=5, seed=0, k=k, eval_episodes=2)


def run(half: int) -> None:
    """Compile half ``half`` (see the module docstring)."""
    for name in HALVES[half]:
        _steps(name)
    if half == 0:  # the spatial vector environment here too: half 1 holds the tripods, the longest
        _vector("paper-box")
        _vector("box-3d")
        _planning()


if __name__ == "__main__":
    run(int(sys.argv[1]))

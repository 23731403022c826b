"""MushroomRL's own SARSA and Q-learning on the learner benchmark's protocol, in a venv of their own.

``benchmarks/learner_seeds.py`` compares crmgrasp's learners with peers on the same checkpoint
starts. Its SARSA and Q-learning rows are crmgrasp's updates; this script runs MushroomRL's
(``mushroom_rl.algorithms.value.SARSA`` and ``QLearning``, driven by MushroomRL's ``Core``) on
the same protocol: per seed one agent learns for EPISODES episodes of the task itself, over
k = 1 histories (the state ``(o_t, a_{t-1})`` as one integer), with the rows' settings
(learning rate 0.3, Q0 = 0, greedy: ``EpsGreedy`` with epsilon 0, discount 0.9, no mirror
quotient); after each checkpoint (5, 10, 15, 20, 30, ... episodes) its Q table's greedy policy
runs on the benchmark's 1,000 checkpoint starts of that seed (``checkpoint_generators``), ties
broken by their generator. It prints the benchmark's columns.

MushroomRL 1.10.2 pins numpy 1.24.4, which crmgrasp (numpy >= 1.26) cannot share. Its tabular
algorithms run on numpy 2, so ``--make-venv`` builds ``.venv-mushroom`` with crmgrasp, the CPU
build of torch that MushroomRL imports, ``mushroom-rl==1.10.2`` without its pins
(``--no-deps``) and the modules it imports (tqdm, OpenCV, scikit-learn, pygame); about 2 minutes
with pip's cache warm. The environment (``CRMEnvironment``) is a MushroomRL ``Environment`` over
the task's kernel: starts and sensing draw from the trial's environment generator
(``trial_generators``), as crmgrasp's training does; MushroomRL draws its tie-breaking from
NumPy's global generator, which the script seeds with the seed (its only way; the numbers
repeat run to run).

Usage: ``python benchmarks/mushroom_peer.py --make-venv``, then ``.venv-mushroom/bin/python
benchmarks/mushroom_peer.py [--episodes 200] [--seeds 10] [--first 0] [--task paper-box --task
box-family]``. Prints one JSON object; progress on stderr.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from crmgrasp.agents.base import greedy_choice
from crmgrasp.agents.training import (
    DEFAULT_CHECKPOINTS,
    checkpoint_generators,
    checkpoints_to_within,
    encoder_for,
    evaluate,
    trial_generators,
)
from crmgrasp.kernels import kernel_for
from crmgrasp.tasks import make_task

sys.path.insert(0, str(Path(__file__).resolve().parent))
from learner_seeds import summary

ROOT = Path(__file__).resolve().parents[1]
VENV = ROOT / ".venv-mushroom"
ALPHA, GAMMA = 0.3, 0.9  # the SARSA and Q-learning rows' settings (crmgrasp's defaults)


def make_venv() -> None:
    """Build ``.venv-mushroom`` (module docstring)."""
    pip = [str(VENV / "bin" / "pip"), "install", "-q"]
    for cmd in (
        [sys.executable, "-m", "venv", str(VENV)],
        [*pip, "torch==2.13.0", "-e", str(ROOT)],
        [*pip, "--no-deps", "mushroom-rl==1.10.2"],
        [*pip, "tqdm", "opencv-python-headless", "scikit-learn", "pygame"],
    ):
        print("+ " + " ".join(cmd), file=sys.stderr, flush=True)
        subprocess.run(cmd, check=True)
    print(f"built {VENV}; run: {VENV}/bin/python {Path(__file__).relative_to(ROOT)}", file=sys.stderr)


class GreedyTable:
    """A Q table's greedy policy as a crmgrasp agent (evaluation only): the best action of the
    state's row, ties broken by the evaluation's generator."""

    name = "mushroom-greedy"

    def __init__(self, table: np.ndarray) -> None:
        self.table, self.n_actions = table, table.shape[1]

    def begin_episode(self) -> None:
        pass

    def greedy(self, state: int, rng: np.random.Generator) -> int:
        return greedy_choice(self.table[state].tolist(), rng)

    act = greedy

    def update(self, *args: Any) -> None:
        pass


def environment_class() -> type:
    """``CRMEnvironment``, made when MushroomRL is importable (a one-line exit where it is not)."""
    try:
        from mushroom_rl.core import Environment, MDPInfo
        from mushroom_rl.utils.spaces import Discrete
    except ImportError:
        raise SystemExit(
            "MushroomRL is not installed here: run `python benchmarks/mushroom_peer.py --make-venv`, "
            "then `.venv-mushroom/bin/python benchmarks/mushroom_peer.py`"
        ) from None

    class CRMEnvironment(Environment):  # type: ignore[misc, valid-type]
        """A task as a MushroomRL environment over k = 1 history codes; an episode ends on a
        grasp (absorbing) or after the task's ``max_steps`` CRMs (MushroomRL's horizon)."""

        def __init__(self, task: Any, rng: np.random.Generator) -> None:
            self.task, self.kernel, self.rng = task, kernel_for(task), rng
            self.enc = encoder_for(task, 1)
            info = MDPInfo(Discrete(self.enc.size), Discrete(len(task.actions)), GAMMA, task.max_steps)
            super().__init__(info)

        def reset(self, state: Any = None) -> np.ndarray:
            out = self.kernel.begin(self.kernel.sample_start(self.rng), self.rng)
            self._state, self._hist = out.state, self.enc.start(out.obs_index)
            return np.array([self.enc.encode(self._hist)])

        def step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool, dict]:
            a = int(action[0])
            out = self.kernel.step_one(self._state, a, self.rng)
            self._state, self._hist = out.state, self.enc.push(self._hist, a, out.obs_index)
            return np.array([self.enc.encode(self._hist)]), float(out.reward), bool(out.terminated), {}

    return CRMEnvironment


def run_algorithm(task_name: str, algo: str, episodes: int, seeds: range) -> dict[str, Any]:
    """One MushroomRL algorithm on one task over the seeds: the benchmark's columns."""
    env_class = environment_class()  # first: a one-line exit where MushroomRL is missing
    from mushroom_rl.algorithms.value import SARSA, QLearning
    from mushroom_rl.core import Core
    from mushroom_rl.policy import EpsGreedy
    from mushroom_rl.utils.parameters import Parameter

    task = make_task(task_name)
    ref, enc = task.reference_mean_steps, encoder_for(task, 1)
    checks = np.array([c for c in DEFAULT_CHECKPOINTS if c <= episodes])
    t0, to5, curves = time.perf_counter(), [], []
    for seed in seeds:
        np.random.seed(seed)  # noqa: NPY002 -- MushroomRL draws its tie-breaking from the global generator
        env_rng = trial_generators(seed, 1)[0][0]
        mdp = env_class(task, env_rng)
        agent = (SARSA if algo == "sarsa" else QLearning)(mdp.info, EpsGreedy(Parameter(0.0)), Parameter(ALPHA))
        core, done, curve = Core(agent, mdp), 0, []
        for c in checks:
            core.learn(n_episodes=int(c) - done, n_steps_per_fit=1, quiet=True)
            done = int(c)
            greedy = GreedyTable(agent.Q.table)
            curve.append(
                float(evaluate(task, greedy, enc, 1000, *checkpoint_generators(seed), kernel=mdp.kernel)[0].mean())
            )
        curves.append(curve)
        to5.append(checkpoints_to_within(checks, np.array(curve), ref))
        print(f"{task_name}: MushroomRL {algo} seed {seed}: within 5% from {to5[-1]}", file=sys.stderr, flush=True)
    return summary(to5, curves, tuple(int(c) for c in checks), episodes, ref, time.perf_counter() - t0)


def main(argv: list[str] | None = None) -> dict[str, Any]:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--make-venv", action="store_true", help="build .venv-mushroom and stop")
    ap.add_argument("--episodes", type=int, default=200)
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--first", type=int, default=0)
    ap.add_argument("--task", action="append", dest="tasks")
    args = ap.parse_args(argv)
    if args.make_venv:
        make_venv()
        return {}
    out: dict[str, Any] = {"episodes": args.episodes, "seeds": [args.first, args.first + args.seeds - 1]}
    for task_name in args.tasks or ("paper-box", "box-family"):
        seeds = range(args.first, args.first + args.seeds)
        out[task_name] = {f"MushroomRL {a}": run_algorithm(task_name, a, args.episodes, seeds) for a in ("sarsa", "q")}
    print(json.dumps(out, indent=1))
    return out


if __name__ == "__main__":
    main()

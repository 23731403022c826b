"""The learned policy that Figures 8 and 9 and the MuJoCo transfers execute."""

from __future__ import annotations

from pathlib import Path

from crmgrasp._progress import Progress
from crmgrasp.agents import GreedyPolicy
from crmgrasp.experiments.learning import LearnerSpec, best_policy, learn
from crmgrasp.tasks import Task

PAPER_SARSA = LearnerSpec("sarsa", 2)
"""The paper's learner: SARSA on second-order histories."""


def learned_policy(
    task: Task,
    policy_path: str | Path | None,
    seed: int,
    trials: int,
    episodes: int,
    backend: str = "auto",
    progress: Progress | None = None,
    spec: LearnerSpec = PAPER_SARSA,
) -> GreedyPolicy:
    """Load ``policy_path`` if given, else train ``spec`` (default: the paper's SARSA;
    ``trials`` trials of ``episodes`` episodes from ``seed``, on the kernel ``backend``)
    and take the best trial's greedy policy."""
    if policy_path is not None:
        return GreedyPolicy.load(policy_path, task)
    run = learn(
        task,
        spec,
        trials=trials,
        episodes=episodes,
        seed=seed,
        eval_episodes=200,
        checkpoint_episodes=0,
        backend=backend,
        progress=progress,
    )
    policy = best_policy(task, run)
    assert isinstance(policy, GreedyPolicy)  # the experiments learn tabular policies
    return policy

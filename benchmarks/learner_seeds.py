"""Sample efficiency across seeds: the fastest learner against Dyna-Q, on paper-box and a family.

For each seed 0..SEEDS-1, ``crmgrasp.experiments.learning.learn`` runs 20 trials x
EPISODES episodes of each learner below and records ``greedy_episodes_to_5pct``: the
first checkpoint (5, 10, 15, 20, 30, ...) from which the mean greedy policy over the
20 trials, evaluated on 1,000 fixed starts per checkpoint, stays within 5% of the
task's reference (paper-box: the belief-space optimum 1.66; box-family: 1.75), and the
mean greedy CRMs at checkpoint 20.

Learners: ``model-vi`` from scratch (k = 1, mirror quotient: ``crmgrasp learn --agent
model-vi --k 1 --symmetric``; ``--preset fastest`` on box-family), the same with a prior
learned in 500 episodes on ``box-family`` (paper-box only: the family has paper-box's CRMs
and bins; ``--preset fastest`` on paper-box), and Dyna-Q k = 1 with value-iteration
sweeps on the mirror quotient (the fastest learner before ``model-vi``).

Usage: ``python benchmarks/learner_seeds.py [EPISODES] [SEEDS]`` (defaults 60 and 10).
Prints one JSON object.
"""

import json
import statistics
import sys

from crmgrasp.experiments.learning import SYMMETRIC_DYNA_Q, LearnerSpec, learn
from crmgrasp.tasks import make_task

FASTEST = LearnerSpec("model-vi", 1, {"symmetric": True}, "model-vi k=1 (mirror quotient)")
WITH_PRIOR = LearnerSpec(
    "model-vi", 1, {"symmetric": True, "prior_task": "box-family"}, "model-vi k=1 + box-family prior"
)


def _row(task_name: str, spec: LearnerSpec, episodes: int, seeds: int, trials: int, checks: int) -> dict:
    task = make_task(task_name)
    runs = [
        learn(task, spec, trials=trials, episodes=episodes, seed=s, eval_episodes=0, checkpoint_episodes=checks)
        for s in range(seeds)
    ]
    to5 = [r.summary["greedy_episodes_to_5pct"] for r in runs]
    at20 = [float(r.result.checkpoint_steps.mean(axis=0)[list(r.result.checkpoints).index(20)]) for r in runs]
    target = 1.05 * task.reference_mean_steps  # type: ignore[operator]
    return {
        "greedy_episodes_to_5pct": to5,
        "median_greedy_episodes_to_5pct": statistics.median(episodes + 1 if v is None else v for v in to5),
        "seeds_within_5pct_by_20": sum(v is not None and v <= 20 for v in to5),
        "greedy_mean_steps_at_20": [round(v, 3) for v in at20],
        "seeds_at_20_within_5pct": sum(v <= target + 1e-12 for v in at20),
    }


def main(episodes: int = 60, seeds: int = 10, trials: int = 20, checkpoint_episodes: int = 1000) -> dict:
    out: dict = {"episodes": episodes, "trials": trials, "checkpoint_episodes": checkpoint_episodes}
    for task_name, specs in (
        ("paper-box", (FASTEST, WITH_PRIOR, SYMMETRIC_DYNA_Q)),
        ("box-family", (FASTEST, SYMMETRIC_DYNA_Q)),
    ):
        out[task_name] = {
            spec.name: _row(task_name, spec, episodes, seeds, trials, checkpoint_episodes) for spec in specs
        }
    return out


if __name__ == "__main__":
    args = [int(a) for a in sys.argv[1:3]]
    print(json.dumps(main(*args), indent=2))

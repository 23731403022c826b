"""Sample efficiency across seeds: the fastest learner versus plain Dyna-Q.

For each seed, ``crmgrasp.experiments.learning.learn`` runs 20 trials x EPISODES
episodes of Dyna-Q k=1 with value-iteration sweeps, with and without the mirror
quotient (``symmetric=True``), and records ``episodes_to_5pct`` (training-curve
rule) and ``greedy_episodes_to_5pct`` (greedy policy on the fixed checkpoint
starts). Prints one JSON object with the per-seed values and their medians.

Usage: ``python benchmarks/learner_seeds.py [EPISODES] [SEEDS]`` (defaults 200 and 10).
"""

import json
import statistics
import sys

from crmgrasp import paper_box
from crmgrasp.experiments.learning import SYMMETRIC_DYNA_Q, LearnerSpec, learn


def main(episodes: int = 200, seeds: int = 10) -> dict:
    task = paper_box()
    plain = LearnerSpec("dyna-q", 1, {"planning": "sweep", "n_planning": 50}, "Dyna-Q k=1 (VI sweeps)")
    out: dict = {"episodes": episodes, "trials": 20}
    for spec in (SYMMETRIC_DYNA_Q, plain):
        rows = [learn(task, spec, trials=20, episodes=episodes, seed=s, eval_episodes=0).summary for s in range(seeds)]
        curve = [r["episodes_to_5pct"] for r in rows]
        greedy = [r["greedy_episodes_to_5pct"] for r in rows]
        never = episodes + 1  # medians count "never" as beyond the run
        out[spec.name] = {
            "episodes_to_5pct": curve,
            "greedy_episodes_to_5pct": greedy,
            "median_episodes_to_5pct": statistics.median(never if v is None else v for v in curve),
            "median_greedy_episodes_to_5pct": statistics.median(never if v is None else v for v in greedy),
            "seeds_with_episodes_to_5pct_at_most_60": sum(v is not None and v <= 60 for v in curve),
        }
    return out


if __name__ == "__main__":
    args = [int(a) for a in sys.argv[1:3]]
    print(json.dumps(main(*args), indent=2))

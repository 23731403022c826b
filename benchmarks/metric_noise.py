"""How noisy is ``episodes_to_5pct``? Score a fixed, converged policy with it.

Trains the paper's SARSA (5 trials x 3,000 episodes, seed 99), keeps the best
trial's greedy policy, then runs that *fixed* policy (no learning) through the
same 20-trial episode streams ``crmgrasp learn`` uses (seed 0) for 200 and for
2,000 episodes, and applies the ``episodes_to_5pct`` rule to its curve; then does
the same over 200 episodes for seeds 0-9 (the streams of
``benchmarks/learner_seeds.py``). A policy that does not learn can only fail the
rule by chance, so this is the best any learner can score.

Usage: ``python benchmarks/metric_noise.py``; prints one JSON object. ``main``'s arguments
shrink it (the tests' smoke run): the training episodes, the two curve lengths and the seeds of
the per-seed rule.
"""

import json

import numpy as np

from crmgrasp import paper_box
from crmgrasp.agents import GreedyPolicy, episodes_to_within, train_trials
from crmgrasp.agents.training import encoder_for, run_episode, trial_generators


def main(train_episodes: int = 3000, lengths: tuple[int, int] = (200, 2000), seeds: int = 10) -> dict:
    task = paper_box()
    res = train_trials(task, "sarsa", trials=5, episodes=train_episodes, seed=99, eval_episodes=2000)
    best = int(np.argmin(res.greedy_steps.mean(axis=1)))
    policy = GreedyPolicy.from_agent(task, 2, res.agents[best])
    enc = encoder_for(task, 2)
    out = {"fixed_policy_greedy_mean_steps": float(res.greedy_steps[best].mean())}

    def curve(seed: int, episodes: int) -> np.ndarray:
        steps = np.zeros((20, episodes))
        for t, (env_rng, agent_rng, _) in enumerate(trial_generators(seed, 20)):
            for e in range(episodes):
                steps[t, e] = run_episode(task, policy, enc, env_rng, agent_rng, learn=False)[0]
        return steps.mean(axis=0)

    for episodes in lengths:
        c = curve(0, episodes)
        ma = np.convolve(c, np.ones(10) / 10, mode="valid")
        out[f"episodes_to_5pct_over_{episodes}"] = episodes_to_within(c, task.reference_mean_steps)
        out[f"max_10_episode_average_over_{episodes}"] = round(float(ma.max()), 3)
        out[f"mean_over_{episodes}"] = round(float(c.mean()), 3)
    out[f"episodes_to_5pct_over_{lengths[0]}_seeds_0_{seeds - 1}"] = [
        episodes_to_within(curve(seed, lengths[0]), task.reference_mean_steps) for seed in range(seeds)
    ]
    print(json.dumps(out, indent=2))
    return out


if __name__ == "__main__":
    main()

"""Learning on the MuJoCo stand-in from scratch: success per seed, episode wall time, workers.

Protocol, per task and seed ``first .. first + SEEDS - 1``: one ``pooled-vi`` agent (k = 1,
the mirror quotient where the task declares one, no prior, no kinematic episode) learns for
EPISODES MuJoCo episodes (``crmgrasp.hardware.mujoco.steps.MujocoSteps``: the object free
on the table, the stand-in's sensor bias, drift, noise, tare and averaging; episodes end on
the sensed grasp); its greedy policy then runs SCORE MuJoCo episodes from worlds drawn from
one generator per seed. Success: the true least friction, from MuJoCo's contacts, at or
below ``mu_goal``. Printed per task: success and CRMs per seed, the seeds at or above 95% and
90%, the training episodes' median and 90th-percentile wall time (this process, one core),
the episodes MuJoCo ended early, and, for scale, a uniformly random policy's success and CRMs
on the same scoring worlds (within ``max_steps`` = 10 CRMs most random sequences grasp a box:
success alone is a weak test; the CRMs per episode tell the learned policy apart).

``--workers`` (``--workers-only``): the same ``crmgrasp learn --hand mujoco`` run (``learn``:
4 trials x ``--workers-episodes`` (100) episodes, no evaluation) with one and with two worker
processes, measured in this run; the ratio is the speed-up (the results are identical,
checked).

Usage: ``python benchmarks/mujoco_learning.py [--task paper-box --task cup-3d]
[--episodes 100 --episodes 200] [--seeds 10] [--first 0] [--score 100] [--workers]``.
Prints one JSON object; progress on stderr. About 3 min for paper-box at the defaults.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time

import numpy as np

from crmgrasp.agents.training import build_agent, encoder_for
from crmgrasp.experiments.learning import LearnerSpec, learn
from crmgrasp.experiments.physics_learning import score_on_mujoco, train_episodes
from crmgrasp.hardware.mujoco.steps import MujocoSteps
from crmgrasp.tasks import make_task


def one_task(name: str, episodes: int, seeds: range, score: int) -> dict:
    task = make_task(name)
    encoder = encoder_for(task, 1)
    params = {"symmetric": True} if task.symmetry is not None else {}
    rows, times, faults = [], [], {}
    for seed in seeds:
        agent = build_agent(task, encoder, "pooled-vi", params)
        steps = MujocoSteps(task)
        rngs = [np.random.default_rng(s) for s in np.random.SeedSequence(seed, spawn_key=(1,)).spawn(2)]
        _, _, seconds = train_episodes(task, agent, encoder, episodes, steps, rngs)
        times += seconds
        got = score_on_mujoco(task, agent, encoder, score, seed)
        for d in (steps.faults, got["faults"]):
            for k, v in d.items():
                faults[k] = faults.get(k, 0) + v
        blind = score_on_mujoco(task, build_agent(task, encoder, "random"), encoder, score, seed)
        rows.append({"seed": seed, "success": got["success"], "crms": round(got["crms"], 3)})
        rows[-1].update(random_success=blind["success"], random_crms=round(blind["crms"], 3))
        print(f"{name} seed {seed}: success {got['success']:.0%}, {got['crms']:.2f} CRMs", file=sys.stderr)
    success = [r["success"] for r in rows]
    return {
        "task": name,
        "mujoco_episodes": episodes,
        "score_episodes": score,
        "per_seed": rows,
        "seeds_at_95pct": sum(s >= 0.95 for s in success),
        "seeds_at_90pct": sum(s >= 0.90 for s in success),
        "mean_success": round(statistics.fmean(success), 4),
        "mean_crms": round(statistics.fmean(r["crms"] for r in rows), 3),
        "random_policy_mean_success": round(statistics.fmean(r["random_success"] for r in rows), 4),
        "random_policy_mean_crms": round(statistics.fmean(r["random_crms"] for r in rows), 3),
        "reference_crms_kinematic": task.reference_mean_steps,
        "episode_seconds_median": round(statistics.median(times), 4),
        "episode_seconds_p90": round(float(np.percentile(times, 90)), 4),
        "faults": faults,
    }


def workers(episodes: int) -> dict:
    task = make_task("paper-box")
    spec = LearnerSpec("pooled-vi", 1, {"symmetric": True})
    out: dict = {"trials": 4, "episodes": episodes}
    runs = {}
    for jobs in (1, 2):
        t0 = time.perf_counter()
        runs[jobs] = learn(
            task,
            spec,
            trials=4,
            episodes=episodes,
            seed=0,
            eval_episodes=0,
            checkpoint_episodes=0,
            hand="mujoco",
            jobs=jobs,
        )
        out[f"seconds_{jobs}_worker"] = round(time.perf_counter() - t0, 2)
        print(f"workers {jobs}: {out[f'seconds_{jobs}_worker']} s", file=sys.stderr)
    same = np.array_equal(runs[1].result.steps, runs[2].result.steps)
    out["speedup_2_workers"] = round(out["seconds_1_worker"] / out["seconds_2_worker"], 2)
    out["identical_results"] = bool(same)
    return out


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--task", action="append", help="task (repeatable; default paper-box and cup-3d)")
    p.add_argument("--episodes", action="append", type=int, help="MuJoCo episodes per task, in order (100, 200)")
    p.add_argument("--seeds", type=int, default=10)
    p.add_argument("--first", type=int, default=0)
    p.add_argument("--score", type=int, default=100, help="MuJoCo episodes that score each greedy policy")
    p.add_argument("--workers", action="store_true", help="also time 1 against 2 worker processes")
    p.add_argument("--workers-episodes", type=int, default=100, help="episodes per trial of the workers run")
    p.add_argument("--workers-only", action="store_true", help="only the workers run")
    a = p.parse_args()
    tasks = a.task or ["paper-box", "cup-3d"]
    episodes = a.episodes or [100, 200][: len(tasks)]
    if len(episodes) != len(tasks):
        p.error("give one --episodes per --task")
    seeds = range(a.first, a.first + a.seeds)
    result = {"tasks": [] if a.workers_only else [one_task(t, e, seeds, a.score) for t, e in zip(tasks, episodes)]}
    if a.workers or a.workers_only:
        result["workers"] = workers(a.workers_episodes)
    print(json.dumps(result, indent=1))


if __name__ == "__main__":
    main()

"""Three-finger policies on the three-fingertip MuJoCo stand-in: learned on the kinematic model, transferred.

Per task (``triangles-3f``, ``box-family-3f``, ``cup-family-3f`` by default) and seed: one
``pooled-vi`` agent (k = 1, the mirror quotient where the task declares one; ``--learner`` and
``--k`` choose another learner and history order) learns for
EPISODES kinematic episodes; its greedy policy then runs WORLDS MuJoCo episodes
(``crmgrasp.experiments.physics_learning.score_on_mujoco``: worlds drawn from one generator
per seed, the object free on the table, three fingertips with the stand-in's sensor model;
an episode ends on the sensed grasp or after ``max_steps`` CRMs) and, for comparison, 1,000
kinematic episodes. ``--learner policy-search`` (the k-order policy search of
``crmgrasp.planners.korder`` from a blank table: a learner from simulated episodes, its budget
the episodes it re-runs) and ``--learner korder-search`` (the same search from the
belief-optimal policy projected onto k-order histories: a planner, it uses the hidden
states) search on ``--search-worlds`` kinematic worlds (seed 10,000 + seed) instead of
learning from EPISODES episodes; their row adds the policy's mean cost on the worlds searched
(and the belief optimum there, for ``korder-search``). With ``--mujoco-episodes N`` a learner
then goes on learning for N episodes on the MuJoCo stand-in itself (the fine-tuning of
``crmgrasp reproduce physics-learning``: the same agent, its counts from both; episodes end on
the *sensed* grasp; worlds from their own generator, not the scoring one). Success on MuJoCo: the true least
friction from MuJoCo's contacts at or below ``mu_goal``. Printed per task: MuJoCo successes
out of WORLDS and CRMs per seed (with more than 20 worlds, also the successes on the first 20,
the worlds of a 20-world run), the worlds lost that ran to the step limit (the rest of the
worlds lost ended on a sensed grasp that MuJoCo's contacts do not confirm, or early), the
kinematic greedy success and CRMs, and the episodes MuJoCo ended early.

Usage: ``python benchmarks/mujoco_three_fingers.py [--task triangles-3f ...] [--episodes 3000]
[--worlds 20] [--seeds 3] [--first-seed 0] [--learner pooled-vi] [--k 1] [--param KEY=VALUE ...]
[--search-worlds 1000] [--mujoco-episodes 0] [--mirror]`` (``--param``: a
learner parameter, e.g. ``explore=1``; ``--mirror``: the learner on the mirror quotient of a
spatial task that has the symmetry undeclared, ``crmgrasp.tasks.spatial.mirrored``). Prints one
JSON object; progress on stderr. About 4 min at the defaults on 2 cores.
"""

from __future__ import annotations

import argparse
import json
import sys
import time

import numpy as np

from crmgrasp._validation import CrmgraspError, setting
from crmgrasp.agents.training import AGENTS, encoder_for, evaluate, train_trials
from crmgrasp.experiments.physics_learning import score_on_mujoco, train_episodes
from crmgrasp.hardware.mujoco.steps import MujocoSteps
from crmgrasp.planners.korder import korder_search
from crmgrasp.planners.references import sample_starts
from crmgrasp.tasks import make_task
from crmgrasp.tasks.spatial import MIRROR_INVARIANT, mirrored

SEARCHES = {"policy-search": "blank", "korder-search": "belief"}
"""The k-order policy search's two starts (``crmgrasp plan --init``), by the name ``--learner`` takes."""


def one(
    name: str,
    episodes: int,
    worlds: int,
    seed: int,
    learner: str = "pooled-vi",
    k: int = 1,
    extra: dict | None = None,
    search_worlds: int = 1000,
    mujoco_episodes: int = 0,
    mirror: bool = False,
) -> dict:
    task = mirrored(make_task(name)) if mirror else make_task(name)
    t0 = time.perf_counter()
    encoder = encoder_for(task, k)
    row: dict = {"seed": seed}
    if learner in SEARCHES:
        found = korder_search(task, sample_starts(task, search_worlds, 10_000 + seed), k=k, init=SEARCHES[learner])
        agent = found.policy
        row["kinematic_episodes"] = found.episodes
        row["cost_on_worlds_searched"] = round(found.mean_cost, 3)
        if found.belief_optimum is not None:
            row["belief_optimum_on_worlds_searched"] = round(found.belief_optimum, 3)
    else:
        params = {**({"symmetric": True} if task.symmetry is not None else {}), **(extra or {})}
        res = train_trials(task, learner, trials=1, episodes=episodes, seed=seed, k=k, eval_episodes=0, params=params)
        agent = res.agents[0]
        row["kinematic_episodes"] = episodes
        if mujoco_episodes:
            rngs = [np.random.default_rng(s) for s in np.random.SeedSequence(seed, spawn_key=(1,)).spawn(2)]
            hand = MujocoSteps(task)
            _, sensed, _ = train_episodes(task, agent, encoder, mujoco_episodes, hand, rngs)
            row |= {"mujoco_episodes": mujoco_episodes, "mujoco_training_sensed_grasps": int(sum(sensed))}
            row["mujoco_training_faults"] = dict(hand.faults)
    steps, success = evaluate(task, agent, encoder, 1000, np.random.default_rng(seed + 1))
    got = score_on_mujoco(task, agent, encoder, worlds, seed)
    row |= {
        "mujoco_successes": round(got["success"] * worlds),
        "mujoco_crms": round(got["crms"], 3),
        "kinematic_success": round(float(success.mean()), 4),
        "kinematic_crms": round(float(steps.mean()), 3),
        "faults": got["faults"],
        "mujoco_lost_at_step_limit": sum(
            not ok and n >= task.max_steps for ok, n in zip(got["outcomes"], got["episode_crms"], strict=True)
        ),
        "seconds": round(time.perf_counter() - t0, 1),
    }
    if worlds > 20:  # the worlds of a 20-world run come first
        row["mujoco_successes_first_20"] = sum(got["outcomes"][:20])
    print(f"{name} seed {seed}: {row}", file=sys.stderr)
    return row


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--task", action="append", help="task (repeatable)")
    p.add_argument("--episodes", type=int, default=3000, help="kinematic training episodes")
    p.add_argument("--worlds", type=int, default=20, help="MuJoCo worlds per policy")
    p.add_argument("--seeds", type=int, default=3)
    p.add_argument("--first-seed", type=int, default=0, help="seeds FIRST_SEED .. FIRST_SEED + SEEDS - 1")
    p.add_argument(
        "--learner",
        choices=(*AGENTS, *SEARCHES),
        default="pooled-vi",
        help="the learner (an agent of crmgrasp learn, or the k-order policy search)",
    )
    p.add_argument("--search-worlds", type=int, default=1000, help="kinematic worlds of the policy search")
    p.add_argument("--k", type=int, default=1, help="its history order")
    p.add_argument(
        "--mujoco-episodes", type=int, default=0, help="episodes the learner then learns on the MuJoCo stand-in"
    )
    p.add_argument(
        "--param",
        action="append",
        default=[],
        metavar="KEY=NUMBER|true|false",
        type=setting,
        help="a learner parameter",
    )
    p.add_argument(
        "--mirror", action="store_true", help=f"the learner on the mirror quotient of {', '.join(MIRROR_INVARIANT)}"
    )
    a = p.parse_args()
    if a.search_worlds < 1:
        p.error(f"--search-worlds must be at least 1, got {a.search_worlds}")
    if a.mujoco_episodes < 0 or (a.mujoco_episodes and a.learner in SEARCHES):
        p.error(f"--mujoco-episodes must be at least 0, and 0 for a search, got {a.mujoco_episodes}")
    extra = dict(a.param)
    tasks = a.task or ["triangles-3f", "box-family-3f", "cup-family-3f"]
    try:
        for name in tasks if a.mirror else ():
            mirrored(make_task(name))
    except CrmgraspError as exc:
        p.error(str(exc))
    out = {"episodes": a.episodes, "worlds": a.worlds, "learner": a.learner, "k": a.k, "params": extra, "tasks": {}}
    out["mujoco_episodes"] = a.mujoco_episodes
    if a.mirror:
        out["mirror"] = True
    if a.learner in SEARCHES:
        out["search_worlds"] = a.search_worlds
    for name in tasks:
        rows = [
            one(name, a.episodes, a.worlds, seed, a.learner, a.k, extra, a.search_worlds, a.mujoco_episodes, a.mirror)
            for seed in range(a.first_seed, a.first_seed + a.seeds)
        ]
        out["tasks"][name] = {
            "per_seed": rows,
            "median_mujoco_successes": float(np.median([r["mujoco_successes"] for r in rows])),
            "seeds_at_18_of_20": sum(r["mujoco_successes"] >= 0.9 * a.worlds for r in rows),
        }
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()

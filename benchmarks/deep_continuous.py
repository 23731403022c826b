"""The deep peer in the continuous action space: RecurrentPPO on a contact pair and a real offset.

Trains sb3-contrib's RecurrentPPO (extra ``crmgrasp[deep]``) through ``FlatCRMAction`` on
paper-box with the paper's hand (palm tolerance 1e-9: the grasping opposition is the single
offset ``r = 0``) and with a palm that tolerates a 10 degree tilt (``r`` within 5 mm grasps),
and, as the peer, RecurrentPPO on the same two tasks' four hand-picked CRMs. Each policy is
evaluated greedily on the same 500 fresh starts.

With ``--sac EPISODES``, instead: stable-baselines3's SAC (``crmgrasp learn --agent sac``: an
MLP on the current observation, continuous actions only) on the same two tasks, ``TRIALS``
trials (default 3) of ``EPISODES`` task episodes each, every trial evaluated greedily on 1,000
fresh episodes (``train_deep_trials``, as ``learn`` runs it).

Prints one JSON object. Usage: ``python benchmarks/deep_continuous.py [STEPS] [SEED]``
(default 150,000 environment steps, seed 0; about 5 minutes on 2 cores), or
``python benchmarks/deep_continuous.py --sac EPISODES [TRIALS] [SEED]``.
"""

from __future__ import annotations

import dataclasses
import json
import math
import sys
import time
from typing import Any

import numpy as np

from crmgrasp.agents.deep import RecurrentPPOConfig, evaluate_recurrent, train_recurrent_ppo
from crmgrasp.tasks import Task, make_task


def tasks() -> dict[str, Task]:
    """paper-box, and paper-box with a palm that tolerates a 10 degree tilt."""
    box = make_task("paper-box")
    tilt = dataclasses.replace(box.hand, palm_normal_tol=math.sin(math.radians(10)))
    return {"paper-box": box, "paper-box, palm tolerance 10 deg": dataclasses.replace(box, hand=tilt)}


def main(steps: int = 150_000, seed: int = 0, episodes: int = 500) -> dict[str, Any]:
    out: dict[str, Any] = {"steps": steps, "seed": seed, "eval_episodes": episodes}
    for name, task in tasks().items():
        rng = np.random.default_rng(seed + 123)
        starts = [task.sample_world(rng) for _ in range(episodes)]
        for continuous in (True, False):
            t0 = time.perf_counter()
            cfg = RecurrentPPOConfig(total_steps=steps, continuous=continuous, checkpoint_episodes=0)
            run = train_recurrent_ppo(task, seed, cfg)
            crms, ok = evaluate_recurrent(run.model, task, starts, np.random.default_rng(seed))
            out[f"{name}: {'pair and offset' if continuous else 'hand-picked CRMs'}"] = {
                "greedy_crms": round(float(crms.mean()), 3),
                "success": round(float(ok.mean()), 3),
                "training_episodes": len(run.episode_steps),
                "seconds": round(time.perf_counter() - t0, 1),
            }
    return out


def sac(episodes: int, trials: int = 3, seed: int = 0, eval_episodes: int = 1000) -> dict[str, Any]:
    """SAC's greedy CRMs and success per trial on the two tasks (see the module docstring)."""
    from crmgrasp.agents.deep_trials import train_deep_trials

    out: dict[str, Any] = {"agent": "sac", "episodes": episodes, "trials": trials, "seed": seed}
    for name, task in tasks().items():
        t0 = time.perf_counter()
        res = train_deep_trials(task, "sac", trials=trials, episodes=episodes, seed=seed, eval_episodes=eval_episodes)
        out[name] = {
            "greedy_crms": [round(float(v), 3) for v in res.greedy_steps.mean(axis=1)],
            "success": [round(float(v), 3) for v in res.greedy_success.mean(axis=1)],
            "seconds": round(time.perf_counter() - t0, 1),
        }
    return out


if __name__ == "__main__":
    if sys.argv[1:2] == ["--sac"]:
        print(json.dumps(sac(*(int(a) for a in sys.argv[2:5])), indent=2))
    else:
        print(json.dumps(main(*(int(a) for a in sys.argv[1:3])), indent=2))

"""Lockstep (batched) training gives exactly the sequential results."""

import dataclasses
import math

import numpy as np
import pytest

from crmgrasp import SensorNoise, make_task
from crmgrasp.agents.lockstep import train_trials_lockstep
from crmgrasp.agents.training import train_trials

from .strategies import BACKENDS


@pytest.mark.parametrize(
    "agent, params, k, noisy",
    [
        ("sarsa", {}, 2, False),
        ("q", {"epsilon": 0.1}, 1, False),
        ("sarsa-lambda", {"trace": "accumulating"}, 2, False),
        ("dyna-q", {"n_planning": 5}, 1, False),
        ("dyna-q", {"planning": "sweep", "n_planning": 10}, 1, False),
        ("dyna-q", {"planning": "sweep", "n_planning": 10, "symmetric": True}, 1, False),
        ("sarsa", {"symmetric": True}, 2, True),
        ("sarsa", {}, 2, True),
    ],
)
@pytest.mark.parametrize("backend", BACKENDS)
def test_lockstep_equals_sequential(agent, params, k, noisy, backend):
    task = make_task("paper-box")
    if noisy:
        hand = dataclasses.replace(task.hand, palm_normal_tol=math.sin(math.radians(10)))
        task = dataclasses.replace(task, noise=SensorNoise(math.radians(3), 0.002), hand=hand)
    kw = dict(trials=6, episodes=60, seed=11, k=k, eval_episodes=30, params=params, checkpoints=(5, 20, 60))
    a = train_trials(task, agent, **kw)
    b = train_trials_lockstep(task, agent, **kw, backend=backend)
    np.testing.assert_array_equal(a.steps, b.steps)
    np.testing.assert_array_equal(a.success, b.success)
    np.testing.assert_array_equal(a.greedy_steps, b.greedy_steps)
    np.testing.assert_array_equal(a.checkpoint_steps, b.checkpoint_steps)
    assert [x.q for x in a.agents] == [y.q for y in b.agents]

"""The compiled single step of three or more spatial contacts
(crmgrasp.kernels.fingers3d.FusedFingersSpatialKernel) against the readable rules, bit for bit."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from crmgrasp._validation import CrmgraspError
from crmgrasp.kernels import kernel_for
from crmgrasp.model.sensing import SensorNoise
from crmgrasp.model.spatial import CRM3D
from crmgrasp.tasks import make_task

TRIPODS = ("cup-3d-3f", "box-3d-3f")


def _same_episodes(task, actions, seed: int) -> int:
    """Step the compiled and the readable kernel side by side (resets through each one's
    start rule), asserting every outcome equal; returns the episodes run."""
    fast, slow = kernel_for(task, "auto"), kernel_for(task, "reference")
    rng_f, rng_s = np.random.default_rng(seed), np.random.default_rng(seed)
    a, b = fast.begin(fast.sample_start(rng_f), rng_f), slow.begin(slow.sample_start(rng_s), rng_s)
    episodes = 1
    for action in actions:
        assert a == b
        if a.terminated or a.truncated:
            a, b = fast.begin(fast.sample_start(rng_f), rng_f), slow.begin(slow.sample_start(rng_s), rng_s)
            episodes += 1
        else:
            a, b = fast.step_one(a.state, action, rng_f), slow.step_one(b.state, action, rng_s)
    assert a == b
    assert rng_f.random() == rng_s.random()  # the same draws
    return episodes


@pytest.mark.parametrize("name", TRIPODS)
def test_fused_tripod_steps_equal_the_readable_rules(name: str) -> None:
    """Random CRMs of the task over many episodes (starts, every error, grasps): the same
    configurations, observations, bins, least friction, rewards and ends."""
    task = make_task(name)
    assert kernel_for(task).current.name == "numba-spatial-fingers-fused"
    actions = np.random.default_rng(1).integers(len(task.actions), size=250).tolist()
    assert _same_episodes(task, actions, 3) >= 20


@pytest.mark.parametrize("name", TRIPODS)
def test_fused_tripod_continuous_crms_and_no_table(name: str) -> None:
    """CRMs with random real offsets (any pair, a contact onto itself included), and the
    same task without a table: still bit for bit."""
    task = make_task(name)
    rng = np.random.default_rng(7)
    labels, reach = task.hand.labels, task.hand.reach / math.sqrt(2.0)
    crms = [
        CRM3D(labels[int(c)], labels[int(f)], (float(r1), float(r2)))
        for c, f, r1, r2 in zip(
            rng.integers(3, size=100), rng.integers(3, size=100), *rng.uniform(-reach, reach, size=(2, 100))
        )
    ]
    _same_episodes(task, crms, 4)
    inst = task.instance(np.random.default_rng(0))
    bare = dataclasses.replace(inst, table=None, family=None)
    assert kernel_for(bare).name == "numba-spatial-fingers-fused"
    _same_episodes(bare, np.random.default_rng(2).integers(len(task.actions), size=100).tolist(), 5)


def test_fused_tripod_step_row_and_the_seam() -> None:
    """`step_row` equals `step_one` of the same CRM; noise keeps the readable CRMs with the
    compiled least friction, and ``"numba"`` with noise is a one-line error."""
    task = make_task("cup-3d-3f").instance(np.random.default_rng(1))
    kernel = kernel_for(task)
    rng = np.random.default_rng(0)
    now = kernel.begin(kernel.sample_start(rng), rng)
    crm = CRM3D("c", "a", (0.01, -0.02))
    assert kernel.step_row(now.state, kernel.crm_row(crm), rng) == kernel.step_one(now.state, crm, rng)
    noisy = dataclasses.replace(task, noise=SensorNoise(0.05, 0.001))
    assert kernel_for(noisy).name == "numba-spatial-fingers"
    with pytest.raises(CrmgraspError, match="noise-free"):
        kernel_for(noisy, "numba")

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
def test_a_decided_friction_changes_nothing_else(name: str) -> None:
    """``kernel_for(task, friction="decided")``: over random CRMs and many episodes the same
    states, observations, bins, errors, rewards and ends as the exact kernel, from the same
    draws; each least friction replaced by a bound on the same side of ``mu_goal``; and the
    environment with ``exact_friction=False`` steps the same, without ``min_friction``."""
    import gymnasium as gym

    task = make_task(name)
    exact, decided = kernel_for(task), kernel_for(task, friction="decided")
    rng_e, rng_d = np.random.default_rng(5), np.random.default_rng(5)
    a, b = exact.begin(exact.sample_start(rng_e), rng_e), decided.begin(decided.sample_start(rng_d), rng_d)
    moved = 0
    for action in np.random.default_rng(6).integers(len(task.actions), size=300).tolist():
        assert a._replace(min_friction=0.0) == b._replace(min_friction=0.0)
        assert task.grasped(a.min_friction) == task.grasped(b.min_friction)
        assert b.min_friction >= a.min_friction if task.grasped(a.min_friction) else b.min_friction <= a.min_friction
        moved += a.min_friction != b.min_friction
        if a.terminated or a.truncated:
            a, b = exact.begin(exact.sample_start(rng_e), rng_e), decided.begin(decided.sample_start(rng_d), rng_d)
        else:
            a, b = exact.step_one(a.state, action, rng_e), decided.step_one(b.state, action, rng_d)
    assert moved > 20 and rng_e.random() == rng_d.random()
    env_id = {"cup-3d-3f": "crmgrasp/Cup3D3F-v0", "box-3d-3f": "crmgrasp/Box3D3F-v0"}[name]
    full, lean = gym.make(env_id), gym.make(env_id, exact_friction=False)
    (o1, i1), (o2, i2) = full.reset(seed=1), lean.reset(seed=1)
    for action in np.random.default_rng(8).integers(len(task.actions), size=60).tolist():
        assert {**o1, "error": 0}.keys() == o2.keys() and all(np.array_equal(o1[k], o2[k]) for k in o1)
        assert "min_friction" not in i2 and i2 == {k: v for k, v in i1.items() if k != "min_friction"}
        o1, r1, t1, u1, i1 = full.step(action)
        o2, r2, t2, u2, i2 = lean.step(action)
        assert (r1, t1, u1) == (r2, t2, u2)
        if t1 or u1:
            (o1, i1), (o2, i2) = full.reset(), lean.reset()


def test_the_vector_environment_takes_exact_friction() -> None:
    """``make_vec`` with ``exact_friction=False``: the same batched observations, rewards and
    ends as the default, and no ``min_friction`` in ``info``."""
    import gymnasium as gym

    envs = [
        gym.make_vec("crmgrasp/Cup3D3F-v0", num_envs=3, vectorization_mode="vector_entry_point", **kw)
        for kw in ({}, {"exact_friction": False})
    ]
    (o1, i1), (o2, i2) = (env.reset(seed=4) for env in envs)
    rng = np.random.default_rng(2)
    for _ in range(40):
        assert all(np.array_equal(o1[k], o2[k]) for k in o1) and "min_friction" not in i2
        assert np.array_equal(i1["obs_index"], i2["obs_index"]) and "min_friction" in i1
        actions = rng.integers(envs[0].single_action_space.n, size=3)
        (o1, r1, t1, u1, i1), (o2, r2, t2, u2, i2) = (env.step(actions) for env in envs)
        assert np.array_equal(r1, r2) and np.array_equal(t1, t2) and np.array_equal(u1, u2)


def test_the_friction_argument_is_checked() -> None:
    """An unknown ``friction`` or a non-boolean ``exact_friction``: a one-line error."""
    import gymnasium as gym

    with pytest.raises(CrmgraspError, match="unknown friction 'rough'"):
        kernel_for(make_task("box-3d-3f"), friction="rough")
    with pytest.raises(CrmgraspError, match="exact_friction must be true or false"):
        gym.make("crmgrasp/Box3D3F-v0", exact_friction=1)


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


def test_fused_tripod_on_a_mesh() -> None:
    """Three fingers on an open cup (a non-convex mesh): the compiled steps are the readable
    rules' too."""
    from crmgrasp.model.mesh import open_cup

    task = dataclasses.replace(make_task("cup-3d-3f").instance(np.random.default_rng(0)), obj=open_cup(0.05, 0.12))
    assert kernel_for(task).name == "numba-spatial-fingers-fused"
    _same_episodes(task, np.random.default_rng(3).integers(len(task.actions), size=120).tolist(), 6)


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

import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import crmgrasp
from crmgrasp import CRMGraspEnv, CrmgraspError, KOrderHistory
from crmgrasp.envs.single import ENV_ID


def test_check_env_passes_without_warnings():
    env = gym.make(ENV_ID)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_env(env.unwrapped)


def _trajectory(seed):
    env = gym.make(ENV_ID)
    obs, info = env.reset(seed=seed)
    out = [(obs["rho"].item(), obs["m_a"].item(), info["obs_index"])]
    rng = np.random.default_rng(seed)
    for _ in range(30):
        obs, r, term, trunc, info = env.step(int(rng.integers(4)))
        out.append((obs["rho"].item(), obs["m_a"].item(), obs["error"], r, term, trunc, info["obs_index"]))
        if term or trunc:
            obs, info = env.reset()
    return out


def test_deterministic_under_seed():
    assert _trajectory(5) == _trajectory(5)
    assert _trajectory(5) != _trajectory(6)


def test_success_terminates_and_failures_truncate(task):
    env = CRMGraspEnv(task)
    near = task.hand.contact(task.obj, (-0.15, -0.02), (-0.10, -0.05))
    obs, info = env.reset(seed=0, options={"config": near})
    assert info["obs_index"] == task.discretizer.index(crmgrasp.observe(near), 0)
    obs, r, term, trunc, info = env.step(0)
    assert (r, term, trunc) == (-1.0, True, False) and info["min_friction"] == 0.0
    env.reset(seed=0, options={"config": near})
    for i in range(task.max_steps):
        obs, r, term, trunc, info = env.step(1)  # C2 is an aperture error every time
        assert obs["error"] == 1 and not term
        assert trunc == (i == task.max_steps - 1)
    assert info["config"] == near


def test_render_and_bad_actions(task):
    env = CRMGraspEnv(task, render_mode="rgb_array")
    env.reset(seed=0)
    img = env.render()
    assert img.shape[2] == 3 and img.dtype == np.uint8
    env.step(0)
    assert env.render().shape == img.shape
    with pytest.raises(CrmgraspError, match="action must be an integer in"):
        env.step(7)
    with pytest.raises(CrmgraspError, match="reset"):
        CRMGraspEnv(task).step(0)
    with pytest.raises(CrmgraspError, match="render_mode"):
        CRMGraspEnv(task, render_mode="human")


def test_k_order_wrapper(task):
    env = KOrderHistory(gym.make(ENV_ID), k=2)
    assert env.observation_space.n == 15000 and env.encoder.unpadded_size == 9216
    s, info = env.reset(seed=3)
    assert env.encoder.decode(s) == (info["obs_index"], 4, 24, 4)
    s2, _, _, _, info2 = env.step(2)
    assert env.encoder.decode(s2) == (info2["obs_index"], 2, info["obs_index"], 4)
    e0 = KOrderHistory(gym.make(ENV_ID), k=0)
    s, info = e0.reset(seed=3)
    assert s == info["obs_index"] and e0.observation_space.n == 24


def _run(env, seed, n=3000):
    rng = np.random.default_rng(seed)
    obs, info = env.reset(seed=seed)
    out = []
    for _ in range(n):
        obs, r, term, trunc, info = env.step(int(rng.integers(4)))
        out.append(
            (
                obs["rho"].item(),
                obs["m_a"].item(),
                obs["m_b"].item(),
                obs["error"],
                r,
                term,
                trunc,
                info["obs_index"],
                info["min_friction"],
                info["config"],
                info["steps"],
            )
        )
        if term or trunc:
            obs, info = env.reset()
    return out


@pytest.mark.parametrize("noisy", [False, True])
def test_every_backend_gives_the_same_episodes(task, noisy):
    """The env on the compiled kernel and on the reference kernel (sim.step) agree."""
    from dataclasses import replace

    from crmgrasp import SensorNoise

    if noisy:
        task = replace(task, noise=SensorNoise(0.05, 0.002))
    fast = CRMGraspEnv(task, backend="numba")
    slow = CRMGraspEnv(task, backend="reference")
    assert (fast.kernel.name, slow.kernel.name) == ("numba-polygon" + ("" if noisy else "-fused"), "reference")
    assert _run(fast, 3) == _run(slow, 3)


def test_starts_come_in_blocks_but_reseeding_restarts_them(task):
    env = CRMGraspEnv(task)
    first = [env.reset(seed=1)[1]["config"]] + [env.reset()[1]["config"] for _ in range(100)]
    again = [env.reset(seed=1)[1]["config"]] + [env.reset()[1]["config"] for _ in range(100)]
    assert first == again and len(set(first)) == len(first)
    assert all(task.hand.feasible(task.obj, c) == 0 and not task.is_success(c) for c in first)


def test_the_history_wrapper_passes_check_env_and_is_recreated_from_its_spec():
    """KOrderHistory records its ``k``: Gymnasium's checker can rebuild it from the spec."""
    env = KOrderHistory(gym.make("crmgrasp/PaperBox-v0"), k=1)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        check_env(env)
    assert all("different from the unwrapped version" in str(w.message) for w in caught)
    again = env.spec.make()
    assert isinstance(again, KOrderHistory) and again.encoder.k == 1
    assert again.reset(seed=3)[0] == env.reset(seed=3)[0]


def test_mujoco_envs_are_registered_and_name_a_missing_extra(hide_module):
    """Without MuJoCo, making a MuJoCo environment is one line naming the extra."""
    from crmgrasp.envs.single import MUJOCO_ENVS

    assert set(MUJOCO_ENVS) <= set(gym.registry)
    hide_module("mujoco")
    with pytest.raises(
        CrmgraspError, match=r"^the MuJoCo stand-in needs the optional extra: pip install 'crmgrasp\[mujoco\]'"
    ):
        gym.make("crmgrasp/PaperBoxMujoco-v0")
    with pytest.raises(CrmgraspError, match=r"crmgrasp\[mujoco\]"):
        from crmgrasp.hardware import hand_steps

        hand_steps("mujoco")

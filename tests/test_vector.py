"""The batched vector environment: construction, spaces, seeding, NEXT_STEP autoreset."""

import gymnasium as gym
import numpy as np
import pytest

import crmgrasp  # noqa: F401
from crmgrasp import Config, Contact, CrmgraspError, min_friction
from crmgrasp.envs.single import ENV_ID
from crmgrasp.envs.vector import CRMGraspVectorEnv, FamilyVectorEnv
from crmgrasp.model.hand import execute_crm, feasible
from crmgrasp.model.sensing import Error

from .strategies import BACKENDS


def test_make_vec_and_spaces():
    env = gym.make_vec(ENV_ID, num_envs=16, vectorization_mode="vector_entry_point")
    assert isinstance(env.unwrapped, CRMGraspVectorEnv) and env.num_envs == 16
    assert env.metadata["autoreset_mode"] == gym.vector.AutoresetMode.NEXT_STEP
    obs, info = env.reset(seed=0)
    assert obs in env.observation_space
    assert info["obs_index"].shape == (16,) and info["config"].shape == (16, 8)
    for _ in range(30):
        obs, rew, term, trunc, info = env.step(env.action_space.sample())
        assert obs in env.observation_space
        assert rew.shape == term.shape == trunc.shape == (16,)


def _run(seed, n=8, steps=25):
    env = CRMGraspVectorEnv(n)
    out = [env.reset(seed=seed)[1]["config"]]
    rng = np.random.default_rng(seed)
    for _ in range(steps):
        obs, rew, term, trunc, info = env.step(rng.integers(4, size=n))
        out.append(np.concatenate([info["config"].ravel(), rew, term, trunc, obs["rho"].ravel()]))
    return out


def test_seeded_determinism():
    a, b, c = _run(3), _run(3), _run(4)
    assert all(np.array_equal(x, y) for x, y in zip(a, b))
    assert not all(np.array_equal(x, y) for x, y in zip(a, c))


def test_starts_are_valid_paper_box_starts(task):
    env = CRMGraspVectorEnv(512)
    _, info = env.reset(seed=1)
    for row in info["config"][:200]:
        cfg = Config(Contact(*row[:4]), Contact(*row[4:]))
        assert feasible(task.obj, task.hand, cfg) is Error.NONE and min_friction(cfg) > task.mu_goal
        assert len({task.obj.edge_index(c.point) for c in cfg}) == 2
    # both corner families occur, roughly as often as the scalar sampler gives them
    near = np.mean(np.abs(info["config"][:, 0]) > 0.14)
    assert 0.2 < near < 0.8


@pytest.mark.parametrize("backend", BACKENDS)
def test_step_matches_the_scalar_simulator(task, backend):
    env = CRMGraspVectorEnv(64, backend=backend)
    _, info = env.reset(seed=2)
    before = info["config"].copy()
    actions = np.random.default_rng(0).integers(4, size=64)
    obs, rew, term, _, info = env.step(actions)
    for i in range(64):
        cfg = Config(Contact(*before[i, :4]), Contact(*before[i, 4:]))
        out = execute_crm(task.obj, task.hand, cfg, task.actions[actions[i]], cfg)
        assert tuple(info["config"][i]) == tuple(np.asarray(out.config).ravel())
        assert obs["error"][i] == int(out.error) and rew[i] == -1.0
        assert term[i] == (min_friction(out.config) <= task.mu_goal)


def test_next_step_autoreset():
    env = CRMGraspVectorEnv(32)
    env.reset(seed=5)
    rng = np.random.default_rng(5)
    done_prev = np.zeros(32, bool)
    seen_reset = False
    for _ in range(40):
        obs, rew, term, trunc, info = env.step(rng.integers(4, size=32))
        # rows that ended last step were reset now: reward 0, not done, step counter 0, no error
        assert np.all(rew[done_prev] == 0.0) and not term[done_prev].any() and not trunc[done_prev].any()
        assert np.all(info["steps"][done_prev] == 0) and np.all(obs["error"][done_prev] == 0)
        assert np.all(rew[~done_prev] == -1.0) and np.all(info["steps"][~done_prev] >= 1)
        seen_reset |= done_prev.any()
        assert not (term & trunc).any()
        done_prev = term | trunc
    assert seen_reset


def test_bad_vector_input():
    with pytest.raises(CrmgraspError, match="num_envs"):
        CRMGraspVectorEnv(0)
    with pytest.raises(CrmgraspError, match=r"num_envs must be an integer in \[1, 1,000,000\], got 1000000000"):
        CRMGraspVectorEnv(10**9)  # refused before its spaces are allocated (once: 23 GB, then the OOM killer)
    env = CRMGraspVectorEnv(4)
    with pytest.raises(CrmgraspError, match="reset"):
        env.step(np.zeros(4, dtype=int))
    env.reset(seed=0)
    with pytest.raises(CrmgraspError, match="4 integers"):
        env.step(np.zeros(3, dtype=int))
    with pytest.raises(CrmgraspError, match=r"\[0, 4\)"):
        env.step(np.full(4, 9))
    with pytest.raises(CrmgraspError, match="takes no reset options"):
        env.reset(options={"config": None})


def test_the_class_is_picked_by_the_task_and_a_family_is_refused_at_construction() -> None:
    from crmgrasp.envs.vector import FamilyVectorEnv, vector_env

    assert type(vector_env(2, "paper-box")) is CRMGraspVectorEnv
    assert type(vector_env(2, "box-family")) is FamilyVectorEnv
    # the registered id takes any task, and builds the class that task needs
    vec = gym.make_vec("crmgrasp/PaperBox-v0", num_envs=2, vectorization_mode="vector_entry_point", task="box-3d")
    assert type(vec.unwrapped) is FamilyVectorEnv
    obs, _ = vec.reset(seed=0)
    assert obs["error"].shape == (2,)
    with pytest.raises(CrmgraspError, match="'box-3d' draws an object per episode: use CRMGraspVectorEnv's family"):
        CRMGraspVectorEnv(2, "box-3d")


@pytest.mark.parametrize("make", [lambda: CRMGraspVectorEnv(2), lambda: FamilyVectorEnv(2, "box-family")])
def test_a_reset_seed_is_checked_in_one_line(make):
    """Both vector environments check a reset's seed the same way (the family's went to
    Gymnasium's own error)."""
    env = make()
    for seed in (float("nan"), -1, "7x", 1.5):
        with pytest.raises(CrmgraspError, match="seed"):
            env.reset(seed=seed)
    assert env.reset(seed=3)[1]["obs_index"].shape == (2,)

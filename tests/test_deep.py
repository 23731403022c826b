"""The deep-RL peer: observation features, settings, and RecurrentPPO (extra ``crmgrasp[deep]``)."""

import csv
import sys
import tempfile

import numpy as np
import pytest

from crmgrasp import make_task
from crmgrasp._validation import CrmgraspError
from crmgrasp.agents.deep import (
    ContinuousObservation,
    RecurrentPPOConfig,
    deep_available,
    evaluate_recurrent,
    features,
    train_recurrent_ppo,
)
from crmgrasp.cli.main import main
from crmgrasp.envs.single import CRMGraspEnv
from crmgrasp.experiments.compare import CompareConfig, compare
from crmgrasp.experiments.learning import LearnerSpec

TINY = RecurrentPPOConfig(total_steps=512, n_envs=2, n_steps=64, checkpoint_episodes=10)


def test_features_scale_clip_and_one_hot():
    v = features((2.0, 0.16, -1.0), 2, ((0.0, 4.0), (-0.32, 0.32), (-0.32, 0.32)))
    np.testing.assert_allclose(v, [0.5, 0.5, -1.0, 0.0, 0.0, 1.0])
    assert v.dtype == np.float32


def test_continuous_observation_stays_in_its_space():
    env = ContinuousObservation(CRMGraspEnv("paper-box"))
    obs, _ = env.reset(seed=0)
    assert env.observation_space.contains(obs) and obs[3] == 1.0  # no error at reset
    rng = np.random.default_rng(0)
    for _ in range(200):
        obs, _, term, trunc, _ = env.step(int(rng.integers(4)))
        assert env.observation_space.contains(obs) and obs[3:].sum() == 1.0
        if term or trunc:
            obs, _ = env.reset()


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"total_steps": 0}, "total_steps"),
        ({"gamma": 1.5}, "gamma"),
        ({"n_envs": 2.5}, "n_envs"),
        ({"checkpoint_episodes": -1}, "checkpoint_episodes"),
    ],
)
def test_config_validates(kwargs, match):
    with pytest.raises(CrmgraspError, match=match):
        RecurrentPPOConfig(**kwargs)


def test_missing_extra_is_a_one_line_error(monkeypatch):
    monkeypatch.setitem(sys.modules, "sb3_contrib", None)
    assert not deep_available()
    with pytest.raises(CrmgraspError, match=r"crmgrasp\[deep\]"):
        train_recurrent_ppo(make_task("paper-box"), 0, TINY)


needs_deep = pytest.mark.skipif(not deep_available(), reason="needs the extra: pip install 'crmgrasp[deep]'")


@needs_deep
def test_training_is_deterministic_and_evaluates(tmp_path, monkeypatch):
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    task = make_task("paper-box")
    runs = [train_recurrent_ppo(task, 3, TINY) for _ in range(2)]
    assert not list(tmp_path.glob("SB3-*"))  # no stable-baselines3 log folder left behind
    np.testing.assert_array_equal(runs[0].episode_steps, runs[1].episode_steps)
    np.testing.assert_array_equal(runs[0].checkpoint_steps, runs[1].checkpoint_steps)
    assert runs[0].episode_steps.sum() <= TINY.total_steps and len(runs[0].checkpoints) == 4  # 512 / (2 * 64)
    starts = [task.sample_start(np.random.default_rng(i)) for i in range(20)]
    steps, ok = evaluate_recurrent(runs[0].model, task, starts, np.random.default_rng(0))
    assert steps.shape == ok.shape == (20,) and ((steps >= 1) & (steps <= task.max_steps)).all()
    assert (ok | (steps == task.max_steps)).all()


@needs_deep
def test_compare_has_the_deep_row(tmp_path):
    cfg = CompareConfig(
        trials=2,
        episodes=20,
        eval_episodes=20,
        reference_starts=200,
        learners=(LearnerSpec("random", 2, {}, "random"),),
        deep=TINY,
    )
    s = compare(tmp_path, cfg)
    with open(tmp_path / "compare.csv") as fh:
        rows = {r["method"]: r for r in csv.DictReader(fh)}
    row = rows["RecurrentPPO (LSTM 32), 512 steps"]
    assert row["kind"] == "learner" and 1.0 <= float(row["mean_crms"]) <= task_max()
    assert s["deep_rl"]["training_episodes"] > 0


def task_max() -> int:
    return make_task("paper-box").max_steps


def test_compare_cli_deep_steps_below_0_are_refused(tmp_path):
    """(``--deep-steps 0`` runs in ``tests/test_controller.py``.)"""
    with pytest.raises(SystemExit) as info:  # refused by the parser, before any work
        main(["compare", "--quick", "--deep-steps", "-5", "--out", str(tmp_path)])
    assert info.value.code == 2
    assert not any(tmp_path.iterdir())


@needs_deep
def test_recurrent_policy_saves_loads_predicts_and_runs(tmp_path, capsys):
    from crmgrasp.agents.deep import RecurrentPolicy
    from crmgrasp.agents.loading import load_policy
    from crmgrasp.cli import main
    from crmgrasp.model.sensing import observe

    task = make_task("paper-box")
    run = train_recurrent_ppo(task, 3, TINY)
    path = RecurrentPolicy(run.model, task).save(tmp_path / "deep.zip")
    policy = load_policy(path)  # by path alone: the file carries its task
    assert isinstance(policy, RecurrentPolicy) and policy.task == task
    starts = [task.sample_start(np.random.default_rng(i)) for i in range(10)]
    a = evaluate_recurrent(run.model, task, starts, np.random.default_rng(0))
    b = evaluate_recurrent(policy.model, task, starts, np.random.default_rng(0))
    np.testing.assert_array_equal(a[0], b[0])  # the same model
    first = (*observe(starts[0]), 0)
    assert policy.predict([first]) == int(
        run.model.predict(
            np.array([list(policy_features(task, first))], dtype=np.float32),
            deterministic=True,
            episode_start=np.array([True]),
        )[0][0]
    )
    assert main(["evaluate", "--policy", str(path), "--episodes", "5", "--json"]) == 0
    assert '"kind": "deep"' in capsys.readouterr().out
    log = tmp_path / "log.csv"
    assert main(["run", "--policy", str(path), "--a", "-0.15,-0.02", "--b", "-0.10,-0.05", "--log", str(log)]) == 0
    data = bytearray(path.read_bytes())
    data[len(data) // 2] ^= 0xFF
    (tmp_path / "bad.zip").write_bytes(bytes(data))
    assert main(["evaluate", "--policy", str(tmp_path / "bad.zip")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and ("damaged" in err or "checksum" in err)


def policy_features(task, obs):
    from crmgrasp.agents.deep import bounds_of, features

    return features(obs[:-1], obs[-1], bounds_of(task))


@needs_deep
def test_a_continuous_offset_peer_trains_saves_and_runs(tmp_path, capsys):
    """RecurrentPPO in the continuous action space (FlatCRMAction): deterministic for a seed,
    its actions are CRMs of the task's ranges, and its file loads, evaluates and runs."""
    from dataclasses import replace

    from crmgrasp.agents.deep import RecurrentPolicy
    from crmgrasp.agents.loading import load_policy
    from crmgrasp.cli import main
    from crmgrasp.model.hand import CRM
    from crmgrasp.model.sensing import observe

    task = make_task("paper-box")
    cfg = replace(TINY, continuous=True)
    runs = [train_recurrent_ppo(task, 3, cfg) for _ in range(2)]
    np.testing.assert_array_equal(runs[0].checkpoint_steps, runs[1].checkpoint_steps)
    assert runs[0].model.action_space.shape == (2,)
    path = RecurrentPolicy(runs[0].model, task).save(tmp_path / "deep.zip")
    policy = load_policy(path)
    assert policy.continuous
    starts = [task.sample_start(np.random.default_rng(i)) for i in range(10)]
    crm = policy.predict([(*observe(starts[0]), 0)])
    assert isinstance(crm, CRM) and abs(crm.r) <= task.hand.r_max
    assert policy.predict([(*observe(starts[0]), 0), (*observe(starts[0]), 1)], [crm]) is not None
    with pytest.raises(CrmgraspError):
        policy.predict([(*observe(starts[0]), 0), (*observe(starts[0]), 1)], [CRM("a", "b", 0.5)])
    steps, ok = evaluate_recurrent(policy.model, task, starts, np.random.default_rng(0))
    assert ((steps >= 1) & (steps <= task.max_steps)).all() and (ok | (steps == task.max_steps)).all()
    assert main(["evaluate", "--policy", str(path), "--episodes", "5", "--json"]) == 0
    capsys.readouterr()
    log = tmp_path / "log.csv"
    assert main(["run", "--policy", str(path), "--a", "-0.15,-0.02", "--b", "-0.10,-0.05", "--log", str(log)]) == 0
    assert "(" in log.read_text()  # the CRMs it executed, written out
    with pytest.raises(CrmgraspError, match="continuous must be true or false"):
        RecurrentPPOConfig(continuous=1)

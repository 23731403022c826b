"""What every saved policy offers: predict from a history, load by path, the env's limit."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import crmgrasp  # noqa: F401  (registers the environments)
from crmgrasp._validation import CrmgraspError
from crmgrasp.agents import GreedyPolicy
from crmgrasp.agents.loading import load_policy
from crmgrasp.agents.training import train_trials
from crmgrasp.cli import main
from crmgrasp.envs import KOrderHistory
from crmgrasp.tasks import paper_box


def _policy() -> GreedyPolicy:
    task = paper_box()
    res = train_trials(task, "sarsa", trials=1, episodes=300, seed=0, eval_episodes=0)
    return GreedyPolicy.from_agent(task, 2, res.agents[0])


def test_predict_matches_the_k_order_state_of_the_env():
    policy = _policy()
    env = KOrderHistory(gym.make("crmgrasp/PaperBox-v0"), k=2)
    for episode in range(20):
        state, info = env.reset(seed=episode)
        observations, actions = [int(info["obs_index"])], []
        done = False
        while not done:
            action = policy.greedy(state, np.random.default_rng(0))
            assert policy.predict(observations, actions) == action
            state, _, term, trunc, info = env.step(action)
            observations.append(int(info["obs_index"]))
            actions.append(action)
            done = term or trunc


def test_predict_takes_raw_observations_and_checks_the_history():
    policy = _policy()
    d = policy.task.discretizer
    raw = (2.0, 0.05, -0.12, 0)
    assert policy.predict([raw]) == policy.predict([d.index(raw[:-1], raw[-1])])
    for observations, actions, message in (
        ([], [], "one more observation"),
        ([0, 1], [], "one more observation"),
        ([0, 1], [7], "action 7"),
        ([999], [], "outside"),
        ([(float("nan"), 0, 0, 0)], [], "not finite"),
        (["x"], [], "an observation is an index"),
    ):
        with pytest.raises(CrmgraspError, match=message):
            policy.predict(observations, actions)


def test_load_policy_dispatches_and_env_has_a_limit(tmp_path):
    path = _policy().save(tmp_path / "p.json")
    assert isinstance(load_policy(path), GreedyPolicy)
    (tmp_path / "fake.zip").write_bytes(b"PK\x03\x04 not really")
    with pytest.raises(CrmgraspError, match=r"damaged|not a crmgrasp"):
        load_policy(tmp_path / "fake.zip")
    assert gym.make("crmgrasp/PaperBox-v0").spec.max_episode_steps == paper_box().max_steps


def test_internal_errors_are_one_line(monkeypatch, capsys):
    import importlib

    cli = importlib.import_module("crmgrasp.cli.main")

    def boom(args):
        raise ZeroDivisionError("deep inside\nsecond line")

    monkeypatch.setattr(cli, "_cmd_tasks", boom)
    monkeypatch.delenv("CRMGRASP_DEBUG", raising=False)
    assert main(["tasks"]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "internal error (ZeroDivisionError: deep inside second line)" in err


def test_a_policy_saved_before_a_key_was_written_still_loads(tmp_path):
    """A stored task spec is compared as today's writer states it: a file whose spec lacks
    a key that reads back as its default (``max_tries`` of the starts, written since) loads;
    one that differs in a value does not."""
    from crmgrasp.agents.policy import policy_digest

    policy = _policy()
    doc = policy.to_dict()
    assert doc["task_spec"]["starts"] == {"kind": "corners", "max_tries": 10_000}
    for change, ok in (
        (lambda s: s["starts"].pop("max_tries"), True),
        (lambda s: s["hand"].update(aperture=0.2), False),
    ):
        old = {k: v for k, v in policy.to_dict().items() if k != "sha256"}
        change(old["task_spec"])
        old["sha256"] = policy_digest(old)
        if ok:
            assert GreedyPolicy.from_dict(old, paper_box()).table == policy.table
        else:
            with pytest.raises(
                CrmgraspError, match=r"another version of task 'paper-box' \(it differs in hand.aperture\)"
            ):
                GreedyPolicy.from_dict(old, paper_box())

"""Deep learners in ``crmgrasp learn`` (RecurrentPPO, PPO, SAC; extra ``crmgrasp[deep]``)."""

import json
import zipfile

import numpy as np
import pytest

from crmgrasp import make_task
from crmgrasp._validation import CrmgraspError
from crmgrasp.agents.deep import DEEP_AGENTS, RecurrentPolicy, deep_available
from crmgrasp.agents.deep_trials import check_deep, deep_config, deep_settings, train_deep_trials
from crmgrasp.cli.main import main
from crmgrasp.experiments.learning import LearnerSpec, learn
from crmgrasp.experiments.runs import RunFolder

needs_deep = pytest.mark.skipif(not deep_available(), reason="needs the extra: pip install 'crmgrasp[deep]'")

TINY = ["--trials", "2", "--episodes", "30", "--eval-episodes", "10", "--checkpoint-episodes", "5", "--quiet"]


def test_deep_settings_and_their_errors():
    assert deep_config("ppo").continuous is False and deep_config("sac").continuous is True
    assert deep_config("recurrent-ppo", {"gamma": 0.5}).gamma == 0.5
    assert deep_settings("sac")["algorithm"] == "SAC" and "total_steps" not in deep_settings("ppo")
    with pytest.raises(CrmgraspError, match="continuous action space only"):
        deep_config("sac", {"continuous": False})
    with pytest.raises(CrmgraspError, match="has no parameter 'alpha'"):
        deep_config("ppo", {"alpha": 0.1})
    with pytest.raises(CrmgraspError, match="unknown deep learner"):
        deep_config("dqn")


def test_a_missing_extra_fails_before_any_folder(hide_module, tmp_path, capsys):
    hide_module("stable_baselines3.common.callbacks")
    with pytest.raises(CrmgraspError, match=r"crmgrasp\[deep\]"):
        check_deep("ppo")
    assert main(["learn", "--agent", "ppo", *TINY, "--out", str(tmp_path / "r")]) == 2
    assert "crmgrasp[deep]" in capsys.readouterr().err and not (tmp_path / "r").exists()


@pytest.mark.parametrize(
    "extra, message",
    [
        (["--agent", "ppo", "--symmetric"], "--symmetric does not apply to --agent ppo"),
        (["--agent", "sarsa", "--continuous"], "--continuous does not apply to --agent sarsa"),
        (["--agent", "ppo", "--alpha", "0.1"], "--alpha does not apply to --agent ppo"),
        (["--agent", "recurrent-ppo", "--k", "2"], "--k does not apply to --agent recurrent-ppo"),
        (["--agent", "ppo", "--lockstep"], "not with lockstep"),
    ],
)
def test_options_that_do_not_apply_are_one_line_errors(tmp_path, capsys, extra, message):
    assert main(["learn", *extra, *TINY, "--out", str(tmp_path / "r")]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1 and not (tmp_path / "r").exists()


@needs_deep
@pytest.mark.parametrize("agent, extra", [("ppo", []), ("recurrent-ppo", []), ("sac", []), ("ppo", ["--continuous"])])
def test_learn_trains_saves_and_evaluates_a_deep_learner(tmp_path, capsys, agent, extra):
    out = tmp_path / "run"
    assert main(["learn", "--agent", agent, *extra, *TINY, "--out", str(out)]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["agent"] == agent and summary["k"] is None and summary["label"] == agent
    assert summary["params"]["algorithm"] == DEEP_AGENTS[agent].algorithm
    assert summary["params"]["continuous"] is (agent == "sac" or extra == ["--continuous"])
    assert summary["episodes"] == 30 and 0.0 <= summary["greedy_success_rate"] <= 1.0
    curve = np.loadtxt(out / "curve.csv", delimiter=",", skiprows=1)
    assert curve.shape == (30, 3) and ((curve[:, 1] >= 1) & (curve[:, 1] <= 10)).all()
    assert not (out / "policy.json").exists()
    with zipfile.ZipFile(out / "policy.zip") as archive:
        assert json.loads(archive.read("crmgrasp.json"))["algorithm"] == DEEP_AGENTS[agent].algorithm
    policy = RecurrentPolicy.load(out / "policy.zip")
    assert type(policy.model).__name__ == DEEP_AGENTS[agent].algorithm
    assert policy.continuous is summary["params"]["continuous"]
    capsys.readouterr()
    assert main(["evaluate", "--policy", str(out / "policy.zip"), "--episodes", "5", "--json", "--quiet"]) == 0
    assert json.loads(capsys.readouterr().out)["kind"] == "deep"


@needs_deep
def test_deep_trials_do_not_depend_on_their_grouping_and_repeat_exactly():
    """Trial t draws from its own generator: trial 1 alone equals trial 1 of two, and a rerun
    gives the same curves, checkpoints, evaluations and weights."""
    task = make_task("paper-box")
    kw = {"episodes": 25, "seed": 4, "eval_episodes": 8, "checkpoints": (5, 20), "checkpoint_episodes": 6}
    both = train_deep_trials(task, "recurrent-ppo", trials=2, **kw)
    alone = train_deep_trials(task, "recurrent-ppo", trials=1, first_trial=1, **kw)
    for name in ("steps", "success", "greedy_steps", "greedy_success", "checkpoint_steps"):
        np.testing.assert_array_equal(getattr(both, name)[1:], getattr(alone, name), err_msg=name)
    assert list(both.checkpoints) == [5, 20]
    weights = [zipfile.ZipFile(__import__("io").BytesIO(r.agents[-1].data)).read("policy.pth") for r in (both, alone)]
    assert weights[0] == weights[1]


@needs_deep
def test_a_resumed_deep_run_loads_its_trials(tmp_path):
    task, spec = make_task("paper-box"), LearnerSpec("ppo", 1, {}, "ppo")
    kw = {"trials": 2, "episodes": 20, "seed": 1, "eval_episodes": 5, "checkpoint_episodes": 0}

    def run(resume: bool) -> object:
        with RunFolder(tmp_path / "r", "learn", task.name, {}, resume=resume) as folder:
            return learn(task, spec, store=folder, **kw)

    first, again = run(False), run(True)
    first.summary.pop("seconds"), again.summary.pop("seconds")
    assert first.summary == again.summary and first.policy == again.policy
    (tmp_path / "r" / "trials" / "00000_00000.policy.zip").write_bytes(b"not a zip")
    with pytest.raises(CrmgraspError, match="is damaged"):
        run(True)

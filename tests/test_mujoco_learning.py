"""Learning on the MuJoCo stand-in: its stepper, faults, Gymnasium environments and ``learn --hand mujoco``
(needs the extra ``crmgrasp[mujoco]``; skipped without it)."""

import json
import math

import gymnasium as gym
import numpy as np
import pytest

pytest.importorskip("mujoco", reason="MuJoCo learning tests need the extra: pip install 'crmgrasp[mujoco]'")

from gymnasium.utils.env_checker import check_env

from crmgrasp import make_task
from crmgrasp._validation import CrmgraspError
from crmgrasp.agents import train_trials
from crmgrasp.cli.main import main
from crmgrasp.envs.single import MUJOCO_ENVS
from crmgrasp.hardware import HANDS, hand_steps
from crmgrasp.hardware.contact_sensing import NoContact
from crmgrasp.hardware.mujoco.hand import PhysicsError
from crmgrasp.hardware.mujoco.steps import FAULT_KINDS, MujocoSteps
from crmgrasp.model.hand import Error
from crmgrasp.sim import STEP_REWARD, Episode, run_episode


class Cycle:
    """A policy that takes the task's actions in turn."""

    def __init__(self, n: int) -> None:
        self.n, self.k = n, -1

    def begin(self, first):
        self.seen, self.k = [first], -1

    def act(self):
        self.k += 1
        return self.k % self.n

    def tell(self, percept):
        self.seen.append(percept)


def _episode(steps: MujocoSteps, seed: int) -> Episode:
    return run_episode(
        steps.task, Cycle(len(steps.task.actions)), np.random.default_rng(seed), trace=True, kernel=steps
    )


def test_hands_registry():
    assert hand_steps("kinematic") is None and hand_steps("mujoco") is MujocoSteps
    assert set(HANDS) == {"kinematic", "mujoco"}
    with pytest.raises(CrmgraspError, match="unknown hand 'robonaut'"):
        hand_steps("robonaut")


def test_episode_is_scored_on_the_truth_and_repeats_bit_for_bit():
    steps = MujocoSteps(make_task("paper-box"))
    one, two = _episode(steps, 3), _episode(steps, 3)
    assert one.steps == two.steps and one.success == two.success
    for a, b in zip(one.trace, two.trace):
        assert a.after.observation == b.after.observation and a.after.min_friction == b.after.min_friction
    last = one.trace[-1].after
    # the episode ends on the sensed grasp; its success is the true one, from MuJoCo's contacts
    assert last.terminated and one.success == bool(last.min_friction <= steps.task.mu_goal)
    assert steps.task.quality(last.state.sensed) <= steps.task.mu_goal
    assert abs(steps.task.quality(last.state.sensed) - last.min_friction) < 0.02
    assert steps.episodes == 2 and not steps.faults


def test_family_and_spatial_worlds_are_redrawn():
    for name in ("box-family", "cup-3d"):
        steps = MujocoSteps(make_task(name))
        rng = np.random.default_rng(0)
        first = steps.sample_start(rng)
        obj = steps.instance.obj
        assert steps.begin(first, rng).state.steps == 0
        steps.sample_start(rng)
        assert steps.instance.obj != obj and steps.instance.family is None


def test_a_physics_fault_ends_the_episode_as_a_counted_error(monkeypatch):
    task = make_task("paper-box")
    steps = MujocoSteps(task)
    rng = np.random.default_rng(1)
    first = steps.begin(steps.sample_start(rng), rng)

    def thrown(crm):
        steps.hand.data.qpos[0] += 1.0  # the object is 1 m away: thrown off the table
        steps.hand.check_physics()

    monkeypatch.setattr(steps.hand, "execute", thrown)
    out = steps.step_one(first.state, 0, rng)
    assert out.truncated and not out.terminated and out.min_friction == math.inf
    assert out.observation == first.observation and out.obs_index == first.obs_index
    assert out.reward == STEP_REWARD - task.error_cost and out.state.steps == 1
    assert steps.faults == {"off the table": 1} and steps.fault == "off the table"


def test_a_crash_inside_a_diverged_crm_is_a_fault_not_a_traceback(monkeypatch):
    steps = MujocoSteps(make_task("paper-box"))
    rng = np.random.default_rng(1)
    first = steps.begin(steps.sample_start(rng), rng)

    def diverged(crm):
        steps.hand.data.qvel[0] = np.inf
        raise ValueError("math domain error")

    monkeypatch.setattr(steps.hand, "execute", diverged)
    out = steps.step_one(first.state, 0, rng)
    assert out.truncated and steps.faults == {"unstable": 1}

    def buggy(crm):
        raise ValueError("a bug, not physics")

    steps.begin(steps.sample_start(rng), rng)
    monkeypatch.setattr(steps.hand, "execute", buggy)
    with pytest.raises(ValueError, match="a bug"):
        steps.step_one(first.state, 0, rng)


@pytest.mark.parametrize(
    ("poke", "kind"),
    [
        (lambda d: d.qpos.__setitem__(1, np.nan), "unstable"),
        (lambda d: d.qpos.__setitem__(0, 0.5), "off the table"),
    ],
)
def test_check_physics_names_the_fault(poke, kind):
    steps = MujocoSteps(make_task("paper-box"))
    rng = np.random.default_rng(2)
    steps.begin(steps.sample_start(rng), rng)
    steps.hand.check_physics()  # a placed hand is sound
    poke(steps.hand.data)
    with pytest.raises(PhysicsError, match=kind.replace(" ", ".")) as info:
        steps.hand.check_physics()
    assert info.value.kind == kind and kind in FAULT_KINDS


def test_a_lost_contact_ends_the_episode(monkeypatch):
    steps = MujocoSteps(make_task("paper-box"))
    rng = np.random.default_rng(4)
    first = steps.begin(steps.sample_start(rng), rng)
    monkeypatch.setattr(steps.hand, "sense", lambda: NoContact("fingertip b: no force"))
    monkeypatch.setattr(steps.hand, "execute", lambda crm: Error.NONE)
    out = steps.step_one(first.state, 1, rng)
    assert out.truncated and out.obs_index == first.obs_index and steps.faults == {"contact lost": 1}


@pytest.mark.slow
def test_pooled_vi_learns_paper_box_on_mujoco():
    """95% greedy success after 40 MuJoCo episodes (seed 0; benchmarks/mujoco_learning.py
    measures 10 seeds at 100 episodes)."""
    task = make_task("paper-box")
    res = train_trials(
        task,
        "pooled-vi",
        trials=1,
        episodes=40,
        seed=0,
        k=1,
        eval_episodes=20,
        params={"symmetric": True},
        stepper=MujocoSteps,
    )
    assert res.greedy_success.mean() >= 0.95 and res.success.shape == (1, 40)
    assert res.greedy_steps.mean() <= 1.05 * 2 * task.reference_mean_steps
    assert isinstance(res.faults, dict)


@pytest.mark.parametrize("env_id", sorted(MUJOCO_ENVS))
def test_mujoco_envs_pass_check_env(env_id):
    env = gym.make(env_id)
    check_env(env.unwrapped, skip_render_check=True)
    obs, info = env.reset(seed=0)
    assert env.observation_space.contains(obs) and info["steps"] == 0 and info["fault"] is None
    obs, reward, *_, info = env.step(0)
    assert env.observation_space.contains(obs) and reward <= -1.0 and info["steps"] == 1
    assert info["success"] == bool(info["min_friction"] <= env.unwrapped.task.mu_goal)


def test_mujoco_env_refuses_bad_actions():
    env = gym.make("crmgrasp/PaperBoxMujoco-v0").unwrapped
    with pytest.raises(CrmgraspError, match="call reset"):
        env.step(0)
    env.reset(seed=0)
    with pytest.raises(CrmgraspError, match="action must be an integer in \\[0, 4\\)"):
        env.step(7)


def test_learn_on_mujoco_from_the_cli(tmp_path, capsys):
    out = tmp_path / "run"
    argv = ["learn", "--preset", "fastest", "--hand", "mujoco", "--trials", "2", "--episodes", "6"]
    argv += ["--eval-episodes", "3", "--out", str(out)]
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert "(mujoco hand)" in text and "ended early" in text
    summary = json.loads((out / "summary.json").read_text())
    assert summary["hand"] == "mujoco" and isinstance(summary["faults"], dict)
    run = json.loads((out / "run.json").read_text())
    assert run["config"]["hand"] == "mujoco" and run["config"]["checkpoint_episodes"] == 0
    lock = ["learn", "--hand", "mujoco", "--lockstep", "--trials", "1", "--episodes", "2", "--out", str(tmp_path / "l")]
    assert main(lock) == 2 and not (tmp_path / "l").exists()
    assert "lockstep steps the kinematic model only" in capsys.readouterr().err


@pytest.mark.slow
def test_an_interrupted_mujoco_run_resumes_to_identical_results(tmp_path, monkeypatch):
    import crmgrasp.experiments.learning as learning

    full, cut = tmp_path / "full", tmp_path / "cut"
    argv = ["learn", "--preset", "fastest", "--hand", "mujoco", "--trials", "3", "--episodes", "4"]
    argv += ["--eval-episodes", "2", "--quiet"]
    assert main([*argv, "--out", str(full)]) == 0
    real = learning._save_part

    def save_then_stop(*a, **k):
        real(*a, **k)
        raise KeyboardInterrupt

    monkeypatch.setattr(learning, "_save_part", save_then_stop)
    assert main([*argv, "--out", str(cut)]) == 130
    monkeypatch.setattr(learning, "_save_part", real)
    assert main([*argv, "--out", str(cut), "--resume"]) == 0
    assert (cut / "curve.csv").read_bytes() == (full / "curve.csv").read_bytes()
    faults = [json.loads((d / "summary.json").read_text())["faults"] for d in (full, cut)]
    assert faults[0] == faults[1]


def test_mujoco_env_starts_from_a_given_config_or_world():
    env = gym.make("crmgrasp/PaperBoxMujoco-v0").unwrapped
    near = env.task.place((-0.15, -0.02), (-0.10, -0.05))  # docs/model.md section 7
    obs, info = env.reset(seed=0, options={"config": near})
    assert abs(obs["rho"][0] - 2.0) < 0.05 and abs(obs["m_a"][0] - 0.05) < 0.005
    fam = gym.make("crmgrasp/BoxFamilyMujoco-v0").unwrapped
    world = fam.task.sample_world(np.random.default_rng(3))
    obs, info = fam.reset(seed=0, options={"world": world})
    assert fam.steps.instance.obj == world.task.obj and info["steps"] == 0
    with pytest.raises(CrmgraspError, match="options\\['world'\\] must be a World"):
        fam.reset(options={"world": "a box"})


def test_evaluate_a_saved_policy_on_the_mujoco_hand(tmp_path, capsys):
    out = tmp_path / "run"
    argv = ["learn", "--preset", "fastest", "--trials", "1", "--episodes", "30", "--eval-episodes", "5"]
    assert main([*argv, "--quiet", "--out", str(out)]) == 0
    capsys.readouterr()
    argv = ["evaluate", "--policy", str(out / "policy.json"), "--hand", "mujoco", "--episodes", "4", "--json"]
    assert main([*argv, "--quiet"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["hand"] == "mujoco" and result["episodes"] == 4 and isinstance(result["faults"], dict)
    assert 0.0 <= result["success_rate"] <= 1.0


def test_a_longer_scoring_run_begins_with_the_shorter_ones_worlds():
    """`score_on_mujoco` draws its worlds from one generator per seed: the outcomes of 3 worlds
    are the first 3 of 5, and the success rate is their mean."""
    from crmgrasp.agents.training import build_agent, encoder_for
    from crmgrasp.experiments.physics_learning import score_on_mujoco

    task = make_task("paper-box")
    encoder = encoder_for(task, 1)
    agent = build_agent(task, encoder, "random")
    short, long = (score_on_mujoco(task, agent, encoder, n, 4) for n in (3, 5))
    assert long["outcomes"][:3] == short["outcomes"] and len(long["outcomes"]) == 5
    assert long["success"] == np.mean(long["outcomes"]) and long["crms"] == np.mean(long["episode_crms"])
    assert long["episode_crms"][:3] == short["episode_crms"] and all(
        1 <= n <= task.max_steps for n in long["episode_crms"]
    )


def test_physics_learning_through_reproduce(tmp_path, monkeypatch):
    """The physics-learning experiment end to end through ``reproduce`` (its files and index
    rows), on a budget smaller than ``--quick``'s: one planar and one spatial task. The
    reproduce test runs as a default install, without MuJoCo, so this is the experiment's
    whole run in the suite."""
    import importlib.util

    from crmgrasp.experiments import physics_learning as pl
    from crmgrasp.experiments.reproduce import reproduce

    tiny = pl.PhysicsLearningConfig(
        tasks=("paper-box", "cup-3d"), mujoco_episodes=(2, 2), kinematic_episodes=20, eval_episodes=2, seeds=1
    )
    monkeypatch.setattr(pl.PhysicsLearningConfig, "quick", classmethod(lambda cls, seed=0: tiny))
    s = reproduce(tmp_path, ["physics-learning"], quick=True)["physics-learning"]
    assert set(s["tasks"]) == {"paper-box", "cup-3d"}
    for t in s["tasks"].values():
        assert {"transferred", "scratch", "fine-tuned"} <= set(t) and t["scratch"]["mujoco_episodes"] == 2
    out = tmp_path / "physics-learning"
    for name in ("data.csv", "curves.csv", "summary.json", "physics_learning.png"):
        assert (out / name).exists(), name
    if importlib.util.find_spec("mcap") is not None:  # the records need the extra crmgrasp[mcap]
        assert (out / "paper-box.mcap").exists() and (out / "cup-3d.mcap").exists()
    rows = [line for line in (tmp_path / "README.md").read_text().splitlines() if line.startswith("| physics-learning")]
    assert len(rows) == 3 and "cup-3d: true success on MuJoCo, 1 seeds" in rows[1]

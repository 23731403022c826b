"""Start presets and the grasp-reward reading: distributions, streams, every step path."""

from __future__ import annotations

import math

import numpy as np
import pytest

from crmgrasp._validation import CrmgraspError
from crmgrasp.agents.lockstep import train_trials_lockstep
from crmgrasp.agents.training import train_trials
from crmgrasp.cli import main
from crmgrasp.envs import CRMGraspEnv, CRMGraspVectorEnv
from crmgrasp.kernels import kernel_for
from crmgrasp.tasks import paper_box, task_from_dict, task_to_dict
from crmgrasp.tasks.presets import START_PRESETS, LongSideStarts, MixtureStarts, NearCornerStarts, with_reading
from crmgrasp.tasks.starts import acceptable


def _near(task, cfg, within=0.10):
    return any(max(math.dist(c.point, v) for c in cfg) <= within + 1e-12 for v in task.obj.vertices)


def _long_far(task, cfg, lo=0.10):
    obj = task.obj
    (la, da), (lb, db) = (
        (obj.edge_length(obj.edge_index(c.point)), min(math.dist(c.point, v) for v in obj.vertices)) for c in cfg
    )
    return la != lb and (da if la > lb else db) > lo


@pytest.mark.parametrize("name", list(START_PRESETS))
def test_presets_draw_acceptable_starts_and_the_compiled_filter_changes_nothing(name):
    task = with_reading(paper_box(), starts=name)
    kernel = kernel_for(task, "numba")
    a, b = np.random.default_rng(4), np.random.default_rng(4)
    for _ in range(300):
        cfg = task.sample_start(a)
        assert cfg == task.sample_start(b, kernel.start_filter)
        assert acceptable(task.obj, task.hand, task.mu_goal, cfg)
        if name == "near-corner":
            assert _near(task, cfg)
        if name == "long-side":
            assert _long_far(task, cfg)


def test_mixture_weights():
    task = with_reading(paper_box(), starts="mixture")
    rng = np.random.default_rng(0)
    n = 2000
    near = sum(_near(task, task.sample_start(rng)) for _ in range(n))
    se = math.sqrt(0.4 * 0.6 / n)
    assert abs(near / n - 0.4) < 4 * se  # the two kinds are disjoint: near-corner has no far long-side contact


def test_preset_errors_and_task_round_trip():
    with pytest.raises(CrmgraspError, match="unknown start preset"):
        with_reading(paper_box(), starts="nowhere")
    with pytest.raises(CrmgraspError, match="within"):
        NearCornerStarts(-1.0)
    with pytest.raises(CrmgraspError, match="lo < hi"):
        LongSideStarts(0.2, 0.1)
    with pytest.raises(CrmgraspError, match="weights"):
        MixtureStarts((NearCornerStarts(),), (1.0, 2.0))
    for name in START_PRESETS:
        task = with_reading(paper_box(), starts=name, grasp_reward=0.0)
        assert task_from_dict(task_to_dict(task)) == task
    t = with_reading(paper_box(), starts="long-side")
    assert t.symmetry is None and t.reference_mean_steps is None
    assert with_reading(paper_box(), starts="near-corner").symmetry is not None


def test_grasp_reward_reaches_every_step_path():
    task = with_reading(paper_box(), grasp_reward=0.0)
    for backend in ("numba", "reference"):
        env = CRMGraspEnv(task, backend=backend)
        env.reset(seed=1)
        rewards, done = [], False
        while not done:
            _, r, term, trunc, _ = env.step(0)
            rewards.append((r, term))
            done = term or trunc
        assert all(r == (0.0 if term else -1.0) for r, term in rewards)
    venv = CRMGraspVectorEnv(64, task)
    venv.reset(seed=0)
    seen = set()
    for _ in range(20):
        _, r, term, trunc, _ = venv.step(np.zeros(64, dtype=np.int64))
        seen |= {(float(x), bool(t)) for x, t in zip(r, term)}
    assert (0.0, True) in seen and (-1.0, False) in seen and (-1.0, True) not in seen
    kw = dict(trials=4, episodes=60, seed=3, eval_episodes=20, params={})
    a = train_trials(task, "sarsa", **kw)
    b = train_trials_lockstep(task, "sarsa", **kw)
    np.testing.assert_array_equal(a.steps, b.steps)
    c = train_trials(paper_box(), "sarsa", **kw)
    assert not np.array_equal(a.steps, c.steps)  # the reading changes learning


def test_cli_reading_options(tmp_path, capsys):
    import json

    argv = ["learn", "--start-preset", "near-corner", "--grasp-reward", "0", "--trials", "2", "--episodes", "30"]
    assert main([*argv, "--eval-episodes", "5", "--quiet", "--out", str(tmp_path / "r")]) == 0
    capsys.readouterr()
    rec = json.loads((tmp_path / "r" / "run.json").read_text())
    assert rec["config"]["task"]["grasp_reward"] == 0.0 and rec["config"]["task"]["starts"]["kind"] == "near-corner"
    assert main(["references", "--start-preset", "long-side", "--starts", "300", "--json"]) == 0
    res = json.loads(capsys.readouterr().out)
    assert res["belief_optimum"] > 1.0
    with pytest.raises(SystemExit) as exit_:
        main(["references", "--start-preset", "everywhere"])
    assert exit_.value.code == 2 and "invalid choice" in capsys.readouterr().err


def test_learner_presets_fill_what_the_user_left_out():
    from crmgrasp.agents.presets import LearnerChoice, apply_preset
    from crmgrasp.tasks import make_task

    box, cup = make_task("paper-box"), make_task("cup-3d")
    assert apply_preset("paper", box) == LearnerChoice("sarsa", 2, False, None)
    skip = (("skip_errored", True),)
    assert apply_preset("fastest", box) == LearnerChoice("pooled-vi", 1, True, None, skip)  # from scratch
    families = LearnerChoice("backoff-vi", 2, True, None, (("skip_errored", True), ("mean_after", 2000)))
    assert apply_preset("families", box) == families
    assert apply_preset("fastest", cup) == LearnerChoice("pooled-vi", 1, False, None, skip)  # no symmetry declared
    assert apply_preset("fastest", box, agent="dyna-q", k=2) == LearnerChoice("dyna-q", 2, True, None)
    assert apply_preset("fastest", box, prior_task="mixed").prior_task == "mixed"
    assert apply_preset("fastest", box, agent="random").symmetric is False  # not tabular
    with pytest.raises(CrmgraspError, match="unknown preset 'slow'"):
        apply_preset("slow", box)
    costly = apply_preset("costly-errors", box)
    assert costly == LearnerChoice("backoff-vi", 6, True, None, (("explore", 2.0), ("explore_tried", 2.0)))
    assert apply_preset("costly-errors", box, agent="pooled-vi").params == ()  # its parameters are its agent's


def test_a_preset_sets_its_agent_parameters_where_the_user_gave_none(tmp_path):
    """``--preset costly-errors`` runs backoff-vi with explore = explore_tried = 2 unless
    ``--explore`` or ``--explore-tried`` is given; the run records the parameters it used."""
    import json

    from crmgrasp.cli.main import main

    base = ["learn", "--task", "notch-or-box", "--trials", "1", "--episodes", "20", "--eval-episodes", "5", "--quiet"]
    assert main([*base, "--preset", "costly-errors", "--out", str(tmp_path / "a")]) == 0
    run = json.loads((tmp_path / "a" / "run.json").read_text())
    assert run["config"]["agent"] == "backoff-vi" and run["config"]["k"] == 6
    assert run["config"]["params"]["explore"] == 2.0 and run["config"]["params"]["explore_tried"] == 2.0
    assert main([*base, "--preset", "costly-errors", "--explore", "1", "--out", str(tmp_path / "b")]) == 0
    params = json.loads((tmp_path / "b" / "run.json").read_text())["config"]["params"]
    assert params["explore"] == 1.0 and params["explore_tried"] == 2.0
    assert main([*base, "--preset", "costly-errors", "--explore-tried", "0", "--out", str(tmp_path / "c")]) == 0
    params = json.loads((tmp_path / "c" / "run.json").read_text())["config"]["params"]
    assert params["explore"] == 2.0 and params["explore_tried"] == 0.0
    assert main([*base, "--preset", "families", "--out", str(tmp_path / "d")]) == 0
    params = json.loads((tmp_path / "d" / "run.json").read_text())["config"]["params"]
    assert params["skip_errored"] is True and params["mean_after"] == 2000
    assert json.loads((tmp_path / "d" / "policy.json").read_text())["version"] == 4
    assert main([*base, "--preset", "families", "--skip-errored", "false", "--out", str(tmp_path / "e")]) == 0
    assert json.loads((tmp_path / "e" / "run.json").read_text())["config"]["params"]["skip_errored"] is False
    assert main([*base, "--preset", "families", "--plan-every", "5", "--out", str(tmp_path / "f")]) == 0
    params = json.loads((tmp_path / "f" / "run.json").read_text())["config"]["params"]
    assert params["plan_every"] == 5 and params["skip_errored"] is True  # the user's option and the preset's
    assert main([*base, "--preset", "families", "--decay", "0.999", "--out", str(tmp_path / "g")]) == 0
    assert json.loads((tmp_path / "g" / "run.json").read_text())["config"]["params"]["decay"] == 0.999
    assert main([*base, "--preset", "families", "--mean-after", "20", "--out", str(tmp_path / "h")]) == 0
    assert json.loads((tmp_path / "h" / "run.json").read_text())["config"]["params"]["mean_after"] == 20


def test_the_fastest_presets_greedy_policy_does_not_cycle_on_an_error():
    """Paper-box seed 49 after 20 episodes: pooled-vi's greedy policy without ``skip_errored``
    alternates two CRMs that both err at the same contacts until the step limit (3.05 CRMs per
    episode on the 1,000 checkpoint starts); the preset's, which never repeats a CRM that erred
    since the contacts last moved, moves them instead (1.93)."""
    from crmgrasp.agents.presets import apply_preset
    from crmgrasp.agents.training import checkpoint_generators, encoder_for, evaluate
    from crmgrasp.tasks import make_task

    task = make_task("paper-box")
    choice = apply_preset("fastest", task)
    params = {"symmetric": choice.symmetric, **dict(choice.params)}
    steps = {}
    for skip in (False, True):
        res = train_trials(
            task,
            choice.agent,
            trials=1,
            episodes=20,
            seed=49,
            k=choice.k,
            eval_episodes=0,
            params={**params, "skip_errored": skip},
        )
        steps[skip] = evaluate(task, res.agents[0], encoder_for(task, choice.k), 1000, *checkpoint_generators(49))[0]
    assert (steps[False] == task.max_steps).sum() > 150 and steps[False].mean() > 2.9
    assert (steps[True] == task.max_steps).sum() < 10 and steps[True].mean() < 2.0

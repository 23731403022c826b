"""Learning the offset: the dyadic offset tree of a gridded task and the learner that
refines offsets history by history (`refine-vi`)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from crmgrasp._validation import CrmgraspError
from crmgrasp.agents.refine import CLOSED, RefineVI
from crmgrasp.agents.training import build_agent, encoder_for, train_trials
from crmgrasp.experiments._episodes import greedy_records
from crmgrasp.planners.references import sample_starts
from crmgrasp.tasks import make_task
from crmgrasp.tasks.offsets import grid_crms, offset_grid, offset_tree


# ---------------------------------------------------------------- the tree
def test_levels_are_the_nested_grids_and_children_are_one_level_finer():
    task = offset_grid(make_task("paper-box"), 17)
    tree = offset_tree(task)
    assert tree.depth == 4
    for level in range(5):
        assert [task.actions[a] for a in tree.coarse(level)] == list(grid_crms(task, 2**level + 1))
    for a, kids in enumerate(tree.children):
        assert all(tree.level[c] == tree.level[a] + 1 for c in kids)
        spacing = 0.32 / 2 ** (tree.level[a] + 1)
        assert all(
            task.actions[c].c == task.actions[a].c
            and task.actions[c].f == task.actions[a].f
            and abs(abs(task.actions[c].r - task.actions[a].r) - spacing) < 1e-12
            for c in kids
        )
        assert len(kids) == (0 if tree.level[a] == 4 else 1 if tree.level[a] == 0 else 2)


def test_a_spatial_offset_has_the_eight_neighbours_at_half_spacing():
    task = offset_grid(make_task("cup-3d"), 5)
    tree = offset_tree(task)
    centre = tree.coarse(1)[4]  # the first pair's 3 x 3 grid, row-major: its centre
    assert task.actions[centre].r == (0.0, 0.0)
    assert len(tree.children[centre]) == 8 and {tree.level[c] for c in tree.children[centre]} == {2}


@pytest.mark.parametrize("n", [None, 4, 7])
def test_a_task_off_the_dyadic_grids_is_refused(n):
    task = make_task("paper-box") if n is None else offset_grid(make_task("paper-box"), n)
    with pytest.raises(CrmgraspError, match="grid of 2\\*\\*d \\+ 1 offsets"):
        offset_tree(task)
    with pytest.raises(CrmgraspError, match="grid of 2\\*\\*d \\+ 1 offsets"):
        build_agent(task, encoder_for(task, 1), "refine-vi")


# ---------------------------------------------------------------- the learner
def _greedy_crms(task, agents, k=1):
    records = greedy_records(task, agents, sample_starts(task, 30, 3), 3, k=k)
    return [[[task.crm(a) for a in r.actions] for r in trial] for trial in records]


def test_with_every_offset_open_it_is_model_vi_bit_for_bit():
    task = offset_grid(make_task("paper-box"), 5)
    runs = [
        train_trials(task, name, trials=2, episodes=60, seed=4, k=1, eval_episodes=0, params=params)
        for name, params in (("model-vi", {}), ("refine-vi", {"start_level": 2}))
    ]
    for mine, theirs in zip(runs[0].agents, runs[1].agents, strict=True):
        assert mine.q == theirs.q and mine.q_greedy == theirs.q_greedy
    assert _greedy_crms(task, runs[0].agents) == _greedy_crms(task, runs[1].agents)


def test_never_refining_it_learns_as_model_vi_on_the_coarse_grid():
    fine, coarse = (offset_grid(make_task("paper-box"), n) for n in (9, 3))
    a = train_trials(
        fine,
        "refine-vi",
        trials=2,
        episodes=60,
        seed=5,
        k=1,
        eval_episodes=0,
        params={"start_level": 1, "refine_after": 10**6},
    )
    b = train_trials(coarse, "model-vi", trials=2, episodes=60, seed=5, k=1, eval_episodes=0)
    assert _greedy_crms(fine, a.agents) == _greedy_crms(coarse, b.agents)


def test_it_opens_finer_offsets_only_around_the_best_and_only_acts_on_open_ones():
    task = offset_grid(make_task("u-handle"), 17)
    res = train_trials(
        task,
        "refine-vi",
        trials=1,
        episodes=150,
        seed=0,
        k=1,
        eval_episodes=0,
        params={"start_level": 1, "refine_after": 2},
    )
    agent = res.agents[0]
    assert isinstance(agent, RefineVI)
    tree = offset_tree(task)
    refined = [s for s, acts in agent.open.items() if len(acts) > len(agent.coarse)]
    assert refined, "some history refined its offsets"
    for s, tried in agent.tried.items():
        assert tried <= agent.opened(s)
        assert all((agent.q[s][a] == CLOSED) == (a not in agent.opened(s)) for a in range(agent.n_actions))
    for s in refined:  # every opened CRM is a child of an open one
        opened = agent.open[s]
        assert all(lv <= 1 for lv in (tree.level[a] for a in agent.coarse))
        assert all(any(a in tree.children[p] for p in opened) for a in opened - set(agent.coarse))
    levels = {tree.level[a] for acts in agent.tried.values() for a in acts}
    assert max(levels) >= 2, "it tried an offset finer than its start grid"


def test_its_parameters_are_checked():
    task = offset_grid(make_task("paper-box"), 5)
    enc = encoder_for(task, 1)
    with pytest.raises(CrmgraspError, match="start_level 3 is finer"):
        build_agent(task, enc, "refine-vi", {"start_level": 3})
    with pytest.raises(CrmgraspError, match="refine_after"):
        build_agent(task, enc, "refine-vi", {"refine_after": 0})
    fine = offset_grid(make_task("paper-box"), 9)
    agent = build_agent(fine, encoder_for(fine, 1), "refine-vi")
    with pytest.raises(CrmgraspError, match="not open"):
        agent.update(1, 1, -1.0, 2, None, True, np.random.default_rng(0))


def test_learn_writes_a_policy_with_its_offsets_that_evaluate_reads(tmp_path, capsys):
    from crmgrasp.cli import main

    out = tmp_path / "run"
    argv = ["learn", "--task", "paper-box", "--offset-grid", "9", "--agent", "refine-vi", "--k", "1"]
    assert main([*argv, "--episodes", "40", "--trials", "1", "--out", str(out), "--quiet"]) == 0
    policy = json.loads((out / "policy.json").read_text())
    assert len(policy["actions"]) == 36 and policy["agent"] == "refine-vi"
    capsys.readouterr()
    assert main(["evaluate", "--policy", str(out / "policy.json"), "--episodes", "20", "--json", "--quiet"]) == 0
    assert json.loads(capsys.readouterr().out)["task"] == "paper-box-grid9"


def test_a_prior_opens_the_crms_it_has_outcomes_of():
    task = offset_grid(make_task("paper-box"), 9)
    agent = build_agent(task, encoder_for(task, 1), "refine-vi")
    closed = next(a for a in range(agent.n_actions) if a not in agent.coarse)
    agent.set_prior({(7, closed): {(-1.0, 0, True): 2.0}})
    assert closed in agent.opened(7) and agent.q[7][closed] == -1.0
    assert closed not in agent.opened(8)
    agent.update(7, closed, -1.0, 0, None, True, np.random.default_rng(0))


def test_its_compiled_planning_equals_the_readable_sweeps():
    """Closed CRMs (-inf) and rows written back pair by pair: the compiled value iteration
    still gives the readable sweeps' values bit for bit."""
    task = offset_grid(make_task("u-handle"), 9)
    kw = {"trials": 1, "episodes": 80, "seed": 2, "k": 1, "eval_episodes": 20}
    runs = [
        train_trials(task, "refine-vi", params={"compiled": c, "refine_after": 1, "symmetric": True}, **kw)
        for c in (False, True)
    ]
    assert np.array_equal(runs[0].steps, runs[1].steps) and np.array_equal(runs[0].greedy_steps, runs[1].greedy_steps)
    a, b = (r.agents[0].inner for r in runs)
    assert a.q == b.q and a.q_greedy == b.q_greedy and a.open == b.open
    assert any(len(v) > len(a.coarse) for v in a.open.values())


def test_its_options_are_refused_to_other_agents_naming_only_real_flags(capsys):
    from crmgrasp.cli import main

    argv = ["learn", "--task", "paper-box", "--agent", "model-vi", "--refine-after", "2", "--episodes", "5"]
    assert main([*argv, "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--refine-after does not apply to --agent model-vi" in err[0]
    assert "--q-act" in err[0] and "--sweeps" not in err[0] and "--compiled" not in err[0]  # no flag exists for those

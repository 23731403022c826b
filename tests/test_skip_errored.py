"""``skip_errored``: a greedy policy that never repeats a CRM that erred since the contacts
last moved (``crmgrasp.agents.base``), in the learner, its saved policy and its file."""

from __future__ import annotations

import json

import numpy as np
import pytest

from crmgrasp._validation import CrmgraspError
from crmgrasp.agents.base import LearnerPolicy, allowed_choice
from crmgrasp.agents.policy import GreedyPolicy
from crmgrasp.agents.training import encoder_for, make_agent, train_trials
from crmgrasp.experiments._episodes import episode_records
from crmgrasp.model.hand import Error
from crmgrasp.planners.references import sample_starts
from crmgrasp.tasks import make_task


@pytest.fixture(scope="module")
def handle():
    """A U-handle learner (k = 2, mirror quotient) after 300 episodes, with the skip rule on,
    and 60 worlds."""
    task = make_task("u-handle")
    params = {"symmetric": True, "skip_errored": True}
    agent = train_trials(task, "backoff-vi", trials=1, episodes=300, seed=3, k=2, eval_episodes=0, params=params)
    return task, agent.agents[0], sample_starts(task, 60, 10_000)


def _records(task, agent, worlds, seed=0, k=2):
    enc = encoder_for(task, k)
    return episode_records(task, lambda: LearnerPolicy(agent, enc, np.random.default_rng(seed), learn=False), worlds, 0)


def _choices_after_errors(task, k, agent, loaded, records) -> int:
    """Check that ``loaded`` chooses as ``agent`` (the same sets of choices over 30 tie draws,
    none among the banned CRMs) at every history of ``records`` with a CRM that erred since
    the contacts last moved; return how many such histories there were."""
    enc, checked = encoder_for(task, k), 0
    for r in records:
        h, banned = enc.start(r.first_obs), frozenset()
        for a, o, erred in zip(r.actions, r.observations, r.errors):
            if banned:
                s = enc.encode(h)
                mine = {agent.greedy(s, np.random.default_rng(i), banned) for i in range(30)}
                saved = {loaded.greedy(s, np.random.default_rng(i), banned) for i in range(30)}
                assert mine == saved and not mine & banned
                checked += 1
            h, banned = enc.push(h, a, o), banned | {a} if erred else frozenset()
    return checked


def _repeats(record) -> int:
    """CRMs of an episode that repeat one that erred since the contacts last moved."""
    banned: set[int] = set()
    n = 0
    for a, erred in zip(record.actions, record.errors):
        n += a in banned
        banned = banned | {a} if erred else set()
    return n


def test_allowed_choice():
    rng = np.random.default_rng(0)
    row = [0.0, -1.0, -2.0, -1.0]
    assert allowed_choice(row, [0, 1, 2], 4, set(), rng) == 0
    assert allowed_choice(row, [0, 1, 2], 4, {0}, rng) == 1
    assert {allowed_choice(row, [0, 1, 3], 4, {0}, np.random.default_rng(i)) for i in range(20)} == {1, 3}  # a tie
    assert allowed_choice(row, [0, 1], 4, {0, 1}, rng) in (2, 3)  # every choice erred: an untried action
    assert allowed_choice(row, [1, 2], 4, {0, 1, 2, 3}, rng) == 1  # every action erred: the best choice
    assert allowed_choice([], [], 4, {0, 1, 2, 3}, rng) in range(4)


def test_the_greedy_policy_never_repeats_a_crm_that_erred_where_it_is(handle):
    """With the rule, no episode repeats a CRM that erred since the contacts last moved;
    the same learner without it does, and the rule grasps more of these worlds."""
    task, agent, worlds = handle
    assert agent.skip_errored
    skipping = _records(task, agent, worlds)
    agent.inner.skip_errored = False
    try:
        plain = _records(task, agent, worlds)
    finally:
        agent.inner.skip_errored = True
    assert sum(_repeats(r) for r in skipping) == 0
    assert sum(_repeats(r) for r in plain) > 0
    assert sum(r.success for r in skipping) > sum(r.success for r in plain)
    # an episode without an error before its end is the same either way
    for a, b in zip(skipping, plain):
        if not any(b.errors[:-1]):
            assert a.actions == b.actions


def test_the_saved_policy_acts_as_the_learner(handle, tmp_path):
    """The policy file (version 4, ranked tables) chooses as the learner does (among the
    same best actions, ties drawn uniformly) at every history of the learner's episodes,
    with the CRMs that erred there left out, and ``predict`` leaves them out too."""
    task, agent, worlds = handle
    policy = GreedyPolicy.from_agent(task, 2, agent)
    path = policy.save(tmp_path / "p.json")
    doc = json.loads(path.read_text())
    assert doc["version"] == 4 and doc["skip_errored"] is True and "ranked" in doc["backoff"]
    loaded = GreedyPolicy.load(path)
    assert loaded.skip_errored and loaded.backoff is not None and loaded.backoff.ranked is not None
    assert _choices_after_errors(task, 2, agent, loaded, _records(task, agent, worlds)) > 20
    d = task.discretizer
    o, palm = d.compose((1, 1, 0), Error.NONE), d.compose((1, 1, 0), Error.PALM)
    first = loaded.predict([o], [])
    assert loaded.predict([o, palm], [first]) != first
    other = (first + 1) % len(task.actions)
    assert loaded.predict([o, palm, palm], [other, first]) not in (first, other)
    moved = loaded.predict([o, palm, o], [other, first])  # a move forgets the errors before it
    enc = encoder_for(task, 2)
    h = enc.push(enc.push(enc.start(o), other, palm), first, o)
    assert moved == loaded.greedy(enc.encode(h), np.random.default_rng(0))


def test_a_policy_without_the_rule_is_unchanged(handle, tmp_path):
    task, agent, _ = handle
    agent.inner.skip_errored = False
    try:
        doc = GreedyPolicy.from_agent(task, 2, agent).to_dict()
    finally:
        agent.inner.skip_errored = True
    assert doc["version"] == 3 and "ranked" not in doc and "skip_errored" not in doc


def test_corrupt_ranked_tables_are_refused(handle, refused_policy):
    task, agent, _ = handle
    doc = GreedyPolicy.from_agent(task, 2, agent).to_dict()

    def refused(edit, match: str) -> None:
        refused_policy(doc, edit, match)

    state = next(iter(doc["ranked"]))
    refused(lambda d: d.pop("ranked"), '"skip_errored": true and a "ranked" table')
    refused(lambda d: d.update(skip_errored=False), '"skip_errored": true and a "ranked" table')
    refused(lambda d: d.update(version=3), '"skip_errored": true and a "ranked" table')
    refused(lambda d: d["ranked"].pop(state), "exactly the states")
    refused(lambda d: d["ranked"].update({state: [[99]]}), r"integers in \[0, 10\)")
    refused(lambda d: d["ranked"].update({state: []}), "non-empty list of action groups")
    refused(lambda d: d["ranked"][state].append(list(d["ranked"][state][0])), "disjoint")
    refused(lambda d: d["backoff"].pop("ranked"), '"backoff" object has "k", "greedy" and "ranked"')


def test_a_bad_setting_is_a_one_line_error():
    with pytest.raises(CrmgraspError, match="skip_errored must be true or false"):
        make_agent("backoff-vi", 4, skip_errored="yes")


def test_learn_takes_the_flag_and_evaluate_runs_the_file(tmp_path, capsys):
    from crmgrasp.cli import main

    out = tmp_path / "run"
    base = ["learn", "--task", "u-handle", "--agent", "backoff-vi", "--k", "2", "--symmetric", "--episodes", "40"]
    assert (
        main([*base, "--trials", "1", "--eval-episodes", "10", "--quiet", "--skip-errored", "true", "--out", str(out)])
        == 0
    )
    assert json.loads((out / "run.json").read_text())["config"]["params"]["skip_errored"] is True
    assert json.loads((out / "policy.json").read_text())["version"] == 4
    assert main(["evaluate", "--policy", str(out / "policy.json"), "--episodes", "20", "--quiet"]) == 0
    capsys.readouterr()
    assert main(["learn", "--agent", "sarsa", "--skip-errored", "true", "--out", str(tmp_path / "x")]) == 2
    assert "--skip-errored does not apply to --agent sarsa" in capsys.readouterr().err
    assert not (tmp_path / "x").exists()


@pytest.mark.parametrize("learner", ["model-vi", "pooled-vi"])
def test_every_model_based_learner_takes_the_rule(learner, tmp_path):
    """``model-vi`` and ``pooled-vi`` (k = 1) take ``skip_errored`` too: their greedy policy
    repeats no CRM that erred where it is (the same learner without it does), and their
    policy file (version 4, no back-off table) chooses as they do after every error."""
    task = make_task("u-handle")
    params = {"symmetric": True, "skip_errored": True}
    agent = train_trials(task, learner, trials=1, episodes=300, seed=3, k=1, eval_episodes=0, params=params).agents[0]
    assert agent.skip_errored and agent.inner.params()["skip_errored"] is True
    worlds = sample_starts(task, 60, 10_000)
    skipping = _records(task, agent, worlds, k=1)
    agent.inner.skip_errored = False
    try:
        plain = _records(task, agent, worlds, k=1)
    finally:
        agent.inner.skip_errored = True
    assert sum(_repeats(r) for r in skipping) == 0 < sum(_repeats(r) for r in plain)
    loaded = GreedyPolicy.load(GreedyPolicy.from_agent(task, 1, agent).save(tmp_path / "p.json"))
    assert loaded.skip_errored and loaded.backoff is None
    assert _choices_after_errors(task, 1, agent, loaded, skipping) > 10


@pytest.mark.parametrize("learner", ["model-vi", "pooled-vi", "refine-vi"])
def test_a_bad_setting_is_a_one_line_error_for_every_learner(learner):
    with pytest.raises(CrmgraspError, match="skip_errored must be true or false, got 1"):
        make_agent(learner, 4, skip_errored=1)


@pytest.mark.parametrize("flag", [False, True])
def test_skip_errored_learning_keeps_the_acting_policy_off_crms_that_erred(flag):
    """With ``skip_errored_learning`` the learning episodes never repeat a CRM that erred since
    the contacts last moved; without it they do (posterior draws act on a model that may still
    rate such a CRM best). Learning goes on from the repeats' outcomes either way."""
    from crmgrasp.agents.training import build_agent
    from crmgrasp.sim import run_episode

    task = make_task("u-handle")
    enc = encoder_for(task, 2)
    agent = build_agent(task, enc, "backoff-vi", {"symmetric": True, "skip_errored_learning": flag})
    assert agent.skip_errored_learning is flag and agent.params()["skip_errored_learning"] is flag
    rng, repeats, errors = np.random.default_rng(4), 0, 0
    for _ in range(150):
        ep = run_episode(task, LearnerPolicy(agent, enc, rng), rng, trace=True)
        actions = tuple(int(t.action) for t in ep.trace)
        erred = tuple(int(t.after.error) != 0 for t in ep.trace)
        repeats += _repeats(type("R", (), {"actions": actions, "errors": erred}))
        errors += sum(erred)
    assert errors > 50
    assert (repeats == 0) is flag
    with pytest.raises(CrmgraspError, match="skip_errored_learning must be true or false"):
        make_agent("backoff-vi", 4, skip_errored_learning="yes")

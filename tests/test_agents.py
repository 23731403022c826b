"""Learners: a tiny known MDP, paper-box behaviour, determinism, policy files."""

import json

import numpy as np
import pytest

from crmgrasp import CrmgraspError, make_task
from crmgrasp.agents import GreedyPolicy, evaluate, make_agent, train_trials
from crmgrasp.agents.policy import policy_digest
from crmgrasp.agents.training import encoder_for, episodes_to_within, rollout

LEARNERS = [
    ("sarsa", {}),
    ("q", {}),
    ("sarsa-lambda", {"trace": "replacing"}),
    ("sarsa-lambda", {"trace": "accumulating", "lam": 0.5}),
    ("dyna-q", {"n_planning": 10}),
    ("dyna-q", {"planning": "sweep", "n_planning": 100}),
    ("model-vi", {}),
]


def _chain_episode(agent, rng, learn=True):
    """States 0..3 on a line; action 1 moves right, 0 left (floored at 0); reaching
    4 terminates. Reward -1 per step. Optimal: always right, V(s) = -(1 - 0.9^(4-s))/0.1."""
    s, steps = 0, 0
    agent.begin_episode()
    a = agent.act(s, rng) if learn else agent.greedy(s, rng)
    while True:
        s2 = s + 1 if a == 1 else max(0, s - 1)
        steps += 1
        if s2 == 4:
            if learn:
                agent.update(s, a, -1.0, s2, None, True, rng)
            return steps
        a2 = agent.act(s2, rng) if learn else agent.greedy(s2, rng)
        if learn:
            agent.update(s, a, -1.0, s2, a2, False, rng)
        if steps >= 50:
            return steps
        s, a = s2, a2


@pytest.mark.parametrize("name, params", LEARNERS)
def test_learners_solve_a_chain_to_its_optimum(name, params):
    rng = np.random.default_rng(0)
    agent = make_agent(name, 2, **params)
    for _ in range(300):
        _chain_episode(agent, rng)
    assert _chain_episode(agent, rng, learn=False) == 4
    optimum = [-(1 - 0.9 ** (4 - s)) / 0.1 for s in range(4)]
    values = agent.greedy_table if name == "model-vi" else agent.q
    assert [max(values[s]) for s in range(4)] == pytest.approx(optimum, abs=0.05)


def test_baselines_and_agent_errors():
    rng = np.random.default_rng(0)
    fixed = make_agent("fixed", 4, sequence=(2, 0))
    assert [fixed.act(0, rng) for _ in range(3)] == [2, 0, 2]
    fixed.begin_episode()
    assert fixed.act(0, rng) == 2
    assert all(0 <= make_agent("random", 4).act(0, rng) < 4 for _ in range(20))
    with pytest.raises(CrmgraspError, match="unknown agent"):
        make_agent("nope", 4)
    with pytest.raises(CrmgraspError, match="alpha must be in"):
        make_agent("sarsa", 4, alpha=0.0)
    with pytest.raises(CrmgraspError, match="has no parameter 'lam'"):
        make_agent("sarsa", 4, lam=0.5)
    with pytest.raises(CrmgraspError, match="planning must be"):
        make_agent("dyna-q", 4, planning="full")
    with pytest.raises(CrmgraspError, match="sequence"):
        make_agent("fixed", 4, sequence=(5,))


@pytest.mark.parametrize("seed", [-1, 1.5, 2**63, "x", None])
def test_train_trials_checks_its_seed(task, seed):
    with pytest.raises(CrmgraspError, match=r"seed must be an integer in \[0, 9223372036854775807\]"):
        train_trials(task, "sarsa", trials=1, episodes=1, seed=seed, eval_episodes=0)


def test_a_policy_from_an_agent_of_another_task_or_order_is_refused(task):
    agent = train_trials(task, "sarsa", trials=1, episodes=50, seed=0, eval_episodes=0).agents[0]
    with pytest.raises(CrmgraspError, match="the agent chooses among 4 CRMs; task 'u-handle' has 10"):
        GreedyPolicy.from_agent(make_task("u-handle"), 2, agent)
    with pytest.raises(CrmgraspError, match="not k = 1 histories of task 'paper-box'"):
        GreedyPolicy.from_agent(task, 1, agent)  # k = 2 codes read as k = 1 ones
    assert GreedyPolicy.from_agent(task, 2, agent).table


def test_a_numpy_integer_seed_is_the_same_seed(task):
    a = train_trials(task, "sarsa", trials=2, episodes=20, seed=np.int64(3), eval_episodes=5)
    b = train_trials(task, "sarsa", trials=2, episodes=20, seed=3, eval_episodes=5)
    np.testing.assert_array_equal(a.steps, b.steps)
    np.testing.assert_array_equal(a.greedy_steps, b.greedy_steps)


def test_sarsa_beats_random_and_is_deterministic(task):
    a = train_trials(task, "sarsa", trials=3, episodes=300, seed=1, eval_episodes=200)
    b = train_trials(task, "sarsa", trials=3, episodes=300, seed=1, eval_episodes=200)
    np.testing.assert_array_equal(a.steps, b.steps)
    np.testing.assert_array_equal(a.greedy_steps, b.greedy_steps)
    assert a.agents[0].q == b.agents[0].q
    r = train_trials(task, "random", trials=3, episodes=50, seed=1, eval_episodes=200)
    assert a.greedy_steps.mean() < r.greedy_steps.mean() - 1.0
    assert a.curve[-50:].mean() < r.curve.mean()


@pytest.fixture(scope="module")
def learned():
    task = make_task("paper-box")
    res = train_trials(task, "sarsa", trials=5, episodes=2000, seed=0, eval_episodes=300)
    best = int(np.argmin(res.greedy_steps.mean(axis=1)))
    return task, GreedyPolicy.from_agent(task, 2, res.agents[best]), res


def test_paper_sarsa_reaches_target(learned):
    _, _, res = learned
    assert res.greedy_steps.mean() <= 1.75  # the target; the optimum is about 1.66
    assert res.greedy_success.all()


def test_learned_policy_shows_figure_8_behaviours(learned):
    task, policy, _ = learned
    rng = np.random.default_rng(0)
    oppositions = {0, 1}
    for pa, pb in [((-0.15, -0.02), (-0.10, -0.05)), ((0.10, -0.05), (0.15, -0.02))]:
        steps, ok = rollout(task, policy, policy.encoder, task.hand.contact(task.obj, pa, pb), rng)
        assert ok and steps[0].action in oppositions
        if steps[0].outcome.error != 0:  # aliased: the other opposition after an aperture error
            assert steps[0].outcome.error == 1 and len(steps) == 2
            assert steps[1].action == 1 - steps[0].action
    far = task.hand.contact(task.obj, (-0.15, -0.02), (-0.01, -0.05))  # b is 0.14 from the corner
    steps, ok = rollout(task, policy, policy.encoder, far, rng)
    assert ok and len(steps) == 2
    moved = task.actions[steps[0].action]
    assert moved.c == moved.f and steps[0].outcome.error == 0  # C3 or C4
    opp = task.actions[steps[1].action]
    assert opp.opposition and opp.f == moved.c  # the other contact opposes the moved one


def test_policy_file_roundtrip_and_errors(learned, tmp_path):
    task, policy, _ = learned
    path = policy.save(tmp_path / "p.json")
    back = GreedyPolicy.load(path, task)
    assert back.table == policy.table and back.k == 2
    by_path = GreedyPolicy.load(path)  # the task travels in the file
    assert by_path.task.name == task.name and by_path.table == policy.table
    enc = encoder_for(task, 2)
    s1, _ = evaluate(task, policy, enc, 100, np.random.default_rng(4))
    s2, _ = evaluate(task, back, enc, 100, np.random.default_rng(4))
    np.testing.assert_array_equal(s1, s2)
    doc = json.loads(path.read_text())

    def check(mutate, msg):
        d = json.loads(json.dumps(doc))
        mutate(d)
        d["sha256"] = policy_digest(d)  # re-signed: the fields' own checks answer
        bad = tmp_path / "bad.json"
        bad.write_text(json.dumps(d))
        with pytest.raises(CrmgraspError, match=msg) as info:
            GreedyPolicy.load(bad, task)
        assert "\n" not in str(info.value)

    check(lambda d: d.update(format="x"), "not a crmgrasp policy")
    check(lambda d: d.update(version=9), "unsupported policy version")
    check(lambda d: d.update(task="other"), "for task 'other'")
    check(lambda d: d.pop("bins"), "missing field")
    check(lambda d: d.update(agent={"name": 5}), '"agent" must be the learner')
    check(lambda d: d.update(k=-1), "k must be")
    check(lambda d: d.update(k=1000000), r"k must be an integer in \[0, 10\]")
    check(lambda d: d["actions"][0].__setitem__(2, 0.1), r"CRM set differs from the task's at CRM 1: \['a', 'b', 0.1\]")
    check(lambda d: d.update(actions=d["actions"] * 40), "CRM set has 160 CRMs, the task's 4$")  # not all 160 shown
    check(lambda d: d.update(actions=5), "CRM set is 5, not a list of the task's 4 CRMs")
    check(lambda d: d["bins"].update(rho=[2.0]), r"bins differ from the task's \(in rho\[0\]\)")
    check(lambda d: d["greedy"].update({"99999999": [0]}), "outside")
    check(lambda d: d["greedy"].update({"x": [0]}), "not a canonical non-negative integer")
    check(lambda d: d["greedy"].update({"0": [7]}), "actions must be")
    check(lambda d: d.update(k=0), "outside")  # k = 2 codes do not fit a k = 0 table
    edited = json.loads(json.dumps(doc))
    edited["k"] = 1  # not re-signed: the checksum refuses it
    (tmp_path / "edited.json").write_text(json.dumps(edited))
    with pytest.raises(CrmgraspError, match="checksum does not match"):
        GreedyPolicy.load(tmp_path / "edited.json", task)
    (tmp_path / "corrupt.json").write_text('{"format": ')
    with pytest.raises(CrmgraspError, match="not valid JSON"):
        GreedyPolicy.load(tmp_path / "corrupt.json", task)


def test_episodes_to_within():
    assert episodes_to_within(np.array([3.0] * 5), 1.0) is None
    assert episodes_to_within(np.array([3.0] * 10 + [1.0] * 20), 1.0) == 20
    assert episodes_to_within(np.array([1.0] * 30), 1.0) == 10
    assert episodes_to_within(np.array([1.0] * 30 + [9.0]), 1.0) is None


def test_checkpoints_use_the_same_starts(task):
    from crmgrasp.agents.training import checkpoint_generators

    a, b = checkpoint_generators(7), checkpoint_generators(7)
    assert [task.sample_start(a[0]) for _ in range(5)] == [task.sample_start(b[0]) for _ in range(5)]
    res = train_trials(task, "sarsa", trials=2, episodes=30, seed=7, eval_episodes=10, checkpoints=(10, 30, 99))
    assert res.checkpoints.tolist() == [10, 30] and res.checkpoint_steps.shape == (2, 2)
    # a random policy evaluated twice on the checkpoint starts sees identical starts
    r1 = evaluate(task, make_agent("fixed", 4, sequence=(0, 1)), encoder_for(task, 2), 20, *checkpoint_generators(3))
    r2 = evaluate(task, make_agent("fixed", 4, sequence=(0, 1)), encoder_for(task, 2), 20, *checkpoint_generators(3))
    np.testing.assert_array_equal(r1[0], r2[0])


def test_greedy_prefers_tried_actions():
    rng = np.random.default_rng(0)
    agent = make_agent("sarsa", 3)
    agent.update(5, 1, -1.0, 6, None, True, rng)  # only action 1 tried in state 5: Q = -0.3
    assert agent.act(5, rng) in (0, 2)  # behaviour explores the optimistic untried actions
    assert all(agent.greedy(5, rng) == 1 for _ in range(10))  # the learned policy uses what it knows
    task = make_task("paper-box")
    agent4 = make_agent("q", 4)
    agent4.update(7, 2, -1.0, 8, None, True, rng)
    assert GreedyPolicy.from_agent(task, 2, agent4).table[7] == (2,)


def _aliased_episode(agent, rng, learn=True):
    """A hand-made POMDP with a known answer. Hidden state H (A or B, even odds) is
    aliased: the first observation is 0 either way. Action 0 grasps in A, action 1 in
    B; the wrong one fails and reveals H (observation 1: it is B; 2: it is A); action 2
    always fails and reveals nothing (observation 3). Reward -1 per step; the states
    are the last observation. Optimal: 0 or 1 first, then the other: 1.5 steps."""
    hidden = int(rng.integers(2))  # 0: A, 1: B
    s, steps = 0, 0
    agent.begin_episode()
    a = agent.act(s, rng) if learn else agent.greedy(s, rng)
    while True:
        steps += 1
        done = a == hidden
        s2 = s if done else (3 if a == 2 else (1 if hidden == 1 else 2))
        if done or steps >= 10:
            if learn:
                agent.update(s, a, -1.0, s2, None, done, rng)
            return steps
        a2 = agent.act(s2, rng) if learn else agent.greedy(s2, rng)
        if learn:
            agent.update(s, a, -1.0, s2, a2, False, rng)
        s, a = s2, a2


def test_model_vi_reaches_the_optimum_of_an_aliased_pomdp_and_is_deterministic():
    def run(seed):
        rng = np.random.default_rng(seed)
        agent = make_agent("model-vi", 3)
        lengths = [_aliased_episode(agent, rng) for _ in range(30)]
        return agent, lengths

    agent, lengths = run(0)
    assert run(0)[1] == lengths and run(0)[0].greedy_table == agent.greedy_table
    rng = np.random.default_rng(1)
    assert agent.greedy(1, rng) == 1 and agent.greedy(2, rng) == 0 and agent.greedy(0, rng) in (0, 1)
    greedy = [_aliased_episode(agent, rng, learn=False) for _ in range(2000)]
    assert np.mean(greedy) == pytest.approx(1.5, abs=4 * 0.5 / np.sqrt(2000))
    # the greedy value of the start is the expected return of the optimum: -1 - 0.9 * 0.5
    assert max(agent.greedy_table[0]) == pytest.approx(-1.45, abs=0.15)


def test_model_vi_greedy_never_bets_on_an_untried_action():
    agent = make_agent("model-vi", 3)
    rng = np.random.default_rng(0)
    agent.update(0, 2, -1.0, 5, 0, False, rng)  # action 2 in state 0: failed once
    assert agent.act(0, rng) in (0, 1)  # acting: the untried ones look better (q_act -1.5)
    assert agent.greedy(0, rng) == 2  # greedy: only what was tried


def test_model_vi_prior_from_a_family_and_its_errors():
    from crmgrasp.agents.training import build_agent, encoder_for

    task = make_task("paper-box")
    enc = encoder_for(task, 1)
    params = {"symmetric": True, "prior_task": "box-family", "prior_episodes": 50}
    a, b = build_agent(task, enc, "model-vi", params), build_agent(task, enc, "model-vi", params)
    assert a.inner.model and a.inner.model == b.inner.model  # the same prior, computed once
    with pytest.raises(CrmgraspError, match="other CRMs"):
        build_agent(task, enc, "model-vi", {"prior_task": "cup-family"})
    with pytest.raises(CrmgraspError, match="needs a model-based agent"):
        build_agent(task, enc, "sarsa", {"prior_task": "box-family"})


def test_the_collector_is_held_off_while_a_planning_model_is_rebuilt_and_restored_after():
    """``collector_paused`` restores the collector as it found it (on or off), also on an
    error; the learners that rebuild their planning model, the belief-space optimum and the
    belief policy leave it on."""
    import gc

    from crmgrasp._collector import collector_paused
    from crmgrasp.agents.training import train_trials
    from crmgrasp.planners.references import BeliefPolicy, belief_optimum, sample_starts
    from crmgrasp.sim import run_episode

    with collector_paused():
        assert not gc.isenabled()
    assert gc.isenabled()
    with pytest.raises(ValueError), collector_paused():
        raise ValueError("inside")
    assert gc.isenabled()
    gc.disable()
    try:
        with collector_paused():
            pass
        assert not gc.isenabled()
    finally:
        gc.enable()
    for agent in ("backoff-vi", "pooled-vi"):
        train_trials(make_task("u-handle"), agent, trials=1, episodes=5, seed=0, eval_episodes=1)
        assert gc.isenabled()
    task = make_task("u-handle")
    starts = sample_starts(task, 20, 0)
    belief_optimum(task, starts)
    policy = BeliefPolicy(task, starts)
    policy.optimum()
    run_episode(task, policy, np.random.default_rng(0))
    assert gc.isenabled()


def test_what_a_paused_build_made_goes_to_the_oldest_generation_and_its_cycles_are_still_collected():
    """When ``collector_paused`` ends, the objects built in it are in the collector's oldest
    generation, where no young pass walks them; a cycle made and dropped in the block is still
    freed by a full pass; objects the process had frozen itself stay frozen."""
    import gc
    import weakref

    from crmgrasp._collector import collector_paused

    class Node:
        pass

    gc.collect()
    with collector_paused():
        built = [[i] for i in range(1000)]  # lists: the collector tracks them (not all dicts)
        cycle = Node()
        cycle.me = cycle  # type: ignore[attr-defined]
        gone = weakref.ref(cycle)
        del cycle
    oldest = {id(o) for o in gc.get_objects(generation=2)}
    assert all(id(d) in oldest for d in built)
    assert not any(o is built for o in gc.get_objects(generation=0))
    assert gone() is not None  # a cycle waits for the collector ...
    gc.collect()
    assert gone() is None  # ... and is freed by a full pass: nothing stayed frozen
    assert gc.get_freeze_count() == 0
    mine = [{"frozen": True}]
    gc.freeze()
    try:
        frozen = gc.get_freeze_count()
        with collector_paused():
            later = [{"outcome": 0}]
        assert gc.get_freeze_count() == frozen  # the process's own freeze kept
        assert any(o is later for o in gc.get_objects(generation=0))
    finally:
        gc.unfreeze()
    del mine

"""The back-off learner (``backoff-vi``): its two-level planning model, the policy file with
its back-off table, and what it learns."""

from __future__ import annotations

import json

import numpy as np
import pytest

from crmgrasp._validation import CrmgraspError
from crmgrasp.agents.backoff import BackoffVI
from crmgrasp.agents.policy import GreedyPolicy
from crmgrasp.agents.training import build_agent, encoder_for, make_agent, train_trials
from crmgrasp.model.hand import Error
from crmgrasp.tasks import make_task


@pytest.fixture(scope="module")
def box():
    return make_task("paper-box")


def _agent(task, k=2, symmetric=False, **params) -> BackoffVI:
    agent = build_agent(task, encoder_for(task, k), "backoff-vi", {"symmetric": symmetric, **params})
    return getattr(agent, "inner", agent)


def test_long_histories_that_k1_aliases_get_their_own_crm(box):
    """Two histories end in the same k = 1 suffix ``(o, CRM 0)`` but began differently. After
    one, CRM 1 grasps; after the other, CRM 2 does, and each failed CRM senses ``o`` again.
    The k = 1 model pools them (each CRM grasps half the time); the long model tells them
    apart: its greedy policy takes CRM 1 after the first and CRM 2 after the second."""
    enc, d, rng = encoder_for(box, 2), box.discretizer, np.random.default_rng(0)
    o = d.compose((1, 0, 0), Error.NONE)
    first = [d.compose((0, 0, 0), Error.NONE), d.compose((0, 1, 1), Error.NONE)]
    agent = _agent(box, beta=1.0)
    hist = [enc.encode(enc.push(enc.start(f), 0, o)) for f in first]
    for _ in range(20):
        for s, good in zip(hist, (1, 2)):
            bad = 3 - good
            agent.update(s, good, -1.0, s, None, True, rng)  # grasped
            agent.update(s, bad, -1.0, enc.encode(enc.push(enc.decode(s), bad, o)), 0, False, rng)
    assert agent.greedy(hist[0], rng) == 1
    assert agent.greedy(hist[1], rng) == 2
    s1 = agent.suffix(hist[0])  # the k = 1 level: one state, both CRMs grasp half the time
    assert s1 == agent.suffix(hist[1])
    for a in (1, 2):
        counts = agent.short.model[(s1, a)]
        assert sum(c for (_, _, t), c in counts.items() if t) == 20 and sum(counts.values()) == 40


def test_planning_model_blends_own_counts_with_the_short_level(box):
    """``p(o | h, a) = (n(h, a, o) + beta p_1(o | h_1, a)) / (n(h, a) + beta)``: one own
    outcome and a short level that saw two other histories with the same suffix."""
    enc, d, rng = encoder_for(box, 2), box.discretizer, np.random.default_rng(0)
    o, o2 = d.compose((1, 0, 0), Error.NONE), d.compose((0, 0, 0), Error.NONE)
    agent = _agent(box, beta=2.0)
    h = enc.encode(enc.push(enc.start(o2), 0, o))
    other = enc.encode(enc.push(enc.start(d.compose((0, 1, 1), Error.NONE)), 0, o))
    after = enc.encode(enc.push(enc.decode(h), 1, o2))
    agent.update(h, 1, -1.0, after, 0, False, rng)  # own: once to o2
    agent.update(other, 1, -1.0, other, None, True, rng)  # short level: twice grasped
    agent.update(other, 1, -1.0, other, None, True, rng)
    judge = agent._planned()
    entry = judge.model[(("L", h), 1)]
    total = sum(entry.values())
    grasped = sum(c for (_, _, t), c in entry.items() if t)
    # short level at the suffix: 1 of 3 to o2, 2 of 3 grasped; own: 1 to o2
    assert grasped / total == pytest.approx((0 + 2.0 * 2 / 3) / (1 + 2.0))
    assert len(judge.tried[("L", h)]) >= 1


@pytest.mark.parametrize("gap", [2, 400])
def test_decay_weighs_a_count_by_its_age_in_episodes(box, gap):
    """With ``decay`` = 0.5 a count made ``gap`` episodes before the plan weighs ``0.5**gap``
    and one made in the plan's episode weighs 1 (``beta`` = 0: the own counts alone). At
    ``gap`` = 400 the stored counts pass 1e100 and are rescaled on the way; the weights hold."""
    enc, d, rng = encoder_for(box, 2), box.discretizer, np.random.default_rng(0)
    o, o2 = d.compose((1, 0, 0), Error.NONE), d.compose((0, 0, 0), Error.NONE)
    agent = _agent(box, beta=0.0, decay=0.5)
    h = enc.encode(enc.push(enc.start(o2), 0, o))
    after = enc.encode(enc.push(enc.decode(h), 1, o2))
    agent.begin_episode()
    agent.update(h, 1, -1.0, after, 0, False, rng)  # episode 1: to o2
    for _ in range(gap):
        agent.begin_episode()
    agent.update(h, 1, -1.0, h, None, True, rng)  # episode 1 + gap: grasped
    entry = agent._planned().model[(("L", h), 1)]
    grasped = sum(c for (_, _, t), c in entry.items() if t)
    moved = sum(c for (_, _, t), c in entry.items() if not t)
    assert grasped == pytest.approx(1.0) and moved == pytest.approx(0.5**gap, rel=1e-12)
    assert (agent._base > 0) == (gap == 400) and agent.params()["decay"] == 0.5  # rescaled or not


def test_a_decay_that_forgets_within_an_episode_rescales_before_it_overflows(box):
    """``decay`` = 1e-320 (a count one episode old weighs less than the smallest float): the
    stored counts are rescaled at each episode before ``decay ** -1`` would overflow (it did:
    OverflowError at the second episode), and the old count weighs nothing."""
    enc, d, rng = encoder_for(box, 2), box.discretizer, np.random.default_rng(0)
    o, o2 = d.compose((1, 0, 0), Error.NONE), d.compose((0, 0, 0), Error.NONE)
    agent = _agent(box, beta=0.0, decay=1e-320)
    h = enc.encode(enc.push(enc.start(o2), 0, o))
    agent.begin_episode()
    agent.update(h, 1, -1.0, enc.encode(enc.push(enc.decode(h), 1, o2)), 0, False, rng)
    for _ in range(3):
        agent.begin_episode()
    agent.update(h, 1, -1.0, h, None, True, rng)
    entry = agent._planned().model[(("L", h), 1)]
    assert sum(c for (_, _, t), c in entry.items() if t) == 1.0 and agent._base == 4
    assert sum(c for (_, _, t), c in entry.items() if not t) == 0.0


def test_mean_after_stops_the_draws_after_its_episode(box, monkeypatch):
    """With ``mean_after`` = 3 and ``plan_every`` = 1, the acting plan draws from the posterior
    in episodes 1-3 and is the mean model from episode 4 on; ``mean_after`` = 0 draws to the end."""
    for mean_after, draws in ((3, [1, 2, 3]), (0, [1, 2, 3, 4, 5, 6])):
        agent = _agent(box, plan_every=1, mean_after=mean_after)
        drawn: list[int] = []
        monkeypatch.setattr(agent, "_draw", lambda entries, rng, a=agent, d=drawn: d.append(a.episodes))
        rng = np.random.default_rng(0)
        agent.update(0, 1, -1.0, 0, None, True, rng)  # one count, so that every plan has an entry to draw
        for _ in range(6):
            agent.begin_episode()
            agent.act(0, rng)
        assert drawn == draws and agent.params()["mean_after"] == mean_after


def test_the_posterior_draw_is_one_gamma_draw_per_pseudo_count_in_order():
    """The acting model's draw: each entry's pseudo-counts ``c`` become ``Gamma(c, 1) + 1e-300``,
    entry after entry, outcome after outcome; drawn in one call, the numbers are those of
    successive scalar draws from the same generator, and the generator ends in the same state."""
    shapes = np.random.default_rng(5).uniform(0.01, 4.0, 40).tolist()
    entries = [
        (("L", i), i % 3, {(-1.0, ("S", j), False): c for j, c in enumerate(shapes[4 * i : 4 * i + 4])})
        for i in range(10)
    ]
    one, scalar = np.random.default_rng(9), np.random.default_rng(9)
    BackoffVI._draw(entries, one)
    expected = [float(scalar.gamma(c)) + 1e-300 for c in shapes]
    assert [v for _, _, e in entries for v in e.values()] == expected
    assert one.random() == scalar.random()


@pytest.mark.parametrize("middle", [False, True])
def test_the_middle_level_pools_histories_with_the_same_last_two_crms(box, middle):
    """k = 3. History ``h`` never tried CRM 1; ``h2`` (the same last two CRMs and
    observations, another first observation) grasped with it twice; ``h3`` (the same k = 1
    suffix, another k = 2 one) failed with it six times. The short level says a grasp 2 of 8;
    with ``middle`` the model of ``h`` backs off to the pooled k = 2 counts first:
    ``(2 + beta 2 / 8) / (2 + beta)``."""
    enc, d, rng = encoder_for(box, 3), box.discretizer, np.random.default_rng(0)
    ob, oc, od = (d.compose(v, Error.NONE) for v in ((1, 0, 0), (0, 1, 1), (1, 1, 0)))
    x1, x2 = d.compose((0, 0, 0), Error.NONE), d.compose((0, 0, 1), Error.NONE)

    def history(*obs):
        h = enc.start(obs[0])
        for o in obs[1:]:
            h = enc.push(h, 0, o)
        return enc.encode(h)

    h, h2, h3 = history(x1, ob, oc), history(x2, ob, oc), history(x1, od, oc)
    agent = _agent(box, k=3, beta=1.0, middle=middle)
    agent.update(h, 0, -1.0, h3, 0, False, rng)  # h has data (a long node), not for CRM 1
    for _ in range(2):
        agent.update(h2, 1, -1.0, h2, None, True, rng)
    for _ in range(6):
        agent.update(h3, 1, -1.0, h3, 0, False, rng)
    assert agent.suffix(h) == agent.suffix(h2) == agent.suffix(h3)
    entry = agent._planned().model[(("L", h), 1)]
    grasped = sum(c for (_, _, t), c in entry.items() if t) / sum(entry.values())
    assert grasped == pytest.approx((2 + 0.25) / 3 if middle else 0.25)


def test_the_middle_level_needs_its_counts_pooled_first():
    from crmgrasp.agents.backoff_middle import SuffixPool

    with pytest.raises(CrmgraspError, match="before any counts were pooled"):
        SuffixPool().code(5)


def test_training_repeats_bit_for_bit_and_the_file_is_the_greedy_policy(box, tmp_path):
    kw = {"trials": 1, "episodes": 80, "seed": 4, "k": 3, "eval_episodes": 0, "params": {"symmetric": True}}
    a = train_trials(box, "backoff-vi", **kw, checkpoints=(40, 80), checkpoint_episodes=100)
    b = train_trials(box, "backoff-vi", **kw, checkpoints=(40, 80), checkpoint_episodes=100)
    np.testing.assert_array_equal(a.steps, b.steps)
    np.testing.assert_array_equal(a.checkpoint_steps, b.checkpoint_steps)
    c = train_trials(box, "backoff-vi", **kw)  # no checkpoints: the same training episodes
    np.testing.assert_array_equal(a.steps, c.steps)
    agent = a.agents[0]
    policy = GreedyPolicy.from_agent(box, 3, agent)  # type: ignore[arg-type]
    assert policy.backoff is not None and policy.backoff.k == 1 and policy.backoff.table
    path = policy.save(tmp_path / "p.json")
    doc = json.loads(path.read_text())
    assert doc["version"] == 3 and doc["backoff"]["k"] == 1
    loaded = GreedyPolicy.load(path)
    enc, rng = encoder_for(box, 3), np.random.default_rng(2)
    kinds = {"long": 0, "backoff": 0, "unknown": 0}
    for _ in range(3000):  # random histories: listed, backed off or unknown
        h = enc.start(int(rng.integers(box.discretizer.size)))
        for _ in range(int(rng.integers(0, 4))):
            h = enc.push(h, int(rng.integers(4)), int(rng.integers(box.discretizer.size)))
        s = enc.encode(h)
        acts = loaded.table.get(s)
        kind = "long" if acts is not None else "backoff"
        if acts is None:
            acts = loaded.backoff.table.get(loaded.backoff.encoder.encode(h[:2]))
        if acts is None:
            kinds["unknown"] += 1
            continue
        kinds[kind] += 1
        for i in range(3):
            assert agent.greedy(s, np.random.default_rng(i)) in acts
            assert loaded.greedy(s, np.random.default_rng(i)) in acts
    assert min(kinds.values()) > 0, kinds


@pytest.mark.parametrize(("task_name", "k", "symmetric"), [("paper-box", 2, False), ("u-handle", 3, True)])
def test_a_crm_a_history_never_tried_gets_the_entry_its_own_routing_gives(task_name, k, symmetric):
    """Histories that share their newest ``k - 1`` CRMs share one untried entry per plan: it
    must be, outcome for outcome and in the same order, the entry routed from each history
    on its own (``p_1(. | h_1, b)`` through ``next_state`` to the nodes with data)."""
    task = make_task(task_name)
    trained = train_trials(
        task, "backoff-vi", trials=1, episodes=60, seed=1, k=k, eval_episodes=0, params={"symmetric": symmetric}
    )
    agent = getattr(trained.agents[0], "inner", trained.agents[0])
    judge = agent._planned()
    known = {s for s, _ in agent.counts}
    shared = 0
    for (node, b), entry in judge.model.items():
        if node[0] != "L" or (node[1], b) in agent.counts:
            continue
        s, own = node[1], {}
        for r, obs, t, p, n_seen in agent._short_in_frame(s, b):
            o = (r, agent._route(agent._next_state(s, b, obs), known), t)
            own[o] = own.get(o, 0.0) + 1.0 * p / n_seen
        assert list(entry.items()) == list(own.items())
        shared += 1
    assert shared > len(known)  # most long pairs were never tried, and each was checked


def test_the_back_off_table_is_checked(box, refused_policy):
    res = train_trials(box, "backoff-vi", trials=1, episodes=20, seed=0, k=2, eval_episodes=0)
    doc = GreedyPolicy.from_agent(box, 2, res.agents[0]).to_dict()  # type: ignore[arg-type]

    def refused(edit, match: str) -> None:
        refused_policy(doc, edit, match)

    refused(lambda d: d["backoff"].update(k=2), r"backoff k must be an integer in \[0, 2\)")
    refused(lambda d: d.pop("backoff"), 'has a "backoff" object')
    refused(lambda d: d.update(version=2), "only version 3 has one")
    refused(lambda d: d["backoff"]["greedy"].update({"999999": [0]}), "outside")
    refused(lambda d: d["backoff"].update(extra=1), 'has a "backoff" object')


def test_bad_settings_are_one_line_errors(box):
    with pytest.raises(CrmgraspError, match="needs long histories, k >= 2"):
        build_agent(box, encoder_for(box, 1), "backoff-vi")
    with pytest.raises(CrmgraspError, match="beta must be >= 0"):
        make_agent("backoff-vi", 4, beta=-1.0)
    with pytest.raises(CrmgraspError, match="plan_every"):
        make_agent("backoff-vi", 4, plan_every=0)
    with pytest.raises(CrmgraspError, match="sample must be true or false"):
        make_agent("backoff-vi", 4, sample="yes")
    with pytest.raises(CrmgraspError, match="middle must be true or false"):
        make_agent("backoff-vi", 4, middle=1)
    with pytest.raises(CrmgraspError, match="explore must be >= 0"):
        make_agent("backoff-vi", 4, explore=-0.5)
    with pytest.raises(CrmgraspError, match="explore_tried must be >= 0"):
        make_agent("backoff-vi", 4, explore_tried=-1.0)
    with pytest.raises(CrmgraspError, match="explore_tried"):
        make_agent("backoff-vi", 4, explore_tried=float("nan"))
    with pytest.raises(CrmgraspError, match="mean_after"):
        make_agent("backoff-vi", 4, mean_after=-1)
    for bad in (0.0, -0.5, float("nan")):
        with pytest.raises(CrmgraspError, match="decay must be"):
            make_agent("backoff-vi", 4, decay=bad)
    with pytest.raises(CrmgraspError, match=r"decay must be in \(0, 1\], got 1.5"):
        make_agent("backoff-vi", 4, decay=1.5)
    with pytest.raises(CrmgraspError, match="needs its state structure"):
        make_agent("backoff-vi", 4).update(0, 0, -1.0, 1, 0, False, np.random.default_rng(0))


def test_learns_the_paper_box(box):
    """From scratch, 200 task episodes, seeds 0-2: the greedy policy on 1,000 fixed starts
    is within 5% of the optimum (1.66) in every seed."""
    for seed in range(3):
        res = train_trials(
            box,
            "backoff-vi",
            trials=1,
            episodes=200,
            seed=seed,
            k=4,
            eval_episodes=0,
            params={"symmetric": True},
            checkpoints=(200,),
            checkpoint_episodes=1000,
        )
        assert res.checkpoint_steps[0, 0] <= 1.05 * 1.66


def test_explore_tries_what_the_short_level_rates_an_error():
    """notch-or-box at error cost 30, seed 4: after the sensing CRM on a box, the short
    level rates the grasping CRM a sure error (it errs after the same suffix on the notched
    block), so the draw never tries it and the greedy policy spends a CRM more on every box
    (+40%). With ``explore`` the draw tries it once and the policy is the optimum's (2.0)."""
    import dataclasses

    from crmgrasp.experiments._episodes import greedy_records
    from crmgrasp.planners.references import sample_starts

    task = dataclasses.replace(make_task("notch-or-box"), error_cost=30.0)
    test = sample_starts(task, 300, 1)
    cost = {}
    for explore in (0.0, 1.0):
        res = train_trials(task, "backoff-vi", trials=1, episodes=3000, seed=4, k=6, eval_episodes=0,
                           params={"explore": explore})  # fmt: skip
        (records,) = greedy_records(task, res.agents, test, 4, k=6)
        cost[explore] = np.mean([len(r.actions) + 30.0 * sum(r.errors) for r in records])
    assert cost[0.0] > 2.6 and cost[1.0] <= 2.05


def test_explore_tried_retries_a_crm_whose_first_tries_erred():
    """notch-or-box at error cost 1, seed 27: the grasping CRM's one early try from the start
    erred, so a draw from the counts never gives it a grasp and the greedy policy senses
    first (2.0 CRMs, no error); with ``explore_tried`` the draw retries it and the policy
    takes the risk as the optimum does (1.40, errors counted at 1)."""
    import dataclasses

    from crmgrasp.experiments._episodes import greedy_records
    from crmgrasp.planners.references import sample_starts

    task = dataclasses.replace(make_task("notch-or-box"), error_cost=1.0)
    test = sample_starts(task, 300, 1)
    cost = {}
    for tried in (0.0, 2.0):
        res = train_trials(task, "backoff-vi", trials=1, episodes=3000, seed=27, k=6, eval_episodes=0,
                           params={"explore": 2.0, "explore_tried": tried})  # fmt: skip
        (records,) = greedy_records(task, res.agents, test, 27, k=6)
        cost[tried] = np.mean([len(r.actions) + sum(r.errors) for r in records])
    assert cost[0.0] >= 1.95 and cost[2.0] <= 1.45


def test_a_draw_and_its_grasp_bonus_leave_the_shared_untried_entries_as_they_are():
    """A plan hands every history of a group the group's one untried entry (no copy); the
    posterior draw makes new entries, and the ``explore`` bonus is added to a copy. So the shared
    entries after a drawn plan with a bonus are those a plan without either makes, and the drawn
    plan's untried entries are the draws, one per history, with the bonus outcome in them."""
    task = make_task("u-handle")
    trained = train_trials(
        task, "backoff-vi", trials=1, episodes=60, seed=2, k=2, eval_episodes=0, params={"symmetric": True}
    )
    agent = getattr(trained.agents[0], "inner", trained.agents[0])
    agent.explore = 1.0
    judge = agent._rebuilt(np.random.default_rng(0))
    after_draw = {key: list(entry.items()) for key, entry in agent._untried.items()}
    untried = [(node, b) for node, b in judge.model if node[0] == "L" and (node[1], b) not in agent.counts]
    assert len(untried) > 100 and len({id(judge.model[pair]) for pair in untried}) == len(untried)
    grasp = task.grasp_reward
    assert all((grasp, node, True) in judge.model[(node, b)] for node, b in untried)
    agent._rebuilt(None)  # the mean model: the shared entries made afresh, nothing drawn or added
    assert {key: list(entry.items()) for key, entry in agent._untried.items()} == after_draw
    model = agent._planned().model
    shared = [(node, b) for node, b in model if node[0] == "L" and (node[1], b) not in agent.counts]
    assert len({id(model[pair]) for pair in shared}) < len(shared) / 2  # held, not copied

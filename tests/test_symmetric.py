"""Mirror symmetry of tasks and learning on the mirror quotient."""

import dataclasses
import json

import numpy as np
import pytest

from crmgrasp import make_task
from crmgrasp._validation import CrmgraspError
from crmgrasp.agents import GreedyPolicy
from crmgrasp.agents.symmetric import SymmetricAgent, mirror_observation_map
from crmgrasp.agents.tabular import DynaQ
from crmgrasp.agents.training import build_agent, encoder_for
from crmgrasp.cli.main import main
from crmgrasp.experiments.learning import SYMMETRIC_DYNA_Q, learn
from crmgrasp.model.hand import CRM
from crmgrasp.model.sensing import Discretizer, Error, observe
from crmgrasp.tasks import Symmetry

from .strategies import mirror_swap, mirror_x


def test_paper_box_declares_the_mirror_symmetry():
    task = make_task("paper-box")
    assert task.symmetry == Symmetry((1, 0, 3, 2))
    assert set(mirror_x(task.obj).vertices) == set(task.obj.vertices)  # the box is its own mirror image


@pytest.mark.parametrize(
    "change, match",
    [
        ({"symmetry": Symmetry((0, 1, 2, 3))}, "maps"),
        ({"symmetry": Symmetry((1, 2, 3, 0))}, "involutive permutation"),
        ({"symmetry": Symmetry((1, 0, 3))}, "involutive permutation"),
        ({"discretizer": Discretizer(m_a=(0.1,), m_b=(0.2,))}, "same m_a and m_b"),
        ({"symmetry": (1, 0, 3, 2)}, "must be a Symmetry"),
    ],
)
def test_bad_symmetry_is_a_clear_error(change, match):
    with pytest.raises(CrmgraspError, match=match):
        dataclasses.replace(make_task("paper-box"), **change)


def test_observation_map_matches_the_geometry():
    """Reflect the world and swap the labels: the discretized observation maps as declared."""
    task = make_task("paper-box")
    omap = mirror_observation_map(task)
    rng = np.random.default_rng(0)
    for _ in range(300):
        cfg = task.sample_start(rng)
        i = task.discretizer.index(observe(cfg), Error.NONE)
        assert task.discretizer.index(observe(mirror_swap(cfg)), Error.NONE) == omap[i]
        swap = {"a": "b", "b": "a"}
        for a, crm in enumerate(task.actions):
            mirrored = task.actions[task.symmetry.actions[a]]
            assert mirrored == CRM(swap[crm.c], swap[crm.f], -crm.r)


def test_mirror_is_an_involution_and_the_table_is_symmetric():
    task = make_task("paper-box")
    enc = encoder_for(task, 1)
    agent = build_agent(task, enc, "dyna-q", {"planning": "sweep", "n_planning": 10, "symmetric": True})
    assert isinstance(agent, SymmetricAgent) and agent.params()["symmetric"] is True
    for s in range(0, enc.size, 7):
        assert agent.mirror(agent.mirror(s)) == s
    learn_rng = np.random.default_rng(0)
    from crmgrasp.agents.training import run_episode

    for _ in range(30):
        run_episode(task, agent, enc, learn_rng, learn_rng)
    q, amap = agent.q, task.symmetry.actions
    assert len(q) > len(agent.inner.q)
    for s, row in q.items():
        m = agent.mirror(s)
        assert q[m] == [row[amap[a]] for a in range(4)]
    policy = GreedyPolicy.from_agent(task, 1, agent)
    for s, acts in policy.table.items():
        assert sorted(amap[a] for a in acts) == sorted(policy.table[agent.mirror(s)])


def test_symmetric_dyna_q_is_near_optimal_within_60_episodes():
    run = learn(make_task("paper-box"), SYMMETRIC_DYNA_Q, trials=20, episodes=60, seed=0, eval_episodes=0)
    assert run.summary["greedy_episodes_to_5pct"] is not None and run.summary["greedy_episodes_to_5pct"] <= 60
    plain = dataclasses.replace(SYMMETRIC_DYNA_Q, params={"planning": "sweep", "n_planning": 50})
    base = learn(make_task("paper-box"), plain, trials=20, episodes=60, seed=0, eval_episodes=0)
    assert base.summary["greedy_episodes_to_5pct"] is None  # without the symmetry: not yet


def test_symmetric_needs_a_declared_symmetry_and_a_tabular_learner(tmp_path, capsys):
    task = dataclasses.replace(make_task("paper-box"), symmetry=None)
    with pytest.raises(CrmgraspError, match="declares no symmetry"):
        build_agent(task, encoder_for(task, 1), "sarsa", {"symmetric": True})
    with pytest.raises(CrmgraspError, match="tabular learner"):
        build_agent(make_task("paper-box"), encoder_for(task, 1), "random", {"symmetric": True})
    with pytest.raises(CrmgraspError, match="true or false"):
        build_agent(make_task("paper-box"), encoder_for(task, 1), "sarsa", {"symmetric": "yes"})
    assert SymmetricAgent(DynaQ(4), make_task("paper-box"), encoder_for(task, 1)).name == "dyna-q"


def test_cli_learn_symmetric(tmp_path, capsys):
    out = tmp_path / "run"
    argv = ["learn", "--agent", "dyna-q", "--planning", "sweep", "--k", "1", "--symmetric", "--trials", "2"]
    assert main([*argv, "--episodes", "30", "--eval-episodes", "20", "--out", str(out)]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["params"]["symmetric"] is True and (out / "policy.json").exists()
    assert main(["learn", "--agent", "random", "--symmetric", "--episodes", "5", "--out", str(out)]) == 2
    assert "tabular learner" in capsys.readouterr().err

"""The reference peers PSRL and UCBVI: their planning, their learning on paper-box, and
their errors."""

from __future__ import annotations

import numpy as np
import pytest

from crmgrasp._validation import CrmgraspError
from crmgrasp.agents.peers import PSRL, UCBVI
from crmgrasp.agents.pooled import HistoryFrame
from crmgrasp.agents.training import build_agent, encoder_for, make_agent, train_trials
from crmgrasp.model.hand import Error
from crmgrasp.tasks import make_task


@pytest.fixture(scope="module")
def box():
    return make_task("paper-box")


def test_backward_induction_on_counted_outcomes(box):
    """From a start, CRM 0 grasps; CRM 1 leads to a history where CRM 2 grasps. The point
    estimate values them -1 and -2 with the whole horizon left, and -1 and -10 (the
    unknown worst case, ``v_max``) with one step left."""
    enc, d, rng = encoder_for(box, 1), box.discretizer, np.random.default_rng(0)
    o = d.compose((1, 0, 0), Error.NONE)
    s0 = enc.encode(enc.start(o))
    s1 = enc.encode(enc.push(enc.start(o), 1, d.compose((0, 1, 0), Error.NONE)))
    for cls in (PSRL, UCBVI):
        agent = make_agent(cls.name, 4)
        assert isinstance(agent, cls)
        agent.bind(HistoryFrame(box, enc))
        for _ in range(50):
            agent.update(s0, 0, -1.0, s0, None, True, rng)
            agent.update(s0, 1, -1.0, s1, 2, False, rng)
            agent.update(s1, 2, -1.0, s1, None, True, rng)
        q = agent._plan(agent._mean_model(), agent._mean_reward(), agent._point_estimate)
        tol = 0.1 if cls is PSRL else 1e-12  # PSRL's posterior mean keeps its prior's pseudo-counts
        assert q[0, s0, 0] == pytest.approx(-1.0, abs=tol) and q[0, s0, 1] == pytest.approx(-2.0, abs=tol)
        assert q[-1, s0, 1] == pytest.approx(-1.0, abs=tol) and q[0, s0, 3] == -10.0
        agent.begin_episode()
        assert agent.greedy(s0, rng) == 0


@pytest.mark.parametrize("agent", ["psrl", "ucbvi"])
def test_peers_learn_paper_box_and_repeat_bit_for_bit(box, agent):
    kw = {"trials": 1, "episodes": 200, "seed": 0, "k": 1, "eval_episodes": 0}
    a = train_trials(box, agent, **kw, checkpoints=(200,), checkpoint_episodes=1000)
    b = train_trials(box, agent, **kw, checkpoints=(200,), checkpoint_episodes=1000)
    np.testing.assert_array_equal(a.steps, b.steps)
    assert a.checkpoint_steps[0, 0] == b.checkpoint_steps[0, 0] <= 1.05 * 1.66  # seed 0: within 5% by 200


def test_peer_errors_are_one_line(box):
    with pytest.raises(CrmgraspError, match="alpha0 must be > 0"):
        make_agent("psrl", 4, alpha0=0.0)
    with pytest.raises(CrmgraspError, match="scale must be > 0"):
        make_agent("ucbvi", 4, scale=-1.0)
    with pytest.raises(CrmgraspError, match=r"dense table of .* cells"):
        build_agent(box, encoder_for(box, 3), "psrl")
    with pytest.raises(CrmgraspError, match="symmetric learning needs a tabular learner, got 'ucbvi'"):
        build_agent(box, encoder_for(box, 1), "ucbvi", {"symmetric": True})

"""pomdp_py's POUCT as an online peer (needs the extra ``crmgrasp[pomdp]``; skipped without it)."""

import numpy as np
import pytest

from crmgrasp import make_task
from crmgrasp._validation import CrmgraspError
from crmgrasp.agents.training import checkpoint_generators
from crmgrasp.planners.pouct import POUCTSettings, require_pomdp_py
from crmgrasp.sim import run_episode


def test_missing_extra_is_one_line(hide_module):
    hide_module("pomdp_py")
    with pytest.raises(CrmgraspError, match=r"pip install 'crmgrasp\[pomdp\]'"):
        require_pomdp_py()


def test_settings_are_checked():
    with pytest.raises(CrmgraspError, match="num_sims"):
        POUCTSettings(num_sims=0)
    with pytest.raises(CrmgraspError, match="exploration_const"):
        POUCTSettings(exploration_const=float("nan"))


pomdp_py = pytest.importorskip("pomdp_py", reason="needs the extra crmgrasp[pomdp]")

from crmgrasp.planners.pouct import POUCTPolicy  # noqa: E402


def _run(task, seed, episodes, sims=100):
    starts, _ = checkpoint_generators(0)
    policy = POUCTPolicy(task, np.random.default_rng(seed), POUCTSettings(num_sims=sims, particles=300))
    return policy, [run_episode(task, policy, starts) for _ in range(episodes)]


def test_pouct_grasps_paper_box_near_the_optimum_and_repeats():
    task = make_task("paper-box")
    _, first = _run(task, 1, 20)
    _, again = _run(task, 1, 20)
    assert [e.steps for e in first] == [e.steps for e in again]
    assert all(e.success for e in first)
    assert np.mean([e.steps for e in first]) <= 1.25 * task.reference_mean_steps


def test_the_belief_keeps_only_worlds_that_explain_the_readings():
    task = make_task("box-family")
    starts, _ = checkpoint_generators(3)
    policy = POUCTPolicy(task, np.random.default_rng(2), POUCTSettings(num_sims=30, particles=200))

    class Watch:
        def begin(self, first):
            policy.begin(first)
            assert policy._worlds and all(w.obs == first.obs_index for w in policy._worlds)

        def act(self):
            return policy.act()

        def tell(self, percept):
            policy.tell(percept)
            if not (percept.terminated or percept.truncated):
                assert all(w.obs == percept.obs_index for w in policy._worlds)

    episode = run_episode(task, Watch(), starts)
    assert episode.steps >= 1

"""pomdp_py's POUCT as an online peer (needs the extra ``crmgrasp[pomdp]``; skipped without it)."""

import numpy as np
import pytest

from crmgrasp import make_task
from crmgrasp._validation import CrmgraspError
from crmgrasp.agents.training import checkpoint_generators
from crmgrasp.cli.main import main
from crmgrasp.planners.pouct import POUCTSettings, require_pomdp_py
from crmgrasp.sim import run_episode


def test_missing_extra_is_one_line(hide_module, tmp_path, capsys):
    hide_module("pomdp_py")
    with pytest.raises(CrmgraspError, match=r"pip install 'crmgrasp\[pomdp\]'"):
        require_pomdp_py()
    out = tmp_path / "box.pomdp"
    assert main(["pomdp", "--cell", "0.02", "--pouct", "10", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert "crmgrasp[pomdp]" in err and len(err.splitlines()) == 1 and not out.exists()


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


def test_pouct_on_the_exported_pomdp_grasps_and_repeats(tmp_path):
    """POUCT on the sampled POMDP, its model read back from the Cassandra file: every start
    grasped, near the optimum, the same run from the same seed, the belief a distribution."""
    from crmgrasp.planners.pomdp import read_cassandra, write_cassandra
    from crmgrasp.planners.pomdp_task import TaskPOMDP, build_task_pomdp
    from crmgrasp.planners.pouct import ModelPOUCTPolicy

    task = make_task("paper-box")
    tp = build_task_pomdp(task, cell=0.02, n_starts=500, seed=0)
    tp = TaskPOMDP(task, read_cassandra(write_cassandra(tp.model, tmp_path / "box.pomdp")), tp.cells, tp.z0, tp.bins)

    def run(seed):  # type: ignore[no-untyped-def]
        starts, _ = checkpoint_generators(0)
        policy = ModelPOUCTPolicy(tp, np.random.default_rng(seed), POUCTSettings(num_sims=100))
        eps = []
        for _ in range(20):
            eps.append(run_episode(task, policy, starts))
            b = policy._b
            assert np.isclose(b.sum(), 1.0) and (b >= 0).all() and not b[tp.model.goal].any()
        return eps

    first, again = run(1), run(1)
    assert [e.steps for e in first] == [e.steps for e in again] and all(e.success for e in first)
    assert np.mean([e.steps for e in first]) <= 1.25 * task.reference_mean_steps


def test_the_model_draw_follows_the_running_sums():
    from crmgrasp.planners.pouct import _draw

    rng = np.random.default_rng(0)
    counts = np.bincount([_draw(np.cumsum([0.2, 0.0, 0.8]), rng) for _ in range(5000)], minlength=3)
    assert counts[1] == 0 and 900 < counts[0] < 1100 and counts.sum() == 5000
    assert _draw(np.cumsum([0.0, 0.0, 3.0]), rng) == 2


def test_the_pomdp_command_runs_pouct_on_its_model(tmp_path, capsys):
    out = tmp_path / "box.pomdp"
    argv = ["pomdp", "--cell", "0.02", "--samples", "5", "--starts", "300", "--episodes", "20", "--out", str(out)]
    assert main([*argv, "--pouct", "30", "--quiet"]) == 0
    text = capsys.readouterr().out
    line = next(x for x in text.splitlines() if x.startswith("pomdp_py's POUCT on the same model, 30 simulations"))
    assert line.endswith("success 100.0%") and out.read_text().startswith("# crmgrasp POMDP")

"""The grasp-controller baseline and the compare command."""

import csv
import json

import numpy as np
import pytest

from crmgrasp import Error, min_friction
from crmgrasp.agents.controller import GraspController, run_controller
from crmgrasp.cli.main import main
from crmgrasp.experiments.compare import CompareConfig, compare
from crmgrasp.experiments.learning import LearnerSpec
from crmgrasp.model.hand import execute_crm
from crmgrasp.sim import run_episode


def _episode(task, cfg):
    """The controller as a Policy through the one episode loop, from ``cfg``."""
    ep = run_episode(task, GraspController(task), np.random.default_rng(0), start=cfg, trace=True)
    for tr in ep.trace:  # the loop executed exactly what execute_crm gives
        out = execute_crm(task.obj, task.hand, tr.before.state.config, tr.action, tr.before.state.sensed)
        assert (out.config, out.error) == (tr.after.state.config, tr.after.error)
    assert ep.success == (min_friction(ep.trace[-1].after.state.config) <= task.mu_goal)
    return [(tr.action, tr.after.error) for tr in ep.trace], ep.success


def test_controller_by_hand(task):
    # far start: oppose with a (larger moment) -> palm error; slide b toward the corner by 0.08; oppose
    far = task.hand.contact(task.obj, (-0.15, -0.02), (-0.01, -0.05))
    crms, ok = _episode(task, far)
    assert ok and [str(c) for c, _ in crms] == ["(a,b,0)", "(b,b,-0.08)", "(a,b,0)"]
    assert [e for _, e in crms] == [Error.PALM, Error.NONE, Error.NONE]
    # near start where a has the larger moment and opposing with a works at once
    near = task.hand.contact(task.obj, (-0.15, -0.02), (-0.10, -0.05))
    crms, ok = _episode(task, near)
    assert ok and len(crms) == 1


def test_controller_statistics(task):
    steps, ok = run_controller(task, 500, np.random.default_rng(0))
    assert ok.all() and 1.8 < steps.mean() < 2.6
    again, _ = run_controller(task, 500, np.random.default_rng(0))
    np.testing.assert_array_equal(steps, again)


def test_compare_small(tmp_path):
    cfg = CompareConfig(
        trials=5,  # intervals over trials need 5 (stats.MIN_TRIALS)
        episodes=40,
        eval_episodes=30,
        reference_starts=300,
        learners=(LearnerSpec("sarsa", 2, {}, "SARSA"), LearnerSpec("random", 2, {}, "random")),
        deep=None,
    )
    s = compare(tmp_path, cfg)
    with open(tmp_path / "compare.csv") as fh:
        rows = {r["method"]: r for r in csv.DictReader(fh)}
    expected = {
        "SARSA",
        "random",
        "grasp controller",
        "belief-space optimum",
        "clairvoyant bound",
        "belief-space policy, executed",
    }
    assert expected <= set(rows) and any(name.startswith("sampled POMDP") for name in rows)
    assert float(rows["clairvoyant bound"]["mean_crms"]) <= float(rows["belief-space optimum"]["mean_crms"])
    # no policy beats the exact optimum of the starts it runs on (noise-free): the executed rows compare to it
    on_eval = float(rows["belief-space optimum, evaluation starts"]["mean_crms"])
    assert float(rows["belief-space policy, executed"]["mean_crms"]) >= on_eval - 1e-9
    assert float(rows["random"]["ci95_low"]) <= float(rows["random"]["mean_crms"]) <= float(rows["random"]["ci95_high"])
    assert "| grasp controller | baseline |" in (tmp_path / "compare.md").read_text()
    assert (tmp_path / "compare.png").stat().st_size > 1000
    assert json.loads((tmp_path / "config.json").read_text())["summary"] == s
    assert s["deep_rl"] == "not run (deep=None)"


@pytest.mark.slow
def test_compare_cli_quick(tmp_path, capsys):
    """The command line's quick comparison; RecurrentPPO is left out (``--deep-steps 0``), as
    ``reproduce --quick`` runs it (``tests/test_experiments.py``)."""
    assert main(["compare", "--quick", "--deep-steps", "0", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "belief-space optimum" in out and "grasp controller" in out and "not run" in out
    assert main(["compare", "--task", "nope", "--out", str(tmp_path)]) == 2


def test_the_controller_refuses_a_spatial_task():
    from crmgrasp import CrmgraspError, make_task
    from crmgrasp.agents.controller import GraspController

    with pytest.raises(CrmgraspError, match="two contacts in the plane; 'cup-3d' is spatial"):
        GraspController(make_task("cup-3d"))

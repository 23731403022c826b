"""The realizable reference: the belief-space policy over other starts, run from the starts
(`crmgrasp.planners.realizable`, `crmgrasp references --planner`)."""

import json
from dataclasses import replace

import numpy as np
import pytest

from crmgrasp import CrmgraspError, make_task
from crmgrasp.cli import main
from crmgrasp.model.sensing import SensorNoise
from crmgrasp.planners.realizable import policy_costs, realizable_reference
from crmgrasp.planners.references import (
    BeliefPolicy,
    belief_optimum,
    graspable_starts,
    sample_starts,
    ungraspable_fraction,
)


@pytest.mark.parametrize(
    ("make", "n"),
    [
        (lambda: make_task("paper-box"), 120),
        (lambda: make_task("u-handle"), 60),
        # errored CRMs cost 1 more: the optimum errs here (1.5 against 1.25 at cost 0), so
        # a policy's cost that left the errors out would not come out equal
        (lambda: replace(make_task("notch-or-box"), error_cost=1.0), 100),
        # sensing noise: the references' dynamics are noise-free, so are these costs
        (lambda: replace(make_task("paper-box"), noise=SensorNoise(0.05, 0.002)), 60),
    ],
)
def test_the_policy_over_the_starts_themselves_costs_the_optimum(make, n) -> None:
    task = make()
    starts = sample_starts(task, n, 3)
    policy = BeliefPolicy(task, starts)
    assert policy.optimum() == belief_optimum(task, starts)  # the same search, bit for bit
    costs = policy_costs(policy, starts)
    assert costs.shape == (n,)
    assert costs.mean() == pytest.approx(belief_optimum(task, starts), abs=1e-12)


def test_graspable_starts_cost_the_step_limit_where_not() -> None:
    task = make_task("u-handle")
    starts = sample_starts(task, 80, 0)
    graspable = graspable_starts(task, starts)
    assert graspable.dtype == bool and 0 < graspable.sum() < len(starts)  # seed 0 holds both kinds
    assert ungraspable_fraction(task, starts) == (~graspable).mean()
    costs = policy_costs(BeliefPolicy(task, sample_starts(task, 200, 1)), starts)
    assert np.all(costs[~graspable] == task.max_steps)


def test_realizable_reference_reports_both_and_their_graspable_means() -> None:
    task = make_task("u-handle")
    starts = sample_starts(task, 60, 0)
    same = realizable_reference(task, starts, 60, 0)  # the same draws: the policy is the optimum's
    assert same["optimum"] == belief_optimum(task, starts)
    assert same["over_optimum"] == 0.0 and same["mean"] == pytest.approx(same["optimum"])
    res = realizable_reference(task, starts, 300, 7, "nearest")
    costs = policy_costs(BeliefPolicy(task, sample_starts(task, 300, 7), "nearest"), starts)
    graspable = graspable_starts(task, starts)
    assert res["mean"] == costs.mean() and res["graspable_starts"] == graspable.sum()
    assert res["standard_error"] == pytest.approx(costs.std(ddof=1) / np.sqrt(60))
    assert res["mean_graspable"] == costs[graspable].mean()
    assert res["over_optimum_graspable"] == pytest.approx(res["mean_graspable"] / res["optimum_graspable"] - 1.0)
    assert (res["seed"], res["fallback"], res["planned_starts"]) == (7, "nearest", 300)
    with pytest.raises(CrmgraspError, match="unknown fallback 'near'"):
        realizable_reference(task, starts, 10, 1, "near")
    with pytest.raises(CrmgraspError, match="policy_costs needs a non-empty list of starts"):
        policy_costs(BeliefPolicy(task, starts), [])


def test_references_planner_command(capsys) -> None:
    args = ["references", "--task", "u-handle", "--starts", "50", "--planner", "200", "--quiet"]
    assert main([*args, "--json"]) == 0
    res = json.loads(capsys.readouterr().out)
    task = make_task("u-handle")
    starts = sample_starts(task, 50, 0)
    expected = realizable_reference(task, starts, 200, 1)  # --seed + 1 by default
    assert res["planner"] == pytest.approx(expected)
    assert res["belief_optimum"] == belief_optimum(task, starts)  # taken from the planner's run, the same
    assert main([*args[:5], "--json", "--quiet"]) == 0  # without --planner, from belief_optimum itself
    alone = json.loads(capsys.readouterr().out)
    for key in ("belief_optimum", "ungraspable_fraction"):  # the planner's run gives the same, bit for bit
        assert alone[key] == res[key]
    assert main([*args, "--planner-seed", "5", "--fallback", "nearest"]) == 0
    out = capsys.readouterr().out
    assert "planned over 200 other starts (seed 5, fallback nearest)" in out and "graspable starts" in out
    for flag, value in (("--planner-seed", "3"), ("--fallback", "restart")):
        assert main(["references", "--starts", "20", flag, value, "--quiet"]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and f"{flag} needs --planner" in err
    with pytest.raises(SystemExit) as stop:  # argparse's own check, before any work
        main(["references", "--starts", "20", "--planner", "0", "--quiet"])
    assert stop.value.code == 2
    assert "argument --planner: value must be an integer in [1, 1000000], got 0" in capsys.readouterr().err


def test_realizable_reference_shows_each_run_over_the_starts() -> None:
    import io

    from crmgrasp._progress import Progress

    task = make_task("u-handle")
    starts = sample_starts(task, 20, 0)
    shown = io.StringIO()
    res = realizable_reference(task, starts, 50, 1, progress=Progress(shown, live=False))
    out = shown.getvalue()
    assert "the optimum over the starts: done 20/20 starts" in out
    assert "a policy over 50 other starts: done 20/20 starts" in out
    assert res == realizable_reference(task, starts, 50, 1)  # the display changes nothing


def test_references_planner_from_a_single_start(capsys) -> None:
    """One start has no standard error: the text leaves it out, the JSON says null."""
    assert main(["references", "--starts", "1", "--planner", "5", "--quiet"]) == 0
    out = capsys.readouterr().out
    assert "planned over 5 other starts (seed 1, fallback restart):" in out and "standard error" not in out
    assert main(["references", "--starts", "1", "--planner", "5", "--quiet", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["planner"]["standard_error"] is None

"""Cost of failure: the episode classification on hand-made episodes, the error cost
in every step path, and a small run of the experiment."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from crmgrasp import CrmgraspError
from crmgrasp.agents import train_trials
from crmgrasp.experiments.cost_of_failure import CostConfig, EpisodeRecord, classify, cost_of_failure, policy_rows
from crmgrasp.planners.references import belief_optimum, sample_starts
from crmgrasp.tasks import make_task


def rec(
    o0: int, actions: tuple[int, ...], obs: tuple[int, ...], errors: tuple[bool, ...], ok: bool = True
) -> EpisodeRecord:
    return EpisodeRecord(o0, actions, obs, errors, ok)


def test_classify_hand_made_episodes() -> None:
    episodes = [
        rec(0, (0,), (9,), (False,)),  # grasped at once: an attempt that worked
        rec(0, (0, 1), (3, 9), (True, False)),  # the attempt failed, then the fallback
        rec(1, (2, 0), (5, 9), (False, False)),  # a sensing move: outcome 5 -> CRM 0 ...
        rec(1, (2, 1), (6, 9), (False, False)),  # ... outcome 6 -> CRM 1
        rec(2, (3, 0), (5, 9), (False, False)),  # a preparatory move: CRM 0 whatever comes
        rec(2, (3, 0), (6, 9), (False, False)),
    ]
    assert classify(episodes) == ["try-first", "try-first", "sense-first", "sense-first", "other", "other"]
    row = policy_rows(episodes, cost=2.0)
    assert row["mean_crms"] == pytest.approx(11 / 6) and row["errors_per_episode"] == pytest.approx(1 / 6)
    assert row["mean_cost"] == pytest.approx((11 + 2) / 6)
    assert (row["try_first_fraction"], row["sense_first_fraction"], row["other_fraction"]) == (2 / 6, 2 / 6, 2 / 6)


def test_ties_in_the_second_crm_are_not_sensing() -> None:
    # the same outcome followed by two CRMs (random tie-breaking) does not make a sensing move
    episodes = [rec(1, (2, 0), (5, 9), (False, False)), rec(1, (2, 1), (5, 9), (False, False))] * 2
    episodes.append(rec(1, (2, 0), (5, 9), (False, False)))
    assert classify(episodes) == ["other"] * 5


@pytest.mark.parametrize("backend", ["auto", "reference"])
def test_error_cost_in_the_rewards_of_every_step_path(backend: str) -> None:
    base = make_task("paper-box")
    task = dataclasses.replace(base, error_cost=3.0)
    from crmgrasp.kernels import kernel_for
    from crmgrasp.sim import step

    kernel = kernel_for(task, backend)
    rng = np.random.default_rng(0)
    seen = set()
    for _ in range(50):
        one = kernel.begin(kernel.sample_start(rng), rng)
        for a in range(4):
            fast = kernel.step_one(one.state, a, rng)
            ref = step(task, one.state, a, rng)
            assert fast.reward == ref.reward == (-4.0 if int(ref.error) else -1.0)
            seen.add(fast.reward)
    assert seen == {-1.0, -4.0}
    with pytest.raises(CrmgraspError, match="error_cost"):
        dataclasses.replace(base, error_cost=-1.0)


def test_belief_optimum_counts_the_error_cost() -> None:
    base = make_task("paper-box")
    starts = sample_starts(base, 150, 0)
    free = belief_optimum(base, starts)
    costly = belief_optimum(dataclasses.replace(base, error_cost=2.0), starts)
    assert free < costly <= free + 2.0 * 10  # more expensive, by at most c per CRM


def test_learners_see_the_error_cost() -> None:
    task = dataclasses.replace(make_task("paper-box"), error_cost=5.0)
    res = train_trials(task, "model-vi", trials=1, episodes=30, seed=0, k=1, eval_episodes=0)
    rewards = {o[0] for counts in res.agents[0].model.values() for o in counts}
    assert -6.0 in rewards


def test_cost_of_failure_writes_its_files(tmp_path) -> None:  # type: ignore[no-untyped-def]
    cfg = dataclasses.replace(CostConfig.quick(), costs=(0.0, 10.0), worlds=60, test_worlds=60, trials=1, episodes=40)
    s = cost_of_failure(tmp_path, cfg)
    for name in ("cost_of_failure.csv", "cost_of_failure.png", "summary.json"):
        assert (tmp_path / name).exists()
    saved = json.loads((tmp_path / "summary.json").read_text())
    assert [r["cost"] for r in saved["rows"]] == [0.0, 10.0]
    for r in saved["rows"] + saved["optimal_rows"]:
        assert {"cost", "mean_crms", "errors_per_episode", "sense_first_fraction"} <= set(r)
        assert r["try_first_fraction"] + r["sense_first_fraction"] + r["other_fraction"] == pytest.approx(1.0)
    assert s["optimal_rows"][1]["errors_per_episode"] <= s["optimal_rows"][0]["errors_per_episode"]
    assert set(s["tasks"]) == {"notch-or-box", "box-family"} and s["task"] == "notch-or-box"
    assert s["switch"] and s["optimal_rows"] == s["tasks"]["notch-or-box"]["optimal_rows"]  # the designed task
    assert not s["tasks"]["box-family"]["switch"]  # no error-free sensing move on boxes

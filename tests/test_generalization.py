"""Generalization and non-convex experiments on small budgets: files, keys, sanity."""

from __future__ import annotations

import dataclasses
import json

import numpy as np

from crmgrasp.experiments.generalization import GeneralizationConfig, _finite, generalization, strategy_rows
from crmgrasp.experiments.non_convex import INNER_EDGES, NonConvexConfig, inside, non_convex
from crmgrasp.model.contacts import Config, Contact
from crmgrasp.model.families import Pose, UHandleFamily
from crmgrasp.tasks import make_task

KEYS = (
    "learner_mean_crms",
    "belief_optimum",
    "clairvoyant_bound",
    "success_rate",
    "heldout_mean_crms",
    "out_of_range_mean_crms",
    "search_heldout_mean_crms",
    "search_gap_to_optimum",
    "search_heldout_gap_normalized",
    "heldout_gap_normalized",
)


def test_generalization_summary_has_every_key(tmp_path) -> None:  # type: ignore[no-untyped-def]
    cfg = dataclasses.replace(GeneralizationConfig.quick(), heldout=60)
    s = generalization(tmp_path, cfg)
    saved = json.loads((tmp_path / "summary.json").read_text())
    for name in cfg.families:
        f = saved["families"][name]
        assert set(KEYS) <= set(f)
        assert f["clairvoyant_bound"] <= f["belief_optimum"] + 1e-12
        assert (tmp_path / f"strategy_{name}.csv").exists()
    cup = s["families"]["cup-family"]  # one opposition grasps every disc: learned at once
    assert cup["heldout_mean_crms"] == cup["belief_optimum"] == 1.0
    assert cup["search_heldout_mean_crms"] == 1.0 and cup["search_episodes"] >= cfg.search_worlds
    box = s["families"]["box-family"]  # normalized: each mean over its own worlds' optimum
    ratio = (box["heldout_mean_crms"] / box["belief_optimum"]) / (box["learner_mean_crms"] / box["seen_belief_optimum"])
    assert box["heldout_gap_normalized"] == ratio - 1.0
    assert "paper_box_policy_mean_crms" in s["families"]["box-family"]
    assert (tmp_path / "generalization.png").exists() and (tmp_path / "generalization.csv").exists()


def test_training_objects_are_a_fixed_finite_set() -> None:
    task = _finite(make_task("box-family"), 3, seed=0)
    rng = np.random.default_rng(1)
    drawn = {task.instance(rng).obj.vertices for _ in range(60)}
    assert len(drawn) == 3


def test_strategy_rows_show_the_second_crm_per_outcome() -> None:
    from crmgrasp.experiments.cost_of_failure import EpisodeRecord

    task = make_task("paper-box")
    records = [EpisodeRecord(0, (0, 1), (16, 0), (True, False), True), EpisodeRecord(0, (0,), (0,), (False,), True)]
    rows = strategy_rows(task, records)
    assert rows[0][:3] == [task.discretizer.label(0), task.action_names()[0], 1.0]
    assert {r[3] for r in rows} == {"grasp", task.discretizer.label(16)}
    assert [r[5] for r in rows if r[3] != "grasp"] == [task.action_names()[1]]


def test_inside_the_handle() -> None:
    u = UHandleFamily(width=(0.2, 0.2), height=(0.1, 0.1), thickness=(0.04, 0.04), pose=Pose((0.0, 0.0), (0.0, 0.0)))
    obj = u.sample(np.random.default_rng(0))
    edges = obj.edges
    mid = [(e[0] + 0.5 * e[2], e[1] + 0.5 * e[3], e[5], e[6]) for e in edges]
    outer = Contact(*mid[0])
    for i, m in enumerate(mid):
        assert inside(obj, Config(outer, Contact(*m))) == (i in INNER_EDGES)


def test_non_convex_writes_its_figure(tmp_path) -> None:  # type: ignore[no-untyped-def]
    s = non_convex(tmp_path, dataclasses.replace(NonConvexConfig.quick(), heldout=40, episodes=80))
    for name in ("non_convex.png", "non_convex.gif", "rollouts.csv", "summary.json"):
        assert (tmp_path / name).exists()
    assert 0.0 <= s["inside_share"] <= 1.0 and s["clairvoyant_bound"] <= s["belief_optimum"]

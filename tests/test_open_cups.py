"""Open cups as a task: the family ``OpenCupOnTable`` (a triangle mesh, not convex), the
registered task ``open-cup-3d``, its task files and its learning and references."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import ConvexHull

from crmgrasp._validation import CrmgraspError
from crmgrasp.agents.training import train_trials
from crmgrasp.model.family_base import Pose
from crmgrasp.model.hand import Error
from crmgrasp.model.mesh import TriangleMesh
from crmgrasp.model.solid_families import OpenCupOnTable
from crmgrasp.planners.references import belief_optimum, clairvoyant_bound, sample_starts
from crmgrasp.tasks import make_task, task_names

STILL = Pose(angle=(0.0, 0.0), offset=(0.0, 0.0))


def test_the_family_draws_upright_and_lying_cups_on_the_table_the_same_per_seed() -> None:
    fam = OpenCupOnTable()
    cups = [fam.sample(np.random.default_rng(s)) for s in range(40)]
    again = [fam.sample(np.random.default_rng(s)) for s in range(40)]
    assert [c.vertices for c in cups] == [c.vertices for c in again]
    upright = 0
    for cup in cups:
        assert isinstance(cup, TriangleMesh)
        assert abs(cup.support((0.0, 0.0, 1.0))) < 1e-12  # resting on the table
        assert not cup.contains(cup.centre)  # the centre of volume is in the cavity
        bottom = cup.vertices[-2]  # the outer bottom's centre: on the table when upright, a radius up when lying
        upright += abs(bottom[2]) < 1e-12
    assert 10 < upright < 30


def test_a_lying_cup_opens_along_its_yaw() -> None:
    cup = OpenCupOnTable(radius=(0.04, 0.04), height=(0.1, 0.1), upright=0.0, pose=STILL).sample(
        np.random.default_rng(0)
    )
    v = np.array(cup.vertices)
    assert np.allclose(v[:, 0].min(), -0.05) and np.allclose(v[:, 0].max(), 0.05)  # the axis along x
    assert np.allclose(v[:, 2].max(), 0.08)  # two radii high
    inside = np.array([0.049, 0.0, 0.04])  # just inside the opening, on the axis
    assert not cup.contains(inside) and cup.contains(np.array([-0.048, 0.0, 0.04]))  # the bottom is at -x


@pytest.mark.parametrize(
    ("kw", "message"),
    [
        ({"wall": 0.03}, "open cup wall must be a number in"),
        ({"wall": float("nan")}, "open cup wall must be a number in"),
        ({"upright": 1.5}, "upright must be a probability"),
        ({"segments": 4}, "segments must be an integer"),
        ({"radius": (0.07, 0.03)}, "open cup radius"),
    ],
)
def test_bad_open_cup_families_get_one_line_errors(kw: dict, message: str) -> None:
    with pytest.raises(CrmgraspError, match=message) as err:
        OpenCupOnTable(**kw)
    assert "\n" not in str(err.value)


def test_open_cup_3d_is_registered_and_a_crm_can_pinch_the_wall() -> None:
    """Some CRMs put a contact on an inner surface (inside the cup's convex hull: the inner
    wall or the inner bottom, reached through the opening), and some of those grasp."""
    assert "open-cup-3d" in task_names()
    task = make_task("open-cup-3d")
    inner = grasps = 0
    for w in sample_starts(task, 30, 0):
        hull = ConvexHull(np.array(w.task.obj.vertices))
        for crm in w.task.actions:
            out = w.task.execute(w.config, crm, w.config)
            if out.error is not Error.NONE:
                continue
            depth = [max(float(e[:3] @ np.array(c.x) + e[3]) for e in hull.equations) for c in out.config]
            if min(depth) < -1e-6:
                inner += 1
                grasps += bool(w.task.is_success(out.config))
    assert inner >= 5 and grasps >= 2


def test_open_cups_in_task_files_round_trip_and_refuse_unknown_keys(tmp_path) -> None:  # type: ignore[no-untyped-def]
    from crmgrasp.tasks import load_task_file, task_from_dict, task_to_dict

    task = make_task("open-cup-3d")
    doc = task_to_dict(task)
    assert doc["family"]["kind"] == "open_cup" and doc["family"]["wall"] == 0.005
    again = task_from_dict(doc)
    assert task_to_dict(again) == doc
    rng, rng2 = np.random.default_rng(3), np.random.default_rng(3)
    assert task.sample_world(rng).config == again.sample_world(rng2).config
    text = (
        'name = "cups"\nmodel = "spatial"\n[hand]\naperture = 0.16\npalm_depth = 0.12\n'
        '[[crm]]\nc = "a"\nf = "b"\n[family]\nkind = "open_cup"\nwall = 0.004\nlength = [0.1, 0.2]\n'
    )
    path = tmp_path / "cups.toml"
    path.write_text(text)
    with pytest.raises(CrmgraspError, match="kind 'open_cup' takes no length") as err:
        load_task_file(path)
    assert "\n" not in str(err.value)
    path.write_text(text.replace("length = [0.1, 0.2]\n", ""))
    assert load_task_file(path).family.wall == 0.004  # type: ignore[union-attr]


@pytest.mark.slow
def test_open_cups_have_references_and_a_learner_beats_random_deterministically() -> None:
    task = make_task("open-cup-3d")
    worlds = sample_starts(task, 12, 0)
    bound = clairvoyant_bound(task, worlds)
    assert 1.0 <= bound <= belief_optimum(task, worlds) < 3.0
    kw = {"trials": 1, "episodes": 120, "seed": 2, "k": 1, "eval_episodes": 60}
    a, b = train_trials(task, "model-vi", **kw), train_trials(task, "model-vi", **kw)
    assert np.array_equal(a.steps, b.steps) and np.array_equal(a.greedy_steps, b.greedy_steps)
    random = train_trials(task, "random", **{**kw, "episodes": 1})  # it learns nothing: scored on 60 episodes
    assert a.greedy_steps.mean() < 0.6 * random.greedy_steps.mean()

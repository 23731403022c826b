"""The cost-of-failure task ``notch-or-box``: its starts, its CRMs' outcomes on each of
its two objects (the design the docs state), and the predicted switch to sensing."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from crmgrasp import CrmgraspError
from crmgrasp.experiments.cost_of_failure import episode_records, policy_rows
from crmgrasp.model import families as fam
from crmgrasp.model.hand import Error
from crmgrasp.planners.references import BeliefPolicy, sample_starts
from crmgrasp.tasks import make_task
from crmgrasp.tasks.families import NOTCHED_BLOCK
from crmgrasp.tasks.presets import VertexStarts

BOX = fam.FixedShape(((0.0, 0.0), (0.30, 0.0), (0.30, 0.10), (0.0, 0.10)))
BLOCK = fam.FixedShape(NOTCHED_BLOCK)


@pytest.fixture(scope="module")
def task():  # type: ignore[no-untyped-def]
    return make_task("notch-or-box")


def _outcomes(task, shape, rng):  # type: ignore[no-untyped-def]
    one = task.with_object(shape.sample(rng))
    start = one.starts(one.obj, one.hand, one.mu_goal, rng)
    out = [one.execute(start, crm, start) for crm in one.actions]
    return one, start, out


def test_vertex_starts_are_near_vertex_0_with_fixed_labels(task) -> None:  # type: ignore[no-untyped-def]
    rng = np.random.default_rng(0)
    for shape in (BOX, BLOCK):
        for _ in range(50):
            one = task.with_object(shape.sample(rng))
            a, b = one.starts(one.obj, one.hand, one.mu_goal, rng)
            v = np.array(one.obj.vertices[0])
            assert 0.005 <= np.hypot(a.x - v[0], a.y - v[1]) <= 0.045 + 1e-12  # a: incoming side
            assert 0.005 <= np.hypot(b.x - v[0], b.y - v[1]) <= 0.035 + 1e-12  # b: outgoing side
            n = len(one.obj.vertices)
            assert one.obj.edge_index((a.x, a.y)) == n - 1 and one.obj.edge_index((b.x, b.y)) == 0


def test_the_two_objects_alias_at_the_start_and_the_slide_tells_them_apart(task) -> None:  # type: ignore[no-untyped-def]
    rng = np.random.default_rng(1)
    d = task.discretizer
    for _ in range(40):
        box, box_start, on_box = _outcomes(task, BOX, rng)
        block, block_start, on_block = _outcomes(task, BLOCK, rng)
        assert d.index(box.observe(box_start), Error.NONE) == d.index(block.observe(block_start), Error.NONE)
        # C1 (oppose across) grasps the box, errs on the block; C2 the other way round
        assert on_box[0].error is Error.NONE and box.is_success(on_box[0].config)
        assert on_block[0].error is Error.APERTURE
        assert on_block[1].error is Error.NONE and block.is_success(on_block[1].config)
        assert on_box[1].error is Error.APERTURE
        # C5 (slide b past the notch) errs on neither, and its outcome differs
        assert on_box[4].error is Error.NONE and on_block[4].error is Error.NONE
        seen_box = d.index(box.observe(on_box[4].config), Error.NONE)
        seen_block = d.index(block.observe(on_block[4].config), Error.NONE)
        assert seen_box != seen_block


def test_costly_failures_switch_the_optimum_from_trying_to_sensing(task) -> None:  # type: ignore[no-untyped-def]
    rows = {}
    for c in (0.0, 10.0):
        t = dataclasses.replace(task, error_cost=c)
        worlds, test = sample_starts(t, 100, 0), sample_starts(t, 200, 1)
        belief = BeliefPolicy(t, worlds)
        rows[c] = policy_rows(episode_records(t, lambda b=belief: b, test, 0), c)
    cheap, dear = rows[0.0], rows[10.0]
    # free failures: try C1, fall back on C2 (errors = the block's share, about 1 in 5)
    assert cheap["try_first_fraction"] == 1.0 and 0.1 < cheap["errors_per_episode"] < 0.3
    # dear failures: slide first, then C1 or C2 by what the slide showed; no errors
    assert dear["sense_first_fraction"] == 1.0 and dear["errors_per_episode"] == 0.0
    assert dear["mean_crms"] == 2.0 and cheap["mean_crms"] < 1.3


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"vertex": -1}, "vertex must be an index >= 0"),
        ({"incoming": (0.05, 0.01)}, "incoming must be \\[low, high\\] with 0 < low <= high"),
        ({"outgoing": (0.0, 0.01)}, "outgoing must be"),
        ({"a_on": "left"}, "a_on must be 'incoming' or 'outgoing'"),
    ],
)
def test_vertex_starts_bad_input(kwargs, message) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(CrmgraspError, match=message):
        VertexStarts(**kwargs)


def test_vertex_starts_refuse_a_missing_vertex_or_too_long_reach(task) -> None:  # type: ignore[no-untyped-def]
    rng = np.random.default_rng(0)
    box = BOX.nominal()
    with pytest.raises(CrmgraspError, match="vertex 7 does not exist on a polygon of 4 vertices"):
        VertexStarts(7)(box, task.hand, task.mu_goal, rng)
    with pytest.raises(CrmgraspError, match="reach past the sides at vertex 0"):
        VertexStarts(0, incoming=(0.01, 0.2))(box, task.hand, task.mu_goal, rng)


def test_fixed_shape_bad_vertices() -> None:
    with pytest.raises(CrmgraspError, match="vertices must be \\[x, y\\] pairs"):
        fam.FixedShape(((0.0, 0.0), "x"))  # type: ignore[arg-type]
    with pytest.raises(CrmgraspError, match="at least 3 vertices"):
        fam.FixedShape(((0.0, 0.0), (0.1, 0.0)))


NOTCH_TOML = """
name = "my-notch"
[family]
kind = "mixed"
weights = [4, 1]
members = [{ kind = "polygon", vertices = [[0, 0], [0.3, 0], [0.3, 0.1], [0, 0.1]] },
           { kind = "polygon", vertices = [[0, 0], [0.04, 0], [0.04, -0.05], [0.14, -0.05], [0.14, 0.2], [0, 0.2]] }]
[hand]
aperture = 0.16
palm_depth = 0.12
[[crm]]
c = "a"
f = "b"
[[crm]]
c = "b"
f = "a"
[starts]
kind = "vertex"
vertex = 0
incoming = [0.005, 0.045]
outgoing = [0.005, 0.035]
a_on = "incoming"
"""


def test_the_task_in_a_file(tmp_path) -> None:  # type: ignore[no-untyped-def]
    from crmgrasp.tasks import load_task_file, task_from_dict, task_to_dict

    path = tmp_path / "notch.toml"
    path.write_text(NOTCH_TOML)
    task = load_task_file(path)
    assert isinstance(task.starts, VertexStarts) and task.starts.outgoing == (0.005, 0.035)
    assert task_from_dict(task_to_dict(task)) == task
    rng = np.random.default_rng(0)
    for _ in range(20):  # both objects, touched near vertex 0 with a on the incoming side
        world = task.sample_world(rng)
        obj, a = world.task.obj, world.config.a
        assert obj.edge_index((a.x, a.y)) == len(obj.vertices) - 1
    path.write_text(NOTCH_TOML.replace("incoming = [0.005, 0.045]", "incoming = [0.005, 0.045, 0.1]"))
    with pytest.raises(CrmgraspError, match=r"\[starts\] incoming must have 2 numbers, got 3"):
        load_task_file(path)
    path.write_text(
        NOTCH_TOML.replace(
            'kind = "polygon", vertices = [[0, 0], [0.3, 0]', 'kind = "polygon", vertices = [[0, 0], [0.3, "x"]'
        )
    )
    with pytest.raises(CrmgraspError, match="polygon vertices must be"):
        load_task_file(path)

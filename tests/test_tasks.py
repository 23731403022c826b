import numpy as np
import pytest

from crmgrasp import CRM, CrmgraspError, Disc, Error, Hand, Polygon, Task, make_task, min_friction, register_task
from crmgrasp.tasks import CornerStarts, UniformStarts, task_names


def test_paper_box_matches_spec(task):
    assert task.name == "paper-box"
    assert task.obj.vertices == ((-0.15, -0.05), (0.15, -0.05), (0.15, 0.05), (-0.15, 0.05))
    assert (task.hand.aperture, task.hand.palm_depth, task.hand.backoff) == (0.16, 0.12, 0.01)
    assert task.actions == (CRM("a", "b", 0), CRM("b", "a", 0), CRM("a", "a", 0.08), CRM("b", "b", -0.08))
    assert task.discretizer.size == 24 and task.max_steps == 10 and task.mu_goal == 0.05
    assert task.reference_mean_steps == 1.66
    assert make_task("paper-box") == task


def test_corner_starts_are_valid_and_deterministic(task):
    starts = [task.sample_start(np.random.default_rng(s)) for s in range(300)]
    again = [task.sample_start(np.random.default_rng(s)) for s in range(300)]
    assert starts == again
    corners = set()
    for cfg in starts:
        assert task.hand.feasible(task.obj, cfg) is Error.NONE
        assert min_friction(cfg) > task.mu_goal
        edges = {task.obj.edge_index(c.point) for c in cfg}
        assert len(edges) == 2 and (max(edges) - min(edges)) in (1, 3)  # adjacent sides
        corners.add(frozenset(edges))
    assert len(corners) == 4  # every corner occurs


def test_uniform_starts_on_a_disc():
    t = Task("disc", Disc(0.05), Hand(0.16, 0.12), (CRM("a", "b", 0),), starts=UniformStarts())
    cfg = t.sample_start(np.random.default_rng(1))
    assert t.hand.feasible(t.obj, cfg) is Error.NONE


def test_corner_starts_need_a_polygon():
    t = Task("disc", Disc(0.05), Hand(0.16, 0.12), (CRM("a", "b", 0),), starts=CornerStarts())
    with pytest.raises(CrmgraspError, match="polygon"):
        t.sample_start(np.random.default_rng(0))


def test_impossible_start_reports_cleanly():
    t = Task("tiny", Disc(0.5), Hand(0.01, 0.12), (CRM("a", "b", 0),), starts=UniformStarts(max_tries=50))
    with pytest.raises(CrmgraspError, match="no feasible uniform start"):
        t.sample_start(np.random.default_rng(0))


def test_registry_and_validation(task):
    with pytest.raises(CrmgraspError, match=r"unknown task 'nope'; known tasks: .*paper-box"):
        make_task("nope")
    register_task("my-disc", lambda: Task("my-disc", Disc(0.05), Hand(0.16, 0.12), (CRM("a", "b", 0),)))
    assert "my-disc" in task_names() and make_task("my-disc").name == "my-disc"
    with pytest.raises(CrmgraspError, match="already registered"):
        register_task("my-disc", lambda: task)
    with pytest.raises(CrmgraspError, match="at least one CRM"):
        Task("x", task.obj, task.hand, ())
    with pytest.raises(CrmgraspError, match="beyond r_max"):
        Task("x", task.obj, task.hand, (CRM("a", "a", 0.5),))
    with pytest.raises(CrmgraspError, match="max_steps"):
        Task("x", task.obj, task.hand, task.actions, max_steps=0)
    with pytest.raises(CrmgraspError, match="Shape"):
        Task("x", "box", task.hand, task.actions)


def _odd_corners_task() -> Task:
    """Acute, obtuse and reflex corners, sides longer than the aperture: the batched
    sampler's per-corner boxes and corner weights all differ from 1."""
    poly = Polygon([(0, 0), (0.4, 0), (0.1, 0.12), (0.12, 0.3), (-0.05, 0.1)])
    return Task("odd-corners", poly, Hand(aperture=0.09, palm_depth=0.02), (CRM("a", "b", 0),), starts=CornerStarts())


@pytest.mark.parametrize("backend", ["reference", "numba"])
@pytest.mark.parametrize("which", ["paper-box", "odd-corners"])
def test_batched_corner_starts_match_the_scalar_distribution(task, backend, which):
    from scipy.stats import chi2_contingency, ks_2samp

    from crmgrasp.kernels import kernel_for
    from crmgrasp.tasks import corner_boxes

    t = task if which == "paper-box" else _odd_corners_task()
    rng = np.random.default_rng(0)
    scalar = np.array([np.asarray(t.sample_start(rng)).ravel() for _ in range(3000)])
    batch = kernel_for(t, backend).sample_starts(np.random.default_rng(1), 3000)
    for col in range(8):  # every coordinate and normal component, two-sample KS test
        assert ks_2samp(scalar[:, col], batch[:, col], method="asymp").pvalue > 1e-3, col
    kinds = [np.unique(np.round(x[:, [2, 3, 6, 7]], 9), axis=0, return_counts=True) for x in (scalar, batch)]
    assert np.array_equal(kinds[0][0], kinds[1][0])  # the same (corner, label order) combinations occur
    assert chi2_contingency(np.stack([kinds[0][1], kinds[1][1]])).pvalue > 1e-3  # equally often
    _, c_in, c_out = corner_boxes(t.obj, t.hand.aperture)
    assert (c_in < 1).any() and (c_out < 1).any()  # the tighter proposal is in use


def test_an_action_index_is_an_integer_in_range_and_every_step_takes_it_so():
    """Task.action_index is the one rule: the readable step and every kernel refuse the same
    values in one line, and take NumPy integers as Python ones."""
    from crmgrasp.kernels import kernel_for
    from crmgrasp.sim import reset, step

    for name in ("paper-box", "triangles-3f", "cup-3d"):
        task = make_task(name)
        world, n = task.instance(np.random.default_rng(0)), len(task.actions)
        assert task.action_index(np.int64(n - 1)) == n - 1 and task.action_index(np.array(0)) == 0
        now, kernel = reset(world, np.random.default_rng(0)), kernel_for(task)
        if task.family is not None:
            kernel.use(world)
        message = rf"^action must be an integer in \[0, {n}\), got "
        for bad in (-1, n, True, 1.0, None, "0", np.array([0]), np.float64(0.0)):
            with pytest.raises(CrmgraspError, match=message):
                step(world, now.state, bad, np.random.default_rng(0))
            with pytest.raises(CrmgraspError, match=message):
                kernel.step_one(now.state, bad, np.random.default_rng(0))
        assert task.action_indices([0, n - 1], 2).tolist() == [0, n - 1]
        for bad, text in (([0, n], rf"in \[0, {n}\)"), ([0.0, 1.0], "2 integers"), ([0], "2 integers")):
            with pytest.raises(CrmgraspError, match=text):
                task.action_indices(bad, 2)


def test_a_registered_task_is_named_by_the_task_name_rule_and_made_by_a_callable(monkeypatch):
    from crmgrasp.tasks import core

    monkeypatch.setattr(core, "_TASKS", dict(core._TASKS))
    for bad in ("", "my task", "../x", "-x", "x" * 65, 3):
        with pytest.raises(CrmgraspError, match=r"^name must be 1-64 letters, digits"):
            register_task(bad, core.paper_box)
    with pytest.raises(CrmgraspError, match=r"^a task factory must be callable with no arguments, got 3$"):
        register_task("three", 3)
    register_task("five", lambda: 5)
    with pytest.raises(CrmgraspError, match=r"^the factory registered as task 'five' returned 5, not a Task$"):
        make_task("five")
    with pytest.raises(CrmgraspError, match=r"^name must be"):
        Task(name="my task", obj=core.paper_box().obj, hand=core.paper_box().hand, actions=core.paper_box().actions)


def test_a_regular_polygon_has_at_most_max_vertices():
    from crmgrasp import regular_polygon
    from crmgrasp.model.polygon import MAX_VERTICES

    assert len(regular_polygon(MAX_VERTICES, 0.1).vertices) == MAX_VERTICES
    for n in (2, MAX_VERTICES + 1, 10**9, 5.0, True):
        with pytest.raises(
            CrmgraspError, match=rf"^a regular polygon needs an integer n in \[3, {MAX_VERTICES}\], got "
        ):
            regular_polygon(n, 0.1)


def test_a_task_made_from_a_task_with_the_longest_name_keeps_a_valid_name():
    """A user's name has at most 64 characters; a task made from it (an offset grid) adds a suffix."""
    import dataclasses

    from crmgrasp.tasks.offsets import offset_grid

    task = dataclasses.replace(make_task("paper-box"), name="n" * 64)
    assert offset_grid(task, 9).name == "n" * 64 + "-grid9"
    with pytest.raises(CrmgraspError, match=r"^name must be 1-128 letters"):
        dataclasses.replace(task, name="n" * 129)

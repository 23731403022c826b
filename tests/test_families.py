"""Object families: samplers, poses, general starts, family tasks, envs and references."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from hypothesis import given, settings
from hypothesis import strategies as st

from crmgrasp import CrmgraspError
from crmgrasp.agents import train_trials
from crmgrasp.envs.single import FAMILY_ENVS
from crmgrasp.model import families as fam
from crmgrasp.model.contacts import Config, Contact
from crmgrasp.model.family_base import _uniform
from crmgrasp.model.geometry import Disc, Polygon, Rectangle
from crmgrasp.model.hand import Error, Hand, execute_crm, feasible
from crmgrasp.model.quality import min_friction
from crmgrasp.model.sensing import observe
from crmgrasp.planners.references import belief_optimum, clairvoyant_bound, sample_starts, ungraspable_fraction
from crmgrasp.tasks import BoundaryStarts, World, default_crms, make_task, task_from_dict, task_to_dict
from crmgrasp.tasks.families import FAMILY_TASKS, family_task

N = 400


def _pose_of(shape: Polygon | Disc) -> tuple[float, float]:
    """The shape's centre (vertex bounding-box centre before the pose is the origin)."""
    if isinstance(shape, Disc):
        return shape.center
    v = np.array(shape.vertices)
    return tuple(v.mean(axis=0))  # type: ignore[return-value]


def _spread(values: list[float], lo: float, hi: float) -> None:
    """Within ``[lo, hi]`` and covering it: min and max within 10% of the ends, and
    the mean within 4 standard errors of the midpoint (uniform draws)."""
    v = np.array(values)
    assert v.min() >= lo - 1e-12 and v.max() <= hi + 1e-12
    assert v.min() <= lo + 0.1 * (hi - lo) and v.max() >= hi - 0.1 * (hi - lo)
    se = (hi - lo) / math.sqrt(12 * len(v))
    assert abs(v.mean() - 0.5 * (lo + hi)) < 4 * se


def test_box_family_sizes_and_poses_spread_over_their_ranges() -> None:
    f = fam.BoxFamily(length=(0.2, 0.4), width=(0.06, 0.14))
    rng = np.random.default_rng(0)
    lengths, widths, angles, xs = [], [], [], []
    for _ in range(N):
        p = f.sample(rng)
        assert isinstance(p, Polygon) and len(p.vertices) == 4
        v = np.array(p.vertices)
        sides = [float(np.hypot(*(v[(i + 1) % 4] - v[i]))) for i in range(4)]
        lengths.append(max(sides))
        widths.append(min(sides))
        long_edge = int(np.argmax(sides))
        e = v[(long_edge + 1) % 4] - v[long_edge]
        angles.append(math.atan2(e[1], e[0]) % math.pi)  # the long axis, modulo a half turn
        xs.append(_pose_of(p)[0])
    _spread(lengths, 0.2, 0.4)
    _spread(widths, 0.06, 0.14)
    _spread(angles, 0.0, math.pi)
    _spread(xs, -0.05, 0.05)


@pytest.mark.parametrize(
    ("family", "measure", "lo", "hi"),
    [
        (fam.DiscFamily(radius=(0.03, 0.07)), lambda s: s.radius, 0.03, 0.07),
        (fam.RegularPolygonFamily(sides=(3, 8)), lambda s: len(s.vertices), 3, 8),
        (fam.ConvexPolygonFamily(vertices=(3, 8)), lambda s: len(s.vertices), 3, 8),
        (fam.StarFamily(points=(4, 6)), lambda s: len(s.vertices) // 2, 4, 6),
        (fam.UHandleFamily(thickness=(0.03, 0.05)), lambda s: fam.width(s), 0.0, 1.0),
    ],
)
def test_family_parameters_stay_in_range_and_spread(family, measure, lo, hi) -> None:  # type: ignore[no-untyped-def]
    rng = np.random.default_rng(1)
    shapes = [family.sample(rng) for _ in range(N)]
    values = [measure(s) for s in shapes]
    assert min(values) >= lo and max(values) <= hi
    if isinstance(lo, int):
        assert set(values) == set(range(lo, hi + 1))  # every integer occurs
    elif hi < 1.0:
        _spread(values, lo, hi)
    xs = [_pose_of(s)[0] for s in shapes]
    assert max(abs(x) for x in xs) <= 0.05 + 0.2  # the offset plus the shape's own size


def test_convex_family_draws_convex_polygons_with_the_centre_inside() -> None:
    rng = np.random.default_rng(2)
    for _ in range(200):
        p = fam.ConvexPolygonFamily(pose=fam.Pose(angle=(0.0, 0.0), offset=(0.0, 0.0))).sample(rng)
        assert isinstance(p, Polygon) and p.convex and p.contains((0.0, 0.0))


def test_non_convex_families_draw_simple_non_convex_polygons() -> None:
    rng = np.random.default_rng(3)
    for f in (fam.UHandleFamily(), fam.LShapeFamily(), fam.TShapeFamily(), fam.StarFamily()):
        for _ in range(50):
            p = f.sample(rng)
            assert isinstance(p, Polygon) and not p.convex


def test_mixed_family_draws_each_member_by_weight() -> None:
    f = fam.MixedFamily((fam.BoxFamily(), fam.DiscFamily()), (3.0, 1.0))
    rng = np.random.default_rng(4)
    discs = sum(isinstance(f.sample(rng), Disc) for _ in range(N))
    assert abs(discs / N - 0.25) < 4 * math.sqrt(0.25 * 0.75 / N)


def _bits(shape: Polygon) -> list[str]:
    """Every coordinate's repr: equal lists are equal bit for bit, the sign of a zero included."""
    return [repr(c) for v in shape.vertices for c in v]


def test_the_box_family_draws_what_placing_its_rectangle_draws() -> None:
    """`BoxFamily.sample` (five draws in one call, the rectangle built posed) gives the polygon
    of the generic rule: the rectangle of two single draws, placed by three more."""
    family = fam.BoxFamily()
    for seed in range(3):
        fast, generic = np.random.default_rng(seed), np.random.default_rng(seed)
        for _ in range(500):
            length, width = _uniform(generic, family.length), _uniform(generic, family.width)
            pose = tuple(_uniform(generic, r) for r in (family.pose.angle, family.pose.offset, family.pose.offset))
            assert _bits(family.sample(fast)) == _bits(fam.place(Rectangle(length, width), *pose))
        assert fast.random() == generic.random()  # the streams stay in step


@settings(max_examples=60, deadline=None)
@given(
    length=st.floats(1e-3, 10.0),
    width=st.floats(1e-3, 10.0),
    angle=st.floats(-10.0, 10.0),
    dx=st.floats(-1.0, 1.0),
    dy=st.floats(-1.0, 1.0),
)
def test_a_rectangle_built_posed_is_the_rectangle_moved(length, width, angle, dx, dy) -> None:  # type: ignore[no-untyped-def]
    assert _bits(Rectangle(length, width, (angle, dx, dy))) == _bits(Rectangle(length, width).moved(angle, dx, dy))


def test_a_rectangle_posed_beyond_the_bound_or_by_nan_is_refused() -> None:
    with pytest.raises(CrmgraspError, match="not finite or beyond"):
        Rectangle(0.3, 0.1, (0.0, 2e6, 0.0))
    with pytest.raises(CrmgraspError, match=r"^rectangle pose\[0\] must be finite, got nan$"):
        Rectangle(0.3, 0.1, (math.nan, 0.0, 0.0))
    with pytest.raises(CrmgraspError, match=r"^rectangle pose must be \(angle, dx, dy\), got 0.5$"):
        Rectangle(0.3, 0.1, 0.5)  # type: ignore[arg-type]


def _move(c: Contact, angle: float, dx: float, dy: float) -> Contact:
    co, si = math.cos(angle), math.sin(angle)
    return Contact(co * c.x - si * c.y + dx, si * c.x + co * c.y + dy, co * c.nx - si * c.ny, si * c.nx + co * c.ny)


@settings(max_examples=40, deadline=None)
@given(
    angle=st.floats(0.0, 2 * math.pi),
    dx=st.floats(-0.5, 0.5),
    dy=st.floats(-0.5, 0.5),
    seed=st.integers(0, 2**32 - 1),
)
def test_a_placed_object_gives_the_same_crm_outcomes_in_its_own_frame(angle, dx, dy, seed) -> None:  # type: ignore[no-untyped-def]
    task = make_task("u-handle")
    rng = np.random.default_rng(seed)
    shape = fam.UHandleFamily(pose=fam.Pose(angle=(0.0, 0.0), offset=(0.0, 0.0))).sample(rng)
    placed = fam.place(shape, angle, dx, dy)
    cfg = BoundaryStarts()(shape, task.hand, task.mu_goal, rng)
    moved = Config(_move(cfg.a, angle, dx, dy), _move(cfg.b, angle, dx, dy))
    for crm in task.actions:
        here = execute_crm(shape, task.hand, cfg, crm, cfg)
        there = execute_crm(placed, task.hand, moved, crm, moved)
        assert here.error == there.error
        want = Config(_move(here.config.a, angle, dx, dy), _move(here.config.b, angle, dx, dy))
        assert np.allclose([*want.a, *want.b], [*there.config.a, *there.config.b], atol=1e-9)
        o1, o2 = observe(here.config), observe(there.config)
        assert np.allclose(o1, o2, atol=1e-9)
        mu1, mu2 = min_friction(here.config), min_friction(there.config)
        assert math.isclose(mu1, mu2, abs_tol=1e-9) or min(mu1, mu2) > 1e6  # parallel normals: inf or huge


@pytest.mark.parametrize("name", sorted(FAMILY_TASKS))
def test_general_starts_are_feasible_and_not_grasps(name: str) -> None:
    task = make_task(name)
    rng = np.random.default_rng(5)
    for _ in range(100):
        w = task.sample_world(rng)
        assert feasible(w.task.obj, w.task.hand, w.config) is Error.NONE
        assert min_friction(w.config) > task.mu_goal
        assert w.task.family is None and w.task.obj is not task.obj


def test_near_vertex_starts_stay_near_a_vertex() -> None:
    box = Rectangle(0.3, 0.1)
    hand = Hand(aperture=0.16, palm_depth=0.12)
    rng = np.random.default_rng(6)
    verts = np.array(box.vertices)
    for _ in range(200):
        cfg = BoundaryStarts(near_vertex=0.04)(box, hand, 0.05, rng)
        for c in (cfg.a, cfg.b):
            assert np.min(np.hypot(*(verts - [c.x, c.y]).T)) <= 0.04 + 1e-12


def test_family_tasks_refuse_a_start_without_an_object() -> None:
    with pytest.raises(CrmgraspError, match="draws an object per episode"):
        make_task("box-family").sample_start(np.random.default_rng(0))


def test_worlds_are_deterministic_per_seed() -> None:
    task = make_task("mixed")
    a = sample_starts(task, 20, 3)
    b = sample_starts(task, 20, 3)
    assert all(isinstance(w, World) for w in a)
    assert [(w.task.obj, w.config) for w in a] == [(w.task.obj, w.config) for w in b]


def test_disc_family_references_one_opposition_always_grasps() -> None:
    task = make_task("cup-family")
    worlds = sample_starts(task, 60, 0)
    assert clairvoyant_bound(task, worlds) == 1.0
    assert belief_optimum(task, worlds) == 1.0
    assert ungraspable_fraction(task, worlds) == 0.0


def test_box_family_references_bracket_the_paper_box() -> None:
    task = make_task("box-family")
    worlds = sample_starts(task, 100, 0)
    clair, belief = clairvoyant_bound(task, worlds), belief_optimum(task, worlds)
    assert 1.0 <= clair < belief <= 2.5
    assert ungraspable_fraction(task, worlds) == 0.0


@pytest.mark.parametrize("env_id", sorted(FAMILY_ENVS))
def test_family_envs_pass_check_env_and_vectorise(env_id: str) -> None:
    import warnings

    env = gym.make(env_id)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_env(env.unwrapped)
    vec = gym.make_vec(env_id, num_envs=3, vectorization_mode="vector_entry_point")
    obs, info = vec.reset(seed=0)
    assert obs["rho"].shape == (3, 1) and info["config"].shape == (3, env.unwrapped.task.model.row_width)
    ended = 0
    for _ in range(25):
        obs, reward, term, trunc, info = vec.step(vec.action_space.sample())
        ended += int(np.sum(term | trunc))
        assert set(np.unique(reward)) <= {-1.0, 0.0}
    assert ended > 0


def test_family_env_resets_from_a_given_world() -> None:
    task = make_task("box-family")
    env = gym.make("crmgrasp/BoxFamily-v0").unwrapped
    w = task.sample_world(np.random.default_rng(0))
    _, info = env.reset(seed=0, options={"world": w})
    assert info["config"] == w.config and env.scene_task.obj == w.task.obj
    with pytest.raises(CrmgraspError, match="World"):
        env.reset(options={"world": w.config})
    u = make_task("u-handle").sample_world(np.random.default_rng(0))  # other CRMs: other action space
    with pytest.raises(CrmgraspError, match="a world of task 'u-handle', whose CRMs, hand or bins are not"):
        env.reset(options={"world": u})


def test_family_training_is_the_same_on_every_backend() -> None:
    task = make_task("box-family")
    kw = {"trials": 2, "episodes": 40, "seed": 3, "eval_episodes": 20, "checkpoints": (20,)}
    fast = train_trials(task, "sarsa", backend="auto", **kw)
    ref = train_trials(task, "sarsa", backend="reference", **kw)
    assert np.array_equal(fast.steps, ref.steps) and np.array_equal(fast.greedy_steps, ref.greedy_steps)
    assert np.array_equal(fast.checkpoint_steps, ref.checkpoint_steps)


def test_cup_family_sarsa_learns_the_one_opposition() -> None:
    res = train_trials(make_task("cup-family"), "sarsa", trials=2, episodes=1000, seed=0, eval_episodes=100)
    assert res.greedy_success.all() and res.greedy_steps.mean() == 1.0


def test_family_task_files_round_trip() -> None:
    for name in FAMILY_TASKS:
        t = make_task(name)
        assert task_from_dict(task_to_dict(t)) == t


@pytest.mark.parametrize(
    ("build", "message"),
    [
        (lambda: fam.BoxFamily(length=(0.4, 0.2)), "box length range .* inverted"),
        (lambda: fam.BoxFamily(width=()), "box width must be a range"),
        (lambda: fam.DiscFamily(radius=(0.0, 0.05)), "disc radius range .* must be above 0"),
        (lambda: fam.DiscFamily(radius=(math.nan, 0.05)), "finite numbers"),
        (lambda: fam.RegularPolygonFamily(sides=(2, 5)), "sides range .* must start at 3"),
        (lambda: fam.UHandleFamily(width=(0.08, 0.1), thickness=(0.03, 0.05)), "U handle thickness .* non-simple"),
        (lambda: fam.LShapeFamily(arm=(0.05, 0.2), thickness=(0.03, 0.06)), "L shape thickness .* non-simple"),
        (lambda: fam.StarFamily(inner=(0.5, 1.2)), "star inner range .* below 1"),
        (lambda: fam.MixedFamily(()), "one or more member"),
        (lambda: fam.MixedFamily((fam.BoxFamily(),), (-1.0,)), "weights"),
        (lambda: family_task("big", fam.BoxFamily(length=(0.3, 0.4), width=(0.2, 0.3))), "beyond the hand's aperture"),
        (lambda: family_task("big", fam.DiscFamily(radius=(0.09, 0.1))), "no object it draws can be grasped"),
    ],
)
def test_bad_families_get_one_line_errors(build, message: str) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(CrmgraspError, match=message) as info:
        build()
    assert "\n" not in str(info.value)


def test_rejection_loops_are_bounded() -> None:
    too_many = fam.ConvexPolygonFamily(vertices=(12, 12))
    rng = np.random.default_rng(0)
    try:  # twelve points with gaps >= 5.7 degrees and <= 150: possible but rare; bounded either way
        too_many.sample(rng)
    except CrmgraspError as exc:
        assert "in 1000 draws" in str(exc)
    starts = BoundaryStarts(max_tries=5)
    with pytest.raises(CrmgraspError, match="no feasible boundary start found in 5 tries"):
        starts(Rectangle(0.3, 0.1), Hand(aperture=0.16, palm_depth=0.12), 100.0, rng)  # every pair a grasp


def test_task_files_state_families(tmp_path) -> None:  # type: ignore[no-untyped-def]
    from crmgrasp.tasks import load_task_file

    text = """
name = "my-boxes"
[family]
kind = "box"
length = [0.2, 0.3]
width = [0.05, 0.1]
pose = { angle = [0.0, 1.0], offset = [0.0, 0.0] }
[hand]
aperture = 0.16
palm_depth = 0.12
[[crm]]
c = "a"
f = "b"
"""
    p = tmp_path / "t.toml"
    p.write_text(text)
    t = load_task_file(p)
    assert isinstance(t.family, fam.BoxFamily) and t.family.length == (0.2, 0.3)
    assert isinstance(t.starts, BoundaryStarts)
    p.write_text(text.replace('kind = "box"', 'kind = "box"\nradius = [0.1, 0.2]'))
    with pytest.raises(CrmgraspError, match="kind 'box' takes no radius"):
        load_task_file(p)
    p.write_text(text.replace("length = [0.2, 0.3]", "length = [0.3, 0.2]"))
    with pytest.raises(CrmgraspError, match=r"box length range .* inverted"):
        load_task_file(p)
    p.write_text(text + "[object]\nrectangle = { length = 0.3, width = 0.1 }\n")
    with pytest.raises(CrmgraspError, match="exactly one of"):
        load_task_file(p)


def test_default_crms_and_their_mirror() -> None:
    acts = default_crms((0.04,))
    assert len(acts) == 6
    t = family_task("x", fam.DiscFamily(), actions=acts)
    assert t.symmetry is not None and t.symmetry.actions == (1, 0, 3, 2, 5, 4)


def test_compare_and_lockstep_on_a_family(tmp_path) -> None:  # type: ignore[no-untyped-def]
    import dataclasses

    from crmgrasp.agents import train_trials_lockstep
    from crmgrasp.experiments.compare import CompareConfig, compare

    cfg = dataclasses.replace(
        CompareConfig.quick("cup-family"), deep=None, reference_starts=60, eval_episodes=20, trials=2, episodes=20
    )
    s = compare(tmp_path, cfg)
    assert s["belief_optimum"] == 1.0 and s["pomdp_counts"].startswith("skipped")
    with pytest.raises(CrmgraspError, match="draws an object per episode: train without lockstep"):
        train_trials_lockstep(make_task("box-family"), "sarsa", trials=2, episodes=5, seed=0)

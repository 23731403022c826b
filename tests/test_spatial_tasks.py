"""Spatial tasks: solids on a table, their families, starts, the table rule, the
environments ``Box3D-v0`` and ``Cup3D-v0``, references and learning in 3-D."""

from __future__ import annotations

import dataclasses
import math
import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

from crmgrasp import CrmgraspError
from crmgrasp.agents.training import train_trials
from crmgrasp.envs.single import SPATIAL_ENVS
from crmgrasp.kernels import kernel_for
from crmgrasp.model.families import Pose
from crmgrasp.model.hand import Error
from crmgrasp.model.solid_families import BoxOnTable, CylinderOnTable
from crmgrasp.model.solids import ConvexPolyhedron, Cylinder, box3d, rotation_z, surface_point
from crmgrasp.model.spatial import CRM3D, Config3D, Contact3D, Hand3D, execute_crm3d, feasible3d
from crmgrasp.planners.references import belief_optimum, clairvoyant_bound, sample_starts, ungraspable_fraction
from crmgrasp.sim import TaskSteps, run_episode
from crmgrasp.tasks import SpatialTask, make_task, spatial_crms

BOX = box3d((-0.15, -0.05, 0.0), (0.15, 0.05, 0.10))
HAND = Hand3D(aperture=0.16, palm_depth=0.12, backoff=0.01)


def test_box_corners_centre_support_and_gap() -> None:
    v = BOX.vertices
    assert len(v) == 8 and np.allclose(np.sort(np.abs(v[:, 0])), 0.15)
    assert np.allclose(BOX.centre, (0.0, 0.0, 0.05))
    assert BOX.support((0, 0, 1)) == pytest.approx(0.0) and BOX.support((-1, 0, 0)) == pytest.approx(-0.15)
    assert BOX.gap((0.15, 0.0, 0.05)) == pytest.approx(0.0) and BOX.gap((0, 0, 0.05)) < 0 < BOX.gap((0.2, 0, 0.05))


def test_moving_a_solid_moves_its_surface() -> None:
    r = rotation_z(0.7)
    moved = BOX.moved(r, (0.1, -0.2, 0.0))
    for p in BOX.vertices:
        assert moved.gap(r @ p + (0.1, -0.2, 0.0)) == pytest.approx(0.0, abs=1e-12)
    cyl = Cylinder((0, 0, 0), (1, 0, 0), 0.05, 0.2).moved(r, (0.0, 0.0, 0.05))
    assert cyl.support((0, 0, 1)) == pytest.approx(0.0, abs=1e-12)
    assert cyl.gap(cyl.centre + 0.05 * np.array((0, 0, 1.0))) == pytest.approx(0.0, abs=1e-12)
    with pytest.raises(CrmgraspError, match="determinant"):
        BOX.moved(np.diag([1.0, 1.0, -1.0]), (0, 0, 0))


@pytest.mark.parametrize("solid", [BOX, Cylinder((0, 0, 0), (0, 0, 1), 0.05, 0.12)])
def test_surface_points_lie_on_the_surface_with_inward_normals(solid) -> None:  # type: ignore[no-untyped-def]
    rng = np.random.default_rng(0)
    for d in rng.standard_normal((200, 3)):
        x, n = surface_point(solid, d)
        assert abs(solid.gap(x)) < 1e-9 and np.linalg.norm(n) == pytest.approx(1.0)
        assert solid.contains(x + 1e-4 * n) and not solid.contains(x - 1e-4 * n)


def test_boxes_on_the_table_are_the_six_single_draws_of_their_rule() -> None:
    """`BoxOnTable.sample` draws its six numbers in one call: the same solids, bit for bit, as
    three single draws for the box and three for its yaw and offset, and the stream in step."""
    from crmgrasp.model.family_base import _uniform

    family = BoxOnTable()
    fast, single = np.random.default_rng(8), np.random.default_rng(8)
    for _ in range(500):
        dims = [_uniform(single, r) for r in (family.length, family.width, family.height)]
        pose = [_uniform(single, r) for r in (family.pose.angle, family.pose.offset, family.pose.offset)]
        want, got = family._box(*dims).yawed(*pose), family.sample(fast)
        assert np.array(got.planes).tobytes() == np.array(want.planes).tobytes()
        assert got.vertices.tobytes() == want.vertices.tobytes()
    assert fast.random() == single.random()


def test_solid_families_sample_within_their_ranges_and_rest_on_the_table() -> None:
    rng = np.random.default_rng(1)
    fam = BoxOnTable()
    yaws, dims = [], []
    for _ in range(300):
        s = fam.sample(rng)
        assert s.support((0, 0, 1)) == pytest.approx(0.0, abs=1e-12)
        edges = np.ptp(s.vertices @ rotation_z(0.0), axis=0)
        dims.append(s.support((0, 0, -1)) * -1)
        yaws.append(edges[0])
    h = np.array(dims)
    assert 0.06 <= h.min() and h.max() <= 0.20 and h.max() - h.min() > 0.1  # spread over the height range
    cups = CylinderOnTable()
    draws = [cups.sample(rng) for _ in range(400)]
    upright = np.mean([abs(c.axis[2]) > 0.99 for c in draws])
    assert abs(upright - 0.5) < 4 * math.sqrt(0.25 / 400)
    assert all(c.support((0, 0, 1)) == pytest.approx(0.0, abs=1e-12) for c in draws)
    assert all(0.03 <= c.radius <= 0.07 and 0.06 <= c.height <= 0.20 for c in draws)
    assert cups.min_width() == pytest.approx(0.06) and fam.min_width() == pytest.approx(0.06)


@pytest.mark.parametrize(
    ("build", "message"),
    [
        (lambda: BoxOnTable(length=(0.3, 0.1)), "box length range .* inverted"),
        (lambda: CylinderOnTable(radius=(0.0, 0.05)), "cylinder radius range .* must be above 0"),
        (lambda: CylinderOnTable(upright=1.5), "upright must be a probability"),
        (lambda: BoxOnTable(pose=Pose(offset=(0.1, 0.0))), "pose offset range .* inverted"),
    ],
)
def test_bad_solid_families_get_one_line_errors(build, message: str) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(CrmgraspError, match=message) as err:
        build()
    assert "\n" not in str(err.value)


def test_a_family_too_wide_for_the_hand_is_refused() -> None:
    with pytest.raises(CrmgraspError, match="beyond the hand's aperture"):
        SpatialTask(
            name="wide",
            obj=BOX,
            hand=HAND,
            actions=spatial_crms(),
            family=BoxOnTable(length=(0.2, 0.3), width=(0.2, 0.3), height=(0.2, 0.3)),  # type: ignore[arg-type]
        )


def test_the_table_rule() -> None:
    top = Contact3D((-0.12, 0.0, 0.10), (0.0, 0.0, -1.0))
    side = Contact3D((-0.12, -0.05, 0.05), (0.0, 1.0, 0.0))
    bottom = Contact3D((0.0, 0.0, 0.0), (0.0, 0.0, 1.0))
    assert feasible3d(BOX, HAND, Config3D(side, bottom), table=0.0) is Error.PALM
    assert feasible3d(BOX, HAND, Config3D(Contact3D((-0.15, 0.0, 0.05), (1.0, 0.0, 0.0)), bottom)) is Error.NONE
    cfg = Config3D(top, side)
    # b onto a's vertical line: it would come from under the table
    out = execute_crm3d(BOX, HAND, cfg, CRM3D("b", "a"), table=0.0)
    assert out.error is Error.PALM and out.config == cfg
    # a onto b's horizontal line: the far side of the 0.10 m wide box, a grasp (palm at x = -0.24)
    out = execute_crm3d(BOX, HAND, cfg, CRM3D("a", "b"), table=0.0)
    assert out.error is Error.NONE and np.allclose(out.config.a.x, (-0.12, 0.05, 0.05))


@pytest.mark.parametrize("name", ["box-3d", "cup-3d"])
def test_spatial_starts_are_feasible_off_the_top_and_not_grasps(name: str) -> None:
    task = make_task(name)
    rng = np.random.default_rng(2)
    for _ in range(60):
        w = task.sample_world(rng)
        t = w.task
        assert isinstance(t, SpatialTask) and t.acceptable(w.config)
        assert not all(c.n[2] <= -0.5 for c in w.config)
        for c in w.config:
            assert abs(t.solid.gap(c.x)) < 1e-9 and c.x[2] > 0.0
    a = [task.sample_world(np.random.default_rng(5)).config for _ in range(2)]
    assert a[0] == a[1]


def test_spatial_task_bad_input() -> None:
    task = make_task("box-3d")
    inst = task.instance(np.random.default_rng(0))
    with pytest.raises(CrmgraspError, match="off the object"):
        inst.check_config(
            Config3D(Contact3D((1.0, 1.0, 1.0), (1.0, 0.0, 0.0)), Contact3D((1.0, 1.0, 1.0), (1.0, 0.0, 0.0)))
        )
    with pytest.raises(CrmgraspError, match="Config3D"):
        inst.check_config((1, 2))
    with pytest.raises(CrmgraspError, match=r"\|r\| <= r_max"):
        inst.crm(CRM3D("a", "a", (0.2, 0.2)))
    with pytest.raises(CrmgraspError, match="contact labels"):
        inst.crm(CRM3D("a", "c", (0.0, 0.0)))
    with pytest.raises(CrmgraspError, match="ConvexPolyhedron, Cylinder or TriangleMesh"):
        SpatialTask(name="x", obj=make_task("paper-box").obj, hand=HAND, actions=spatial_crms())  # type: ignore[arg-type]


def test_episodes_step_through_the_one_loop_and_the_row_kernel_agrees() -> None:
    task = make_task("cup-3d")
    rng = np.random.default_rng(3)
    w = task.sample_world(rng)
    inst = w.task
    kernel = kernel_for(inst, "reference")
    ref = TaskSteps(inst)
    now = ref.begin(w.config, rng)
    rows = np.array([[*w.config.a.x, *w.config.a.n, *w.config.b.x, *w.config.b.n]])
    for a in range(len(inst.actions)):
        one = ref.step_one(now.state, a, rng)
        new, err = kernel.execute(rows, rows, np.array([a]))
        assert int(err[0]) == int(one.error)
        assert np.array_equal(
            new[0], [*one.state.config.a.x, *one.state.config.a.n, *one.state.config.b.x, *one.state.config.b.n]
        )
        rho, m_a, m_b, index, mu = kernel.observe(new, new, err)
        assert (rho[0], m_a[0], m_b[0], index[0], mu[0]) == (*one.observation, one.obs_index, one.min_friction)


def test_upright_cylinders_need_one_crm_with_full_information() -> None:
    fam = CylinderOnTable(upright=1.0)
    task = SpatialTask(name="upright", obj=fam.nominal(), hand=HAND, actions=spatial_crms(), family=fam)  # type: ignore[arg-type]
    worlds = sample_starts(task, 60, 0)
    assert clairvoyant_bound(task, worlds) == 1.0 and ungraspable_fraction(task, worlds) == 0.0
    assert 1.0 <= belief_optimum(task, worlds) < 1.5


@pytest.mark.parametrize("env_id", sorted(SPATIAL_ENVS))
def test_spatial_envs_pass_check_env_vectorise_and_render(env_id: str) -> None:
    env = gym.make(env_id, render_mode="rgb_array")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_env(env.unwrapped)
    env.reset(seed=0)
    env.step(0)
    img = env.render()
    assert img is not None and img.ndim == 3 and img.shape[2] == 3
    vec = gym.make_vec(env_id, num_envs=3, vectorization_mode="vector_entry_point")
    obs, _ = vec.reset(seed=0)
    assert obs["rho"].shape == (3, 1)
    ended = 0
    for _ in range(25):
        obs, _, term, trunc, _ = vec.step(vec.action_space.sample())
        ended += int(np.sum(term | trunc))
    assert ended > 0


def test_spatial_env_resets_from_a_world_and_refuses_a_planar_config() -> None:
    task = make_task("box-3d")
    env = gym.make("crmgrasp/Box3D-v0").unwrapped
    w = task.sample_world(np.random.default_rng(0))
    _, info = env.reset(seed=0, options={"world": w})
    assert info["config"] == w.config
    with pytest.raises(CrmgraspError, match="Config3D"):
        env.reset(options={"config": make_task("paper-box").sample_start(np.random.default_rng(0))})


def test_learning_on_cup3d_beats_random_and_is_deterministic() -> None:
    task = make_task("cup-3d")
    kw = {"trials": 2, "episodes": 150, "seed": 4, "k": 1, "eval_episodes": 100}
    a, b = train_trials(task, "model-vi", **kw), train_trials(task, "model-vi", **kw)
    assert np.array_equal(a.steps, b.steps) and np.array_equal(a.greedy_steps, b.greedy_steps)
    rand = train_trials(task, "random", **kw)
    assert a.greedy_steps.mean() < 0.6 * rand.greedy_steps.mean()


class _Oppose:
    def begin(self, first) -> None:  # type: ignore[no-untyped-def]
        pass

    def act(self) -> int:
        return 0

    def tell(self, percept) -> None:  # type: ignore[no-untyped-def]
        pass


def test_run_episode_on_a_spatial_world() -> None:
    task = make_task("box-3d")
    ep = run_episode(task, _Oppose(), np.random.default_rng(0), trace=True)
    assert 1 <= ep.steps <= task.max_steps and len(ep.trace) == ep.steps


@pytest.mark.parametrize("name", ["box-3d", "cup-3d", "open-cup-3d"])
def test_the_compiled_spatial_kernel_equals_the_reference_bit_for_bit(name: str) -> None:
    from crmgrasp.kernels.spatial import FusedSpatialKernel

    task = make_task(name)
    rng = np.random.default_rng(11)
    steps = 0
    for w in range(40):
        inst = task.instance(rng)
        fast, ref = FusedSpatialKernel(inst), TaskSteps(inst)
        r1, r2 = np.random.default_rng(w), np.random.default_rng(w)
        start = inst.sample_start(r1)
        assert inst.sample_start(r2, fast.start_filter) == start  # same decisions, same stream
        a, b = ref.begin(start, r1), fast.begin(start, r2)
        assert a == b
        acts = np.random.default_rng(w + 100)
        for _ in range(10):
            act = int(acts.integers(len(inst.actions)))
            a, b = ref.step_one(a.state, act, r1), fast.step_one(b.state, act, r2)
            assert a == b
            steps += 1
            if a.terminated:
                break
    assert steps > 100


def test_spatial_training_is_the_same_on_every_backend_and_noise_takes_the_reference() -> None:
    from crmgrasp.kernels.spatial import FusedSpatialKernel, SpatialKernel
    from crmgrasp.model.sensing import SensorNoise

    task = make_task("box-3d")
    kw = {"trials": 2, "episodes": 40, "seed": 3, "eval_episodes": 20, "k": 1}
    fast = train_trials(task, "sarsa", backend="auto", **kw)
    ref = train_trials(task, "sarsa", backend="reference", **kw)
    assert np.array_equal(fast.steps, ref.steps) and np.array_equal(fast.greedy_steps, ref.greedy_steps)
    inst = task.instance(np.random.default_rng(0))
    assert type(kernel_for(inst)) is FusedSpatialKernel and type(kernel_for(inst, "reference")) is SpatialKernel
    noisy = dataclasses.replace(inst, noise=SensorNoise(0.05, 0.001))
    assert type(kernel_for(noisy)) is SpatialKernel
    with pytest.raises(CrmgraspError, match="noise-free"):
        kernel_for(noisy, "numba")
    ep = run_episode(noisy, _Oppose(), np.random.default_rng(0))
    assert 1 <= ep.steps <= noisy.max_steps


def test_the_command_line_on_spatial_tasks(tmp_path, capsys) -> None:  # type: ignore[no-untyped-def]
    import json

    from crmgrasp.cli.main import main

    pts = ["--task", "box-3d", "--a=-0.2,0,0.05", "--b=0,-0.2,0.05"]
    assert main(["crm", *pts, "--crm", "C1", "--json"]) == 0
    res = json.loads(capsys.readouterr().out)
    assert res["error"] == "none" and res["success"] and len(res["config"]["a"]["x"]) == 3
    assert main(["show", *pts, "--crm", "a,a,0,0.05", "--out", str(tmp_path / "s.png")]) == 0
    assert (tmp_path / "s.png").stat().st_size > 1000
    bad = [
        (["show", "--task", "box-3d", "--a=-0.2,0", "--b=0,-0.2,0.05", "--out", str(tmp_path / "x.png")], "X,Y,Z"),
        (["crm", *pts, "--crm", "a,b,0"], "c,f,r1,r2"),
        (["crm", "--task", "paper-box", "--a=-0.2,0,1", "--b=0,-0.2", "--crm", "C1"], "take X,Y"),
        (["compare", "--task", "cup-3d", "--quick", "--out", str(tmp_path / "c")], "planar"),
    ]
    for argv, message in bad:
        capsys.readouterr()
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert message in err and err.count("\n") == 1, err
    run = tmp_path / "run"
    learn = ["learn", "--task", "cup-3d", "--agent", "model-vi", "--k", "1", "--trials", "1", "--episodes", "30"]
    assert main([*learn, "--eval-episodes", "20", "--out", str(run), "--quiet"]) == 0
    assert main(["evaluate", "--policy", str(run / "policy.json"), "--episodes", "20", "--json"]) == 0
    capsys.readouterr()
    hand_run = ["run", "--policy", str(run / "policy.json"), "--log", str(tmp_path / "l.csv")]
    figure = tmp_path / "run.png"
    assert main([*hand_run, "--a=0.1,0,0.05", "--b=0,0.1,0.12", "--figure", str(figure)]) == 0  # kinematic, 3-D
    out = capsys.readouterr().out
    assert "after" in out and "true min_friction" in out
    assert figure.read_bytes().startswith(b"\x89PNG") and f"wrote {figure.resolve()}" in out  # 3-D panels
    with open(tmp_path / "l.csv") as fh:
        assert fh.readline().startswith("step,ax,ay,az,anx,any,anz,bx")
    assert main([*hand_run, "--overwrite", "--a=0.1,0", "--b=0,0.1,0.12"]) == 2
    assert "take X,Y,Z" in capsys.readouterr().err


SPATIAL_FILE = """
name = "my-cup"
model = "spatial"
table = 0.0
mu_goal = 0.05
[hand]
aperture = 0.16
palm_depth = 0.12
[[crm]]
c = "a"
f = "b"
[[crm]]
c = "b"
f = "a"
[[crm]]
c = "a"
f = "a"
r = [0.0, 0.05]
[solid]
cylinder = { radius = 0.04, height = 0.12 }
"""


def test_spatial_task_files_round_trip(tmp_path) -> None:  # type: ignore[no-untyped-def]
    from crmgrasp.tasks import load_task_file, task_from_dict, task_to_dict

    path = tmp_path / "cup.toml"
    path.write_text(SPATIAL_FILE)
    task = load_task_file(path)
    assert isinstance(task, SpatialTask) and isinstance(task.obj, Cylinder) and task.actions[2].r == (0.0, 0.05)
    for t in (task, make_task("box-3d"), make_task("cup-3d")):
        again = task_from_dict(task_to_dict(t))
        assert task_to_dict(again) == task_to_dict(t) and type(again.obj) is type(t.obj)
    rng = np.random.default_rng(0)
    assert task.sample_start(rng) == task_from_dict(task_to_dict(task)).sample_start(np.random.default_rng(0))
    from crmgrasp.model.mesh import open_cup

    cup = SpatialTask(name="open", obj=open_cup(0.04, 0.1), hand=HAND, actions=spatial_crms())  # type: ignore[arg-type]
    assert task_to_dict(task_from_dict(task_to_dict(cup))) == task_to_dict(cup)


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (('model = "spatial"', 'model = "solid"'), 'model must be "planar" or "spatial"'),
        (("cylinder = { radius = 0.04, height = 0.12 }", "sphere = { radius = 0.04 }"), "unknown key 'sphere'"),
        (("r = [0.0, 0.05]", "r = 0.05"), "r must be a list of numbers"),
        (("aperture = 0.16", "aperture = 0.16\nh = [0, 0]"), "hand.h must have 3 numbers"),
        (("radius = 0.04, height", "radius = -0.04, height"), "cylinder radius"),
        (("table = 0.0", "table = 0.0\nobject = 1"), "unknown key 'object'"),
    ],
)
def test_bad_spatial_task_files_get_one_line_errors(tmp_path, edit, message) -> None:  # type: ignore[no-untyped-def]
    from crmgrasp.tasks import load_task_file

    path = tmp_path / "bad.toml"
    path.write_text(SPATIAL_FILE.replace(*edit))
    with pytest.raises(CrmgraspError, match=message) as err:
        load_task_file(path)
    assert "\n" not in str(err.value)


def test_the_spatial_mirror_symmetry_holds_on_sampled_worlds() -> None:
    """Reflecting the world in y -> -y and reversing the labels maps every CRM's outcome
    to the mirrored CRM's (SpatialTask.mirror_crm), with the moments' magnitudes reversed
    too: for two contacts (a <-> b) and for the tripods (a <-> c, b stays)."""
    from crmgrasp.model.spatial import config3d, observe3d
    from crmgrasp.tasks.spatial import SPATIAL_HAND, TRIPOD_HAND, spatial_symmetry

    m = np.diag([1.0, -1.0, 1.0])

    def solid(s):  # type: ignore[no-untyped-def]
        if isinstance(s, Cylinder):
            return Cylinder(tuple(m @ np.array(s.origin)), tuple(m @ np.array(s.axis)), s.radius, s.height)
        return ConvexPolyhedron(tuple((*(m @ np.array(r[:3])), r[3]) for r in s.planes))

    def config(c):  # type: ignore[no-untyped-def]
        flip = [Contact3D(tuple((m @ np.array(k.x)).tolist()), tuple((m @ np.array(k.n)).tolist())) for k in c]
        return config3d(flip[::-1])

    checked = 0
    for name, hand in (
        ("cup-3d", SPATIAL_HAND),
        ("box-3d", SPATIAL_HAND),
        ("cup-3d-3f", TRIPOD_HAND),
        ("box-3d-3f", TRIPOD_HAND),
    ):
        task = make_task(name)
        sym = spatial_symmetry(task.actions, hand)
        mirrored = dataclasses.replace(task, symmetry=sym)  # the declaration itself is checked
        assert mirrored.symmetry == sym
        rng = np.random.default_rng(4)
        for _ in range(40):
            w = task.sample_world(rng)
            inst, mir = w.task, solid(w.task.solid)
            for i, crm in enumerate(inst.actions):
                a = execute_crm3d(inst.solid, inst.hand3d, w.config, crm, table=0.0)
                b = execute_crm3d(mir, inst.hand3d, config(w.config), inst.actions[sym.actions[i]], table=0.0)
                assert a.error is b.error
                want = config(a.config)
                assert np.allclose([[*k.x, *k.n] for k in want], [[*k.x, *k.n] for k in b.config], atol=1e-9)
                rho, *moments = observe3d(a.config)
                assert np.allclose(observe3d(b.config), (rho, *moments[::-1]), atol=1e-9)
                checked += 1
    assert checked == 2 * 40 * 10 + 2 * 40 * 18
    with pytest.raises(CrmgraspError, match="contact 'c' is not one of the hand's contacts a, b"):
        spatial_symmetry(make_task("box-3d-3f").actions)  # the two-contact hand's mirror of tripod CRMs
    with pytest.raises(CrmgraspError, match="no mirror"):
        spatial_symmetry(make_task("cup-3d").actions[:3])


def test_mirrored_declares_the_spatial_mirror_where_it_holds() -> None:
    from crmgrasp.tasks.spatial import MIRROR_INVARIANT, TRIPOD_HAND, mirrored, spatial_symmetry

    tripod = make_task("box-3d-3f")
    assert tripod.symmetry is None and tripod.name in MIRROR_INVARIANT
    declared = mirrored(tripod)
    assert declared.symmetry == spatial_symmetry(tripod.actions, TRIPOD_HAND) and declared.name == tripod.name
    u = make_task("u-handle")
    assert mirrored(u) is u  # its own declared symmetry
    with pytest.raises(CrmgraspError, match="open-cup-3d has no mirror symmetry known to hold"):
        mirrored(make_task("open-cup-3d"))

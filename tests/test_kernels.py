"""Every kernel path against the reference rules, bit for bit; the kernel seam."""

from __future__ import annotations

import ast
import math
import pickle
import re
from collections import Counter
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from crmgrasp import (
    CRM,
    Config,
    Contact,
    CrmgraspError,
    Disc,
    Hand,
    Polygon,
    Rectangle,
    SensorNoise,
    Task,
    make_task,
    regular_polygon,
)
from crmgrasp.envs.vector import CRMGraspVectorEnv
from crmgrasp.kernels import execute_batch, kernel_for
from crmgrasp.model.contacts import array_to_configs, configs_to_array
from crmgrasp.model.hand import Error, execute_crm
from crmgrasp.model.polygon import convex_entry, first_entry
from crmgrasp.model.quality import min_friction
from crmgrasp.model.sensing import Discretizer, observe
from crmgrasp.sim import SimState, begin, step
from crmgrasp.tasks import accept_corner_candidates, corner_boxes, corner_proposal

from .strategies import BACKENDS, on_boundary, scenes

U_SHAPE = Polygon([(0, 0), (0.3, 0), (0.3, 0.2), (0.2, 0.2), (0.2, 0.08), (0.1, 0.08), (0.1, 0.2), (0, 0.2)])

convex_objects = st.one_of(
    st.builds(Rectangle, st.floats(0.05, 0.4), st.floats(0.03, 0.2)),
    st.builds(regular_polygon, st.integers(3, 16), st.floats(0.03, 0.15), rotation=st.floats(0, 2 * math.pi)),
)


def _crm_arrays(crms: list[CRM]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    return np.array([m.ci for m in crms]), np.array([m.fi for m in crms]), np.array([m.r for m in crms])


def _odd_task() -> Task:
    """A hexagon, other bins (more than three thresholds, signed moments) and CRMs."""
    disc = Discretizer(rho=(0.5, 1.0, 2.0, 3.0), m_a=tuple(np.linspace(-0.1, 0.1, 5)), m_b=(), abs_moments=False)
    crms = (CRM("a", "b", 0.0), CRM("b", "a", 0.01), CRM("a", "a", 0.05), CRM("b", "b", -0.05))
    return Task("hexagon", regular_polygon(6, 0.08), Hand(0.2, 0.05), crms, discretizer=disc)


# ----------------------------------------------------------------- the seam
def test_each_builtin_task_takes_a_stated_path():
    """Which kernel each kind of task runs on, per backend (the one selector's table)."""
    box = make_task("paper-box")
    noisy = replace(box, noise=SensorNoise(0.05, 0.002))
    disc = Task("disc", Disc(0.05), box.hand, box.actions, discretizer=box.discretizer)
    u = Task("u", U_SHAPE, box.hand, box.actions)
    paths = {
        (name, backend): kernel_for(t, backend).name
        for name, t in (("paper-box", box), ("noisy", noisy), ("disc", disc), ("u", u))
        for backend in ("auto", "numba", "reference")
        if not (name == "disc" and backend == "numba")
    }
    assert paths == {
        ("paper-box", "auto"): "numba-polygon-fused",
        ("paper-box", "numba"): "numba-polygon-fused",
        ("paper-box", "reference"): "reference",
        ("noisy", "auto"): "numba-polygon",
        ("noisy", "numba"): "numba-polygon",
        ("noisy", "reference"): "reference",
        ("disc", "auto"): "reference",
        ("disc", "reference"): "reference",
        ("u", "auto"): "numba-polygon-fused",
        ("u", "numba"): "numba-polygon-fused",
        ("u", "reference"): "reference",
    }
    with pytest.raises(CrmgraspError, match="no compiled kernel for a Disc"):
        kernel_for(disc, "numba")
    with pytest.raises(CrmgraspError, match="unknown backend 'gpu'; choose one of auto, numba, reference"):
        kernel_for(box, "gpu")


_COMPILE = "crmgrasp.kernels._compile"


_JIT_MODULES = (
    "_polygon_jit",
    "_spatial_jit",
    "_vi_jit",
    "_fingers_jit",
    "_lp_jit",
    "_tripod_jit",
    "_closure_jit",
    "_fingers3d_jit",
    "_mesh_jit",
)


@pytest.mark.parametrize(
    ("module", "allowed"),
    [
        ("_polygon_jit", {"__future__", "numpy", _COMPILE}),
        (
            "_spatial_jit",
            {"__future__", "math", _COMPILE, "crmgrasp.kernels._polygon_jit", "crmgrasp.kernels._mesh_jit"},
        ),
        ("_mesh_jit", {"__future__", "math", _COMPILE}),
        ("_vi_jit", {"__future__", _COMPILE}),
        ("_fingers_jit", {"__future__", "numpy", "numba", _COMPILE, "crmgrasp.kernels._polygon_jit"}),
        ("_lp_jit", {"__future__", "math", "numpy", "numba"}),
        ("_tripod_jit", {"__future__", "math", "numpy", "numba", "crmgrasp.kernels._lp_jit"}),
        (
            "_closure_jit",
            {"__future__", "math", "numpy", "numba", "crmgrasp.kernels._lp_jit", "crmgrasp.kernels._tripod_jit"},
        ),
        (
            "_fingers3d_jit",
            {"__future__", "math", "numpy", "numba", _COMPILE}
            | {f"crmgrasp.kernels._{m}_jit" for m in ("closure", "fingers", "spatial")},
        ),
    ],
)
def test_compiled_code_holds_no_constant_of_the_model(module, allowed):
    """The compiled modules import only numpy, math, numba, how they compile (and the shared bin index)
    and define no float constant: every tolerance arrives as an argument, so numba's
    on-disk cache cannot hold a stale copy of one."""
    import importlib

    jit = importlib.import_module(f"crmgrasp.kernels.{module}")
    tree = ast.parse(Path(jit.__file__).read_text())
    imports = {a.name for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names}
    imports |= {n.module for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)}
    assert imports == allowed
    floats = [n.value for n in ast.walk(tree) if isinstance(n, ast.Constant) and isinstance(n.value, float)]
    assert set(floats) <= {0.0, 0.5, 1.0, 2.0, 4.0, -1.0}, floats  # arithmetic of the rules, no tolerance


def test_every_compiled_module_carries_the_current_stamp():
    """numba's disk cache of a caller does not follow an edit to a callee in another file; the
    stamp line of every compiled module does, so a stale stamp is an error here."""
    from crmgrasp.kernels import _stamp

    assert {p.name for p in _stamp.compiled_modules()} == {f"{m}.py" for m in _JIT_MODULES}
    assert _stamp.stale() == [], "a compiled source changed: run `python -m crmgrasp.kernels._stamp`"


def test_an_edit_to_one_compiled_module_restamps_all_of_them(tmp_path):
    """In a copy of the compiled sources: an edit to one module (or to how they are compiled)
    makes every stamp stale; rewriting changes only the stamp lines and leaves none stale."""
    import shutil

    from crmgrasp.kernels import _stamp

    for path in [*_stamp.compiled_modules(), _stamp.HERE / "_compile.py"]:
        shutil.copy(path, tmp_path / path.name)
    assert _stamp.stale(tmp_path) == []
    for edited in ("_closure_jit.py", "_compile.py"):
        target = tmp_path / edited
        target.write_text(target.read_text().replace("from __future__", "# edited\nfrom __future__", 1))
        before = {p.name: p.read_text() for p in _stamp.compiled_modules(tmp_path)}
        assert _stamp.stale(tmp_path) == sorted(before)
        assert _stamp.write(tmp_path) == sorted(before)
        assert _stamp.stale(tmp_path) == []
        for p in _stamp.compiled_modules(tmp_path):
            old, new = before[p.name].splitlines(), p.read_text().splitlines()
            assert [line for line in old[:-1] if line] == [line for line in new[:-1] if line]
            assert old[-1] != new[-1] and new[-1] == _stamp.PREFIX + _stamp.digest(tmp_path)


def test_a_changed_tolerance_reaches_the_compiled_kernel(monkeypatch):
    """A ray 1e-13 m below a box side enters at the corner with LINE_TOL = 1e-12 and
    misses with 0: a kernel built after the change follows it, as the reference does."""
    import crmgrasp.kernels._polygon_jit as jit
    import crmgrasp.model.polygon as poly
    import crmgrasp.model.shape as base

    task = make_task("paper-box")
    ray = (-0.3, -0.05 - 1e-13, 1.0, 0.0, 1.0)
    k = kernel_for(task, "numba")
    assert jit._entry(*ray, k.e, True, k.p)[0] and convex_entry(*ray, task.obj.edges) is not None
    monkeypatch.setattr(base, "LINE_TOL", 0.0)
    monkeypatch.setattr(poly, "LINE_TOL", 0.0)
    k = kernel_for(task, "numba")
    assert not jit._entry(*ray, k.e, True, k.p)[0] and convex_entry(*ray, task.obj.edges) is None


# ------------------------------------------------------------ entry rules
def _rays(obj: Polygon, rng: np.random.Generator, n: int) -> tuple[np.ndarray, ...]:
    """Rays from points around the object toward points near it."""
    x0, y0, x1, y1 = obj.bounds()
    span = max(x1 - x0, y1 - y0)
    ox, oy = rng.uniform(x0 - span, x1 + span, n), rng.uniform(y0 - span, y1 + span, n)
    tx, ty = rng.uniform(x0, x1, n), rng.uniform(y0, y1, n)
    d = np.hypot(tx - ox, ty - oy)
    return ox, oy, (tx - ox) / d, (ty - oy) / d, rng.uniform(0.0, 3 * span, n)


@settings(max_examples=60, deadline=None)
@given(convex_objects, st.integers(0, 2**32 - 1))
def test_convex_entry_is_first_entry_away_from_vertices(obj, seed):
    """On generic rays the vertex-side rule finds the running minimum's edge and u, bit for bit."""
    ox, oy, dx, dy, umax = _rays(obj, np.random.default_rng(seed), 300)
    for args in zip(ox.tolist(), oy.tolist(), dx.tolist(), dy.tolist(), umax.tolist()):
        assert convex_entry(*args, obj.edges) == first_entry(*args, obj.edges)


@pytest.mark.parametrize("n", [3, 4, 8, 9, 12, 13, 20])
def test_compiled_entry_equals_the_reference_on_any_polygon(n):
    import crmgrasp.kernels._polygon_jit as jit

    for poly in (regular_polygon(n, 0.1, rotation=0.3), U_SHAPE):
        k = kernel_for(Task("t", poly, Hand(0.2, 0.05), (CRM("a", "b", 0),)), "numba")
        ox, oy, dx, dy, umax = _rays(poly, np.random.default_rng(n), 1000)
        entered = 0
        for args in zip(ox.tolist(), oy.tolist(), dx.tolist(), dy.tolist(), umax.tolist()):
            ref = poly.ray_entry(args[:2], args[2:4], args[4])
            got = jit._entry(*args, k.e, poly.convex, k.p)
            assert got[0] == (ref is not None)
            if ref is not None:
                assert got[1:] == (*ref.point, *ref.normal)
                entered += 1
            assert jit._inside(args[0], args[1], k.e, poly.convex, k.p[3]) == poly.contains(args[:2])
        assert 100 < entered < 1000


def test_lines_through_vertices_and_along_edges_enter_at_the_vertex():
    """A ray along a side (either way), through a corner, or missing it by less than
    LINE_TOL enters at the corner; one missing it by more does not enter."""
    box = Rectangle(0.30, 0.10)  # vertices (-0.15, -0.05), (0.15, -0.05), (0.15, 0.05), (-0.15, 0.05)
    cases = [
        ((0.3, -0.05), (-1.0, 0.0), (0.15, -0.05), (-1.0, 0.0)),  # along the bottom, leftward: right side
        ((-0.3, -0.05), (1.0, 0.0), (-0.15, -0.05), (1.0, 0.0)),  # along the bottom, rightward: left side
        ((-0.3, -0.05 - 1e-13), (1.0, 0.0), (-0.15, -0.05 - 1e-13), (1.0, 0.0)),
        ((-0.25, -0.15), (math.sqrt(0.5), math.sqrt(0.5)), (-0.15, -0.05), None),  # through the corner
    ]
    for o, d, point, normal in cases:
        e = box.ray_entry(o, d, 1.0)
        assert e is not None and e.point == pytest.approx(point, abs=1e-15)
        if normal is not None:
            assert e.normal == normal
    assert box.ray_entry((-0.3, -0.05 - 1e-9), (1.0, 0.0), 1.0) is None  # misses by 1 nm


@pytest.mark.parametrize("backend", BACKENDS)
def test_corner_seeking_crms_match_the_reference(task, backend):
    """CRMs whose goal line runs exactly along a box side (as the grasp controller
    issues them) give the reference outcome in every kernel."""
    cfg = Config(Contact(-0.15, 0.023360090626670917, 1.0, 0.0), Contact(-0.13013644553857112, -0.05, -0.0, 1.0))
    crms = [CRM("a", "a", 0.023360090626670917 + 0.05), CRM("b", "a", 0.0), CRM("b", "b", 0.02), CRM("a", "b", 0.0)]
    new, err = execute_batch(task.obj, task.hand, [cfg] * len(crms), *_crm_arrays(crms), backend=backend)
    for i, crm in enumerate(crms):
        out = execute_crm(task.obj, task.hand, cfg, crm)
        assert (int(err[i]), tuple(new[i])) == (int(out.error), tuple(np.asarray(out.config).ravel()))


# --------------------------------------------------------------- CRMs in bulk
@pytest.mark.parametrize("backend", BACKENDS)
@settings(max_examples=100, deadline=None)
@given(st.lists(scenes(), min_size=1, max_size=1), st.integers(2, 12), st.booleans(), st.integers(0, 2**32 - 1))
def test_execute_batch_matches_execute_crm(backend, first, n, noisy, seed):
    obj, hand, cfg0, _ = first[0]
    if backend == "numba" and not isinstance(obj, Polygon):
        backend = "auto"  # the seam sends discs to the reference
    rng = np.random.default_rng(seed)
    configs = [cfg0]
    for _ in range(n - 1):
        s = rng.random(2) * obj.perimeter
        configs.append(Config(on_boundary(obj, s[0]), on_boundary(obj, s[1])))
    crms = [
        CRM("ab"[rng.integers(2)], "ab"[rng.integers(2)], float(rng.uniform(-1, 1) * hand.aperture)) for _ in configs
    ]
    noise = SensorNoise(math.radians(5), 0.003) if noisy else SensorNoise()
    sensed = [noise.sense(c, np.random.default_rng(seed + i)) for i, c in enumerate(configs)]
    arr, sarr = configs_to_array(configs), configs_to_array(sensed)
    new, err = execute_batch(obj, hand, arr, *_crm_arrays(crms), sensed=sarr, backend=backend)
    for i, (cfg, crm) in enumerate(zip(configs, crms)):
        out = execute_crm(obj, hand, cfg, crm, sensed[i])
        assert int(err[i]) == int(out.error)
        assert tuple(new[i]) == tuple(np.asarray(out.config).ravel())


@pytest.mark.parametrize("backend", BACKENDS)
def test_batch_worked_cases(task, backend):
    near = task.hand.contact(task.obj, a=(-0.15, -0.02), b=(-0.10, -0.05))
    far = task.hand.contact(task.obj, a=(-0.15, -0.02), b=(0.00, -0.05))
    cfgs = configs_to_array([near, near, far, far])
    crms = [task.actions[i] for i in (0, 1, 0, 3)]
    new, err = execute_batch(task.obj, task.hand, cfgs, *_crm_arrays(crms), backend=backend)
    assert err.tolist() == [0, 1, 2, 0]
    assert new[0, :4].tolist() == [-0.10, 0.05, 0.0, -1.0]
    assert new[3, 4:6].tolist() == [-0.08, -0.05]


def test_batch_input_errors(task):
    arr = configs_to_array([task.sample_start(np.random.default_rng(0))])
    with pytest.raises(CrmgraspError, match=r"shape \(N, 8\)"):
        execute_batch(task.obj, task.hand, arr[:, :6], 0, 1, 0.0)
    with pytest.raises(CrmgraspError, match=re.escape("c and f must be integers in [0, 1] (the hand's contacts)")):
        execute_batch(task.obj, task.hand, arr, 2, 1, 0.0)
    with pytest.raises(CrmgraspError, match="r_max"):
        execute_batch(task.obj, task.hand, arr, 0, 1, 1.0)
    with pytest.raises(CrmgraspError, match="finite"):
        execute_batch(task.obj, task.hand, arr * np.nan, 0, 1, 0.0)
    with pytest.raises(CrmgraspError, match="unknown backend"):
        execute_batch(task.obj, task.hand, arr, 0, 1, 0.0, backend="numpy")


# ------------------------------------------------------ observation and bins
@pytest.mark.parametrize(
    "disc",
    [
        Discretizer(),
        Discretizer(rho=(0.5, 1.5), m_a=(0.02, 0.1, 0.2), m_b=()),
        Discretizer(rho=(1.0,), m_a=tuple(np.linspace(-0.2, 0.2, 9)), m_b=(0.1,), abs_moments=False),
    ],
)
@pytest.mark.parametrize("noisy", [False, True])
def test_kernel_observe_equals_the_reference(task, disc, noisy):
    t = replace(task, discretizer=disc, symmetry=None)
    rng = np.random.default_rng(3)
    cfg = np.array([(*on_boundary(t.obj, a), *on_boundary(t.obj, b)) for a, b in rng.random((300, 2)) * 0.8])
    sen = cfg + rng.normal(0, 0.01, cfg.shape) if noisy else cfg
    for c in (2, 6):  # sensed normals stay unit vectors (the model rotates them)
        sen[:, c : c + 2] /= np.hypot(sen[:, c], sen[:, c + 1])[:, None]
    err = rng.integers(0, 3, 300)
    outs = [kernel_for(t, b).observe(cfg, sen, err) for b in BACKENDS]
    for j, (row, srow) in enumerate(zip(array_to_configs(cfg), array_to_configs(sen))):
        o = observe(srow)
        want = (o.rho, o.m_a, o.m_b, disc.index(o, int(err[j])), min_friction(row))
        for rho, m_a, m_b, index, mu in outs:
            assert (rho[j], m_a[j], m_b[j], index[j], mu[j]) == want


def test_noise_batch_stream_equals_scalar_stream(task):
    noise = SensorNoise(0.05, 0.002)
    cfgs = [task.sample_start(np.random.default_rng(i)) for i in range(5)]
    batch = noise.sense_batch(configs_to_array(cfgs), np.random.default_rng(9))
    rng = np.random.default_rng(9)
    np.testing.assert_array_equal(batch, configs_to_array([noise.sense(c, rng) for c in cfgs]))


# -------------------------------------------------------- composite steps
def test_fused_single_step_equals_sim_step_on_convex_and_non_convex_objects(task):
    """Random CRMs from random boundary pairs on the box and a U: all three error
    codes occur on each and every result equals :func:`crmgrasp.sim.step` exactly."""
    rng = np.random.default_rng(0)
    for obj in (task.obj, U_SHAPE):
        t = replace(task, obj=obj, symmetry=None)
        k = kernel_for(t, "numba")
        codes: Counter[int] = Counter()
        for _ in range(3000):
            s = rng.random(2) * obj.perimeter
            cfg = Config(on_boundary(obj, s[0]), on_boundary(obj, s[1]))
            action = int(rng.integers(4))
            state = SimState(cfg, cfg, int(rng.integers(10)))
            ref, got = step(t, state, action, rng), k.step_one(state, action, rng)
            want = (ref.state, ref.observation, ref.error, ref.obs_index, ref.min_friction, -1.0)
            assert got == (*want, ref.terminated, ref.truncated) and type(got.error) is Error
            assert got == ref
            ref0, got0 = begin(t, cfg, rng), k.begin(cfg, rng)
            assert got0 == ref0 and got0.min_friction == min_friction(cfg) and got0.state == SimState(cfg, cfg, 0)
            codes[got.error] += 1
        assert set(codes) == {0, 1, 2}, codes


@pytest.mark.parametrize("which", ["paper-box", "hexagon", "noisy", "u-shape", "min-separation"])
def test_backends_agree_on_vector_env_and_starts(which):
    """The vector env gives the same outputs on every backend (the noise-free polygon
    step runs as one compiled pass; with noise, compiled rules around reference sensing)."""
    task = _odd_task() if which == "hexagon" else make_task("paper-box")
    if which == "noisy":
        task = replace(task, noise=SensorNoise(0.05, 0.002))
    if which == "u-shape":
        task = replace(task, obj=U_SHAPE, starts=task.starts, symmetry=None)
    if which == "min-separation":  # large noise, fingertips 1 cm wide
        hand = replace(task.hand, min_separation=0.01, palm_normal_tol=0.2)
        task = replace(task, hand=hand, noise=SensorNoise(math.radians(30), 0.002))

    def run(backend: str) -> list[np.ndarray]:
        env = CRMGraspVectorEnv(256, task, backend=backend)
        out = [env.reset(seed=9)[1]["config"]]
        rng = np.random.default_rng(9)
        for _ in range(12):
            obs, rew, term, trunc, info = env.step(rng.integers(4, size=256))
            out += [*obs.values(), rew, term, trunc, *info.values()]
        return out

    for x, y in zip(run("reference"), run("numba")):
        assert x.dtype == y.dtype and x.shape == y.shape
        np.testing.assert_array_equal(x, y)


def test_corner_filters_agree_across_backends(task):
    """The reference and the compiled corner-start filters accept the same candidates."""
    rng = np.random.default_rng(5)
    for t in (task, replace(task, obj=U_SHAPE, symmetry=None)):
        cum, c_in, c_out = corner_boxes(t.obj, t.hand.aperture)
        u = corner_proposal(rng.random((4, 4000)), cum, c_in, c_out)
        a = accept_corner_candidates(t.obj, t.hand, t.mu_goal, u)
        b = kernel_for(t, "numba").start_filter(t.obj, t.hand, t.mu_goal, u)
        assert a.shape == b.shape and len(a) > 500 and np.array_equal(a, b)


def test_tasks_and_kernels_stay_picklable(task):
    k = kernel_for(task)
    k.sample_starts(np.random.default_rng(0), 10)
    again = pickle.loads(pickle.dumps(task))
    assert again.obj == task.obj and again.obj.contains((0.0, 0.0))
    assert kernel_for(again).name == k.name


@pytest.mark.parametrize("shape", ["box", "u"])
def test_the_scalar_start_stream_does_not_depend_on_the_kernel(task, shape):
    """The one-at-a-time sampler with a kernel's compiled filter draws the same starts
    as the task's own (same uniforms, same decisions)."""
    t = task if shape == "box" else replace(task, obj=U_SHAPE, symmetry=None)
    want = [t.sample_start(rng) for rng in [np.random.default_rng(4)] for _ in range(400)]
    for backend in BACKENDS:
        k, rng = kernel_for(t, backend), np.random.default_rng(4)
        assert [k.sample_start(rng) for _ in range(400)] == want


@pytest.mark.parametrize("noisy", [False, True])
def test_sequential_training_is_the_same_on_every_backend(task, noisy):
    from crmgrasp.agents import train_trials

    if noisy:
        task = replace(task, noise=SensorNoise(0.05, 0.002))
    kw = dict(trials=3, episodes=80, seed=5, eval_episodes=20, checkpoints=(10, 80), checkpoint_episodes=10)
    a, b = (train_trials(task, "sarsa", **kw, backend=backend) for backend in BACKENDS)
    for field in ("steps", "success", "greedy_steps", "greedy_success", "checkpoint_steps"):
        np.testing.assert_array_equal(getattr(a, field), getattr(b, field))
    assert [x.q for x in a.agents] == [y.q for y in b.agents]


@pytest.mark.parametrize(
    ("name", "agent", "k", "params"),
    [
        ("paper-box", "model-vi", 1, {"symmetric": True}),
        ("paper-box", "model-vi", 2, {}),
        ("u-handle", "model-vi", 1, {}),
        ("box-3d", "model-vi", 1, {}),
        ("u-handle", "backoff-vi", 2, {"symmetric": True, "mean_after": 40}),
        ("u-handle", "pooled-vi", 1, {}),
    ],
)
def test_compiled_value_iteration_equals_the_readable_sweeps(name, agent, k, params):
    """The model-based learners' compiled planning gives the readable sweeps' values bit for
    bit: the same episodes, greedy evaluations and value tables. ``backoff-vi`` and
    ``pooled-vi`` hand one entry object to many pairs (their untried CRMs), which the compiled
    path flattens once (``kernels.planning._outcomes``); ``backoff-vi`` draws from the posterior
    up to episode 40, then plans on the mean."""
    from crmgrasp.agents.training import train_trials

    task = make_task(name)
    kw = {"trials": 2, "episodes": 80, "seed": 2, "k": k, "eval_episodes": 30, "checkpoints": (40, 80)}
    ref = train_trials(task, agent, params={**params, "compiled": False}, **kw)
    fast = train_trials(task, agent, params={**params, "compiled": True}, **kw)
    assert np.array_equal(ref.steps, fast.steps) and np.array_equal(ref.greedy_steps, fast.greedy_steps)
    assert np.array_equal(ref.checkpoint_steps, fast.checkpoint_steps)
    for a, b in zip(ref.agents, fast.agents, strict=True):
        inner_a, inner_b = getattr(a, "inner", a), getattr(b, "inner", b)
        assert inner_a.q == inner_b.q and inner_a.greedy_table == inner_b.greedy_table


@pytest.mark.parametrize(
    ("name", "agent", "k", "params"),
    [
        ("u-handle", "model-vi", 2, {}),
        ("u-handle", "model-vi", 1, {"symmetric": True}),
        ("paper-box", "pooled-vi", 1, {"symmetric": True}),
        ("box-3d", "model-vi", 1, {}),
    ],
)
def test_the_kept_outcome_arrays_are_a_copy_of_the_whole_model_at_every_plan(monkeypatch, name, agent, k, params):
    """model-vi keeps its plan's outcome arrays between plans and brings them in step with the
    model (changed counts, new pairs, new states): at every plan of a learning run they equal,
    bit for bit, the arrays copied from the whole model, and most plans keep them."""
    import crmgrasp.kernels.planning as planning
    from crmgrasp.agents.training import train_trials

    real, refresh = planning._model_arrays, planning._Outcomes.refresh
    kept = []

    def counted(self, *args):  # type: ignore[no-untyped-def]
        kept.append(refresh(self, *args))
        return kept[-1]

    def checked(agent, states, row):  # type: ignore[no-untyped-def]
        arrays = real(agent, states, row)
        fresh = planning._outcomes(agent.model, row)[:-1]
        assert len(arrays) == len(fresh) == 7
        for a, b in zip(arrays, fresh, strict=True):
            assert a.dtype == b.dtype
            np.testing.assert_array_equal(a, b)
        return arrays

    monkeypatch.setattr(planning, "_model_arrays", checked)
    monkeypatch.setattr(planning._Outcomes, "refresh", counted)
    train_trials(make_task(name), agent, trials=1, episodes=120, seed=3, k=k, eval_episodes=5, params=params)
    assert sum(kept) > 0.8 * len(kept) > 0  # the kept arrays served most plans, and each was checked


@pytest.mark.parametrize("name", ["box-family", "u-handle", "box-3d", "cup-3d", "triangles-3f", "box-family-3f"])
def test_a_rebound_kernel_is_the_kernel_built_afresh(name):
    """A family's compiled kernel rebound to a new object holds exactly the arrays a kernel
    built for that object holds, and steps it the same."""
    task = make_task(name)
    rng = np.random.default_rng(5)
    first = kernel_for(task.instance(rng))
    fields = ("p", "q", "th", "planes", "cyl", "e", "acts")
    for _ in range(30):
        inst = task.instance(rng)
        rebound, fresh = first.rebind(inst), kernel_for(inst)
        assert type(rebound) is type(fresh) and rebound.task is inst
        for f in fields:
            if hasattr(fresh, f):
                np.testing.assert_array_equal(getattr(rebound, f), getattr(fresh, f), err_msg=f)
        start = fresh.sample_start(np.random.default_rng(1))
        assert rebound.sample_start(np.random.default_rng(1)) == start
        a, b = rebound.begin(start, rng), fresh.begin(start, rng)
        assert a == b
        for action in range(len(task.actions)):
            assert rebound.step_one(a.state, action, rng) == fresh.step_one(b.state, action, rng)


@pytest.mark.parametrize("name", ["box-family", "mixed", "box-3d", "triangles-3f"])
def test_a_family_kernel_moves_one_kernel_per_type_and_leaves_each_object_as_it_was(name):
    """A family's compiled kernel moves itself onto each episode's object (one kernel per
    object type, in place), and never writes into an object's own arrays: the first object's
    edges (or planes) are the same after many others."""
    from crmgrasp.kernels.base import Kernel
    from crmgrasp.kernels.family import FamilyKernel

    task = make_task(name)
    kernel = kernel_for(task)
    assert isinstance(kernel, FamilyKernel)
    rng = np.random.default_rng(4)
    kernel.sample_start(rng)
    first = kernel.instance.obj
    before = repr(getattr(first, "vertices", None)) + repr(getattr(first, "planes", None))
    seen: dict[type, int] = {}
    for _ in range(50):
        kernel.sample_start(rng)
        if type(kernel.current).rebind is Kernel.rebind:  # the readable rules: a new kernel
            continue
        seen.setdefault(type(kernel.instance.obj), id(kernel.current))
        assert id(kernel.current) == seen[type(kernel.instance.obj)]
    assert seen
    assert repr(getattr(first, "vertices", None)) + repr(getattr(first, "planes", None)) == before
    if hasattr(first, "edge_array"):
        assert np.array_equal(first.edge_array, kernel_for(task.with_object(first)).e)


@pytest.mark.parametrize("name", ["box-family", "polygon-family", "u-handle", "l-shape", "t-shape", "star", "mixed"])
def test_compiled_edges_equal_the_polygon_edges(name):
    """`edge_rows`, which rebinds a family's kernel, gives `Polygon.edges` and `convex` bit for bit."""
    import crmgrasp.kernels._polygon_jit as jit
    from crmgrasp.model.polygon import Polygon

    task, rng = make_task(name), np.random.default_rng(11)
    shapes = [task.family.sample(rng) for _ in range(100)] + [U_SHAPE, regular_polygon(7, 0.1, rotation=0.2)]
    polygons = [s for s in shapes if isinstance(s, Polygon)]
    assert len(polygons) > 50
    for poly in polygons:
        e = np.empty((len(poly.vertices), 7))
        convex = jit.edge_rows(np.array(poly.vertices), e)
        assert e.tolist() == [list(row) for row in poly.edges] and convex == poly.convex


def test_the_numba_warm_up_meets_every_compiled_kernel():
    """tests/numba_warmup.py (run by tests/conftest.py before a parallel run) steps a task of
    every compiled kernel class a registered task uses, noise-free and noisy, so a new kind of
    kernel cannot be left for both workers to compile."""
    from crmgrasp.tasks import task_names

    from . import numba_warmup

    def classes(names):  # type: ignore[no-untyped-def]
        out = set()
        for name in names:
            base = make_task(name)
            for task in (base, numba_warmup.noisy(base)):
                k = kernel_for(task, "auto")
                out.add(type(getattr(k, "current", k)).__name__)
        return out - {"ReferenceKernel"}

    warmed = classes(name for half in numba_warmup.HALVES for name in half)
    assert classes(task_names()) <= warmed
    assert {"FusedPolygonKernel", "FusedFingersKernel", "FusedSpatialKernel", "FusedFingersSpatialKernel"} <= warmed

"""Hands with more than two contacts (docs/model.md section 8): the rules written once for
any number of contacts, two contacts bit for bit as before, three-contact grasp quality,
the three-finger tasks and their bad input."""

from __future__ import annotations

import dataclasses
import hashlib
import importlib.util
import math
import struct

import numpy as np
import pytest

from crmgrasp._validation import CrmgraspError
from crmgrasp.kernels import kernel_for
from crmgrasp.model.contacts import Config, Contact, Grip, contacts_from_row
from crmgrasp.model.geometry import Polygon, regular_polygon
from crmgrasp.model.hand import CRM, Error, Hand, feasible
from crmgrasp.model.planar_model import PlanarModel, mirror_crm
from crmgrasp.model.quality import closes, force_closure, least_friction, min_friction
from crmgrasp.model.sensing import Discretizer, SensorNoise, observe
from crmgrasp.sim import begin, step
from crmgrasp.tasks import make_task
from crmgrasp.tasks.core import Task
from crmgrasp.tasks.starts import CornerStarts, UniformStarts

S30, C30 = math.sin(math.pi / 6), math.cos(math.pi / 6)
TRIANGLE = regular_polygon(3, 1.0)  # circumradius 1, a vertex at angle 0 (pointing +x)


def tripod() -> Grip:
    """Contacts at the midpoints of an equilateral triangle's sides (circumradius 1), their
    normals through the centroid: a frictionless equilibrium that closes with any friction."""
    v = TRIANGLE.vertices
    mids = [((v[i][0] + v[(i + 1) % 3][0]) / 2, (v[i][1] + v[(i + 1) % 3][1]) / 2) for i in range(3)]
    return Grip(*(Contact(x, y, -x / math.hypot(x, y), -y / math.hypot(x, y)) for x, y in mids))


# ---------------------------------------------------------------- two contacts, bit for bit
TWO_CONTACT_DIGEST = "58825d2d2e9615516d0c455a3c941ee6a644cfd75f24427f5f11a1b8eedc1151"
"""The digest of 4,500 CRM outcomes computed by the two-contact rules before they were
written for any number of contacts (commit df2b05a): configurations, observations, min
friction, errors and paths on paper-box (with and without noise), discs, U handles and
polygons."""


def _two_contact_outcomes() -> str:
    h = hashlib.sha256()
    cases = (("paper-box", 0.0), ("paper-box", 0.05), ("cup-family", 0.02), ("u-handle", 0.0), ("polygon-family", 0.03))
    for name, noise in cases:
        task = make_task(name)
        if noise:
            task = dataclasses.replace(task, noise=SensorNoise(sigma_n=noise, sigma_p=noise / 10))
        rng = np.random.default_rng(7)
        for _ in range(150):
            inst, config = task.sample_world(rng)
            for _ in range(6):
                c, f = "ab"[int(rng.integers(2))], "ab"[int(rng.integers(2))]
                r = float(rng.uniform(-0.1, 0.1))
                out = inst.execute(config, CRM(c, f, r), inst.read(config, rng))
                o = inst.observe(inst.read(out.config, rng))
                vals = [v for k in out.config for v in k] + list(o) + [inst.quality(out.config), float(out.error)]
                vals += [v for p in out.path for v in p]
                h.update(struct.pack(f"{len(vals)}d", *vals))
                config = out.config
    return h.hexdigest()


def test_two_contacts_are_the_special_case_bit_for_bit():
    """Starts, readings, CRM outcomes (every error kind), observations and min friction of
    the rules written for n contacts equal those of the two-contact rules they replaced."""
    assert _two_contact_outcomes() == TWO_CONTACT_DIGEST


# ---------------------------------------------------------------- grasp quality
def test_least_friction_hand_checked_cases():
    tri = tripod()
    assert least_friction(tri) == 0.0 and min_friction(tri) == 0.0
    assert not closes(tri, 0.0)  # three frictionless contacts never close in the plane
    assert closes(tri, 1e-6)
    two = Grip(tri[0], tri[1])
    assert least_friction(two) == pytest.approx(math.tan(math.pi / 6), abs=1e-9)
    assert min_friction(Config(tri[0], tri[1])) == pytest.approx(math.tan(math.pi / 6), abs=1e-12)


def test_least_friction_of_two_contacts_is_the_closed_form():
    rng = np.random.default_rng(3)
    checked = 0
    for _ in range(400):
        p = rng.normal(size=(2, 2))
        ang = rng.uniform(0, 2 * np.pi, 2)
        cfg = Config(*(Contact(*p[i], math.cos(ang[i]), math.sin(ang[i])) for i in range(2)))
        mu = min_friction(cfg)
        if math.isfinite(mu) and mu < 20:
            checked += 1
            assert least_friction(cfg) == pytest.approx(mu, rel=1e-8, abs=1e-9)
    assert checked > 50


def test_least_friction_agrees_with_the_linear_program():
    rng = np.random.default_rng(4)
    for _ in range(150):
        p = rng.normal(size=(3, 2))
        ang = rng.uniform(0, 2 * np.pi, 3)
        n = np.stack([np.cos(ang), np.sin(ang)], axis=1)
        mu = least_friction(Grip(*(Contact(*p[i], *n[i]) for i in range(3))))
        if math.isinf(mu):
            assert not force_closure(p, n, 1e6)
        else:
            assert force_closure(p, n, mu * 1.001 + 1e-9)
            assert not force_closure(p, n, mu * 0.999)


# ---------------------------------------------------------------- the hand's rules
HAND3 = Hand(aperture=3.0, palm_depth=2.0, contacts=3)


def _tri_grip() -> Grip:
    """The tripod labelled so that the palm (right of a -> c) is clear: a and c on the two
    sides whose normals point away from the palm side, b between them."""
    t = tripod()
    return Grip(t[1], t[0], t[2])


def test_three_contact_feasibility_rules():
    g = _tri_grip()
    assert feasible(TRIANGLE, HAND3, g) is Error.NONE
    assert feasible(TRIANGLE, dataclasses.replace(HAND3, aperture=0.8), g) is Error.APERTURE  # sides 0.87 apart
    assert feasible(TRIANGLE, dataclasses.replace(HAND3, palm_depth=0.1), g) is Error.PALM  # palm inside
    assert feasible(TRIANGLE, HAND3, Grip(g[0], g[2], g[1])) is Error.PALM  # fingers cross
    assert feasible(TRIANGLE, HAND3, Grip(g[2], g[1], g[0])) is Error.PALM  # outer contacts face the palm
    assert feasible(TRIANGLE, HAND3, Grip(g[0], g[0], g[2])) is Error.PALM  # coincident


def test_three_contact_observation_is_eq_2_and_3():
    g = _tri_grip()
    rho, *moments = observe(g)
    assert rho == pytest.approx(0.0, abs=1e-24) and moments == pytest.approx([0, 0, 0], abs=1e-12)
    shifted = Grip(g[0], Contact(g[1].x + 0.1, g[1].y, g[1].nx, g[1].ny), g[2])
    values = observe(shifted)
    for j, p in enumerate(shifted):
        want = sum((c.x - p.x) * c.ny - (c.y - p.y) * c.nx for i, c in enumerate(shifted) if i != j)
        assert values[1 + j] == pytest.approx(want, abs=1e-15)


def test_a_crm_holds_the_other_contacts_and_reaches_within_every_aperture():
    g = _tri_grip()
    out = HAND3.execute(TRIANGLE, g, CRM("b", "b", 0.2))
    assert out.error is Error.NONE
    assert out.config[0] == g[0] and out.config[2] == g[2] and out.config[1] != g[1]
    tight = dataclasses.replace(HAND3, aperture=1.6)  # b's own line leaves a's or c's reach
    far = tight.execute(TRIANGLE, g, CRM("b", "b", 0.9))
    assert far.error is Error.APERTURE and far.config == g


def test_noise_draws_three_normals_per_contact_in_label_order():
    noise = SensorNoise(sigma_n=0.1, sigma_p=0.01)
    g = _tri_grip()
    one = noise.sense(g, np.random.default_rng(5))
    rows = noise.sense_batch(np.array([[v for c in g for v in c]] * 2), np.random.default_rng(5))
    assert isinstance(one, Grip) and list(rows[0]) == [v for c in one for v in c]


def test_model_states_the_sizes_from_the_hand():
    m = PlanarModel(HAND3)
    assert m.labels == ("a", "b", "c") and m.row_width == 12
    assert m.observation_names == ("rho", "m_a", "m_b", "m_c") and m.mirror_axes == (0, 3, 2, 1)
    assert m.observation_bounds()["rho"] == (0.0, 9.0) and m.observation_bounds()["m_b"] == (-12.0, 12.0)
    assert mirror_crm(CRM("a", "b", 0.02), m.labels) == CRM("c", "b", -0.02)
    assert contacts_from_row(m.row_of(_tri_grip())) == _tri_grip()
    placed = m.place(TRIANGLE, [(c.x, c.y) for c in _tri_grip()])
    assert np.allclose(m.row_of(placed), m.row_of(_tri_grip()), atol=1e-12)


# ---------------------------------------------------------------- the compiled kernel
@pytest.mark.parametrize(("name", "noise"), [("triangles-3f", 0.0), ("odd-polygons-3f", 0.0), ("triangles-3f", 0.05)])
def test_the_fingers_kernel_equals_the_readable_rules(name, noise):
    """Batched CRMs, observations, bins and least friction, bit for bit, every action."""
    task = make_task(name)
    if noise:
        task = dataclasses.replace(task, noise=SensorNoise(sigma_n=noise, sigma_p=noise / 10))
    rng = np.random.default_rng(1)
    for _ in range(6):
        inst = task.instance(rng)
        ref, fast = kernel_for(inst, "reference"), kernel_for(inst, "auto")
        assert fast.name == kernel_for(inst, "numba").name == ("numba-fingers" if noise else "numba-fingers-fused")
        rows = inst.model.rows_of([inst.sample_start(rng) for _ in range(8)])
        for a in range(len(inst.actions)):
            sen = inst.model.read_rows(rows, np.random.default_rng(a))
            (n1, e1), (n2, e2) = ref.execute(rows, sen, np.full(8, a)), fast.execute(rows, sen, np.full(8, a))
            assert np.array_equal(n1, n2) and np.array_equal(e1, e2)
            for x, y in zip(ref.observe(n1, sen, e1), fast.observe(n2, sen, e2), strict=True):
                assert np.array_equal(x, y)


@pytest.mark.parametrize("noise", [0.0, 0.05])
def test_the_fingers_kernel_steps_episodes_as_the_readable_step(noise):
    task = make_task("triangles-3f")
    if noise:
        task = dataclasses.replace(task, noise=SensorNoise(sigma_n=noise, sigma_p=noise / 10))
    rng = np.random.default_rng(2)
    for _ in range(10):
        inst, start = task.sample_world(rng)
        fast = kernel_for(inst, "auto")
        seed = int(rng.integers(1 << 30))
        ra, rb = np.random.default_rng(seed), np.random.default_rng(seed)
        a, b = begin(inst, start, ra), fast.begin(start, rb)
        assert a == b
        for _ in range(6):
            action = int(rng.integers(len(inst.actions)))
            a, b = step(inst, a.state, action, ra), fast.step_one(b.state, action, rb)
            assert a == b


def test_the_fused_fingers_kernel_steps_from_any_earlier_state():
    """The fused kernel keeps its row's observation and least friction for the step after an
    errored CRM; stepping from any earlier state (a branch), errors included, is still the
    readable step."""
    task = make_task("triangles-3f")
    rng = np.random.default_rng(5)
    errors = 0
    for _ in range(8):
        inst, start = task.sample_world(rng)
        fast = kernel_for(inst, "auto")
        assert type(fast).__name__ == "FusedFingersKernel"
        states = [fast.begin(start, rng).state]
        for _ in range(40):
            src = states[int(rng.integers(len(states)))] if rng.random() < 0.5 else states[-1]
            action = int(rng.integers(len(inst.actions)))
            a, b = step(inst, src, action, rng), fast.step_one(src, action, rng)
            assert a == b
            errors += a.error != 0
            states.append(b.state)
    assert errors > 50  # the reuse after an error is exercised


@pytest.mark.parametrize("name", ["triangles-3f", "odd-polygons-3f", "box-family-3f"])
def test_the_compiled_uniform_start_rule_draws_the_readable_starts(name):
    """The fingers kernel's uniform start filter makes the readable rule's decisions: the
    same starts from the same stream, one at a time and as rows, on 60 objects; and a start
    on a vertex is refused as the readable rule refuses it."""
    from crmgrasp.tasks.starts import uniform_candidate

    task = make_task(name)
    for i in range(60):
        inst = task.instance(np.random.default_rng(i))
        kernel = kernel_for(inst, "auto")
        assert kernel.start_filter is not None and kernel.start_filter.kind == "uniform"
        assert kernel.sample_start(np.random.default_rng(i)) == inst.sample_start(np.random.default_rng(i))
        got = kernel.sample_starts(np.random.default_rng(i), 3)
        assert np.array_equal(got, inst.sample_starts(np.random.default_rng(i), 3))
    obj, hand = inst.obj, inst.hand
    on_vertex = np.array([obj.vertex_arclengths()[1], 0.3 * obj.perimeter, 0.6 * obj.perimeter])
    assert uniform_candidate(obj, hand, inst.mu_goal, on_vertex) is None
    assert kernel.start_filter(obj, hand, inst.mu_goal, on_vertex) is None


# ---------------------------------------------------------------- tasks
def test_the_references_take_the_compiled_planar_least_friction(monkeypatch):
    """`compiled_rules` hands a three-finger planar task's model the fingers kernel's
    compiled least friction: equal to the readable rule bit for bit on the configurations
    random CRMs visit, and the references computed with it equal the readable ones."""
    from crmgrasp.kernels import compiled_rules
    from crmgrasp.kernels.fingers import compiled_least_friction
    from crmgrasp.planners import references, sampled

    task = make_task("triangles-3f")
    fast = compiled_rules(task)
    assert fast.model.least_friction is not None and task.model.least_friction is None
    assert compiled_rules(make_task("paper-box")).model.least_friction is None
    rule, rng = compiled_least_friction(), np.random.default_rng(3)
    inst = task.instance(rng)
    config, seen = inst.sample_start(rng), 0
    for a in rng.integers(len(task.actions), size=200).tolist():
        config = inst.execute(config, task.actions[a], config).config
        assert rule(config) == least_friction(config)
        assert fast.model.quality(config) == inst.model.quality(config)
        seen += 0.0 < least_friction(config) < math.inf
    assert seen > 10
    starts = references.sample_starts(task, 6, 3)
    values = (references.belief_optimum(task, starts), references.clairvoyant_bound(task, starts))
    monkeypatch.setattr(sampled, "compiled_rules", lambda t: t)
    assert (references.belief_optimum(task, starts), references.clairvoyant_bound(task, starts)) == values


def test_three_finger_tasks_are_registered_and_sample_feasible_starts():
    task = make_task("triangles-3f")
    assert task.model.n_contacts == 3 and "three fingers" in task.headline()
    assert "two fingers" in make_task("triangles").headline()
    rng = np.random.default_rng(0)
    for _ in range(20):
        inst, start = task.sample_world(rng)
        assert isinstance(start, Grip) and inst.feasible(start) is Error.NONE
        assert not inst.is_success(start)


def test_three_finger_bad_input_is_one_line():
    tri = Polygon(TRIANGLE.vertices)
    with pytest.raises(CrmgraspError, match="a hand has 2 to 4 contacts, got 5"):
        Hand(aperture=0.2, palm_depth=0.1, contacts=5)
    with pytest.raises(CrmgraspError, match="names contact 'c', but the hand has contacts a, b"):
        make_task("paper-box").crm(CRM("c", "a", 0.0))
    with pytest.raises(CrmgraspError, match="'corners' starts place two contacts, but the hand has 3"):
        Task(name="t", obj=tri, hand=HAND3, actions=(CRM("a", "b", 0.0),), starts=CornerStarts())
    task = Task(name="t", obj=tri, hand=HAND3, actions=(CRM("c", "a", 0.0),), starts=UniformStarts())
    assert task.discretizer.names == ("rho", "m_a", "m_b", "m_c")  # the default bins over the model
    with pytest.raises(CrmgraspError, match="has 2 contacts; the hand has 3"):
        task.check_config(Config(_tri_grip()[0], _tri_grip()[2]))
    with pytest.raises(CrmgraspError, match="the bins are over rho, m_a, m_b, but the planar model observes"):
        Task(
            name="t",
            obj=tri,
            hand=HAND3,
            actions=(CRM("c", "a", 0.0),),
            starts=UniformStarts(),
            discretizer=Discretizer(m_a=(0.2,)),
        )
    with pytest.raises(CrmgraspError, match="give one point per contact"):
        HAND3.contact(tri, a=(0, 0), b=(1, 0))


def test_the_third_contact_experiment_compares_two_fingers_with_three(tmp_path):
    from crmgrasp.experiments.third_contact import ThirdContactConfig, third_contact

    s = third_contact(tmp_path, ThirdContactConfig.quick())
    two, three = s["rows"]
    assert (two["fingers"], three["fingers"]) == (2, 3) and two["mu_goal"] == three["mu_goal"] == 0.15
    assert two["graspable_share"] == 0.0 and two["belief_optimum"] is None  # tan 30 deg > 0.15: never
    assert three["graspable_share"] >= 0.8
    assert three["clairvoyant_bound"] <= three["belief_optimum"] <= make_task("triangles-3f").max_steps
    assert two["learned_crms"] is None  # nothing to learn where no start can be grasped
    assert three["belief_optimum"] <= three["learned_crms"] <= 10 and 0 <= three["learned_success"] <= 1
    assert three["final_friction"] is None or three["final_friction"] <= 0.15  # a grasp meets its goal
    assert two["mujoco_success"] is None  # no policy where no start can be grasped
    if importlib.util.find_spec("mujoco") is not None:  # the quick run scores 4 MuJoCo worlds
        assert three["mujoco_success"] in (0.0, 0.25, 0.5, 0.75, 1.0)
    for name in ("third_contact.csv", "third_contact.png", "summary.json"):
        assert (tmp_path / name).stat().st_size > 0


def test_the_third_contact_experiment_learns_with_a_named_preset(tmp_path):
    """The learner is a preset of ``crmgrasp learn`` (``families`` by default: backoff-vi on
    two-CRM histories, on the mirror quotient, never repeating an errored CRM); an unknown
    preset is a one-line error before anything runs."""
    from crmgrasp.experiments._episodes import train_preset
    from crmgrasp.experiments.third_contact import ThirdContactConfig, third_contact

    assert ThirdContactConfig().preset == "families"
    agents, k = train_preset(make_task("triangles-3f"), "families", 2, 5, 0)
    assert k == 2 and len(agents) == 2
    assert all(type(a.inner).__name__ == "BackoffVI" and a.skip_errored for a in agents)
    agents, k = train_preset(make_task("triangles-3f"), "fastest", 1, 5, 0)
    assert k == 1 and type(agents[0].inner).__name__ == "PooledVI"
    with pytest.raises(CrmgraspError, match="unknown learner preset 'nope'; known presets: paper"):
        ThirdContactConfig(preset="nope")
    cfg = dataclasses.replace(ThirdContactConfig.quick(), starts=6, episodes=30, mujoco_worlds=0, preset="fastest")
    s = third_contact(tmp_path, cfg)
    assert "learner preset fastest" in s["budget"] and s["rows"][1]["learned_crms"] is not None


def test_the_third_contact_experiment_holds_cups_in_space(tmp_path):
    """The default pairs end with cups in 3-D; a small run of that pair gives a two-finger
    and a tripod row with the same goal, the tripod's optimum above its bound."""
    from crmgrasp.experiments.third_contact import ThirdContactConfig, third_contact

    assert ThirdContactConfig().pairs[-1] == ("cup-3d", "cup-3d-3f")
    cfg = ThirdContactConfig(
        pairs=(("cup-3d", "cup-3d-3f"),), mu_goals=(0.05,), starts=4, trials=1, episodes=20, mujoco_worlds=2
    )
    two, three = third_contact(tmp_path, cfg)["rows"]
    assert (two["fingers"], three["fingers"], two["family"], three["task"]) == (2, 3, "cup-3d", "cup-3d-3f")
    assert two["graspable_share"] == three["graspable_share"] == 1.0
    assert 1.0 <= three["clairvoyant_bound"] <= three["belief_optimum"] <= 10
    from crmgrasp.hardware.mujoco import mujoco_available

    for row in (two, three):  # the transfer to the MuJoCo stand-in ran (two worlds) where the extra is installed
        assert row["mujoco_success"] in ((0.0, 0.5, 1.0) if mujoco_available() else (None,))

"""Three fingers in space: the spatial model of n contacts (docs/model-3d.md section 9)."""

from __future__ import annotations

import dataclasses
import hashlib
import math
import os
import platform
import struct
import subprocess
import sys
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

from crmgrasp import CrmgraspError
from crmgrasp.kernels import kernel_for
from crmgrasp.model.hand import Error
from crmgrasp.model.quality import ANTIPODAL_TOL, positively_spans
from crmgrasp.model.quality3d import force_closure_3d, least_friction_3d, min_friction_3d
from crmgrasp.model.sensing import SensorNoise
from crmgrasp.model.solids import Cylinder, box3d
from crmgrasp.model.spatial import (
    CRM3D,
    Config3D,
    Contact3D,
    Grip3D,
    Hand3D,
    execute_crm3d,
    faces_palm3d,
    feasible3d,
    observe3d,
)
from crmgrasp.tasks import make_task, task_from_dict, task_to_dict
from crmgrasp.tasks.spatial import TRIPOD_HAND, tripod_crms

# ---------------------------------------------------------------- two contacts, bit for bit
SPATIAL_TWO_CONTACT_DIGEST = "c3a2998ccb18b5ef00273e52c278f10b3f424a1937cf6009b1a648f2762b3743"
"""The digest of 1,440 spatial CRM outcomes computed by the two-contact rules before they were
written for any number of contacts (commit a0ca3da): starts, readings with and without noise,
configurations, observations, min friction, feasibility and errors on box-3d and cup-3d."""


def _spatial_two_contact_outcomes() -> str:
    h = hashlib.sha256()
    for name, noise in (("box-3d", 0.0), ("box-3d", 0.05), ("cup-3d", 0.0), ("cup-3d", 0.03)):
        task = make_task(name)
        if noise:
            task = dataclasses.replace(task, noise=SensorNoise(sigma_n=noise, sigma_p=noise / 10))
        rng = np.random.default_rng(11)
        for _ in range(60):
            inst, config = task.sample_world(rng)
            for _ in range(6):
                c, f = "ab"[int(rng.integers(2))], "ab"[int(rng.integers(2))]
                r = tuple(float(v) for v in rng.uniform(-0.07, 0.07, 2))
                out = inst.execute(config, CRM3D(c, f, r), inst.read(config, rng))
                o = inst.observe(inst.read(out.config, rng))
                vals = inst.model.numbers(out.config) + list(o) + [inst.quality(out.config), float(out.error)]
                vals += [float(inst.feasible(out.config))]
                h.update(struct.pack(f"{len(vals)}d", *vals))
                config = out.config
    return h.hexdigest()


def test_two_spatial_contacts_are_the_special_case_bit_for_bit() -> None:
    """Starts, readings, CRM outcomes (every error kind), observations, min friction and
    feasibility of the spatial rules written for n contacts equal the two-contact rules'.

    The digest was recorded with OpenBLAS's Haswell kernels, and the spatial rules' small
    matrix products and solves go through numpy's BLAS, whose last bit depends on the kernel
    the machine picks (an AVX-512 machine picks another). Where the digest differs, the
    outcomes are computed again in a process that asks OpenBLAS for the recorded kernels
    (``OPENBLAS_CORETYPE``, on x86-64): the same rules, the recording's arithmetic."""
    if _spatial_two_contact_outcomes() == SPATIAL_TWO_CONTACT_DIGEST:
        return
    if platform.machine().lower() not in ("x86_64", "amd64"):
        pytest.skip(f"the digest was recorded with x86-64 BLAS kernels; this machine is {platform.machine()}")
    code = "from test_tripod import _spatial_two_contact_outcomes as f; print(f())"
    env = {
        **os.environ,
        "OPENBLAS_CORETYPE": "Haswell",
        "PYTHONPATH": os.pathsep.join(filter(None, [str(Path(__file__).parent), os.environ.get("PYTHONPATH")])),
    }
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    assert out.stdout.strip() == SPATIAL_TWO_CONTACT_DIGEST


# ---------------------------------------------------------------- quality
R = 0.05


def _equator(angles: tuple[float, ...], z: float = 0.0) -> tuple[list, list]:
    """Contacts on a cylinder of radius R about z, their normals toward its axis."""
    pts = [(R * math.cos(a), R * math.sin(a), z) for a in angles]
    return pts, [(-math.cos(a), -math.sin(a), 0.0) for a in angles]


def test_least_friction_hand_checked_cases() -> None:
    """Three contacts 120 degrees apart on an equator, normals through the axis: a frictionless
    equilibrium, closed with any friction; two of them squeeze at tan 30 degrees."""
    pts, nrm = _equator((0.0, 2 * math.pi / 3, 4 * math.pi / 3))
    assert least_friction_3d(pts, nrm) < 1e-6
    assert force_closure_3d(pts, nrm, 1e-3) and not force_closure_3d(pts, nrm, 0.0)
    assert min_friction_3d(pts[:2], nrm[:2]) == pytest.approx(math.tan(math.pi / 6), abs=1e-12)
    assert least_friction_3d(pts[:2], nrm[:2]) == math.inf  # two point contacts never close


def test_least_friction_brackets_the_linear_program() -> None:
    rng = np.random.default_rng(4)
    finite = 0
    for _ in range(12):
        angles = tuple(rng.uniform(0, 2 * math.pi, 3))
        pts, nrm = _equator(angles)
        pts = [(x, y, float(rng.uniform(-0.03, 0.03))) for x, y, _ in pts]
        mu = least_friction_3d(pts, nrm)
        if math.isinf(mu):
            assert not force_closure_3d(pts, nrm, 1e6)
            continue
        finite += 1
        assert force_closure_3d(pts, nrm, mu * 1.001 + 1e-9)
        assert mu < 1e-6 or not force_closure_3d(pts, nrm, mu * 0.999)
    assert finite >= 3


def _tilted_grips(count: int) -> list[tuple[list, list]]:
    """Three contacts on a cylinder at random angles and heights, normals tilted off the axis:
    least frictions spread over 0.05-5 (and some inf)."""
    rng = np.random.default_rng(9)
    out = []
    for _ in range(count):
        pts, nrm = _equator(tuple(rng.uniform(0, 2 * math.pi, 3)))
        pts = [(x, y, float(rng.uniform(-0.03, 0.03))) for x, y, _ in pts]
        nrm = [tuple(np.array(n) + rng.normal(0.0, 0.3, 3)) for n in nrm]
        out.append((pts, [tuple(np.array(n) / np.linalg.norm(n)) for n in nrm]))
    return out


def test_the_search_without_guesses_is_the_bisection(monkeypatch) -> None:
    """With no guesses allowed and no first probe every probe is the bracket's midpoint: the
    least friction is the plain bisection's, written out here, bit for bit."""
    from crmgrasp.model import quality3d

    monkeypatch.setattr(quality3d, "TRIPOD_EXACT", False)  # the search, which four contacts take

    def bisection(pts: list, nrm: list) -> float:
        frames = quality3d._cone_frames(pts, nrm)
        lo, hi = 0.0, quality3d._THETA_MAX_3D
        while hi - lo > quality3d.THETA_TOL_3D:
            mid = 0.5 * (lo + hi)
            closes = positively_spans(quality3d._wrenches(frames, math.tan(mid), 8))
            lo, hi = (lo, mid) if closes else (mid, hi)
        if hi == quality3d._THETA_MAX_3D:
            return math.inf
        return 0.0 if math.tan(hi) < ANTIPODAL_TOL else math.tan(hi)

    monkeypatch.setattr(quality3d, "GUIDE_MAX", 0)
    monkeypatch.setattr(quality3d, "FIRST_PROBE", 0.0)
    for pts, nrm in _tilted_grips(6):
        assert least_friction_3d(pts, nrm) == bisection(pts, nrm)


def test_the_first_probe_is_at_its_friction(monkeypatch) -> None:
    """The search probes friction ``FIRST_PROBE`` first (the midpoint of the whole range with
    it at 0), then the midpoint of what is left: above it when it opened, below when it
    closed."""
    from crmgrasp.model import quality3d

    monkeypatch.setattr(quality3d, "TRIPOD_EXACT", False)  # the search, which four contacts take

    probes: list[float] = []
    wrenches = quality3d._wrenches
    monkeypatch.setattr(quality3d, "_wrenches", lambda f, mu, e: probes.append(mu) or wrenches(f, mu, e))
    for pts, nrm in _tilted_grips(4):
        probes.clear()
        mu = least_friction_3d(pts, nrm)
        first, second = (math.atan(p) for p in probes[:2])
        assert probes[0] == pytest.approx(quality3d.FIRST_PROBE, rel=1e-12)
        end = quality3d._THETA_MAX_3D if mu > quality3d.FIRST_PROBE else 0.0
        assert second == pytest.approx(0.5 * (first + end), rel=1e-12)
    monkeypatch.setattr(quality3d, "FIRST_PROBE", 0.0)
    probes.clear()
    least_friction_3d(*_tilted_grips(1)[0])
    assert math.atan(probes[0]) == pytest.approx(0.5 * quality3d._THETA_MAX_3D, rel=1e-12)


def test_the_first_probe_sits_just_above_the_tripods_goal() -> None:
    """``FIRST_PROBE`` is 1% above the default goal of a task, which the tripod tasks keep:
    a first probe that opens there decides their grasp (above the goal by more than the
    decision's margin), one that closes leaves it to the probes below."""
    import dataclasses

    from crmgrasp.kernels.closure import DECIDED_MARGIN
    from crmgrasp.model import quality3d
    from crmgrasp.tasks import Task

    default = next(f.default for f in dataclasses.fields(Task) if f.name == "mu_goal")
    assert quality3d.FIRST_PROBE == pytest.approx(1.01 * default, rel=1e-12)
    for name in ("cup-3d-3f", "box-3d-3f"):
        goal = make_task(name).mu_goal
        assert goal == default and math.tan(math.atan(quality3d.FIRST_PROBE)) > goal * (1 + DECIDED_MARGIN)


def test_the_guesses_halve_the_programs_and_keep_the_bracket(monkeypatch) -> None:
    """On tilted tripods the search's guesses take at most 16 programs a configuration where
    the bisection takes 24, and the answer still brackets the closure: closed at it, open
    1e-3 rad below it, and within 1e-5 relative of the bisection's."""
    from crmgrasp.model import quality, quality3d

    monkeypatch.setattr(quality3d, "TRIPOD_EXACT", False)  # the search, which four contacts take

    calls = []
    program = quality.max_least_weight
    monkeypatch.setattr(quality, "max_least_weight", lambda w: calls.append(1) or program(w))
    finite = 0
    for pts, nrm in _tilted_grips(10):
        calls.clear()
        mu = least_friction_3d(pts, nrm)
        guided = len(calls)
        with monkeypatch.context() as m:
            m.setattr(quality3d, "GUIDE_MAX", 0)
            m.setattr(quality3d, "FIRST_PROBE", 0.0)
            calls.clear()
            plain = least_friction_3d(pts, nrm)
        if math.isinf(mu) or mu < 1e-6:
            assert mu == plain or (mu < 1e-6 and plain < 1e-6)
            continue
        finite += 1
        assert guided <= 16 and len(calls) == 24, (guided, len(calls))
        assert mu == pytest.approx(plain, rel=1e-5)
        theta = math.atan(mu)
        assert force_closure_3d(pts, nrm, mu)
        assert not force_closure_3d(pts, nrm, math.tan(theta - 1e-3))
    assert finite >= 5


# ---------------------------------------------------------------- the hand and the CRM
CUP = Cylinder((0.0, 0.0, 0.0), (0.0, 0.0, 1.0), R, 0.2)
HAND3 = Hand3D(aperture=0.16, palm_depth=0.12, contacts=3)


def _grip(*angles: float, z: float = 0.1) -> Grip3D:
    pts, nrm = _equator(angles, z)
    return Grip3D(*(Contact3D(p, n) for p, n in zip(pts, nrm)))  # type: ignore[arg-type]


def test_three_finger_feasibility() -> None:
    """Fingers in order along a -> z are feasible (the middle one may face the palm); crossed
    fingers, an outer contact facing the palm and contacts beyond the aperture are not."""
    # a at 120 degrees, b at 0 (the middle, facing the palm at -x), c at -120 degrees
    ok = _grip(2 * math.pi / 3, 0.0, -2 * math.pi / 3)
    assert feasible3d(CUP, HAND3, ok, table=0.0) is Error.NONE
    crossed = _grip(2 * math.pi / 3, math.radians(-100.0), -2 * math.pi / 3)  # b beyond c along a -> c
    assert not faces_palm3d(crossed, HAND3) and feasible3d(CUP, HAND3, crossed, table=0.0) is Error.PALM
    mirrored = Grip3D(ok[2], ok[1], ok[0])  # the palm on the other side: the outer contacts face it
    assert feasible3d(CUP, HAND3, mirrored, table=0.0) is Error.PALM
    wide = Cylinder((0.0, 0.0, 0.0), (0.0, 0.0, 1.0), 0.1, 0.2)
    far = Grip3D(*(Contact3D((0.1 * c.n[0] * -1, 0.1 * c.n[1] * -1, 0.1), c.n) for c in ok))
    assert feasible3d(wide, HAND3, far, table=0.0) is Error.APERTURE  # 0.17 m apart
    low = Grip3D(ok[0], Contact3D((ok[1].x[0], ok[1].x[1], 0.0), ok[1].n), ok[2])
    assert feasible3d(CUP, HAND3, low, table=0.0) is Error.PALM  # a finger on the table


def test_a_crm_stays_within_the_aperture_of_every_still_contact() -> None:
    """An opposition of ``a`` onto ``b``'s line takes the chord within A of both ``b`` and
    ``c``: on a box longer than the aperture, a goal line far from ``c`` fails."""
    box = box3d((-0.05, -0.15, 0.0), (0.05, 0.15, 0.1))
    g = Grip3D(
        Contact3D((-0.05, -0.14, 0.05), (1.0, 0.0, 0.0)),
        Contact3D((0.05, -0.14, 0.05), (-1.0, 0.0, 0.0)),
        Contact3D((0.05, 0.0, 0.05), (-1.0, 0.0, 0.0)),
    )
    hand = Hand3D(aperture=0.16, palm_depth=0.0, contacts=3)
    near = execute_crm3d(box, hand, g, CRM3D("a", "b", (0.0, 0.0)), table=0.0)
    assert near.config[0].x == pytest.approx((-0.05, -0.14, 0.05))  # b's line is within A of c
    two = Hand3D(aperture=0.16, palm_depth=0.0)
    out2 = execute_crm3d(box, two, Config3D(g[0], g[1]), CRM3D("a", "b", (0.0, 0.0)), table=0.0)
    assert out2.config[0].x == pytest.approx(near.config[0].x)
    far = Grip3D(g[0], Contact3D((0.05, 0.14, 0.05), (-1.0, 0.0, 0.0)), g[2])
    g2 = Grip3D(Contact3D((-0.05, 0.14, 0.05), (1.0, 0.0, 0.0)), far[1], Contact3D((0.05, -0.14, 0.05), (-1, 0, 0)))
    assert execute_crm3d(box, hand, g2, CRM3D("a", "b", (0.0, 0.0)), table=0.0).error is Error.APERTURE


def test_three_finger_observation_by_hand() -> None:
    """``rho = |sum n|^2`` and ``|m_j| = |sum_{i != j} (x_i - x_j) x n_i|``."""
    g = _grip(0.0, 2 * math.pi / 3, 4 * math.pi / 3)
    rho, *moments = observe3d(g)
    assert rho == pytest.approx(0.0, abs=1e-24) and moments == pytest.approx([0.0] * 3, abs=1e-15)
    g2 = Grip3D(g[0], g[1], Contact3D(g[2].x, (0.0, 0.0, -1.0)))
    xs, ns = np.array([c.x for c in g2]), np.array([c.n for c in g2])
    rho2, *m2 = observe3d(g2)
    assert rho2 == pytest.approx(float(ns.sum(axis=0) @ ns.sum(axis=0)))
    for j in range(3):
        want = sum(np.cross(xs[i] - xs[j], ns[i]) for i in range(3) if i != j)
        assert m2[j] == pytest.approx(float(np.linalg.norm(want)), abs=1e-15)


# ---------------------------------------------------------------- tasks and environments
@pytest.mark.parametrize("name", ["cup-3d-3f", "box-3d-3f"])
def test_tripod_tasks_start_feasible_step_and_round_trip(name: str) -> None:
    task = make_task(name)
    assert task.model.n_contacts == 3 and task.model.row_width == 18 and len(task.actions) == 18
    assert task.model.observation_names == ("rho", "m_a", "m_b", "m_c")
    rng = np.random.default_rng(2)
    kernel = kernel_for(task)
    for _ in range(3):
        start = kernel.sample_start(rng)
        inst = kernel.instance
        assert isinstance(start, Grip3D) and inst.feasible(start) is Error.NONE and not inst.is_success(start)
        now = kernel.begin(start, rng)
        nxt = kernel.step_one(now.state, 0, rng)
        assert nxt.state.steps == 1 and len(nxt.observation) == 4
    again = task_from_dict(task_to_dict(task))
    assert task_to_dict(again) == task_to_dict(task) and again.hand.contacts == 3
    compiled, readable = kernel_for(task.instance(rng), "numba"), kernel_for(task.instance(rng), "reference")
    assert compiled.name == "numba-spatial-fingers-fused" and compiled.task.model.least_friction is not None
    assert readable.name == "spatial" and readable.task.model.least_friction is None


@pytest.mark.parametrize("env_id", ["crmgrasp/Cup3D3F-v0", "crmgrasp/Box3D3F-v0"])
def test_tripod_envs_pass_check_env_and_vectorise(env_id: str) -> None:
    env = gym.make(env_id)
    check_env(env.unwrapped)
    assert env.action_space.n == 18 and set(env.observation_space.spaces) == {"rho", "m_a", "m_b", "m_c", "error"}
    venv = gym.make_vec(env_id, num_envs=2)
    venv.reset(seed=1)
    obs, *_ = venv.step(np.array([0, 7]))
    assert obs["m_c"].shape == (2, 1)
    venv.close()


def test_tripod_bad_input_gets_one_line_errors() -> None:
    with pytest.raises(CrmgraspError, match="a hand has 2 to 4 contacts"):
        Hand3D(aperture=0.16, palm_depth=0.12, contacts=5)
    with pytest.raises(CrmgraspError, match="contact labels must be 'a' or 'b', got 'c'"):
        make_task("cup-3d").hand.check_crm(CRM3D("c", "a", (0.0, 0.0)))  # type: ignore[attr-defined]
    assert TRIPOD_HAND.check_crm(CRM3D("c", "a", (0.0, 0.0)))
    with pytest.raises(CrmgraspError, match="contact labels must be a, b, c, got 'd'"):
        TRIPOD_HAND.check_crm(CRM3D("d", "a", (0.0, 0.0)))
    task = make_task("cup-3d-3f").instance(np.random.default_rng(0))
    two = make_task("cup-3d").instance(np.random.default_rng(0))
    with pytest.raises(CrmgraspError, match="must be a Grip3D of 3 Contact3D"):
        task.check_config(two.sample_start(np.random.default_rng(1)))
    assert len(tripod_crms(("a", "b"))) == 6

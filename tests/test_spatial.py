"""The spatial CRM model: docs/model-3d.md's worked cases, the planar special case, properties."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from crmgrasp import CrmgraspError, paper_box
from crmgrasp.model.hand import CRM, Error, execute_crm
from crmgrasp.model.spatial import (
    CRM3D,
    Config3D,
    Contact3D,
    ConvexPolyhedron,
    Hand3D,
    box3d,
    execute_crm3d,
    feasible3d,
    observe3d,
    tangent_frame,
)

BOX = box3d((-0.15, -0.05, 0.0), (0.15, 0.05, 0.10))
HAND = Hand3D(aperture=0.16, palm_depth=0.12, backoff=0.01)
START = Config3D(Contact3D((-0.15, -0.02, 0.05), (1.0, 0.0, 0.0)), Contact3D((-0.10, -0.05, 0.05), (0.0, 1.0, 0.0)))


def test_worked_case_opposition_grasps() -> None:
    out = execute_crm3d(BOX, HAND, START, CRM3D("a", "b"))
    assert out.error is Error.NONE
    assert np.allclose(out.config.a.x, (-0.10, 0.05, 0.05)) and np.allclose(out.config.a.n, (0.0, -1.0, 0.0))
    assert out.config.b == START.b


def test_worked_case_start_inside_is_an_aperture_error() -> None:
    out = execute_crm3d(BOX, HAND, START, CRM3D("b", "a"))
    assert out.error is Error.APERTURE and out.config == START


def test_worked_case_vertical_slide_and_its_observation() -> None:
    t1, t2 = tangent_frame(START.a.n, HAND)
    assert np.allclose(t1, (0, -1, 0)) and np.allclose(t2, (0, 0, 1))
    out = execute_crm3d(BOX, HAND, START, CRM3D("a", "a", (0.0, 0.03)))
    assert out.error is Error.NONE
    assert np.allclose(out.config.a.x, (-0.15, -0.02, 0.08)) and np.allclose(out.config.a.n, (1, 0, 0))
    rho, ma, mb = observe3d(out.config)
    assert (
        rho == pytest.approx(2.0) and ma == pytest.approx(0.05831, abs=1e-5) and mb == pytest.approx(0.04243, abs=1e-5)
    )


def _lift(cfg, z: float = 0.05) -> Config3D:  # type: ignore[no-untyped-def]
    return Config3D(*(Contact3D((c.x, c.y, z), (c.nx, c.ny, 0.0)) for c in cfg))


def test_the_planar_model_is_the_special_case() -> None:
    """A prism (the paper box, 0.10 m tall), contacts at mid-height with horizontal normals,
    offsets in the plane: every CRM gives the planar model's error and configuration."""
    task = paper_box()
    rng = np.random.default_rng(0)
    seen = set()
    for _ in range(300):
        cfg = task.sample_start(rng)
        for crm in task.actions:
            flat = execute_crm(task.obj, task.hand, cfg, crm)
            solid = execute_crm3d(BOX, HAND, _lift(cfg), CRM3D(crm.c, crm.f, (crm.r, 0.0)))
            assert solid.error is flat.error
            assert np.allclose(
                [v for c in solid.config for v in c.x], [v for c in _lift(flat.config) for v in c.x], atol=1e-9
            )
            seen.add(flat.error)
    assert seen == {Error.NONE, Error.APERTURE, Error.PALM}


def _rotation(rng: np.random.Generator) -> np.ndarray:
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    return q * np.sign(np.linalg.det(q))


def _on_surface(obj: ConvexPolyhedron, c: Contact3D) -> bool:
    rows = np.array(obj.planes)
    gaps = rows[:, :3] @ np.array(c.x) - rows[:, 3]
    k = int(np.argmax(gaps))
    return bool(np.all(gaps <= 1e-9) and abs(gaps[k]) <= 1e-9 and np.allclose(c.n, -rows[k, :3]))


# Offsets below a micron are left out: there a contact lands a hair off the one opposite it, and the
# palm rule's n . u (about r / 0.1 m) meets its tolerance of 1e-9 exactly (r = 1e-10: a tie that the
# rotation's rounding breaks either way; hypothesis found it, seed 18, labels "ba").
_OFFSET = st.one_of(st.just(0.0), st.floats(-0.1, 0.1).filter(lambda r: abs(r) >= 1e-6))


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2**32 - 1), _OFFSET, _OFFSET, st.sampled_from(["aa", "ab", "ba", "bb"]))
def test_properties_of_the_spatial_crm(seed: int, r1: float, r2: float, labels: str) -> None:
    rng = np.random.default_rng(seed)
    cfg = _lift(paper_box().sample_start(rng), z=float(rng.uniform(0.01, 0.09)))
    crm = CRM3D(labels[0], labels[1], (r1, r2))
    out = execute_crm3d(BOX, HAND, cfg, crm)
    if out.error is Error.NONE:  # the moved contact is on a face with that face's inward normal
        moved = out.config.a if crm.c == "a" else out.config.b
        assert _on_surface(BOX, moved) and feasible3d(BOX, HAND, out.config) is Error.NONE
    else:  # an errored CRM changes nothing
        assert out.config == cfg
    # rotating and moving the whole world (object, contacts, the hand's axes) changes nothing else
    q, shift = _rotation(rng), rng.normal(size=3) * 0.1
    rows = np.array(BOX.planes)
    turned = ConvexPolyhedron(
        tuple(map(tuple, np.column_stack([rows[:, :3] @ q.T, rows[:, 3] + rows[:, :3] @ q.T @ shift])))
    )
    hand = Hand3D(0.16, 0.12, 0.01, h=tuple(q @ np.array(HAND.h)), g=tuple(q @ np.array(HAND.g)))

    def move(c: Contact3D) -> Contact3D:
        return Contact3D(tuple(q @ np.array(c.x) + shift), tuple(q @ np.array(c.n)))

    other = execute_crm3d(turned, hand, Config3D(move(cfg.a), move(cfg.b)), crm)
    assert other.error is out.error
    want = [v for c in out.config for v in move(c).x]
    assert np.allclose([v for c in other.config for v in c.x], want, atol=1e-9)
    assert np.allclose(observe3d(out.config), observe3d(other.config), atol=1e-9)


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda: box3d((0, 0, 0), (1, 0, 1)), "lo < hi"),
        (lambda: ConvexPolyhedron(((1.0, 0.0, 0.0, 1.0),)), "4 or more finite planes"),
        (lambda: Hand3D(0.16, 0.12, h=(0, 0, 1), g=(0, 1, 1)), "perpendicular"),
        (lambda: Hand3D(0.16, 0.12, h=(0, 0, 0)), "non-zero 3-vector"),
        (lambda: execute_crm3d(BOX, HAND, START, CRM3D("a", "c")), "'a' or 'b'"),
        (lambda: execute_crm3d(BOX, HAND, START, CRM3D("a", "a", (0.2, 0.0))), "r_max"),
        (lambda: execute_crm3d(BOX, HAND, START, CRM3D("a", "a", (math.nan, 0.0))), "finite"),
    ],
)
def test_bad_input_is_one_line(call, message: str) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(CrmgraspError, match=message) as info:
        call()
    assert "\n" not in str(info.value)


def test_an_upright_cylinder_is_the_planar_disc() -> None:
    """A cylinder standing on the table, contacts at mid-height: the planar disc model."""
    from crmgrasp.model.geometry import Disc
    from crmgrasp.model.hand import Hand
    from crmgrasp.model.spatial import Cylinder
    from crmgrasp.tasks import UniformStarts

    disc, hand2 = Disc(0.06, (0.01, -0.02)), Hand(aperture=0.16, palm_depth=0.12, backoff=0.01)
    cup = Cylinder((0.01, -0.02, 0.0), (0.0, 0.0, 1.0), 0.06, 0.12)
    crms = [CRM("a", "b", 0.0), CRM("b", "a", 0.0), CRM("a", "a", 0.05), CRM("b", "b", -0.05), CRM("a", "b", 0.03)]
    rng = np.random.default_rng(1)
    seen = set()
    for _ in range(200):
        cfg = UniformStarts()(disc, hand2, 0.05, rng)
        for crm in crms:
            flat = execute_crm(disc, hand2, cfg, crm)
            solid = execute_crm3d(cup, HAND, _lift(cfg, 0.06), CRM3D(crm.c, crm.f, (crm.r, 0.0)))
            assert solid.error is flat.error
            got = [v for c in solid.config for v in (*c.x, *c.n)]
            want = [v for c in _lift(flat.config, 0.06) for v in (*c.x, *c.n)]
            assert np.allclose(got, want, atol=1e-9)
            seen.add(flat.error)
    assert Error.NONE in seen and len(seen) >= 2


def test_cylinder_caps_and_bad_cylinders() -> None:
    from crmgrasp.model.spatial import Cylinder

    cup = Cylinder((0.0, 0.0, 0.0), (0.0, 0.0, 1.0), 0.05, 0.10)
    point, normal = cup.ray_entry((0.01, 0.0, 0.3), (0.0, 0.0, -1.0), 1.0)  # straight down onto the top
    assert np.allclose(point, (0.01, 0.0, 0.10)) and np.allclose(normal, (0, 0, -1))
    point, normal = cup.ray_entry((0.01, 0.0, -0.3), (0.0, 0.0, 1.0), 1.0)  # up into the bottom
    assert np.allclose(point, (0.01, 0.0, 0.0)) and np.allclose(normal, (0, 0, 1))
    assert cup.ray_entry((0.2, 0.0, 0.3), (0.0, 0.0, -1.0), 1.0) is None  # beside it
    assert cup.contains((0.0, 0.0, 0.05)) and not cup.contains((0.05, 0.0, 0.05))
    for kwargs, message in (({"radius": 0.0}, "radius"), ({"height": -1.0}, "height"), ({"axis": (0, 0, 0)}, "axis")):
        args = {"origin": (0, 0, 0), "axis": (0, 0, 1), "radius": 0.05, "height": 0.1, **kwargs}
        with pytest.raises(CrmgraspError, match=message):
            Cylinder(**args)  # type: ignore[arg-type]


def test_sensing_noise_in_3d() -> None:
    from crmgrasp.model.spatial import sense3d

    rng = np.random.default_rng(0)
    assert sense3d(START, 0.0, 0.0, rng, HAND) is START
    assert rng.random() == np.random.default_rng(0).random()  # no draw without noise
    sigma = math.radians(10.0)
    angles, moves = [], []
    for _ in range(4000):
        got = sense3d(START, sigma, 0.002, rng, HAND)
        for before, after in zip(START, got):
            assert np.linalg.norm(after.n) == pytest.approx(1.0)
            angles.append(math.acos(min(1.0, float(np.dot(before.n, after.n)))))
            moves.append(np.array(after.x) - np.array(before.x))
    # the angle between true and sensed normals is |N(0, sigma)|: mean sigma sqrt(2/pi)
    want, se = sigma * math.sqrt(2 / math.pi), sigma * math.sqrt(1 - 2 / math.pi) / math.sqrt(len(angles))
    assert abs(np.mean(angles) - want) < 4 * se
    assert np.allclose(np.std(np.array(moves), axis=0), 0.002, rtol=0.05)
    a = sense3d(START, sigma, 0.01, np.random.default_rng(5), HAND)
    assert a == sense3d(START, sigma, 0.01, np.random.default_rng(5), HAND)  # the same seed, the same reading
    with pytest.raises(CrmgraspError, match="sigma_n"):
        sense3d(START, 1.0, 0.0, rng, HAND)


def _dot3(n, t) -> float:
    """``n . t`` of two 3-vectors summed from 0.0 in order, the sum `_rigid` states (numpy's
    ``np.dot`` goes to the BLAS, whose last bit depends on the kernel the machine picks)."""
    return float(((0.0 + n[0] * t[0]) + n[1] * t[1]) + n[2] * t[2])


def test_rigid_motions_compute_what_numpy_computes_bit_for_bit():
    """`moved` and `yawed` write the faces' arithmetic out in Python floats: the bytes (the sign
    of a zero included) equal numpy's ``R a``, ``b + (R a) . t`` (summed in order) and row
    scaling, on boxes with zero coordinates and on general polyhedra."""
    from crmgrasp.model.solids import ConvexPolyhedron, box3d, rotation_z

    def numpy_moved(planes, r, t):
        rows = np.array(planes)
        normals = rows[:, :3] @ r.T
        raw = np.array([(*n, b + _dot3(n, t)) for n, b in zip(normals, rows[:, 3])])
        return (raw / np.sqrt((raw[:, :3] * raw[:, :3]).sum(axis=1))[:, None]).tobytes()

    rng = np.random.default_rng(8)
    for i in range(300):
        if i % 3 == 0:
            solid = ConvexPolyhedron(tuple(map(tuple, rng.normal(size=(7, 4)).tolist())))
        else:
            size = rng.random(3) + 0.01
            lo = (-size[0], -0.0, 0.0) if i % 3 == 1 else (-size[0], -size[1], -size[2])
            solid = box3d(lo, (size[0], size[1], -0.0 if i % 3 == 2 else size[2]))
        angle, dx, dy, dz = (rng.random(4) - (0.0, 0.5, 0.5, 0.5)) * (6.3, 0.2, 0.2, 0.2)
        r = rotation_z(angle)
        assert np.array(solid.yawed(angle, dx, dy).planes).tobytes() == numpy_moved(solid.planes, r, (dx, dy, 0.0))
        assert np.array(solid.moved(r, (dx, dy, dz)).planes).tobytes() == numpy_moved(solid.planes, r, (dx, dy, dz))


def test_the_quick_rigid_motions_equal_the_checked_constructions():
    """`yawed`, `box3d` and `centre` skip conversions, not arithmetic: the planes equal the
    checked constructor's on the same numbers, and the centre is the corners' mean, bit for bit."""
    from crmgrasp.model.solids import ConvexPolyhedron, Cylinder, box3d, rotation_z

    rng = np.random.default_rng(3)
    for _ in range(200):
        lo = -rng.random(3)
        hi = rng.random(3) + 0.01
        box = box3d(lo, hi)
        faces = [(-1.0, 0.0, 0.0, -lo[0]), (1.0, 0.0, 0.0, hi[0]), (0.0, -1.0, 0.0, -lo[1])]
        faces += [(0.0, 1.0, 0.0, hi[1]), (0.0, 0.0, -1.0, -lo[2]), (0.0, 0.0, 1.0, hi[2])]
        assert box.planes == ConvexPolyhedron(tuple(faces)).planes
        angle, dx, dy = rng.random(3) * (6.0, 0.1, 0.1)
        r, t = rotation_z(angle), np.array([dx, dy, 0.0])
        rows = np.array(box.planes)
        normals = rows[:, :3] @ r.T
        checked = ConvexPolyhedron(tuple((*n, b + _dot3(n, t)) for n, b in zip(normals.tolist(), rows[:, 3].tolist())))
        moved = box.yawed(angle, dx, dy)
        assert moved.planes == checked.planes == box.moved(r, t).planes
        assert moved.centre.tolist() == moved.vertices.mean(axis=0).tolist()
        cyl = Cylinder((0.0, 0.0, 0.0), (0.0, 0.0, 1.0), 0.05, 0.1)
        assert cyl.yawed(angle, dx, dy) == cyl.moved(r, (dx, dy, 0.0))

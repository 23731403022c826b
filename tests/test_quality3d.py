"""Spatial grasp quality: hand-computed cases, the metrics against each other, bad input."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from crmgrasp import CrmgraspError
from crmgrasp.model.contacts import Config, Contact
from crmgrasp.model.quality import min_friction
from crmgrasp.model.quality3d import (
    ferrari_canny,
    force_closure_3d,
    min_friction_3d,
    primitive_wrenches,
    tangent_basis,
)

PAIR = [(0.05, 0.0, 0.0), (-0.05, 0.0, 0.0)]


def _tilted(deg: float) -> list[tuple[float, float, float]]:
    t = math.radians(deg)
    return [(-math.cos(t), 0.0, math.sin(t)), (1.0, 0.0, 0.0)]


def _ring(k: int, radius: float = 0.05) -> tuple[list, list]:
    """``k`` contacts evenly on a circle in the xy plane, normals toward its centre."""
    a = 2 * math.pi * np.arange(k) / k
    pts = [(radius * math.cos(x), radius * math.sin(x), 0.0) for x in a]
    return pts, [(-math.cos(x), -math.sin(x), 0.0) for x in a]


def test_two_contact_min_friction_hand_cases() -> None:
    assert min_friction_3d(PAIR, [(-1, 0, 0), (1, 0, 0)]) == 0.0  # antipodal
    for deg in (10.0, 30.0, 45.0, 60.0):  # one normal tilted by deg out of the line: tan(deg)
        assert min_friction_3d(PAIR, _tilted(deg)) == pytest.approx(math.tan(math.radians(deg)), rel=1e-12)
    assert min_friction_3d(PAIR, [(1, 0, 0), (-1, 0, 0)]) == math.inf  # normals pointing apart
    assert min_friction_3d([(0, 0, 0), (0, 0, 0)], [(1, 0, 0), (-1, 0, 0)]) == math.inf  # coincident


@settings(max_examples=60, deadline=None)
@given(st.lists(st.floats(-1.0, 1.0), min_size=4, max_size=4), st.floats(0, 2 * math.pi), st.floats(0, 2 * math.pi))
def test_planar_pairs_need_the_planar_friction(xy, a1, a2) -> None:  # type: ignore[no-untyped-def]
    ax, ay, bx, by = xy
    assume(math.hypot(bx - ax, by - ay) > 1e-6)  # coincident contacts: each model's own degenerate case
    na, nb = (math.cos(a1), math.sin(a1)), (math.cos(a2), math.sin(a2))
    planar = min_friction(Config(Contact(ax, ay, *na), Contact(bx, by, *nb)))
    spatial = min_friction_3d([(ax, ay, 0.0), (bx, by, 0.0)], [(*na, 0.0), (*nb, 0.0)])
    assert spatial == pytest.approx(planar, rel=1e-9, abs=1e-12) or (math.isinf(planar) and math.isinf(spatial))


def test_two_contacts_are_never_spatial_force_closure() -> None:
    # no force at either contact has a moment about the line through both: rotation about it is free
    for mu in (0.0, 0.5, 2.0, 10.0):
        assert not force_closure_3d(PAIR, [(-1, 0, 0), (1, 0, 0)], mu)
        assert ferrari_canny(PAIR, [(-1, 0, 0), (1, 0, 0)], mu) == 0.0


def test_frictionless_grasps_of_six_or_fewer_contacts_are_not_closed() -> None:
    # six rays cannot positively span R^6 (that takes at least seven)
    for k in (3, 4, 6):
        pts, nrm = _ring(k)
        assert not force_closure_3d(pts, nrm, 0.0)


def test_three_finger_ring_grasp_is_closed_with_friction() -> None:
    # the classical three-finger grasp: in-plane squeeze, friction resists everything else
    pts, nrm = _ring(3)
    assert force_closure_3d(pts, nrm, 0.5) and ferrari_canny(pts, nrm, 0.5) == pytest.approx(0.24679, abs=1e-5)
    assert not force_closure_3d(pts, nrm, 0.0)


def test_epsilon_grows_with_friction_and_with_cone_resolution_converges() -> None:
    pts, nrm = _ring(3)
    eps = [ferrari_canny(pts, nrm, mu) for mu in (0.1, 0.3, 0.5, 1.0)]
    assert eps == sorted(eps) and eps[0] > 0.0
    fine, finer = ferrari_canny(pts, nrm, 0.5, edges=32), ferrari_canny(pts, nrm, 0.5, edges=64)
    assert abs(fine - finer) / finer < 0.01


def _sphere_grasp(rng: np.random.Generator, k: int) -> tuple[np.ndarray, np.ndarray]:
    v = rng.normal(size=(k, 3))
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    return 0.05 * v, -v


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(3, 5), st.floats(0.05, 1.5))
def test_lp_and_epsilon_agree(seed: int, k: int, mu: float) -> None:
    pts, nrm = _sphere_grasp(np.random.default_rng(seed), k)
    closed, eps = force_closure_3d(pts, nrm, mu), ferrari_canny(pts, nrm, mu)
    if closed:
        assert eps > 0.0
    else:
        assert eps < 1e-6


@settings(max_examples=15, deadline=None)
@given(st.integers(0, 2**32 - 1))
def test_rotating_the_whole_grasp_changes_nothing_but_the_cone_facets(seed: int) -> None:
    rng = np.random.default_rng(seed)
    pts, nrm = _sphere_grasp(rng, 4)
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    q *= np.sign(np.linalg.det(q))  # a rotation
    before = ferrari_canny(pts, nrm, 0.6, edges=16)
    after = ferrari_canny(pts @ q.T, nrm @ q.T, 0.6, edges=16)
    # 16-edge cones turn with the frame: each edge set is within 1 - cos(pi/16) = 1.9% of the circular
    # cone, so facets of the unit-force hull move by at most about 0.02
    assert after == pytest.approx(before, abs=0.02)
    assert min_friction_3d(pts[:2], nrm[:2]) == pytest.approx(min_friction_3d(pts[:2] @ q.T, nrm[:2] @ q.T), rel=1e-9)


def test_tangent_basis_is_right_handed_and_orthonormal() -> None:
    for n in ([0, 0, 1.0], [1.0, 0, 0], np.array([1.0, 2.0, 2.0]) / 3.0):
        n = np.asarray(n)
        t1, t2 = tangent_basis(n)
        m = np.array([t1, t2, n])
        assert np.allclose(m @ m.T, np.eye(3)) and np.isclose(np.linalg.det(m), 1.0)


def test_wrenches_have_unit_forces() -> None:
    pts, nrm = _ring(3)
    w = primitive_wrenches(pts, nrm, 0.7, edges=6)
    assert w.shape == (6, 18) and np.allclose(np.linalg.norm(w[:3], axis=0), 1.0)


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda: min_friction_3d([(0, 0)], [(1, 0)]), "shape \\(n, 3\\)"),
        (lambda: min_friction_3d([*PAIR, (0, 0, 0)], [(1, 0, 0)] * 3), "takes 2 contacts"),
        (lambda: min_friction_3d(PAIR, [(math.nan, 0, 0), (1, 0, 0)]), "finite"),
        (lambda: min_friction_3d(PAIR, [(2, 0, 0), (1, 0, 0)]), "unit vectors"),
        (lambda: force_closure_3d(PAIR, [(-1, 0, 0), (1, 0, 0)], -0.1), "mu"),
        (lambda: ferrari_canny(PAIR, [(-1, 0, 0), (1, 0, 0)], 0.5, edges=2), "edges"),
    ],
)
def test_bad_input_is_one_line(call, message: str) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(CrmgraspError, match=message) as info:
        call()
    assert "\n" not in str(info.value)

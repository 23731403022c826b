"""The exact least friction of three spatial contacts (`crmgrasp.model.tripod`, docs/model-3d.md
section 9): hand-checked cases, the search it replaced, and an independent linear program."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import linprog

from crmgrasp.model import quality3d, tripod
from crmgrasp.model.quality3d import least_friction_3d, primitive_wrenches

W, D = 0.04, 0.05  # a box's half-width along x and the third finger's face at y = -D


def _box_grip(rise: float) -> tuple[list, list]:
    """Two fingers squeezing a box across x at height 0.05, the third on the face y = -D at
    height 0.05 + ``rise``, pressing along +y."""
    pts = [(-W, 0.0, 0.05), (W, 0.0, 0.05), (0.0, -D, 0.05 + rise)]
    return pts, [(1.0, 0.0, 0.0), (-1.0, 0.0, 0.0), (0.0, 1.0, 0.0)]


@pytest.mark.parametrize("edges", [4, 8, 16])
def test_a_third_finger_off_the_plane_needs_the_friction_of_its_tilt(edges: int) -> None:
    """An antipodal squeeze and a third finger whose normal leaves the contacts' plane by
    ``atan(rise / D)``: every internal force presses the third finger within that plane, so the
    least friction is ``rise / D`` (the in-plane direction is a vertex of the polyhedral cone,
    whatever its edges), approached as the third force vanishes. In the plane: 0."""
    for rise, want in ((0.02, 0.4), (0.005, 0.1), (0.0, 0.0)):
        got = least_friction_3d(*_box_grip(rise), edges=edges)
        assert got == pytest.approx(want, rel=1e-12, abs=1e-15), (rise, edges)


def test_collinear_contacts_and_a_normal_across_the_plane_never_close() -> None:
    """Three contacts on a line (or two at one point) have no moment about it; a normal across
    the contacts' plane meets no internal force, all of which lie in it: ``inf``."""
    line = [(-0.05, 0.0, 0.0), (0.0, 0.0, 0.0), (0.05, 0.0, 0.0)]
    assert least_friction_3d(line, [(1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (-1.0, 0.0, 0.0)]) == math.inf
    pts, nrm = _box_grip(0.02)
    assert least_friction_3d([pts[0], pts[0], pts[2]], nrm) == math.inf
    assert least_friction_3d([*pts[:2], (0.0, -0.01, 0.05)], [*nrm[:2], (0.0, 0.0, -1.0)]) == math.inf


def _grips(count: int, seed: int) -> list[tuple[np.ndarray, np.ndarray]]:
    """Three contacts on a cylinder at random angles and heights, normals tilted off its axis
    (some exactly through it: frictionless equilibria)."""
    rng = np.random.default_rng(seed)
    out = []
    for i in range(count):
        ang = rng.uniform(0.0, 2 * math.pi, 3)
        pts = np.stack([0.04 * np.cos(ang), 0.04 * np.sin(ang), rng.uniform(-0.03, 0.03, 3)], axis=1)
        nrm = -np.stack([np.cos(ang), np.sin(ang), np.zeros(3)], axis=1)
        if i % 5:
            nrm = nrm + rng.normal(0.0, 0.3, (3, 3))
            nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
        out.append((pts, nrm))
    return out


def _margin(p: np.ndarray, n: np.ndarray, mu: float) -> float:
    """The largest least weight of a convex combination of the primitive wrenches that is the
    origin (> 0: force closure), by HiGHS: an independent solver of the spatial model's test."""
    w = primitive_wrenches(p, n, mu)
    k, m = w.shape
    a_eq = np.vstack([np.hstack([w, np.zeros((k, 1))]), np.r_[np.ones(m), 0.0]])
    a_ub = np.hstack([-np.eye(m), np.ones((m, 1))])
    res = linprog(
        np.r_[np.zeros(m), -1.0], a_ub, np.zeros(m), a_eq, np.r_[np.zeros(k), 1.0], bounds=[(None, None)] * (m + 1)
    )
    return -res.fun


def test_the_rule_is_the_threshold_of_an_independent_solver() -> None:
    """Where the rule says ``mu``, HiGHS finds the wrenches closed at ``mu (1 + 1e-4)`` and open
    at ``mu (1 - 1e-4)``; the search over the cone's half-angle it replaced (still the rule of
    four contacts) answers at most 1e-4 relative (plus 1e-6) above it, never below: its bracket's
    upper end, above the threshold by up to its tolerance and its program's margin."""
    finite = 0
    for p, n in _grips(40, 3):
        mu = least_friction_3d(p, n)
        quality3d.TRIPOD_EXACT = False
        try:
            searched = least_friction_3d(p, n)
        finally:
            quality3d.TRIPOD_EXACT = True
        assert math.isinf(mu) == math.isinf(searched)
        if math.isinf(mu):
            continue
        assert mu <= searched <= mu * (1 + 1e-4) + 1e-6, (mu, searched)
        if mu > 1e-3:
            finite += 1
            assert _margin(p, n, mu * (1 + 1e-4)) > 1e-12 >= _margin(p, n, mu * (1 - 1e-4)), mu
    assert finite >= 20


def test_both_parts_of_the_rule_decide_some_grips(monkeypatch) -> None:
    """On tilted grips some least frictions are the first bound ``B`` (one force vanishing: the
    programs find nothing below it) and others lie below it (every force pressing), found in a
    few programs each; every one lies between the lower bound ``max_i rho_i`` and ``B``."""
    programs: list[int] = []
    program = tripod._program
    monkeypatch.setattr(tripod, "_program", lambda *a: programs.append(1) or program(*a))
    kinds, counts = set(), []
    for p, n in _grips(40, 4):
        programs.clear()
        mu = least_friction_3d(p, n)
        frames = quality3d._cone_frames(p, n)
        tangents = np.array([np.concatenate(t) for t in frames.tangents])
        rows = tripod._rows(np.array(frames.arms), np.array(frames.normals), tangents, frames.rho, 8)
        if rows is None or math.isinf(mu):
            continue
        lightest = [tripod._lightest(rows, i) for i in range(3)]
        bound = tripod._vanishing(rows, lightest)
        kinds.add("vanishing" if mu == bound else "pressing")
        assert max(lightest) * (1 - 1e-12) <= mu <= bound
        counts.append(len(programs))
    assert kinds == {"vanishing", "pressing"}
    assert max(counts) <= 12 and float(np.mean(counts)) <= 5.0, counts


def test_the_tripod_rule_takes_the_edges_check() -> None:
    """A bad ``edges`` is a one-line error on the exact rule as on the search."""
    from crmgrasp import CrmgraspError

    with pytest.raises(CrmgraspError, match="edges must be an integer"):
        least_friction_3d(*_box_grip(0.02), edges=2)

"""The force-closure linear program's simplex method (crmgrasp.model.lp) against scipy's
HiGHS on the same program, and its hand-checked cases."""

from __future__ import annotations

import math

import numpy as np
import pytest

from crmgrasp.model import lp
from crmgrasp.model.lp import max_least_weight
from crmgrasp.model.quality import LP_TOL, positively_spans
from crmgrasp.model.quality3d import primitive_wrenches


def _highs(w: np.ndarray) -> float:
    """The same program, ``max d  s.t.  W lambda = 0, sum lambda = 1, lambda_j >= d``, by HiGHS."""
    from scipy.optimize import linprog

    k, m = w.shape
    c = np.zeros(m + 1)
    c[-1] = -1.0
    a_eq = np.zeros((k + 1, m + 1))
    a_eq[:k, :m] = w
    a_eq[k, :m] = 1.0
    b_eq = np.zeros(k + 1)
    b_eq[k] = 1.0
    a_ub = np.hstack([-np.eye(m), np.ones((m, 1))])
    bounds = [(0, None)] * m + [(None, 1)]
    res = linprog(c, A_ub=a_ub, b_ub=np.zeros(m), A_eq=a_eq, b_eq=b_eq, bounds=bounds, method="highs")
    return -res.fun if res.status == 0 else -math.inf


def _tripod_wrenches(rng: np.random.Generator, mu: float) -> np.ndarray:
    points = rng.normal(size=(3, 3))
    normals = points.mean(axis=0) - points + 0.5 * rng.normal(size=(3, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    return primitive_wrenches(points, normals, mu)


@pytest.mark.parametrize(("seed", "streak"), [(0, 0), (1, 1), (2, None), (3, None)])
def test_the_optimum_is_highs_optimum_on_random_tripods(monkeypatch, seed: int, streak: int | None) -> None:
    """Random three-contact wrench sets (24 columns in R^6) over frictions 0 to 3: the same
    feasibility and the same optimum to 1e-12 (HiGHS's own tolerance is far looser), so the
    same force-closure decision; with Dantzig's rule (the default), with Bland's throughout
    (``DEGENERATE_STREAK`` 0) and with Bland's after each degenerate pivot (1)."""
    if streak is not None:
        monkeypatch.setattr(lp, "DEGENERATE_STREAK", streak)
    rng = np.random.default_rng(seed)
    feasible = 0
    for mu in np.tile([0.0, 0.05, 0.2, 0.5, 1.0, 3.0], 25):
        w = _tripod_wrenches(rng, float(mu))
        ours, theirs = max_least_weight(w), _highs(w)
        assert math.isinf(ours) == math.isinf(theirs)
        if math.isfinite(ours):
            feasible += 1
            assert abs(ours - theirs) < 1e-12
            assert (ours > LP_TOL) == (theirs > LP_TOL)
    assert feasible > 20  # both outcomes are exercised


def test_hand_checked_programs() -> None:
    """``e_1, e_2, -e_1 - e_2``: weights 1/3; the square's four corners: 1/4; a half plane's
    columns: no convex combination is the origin; in R^3, planar columns are feasible but
    not of full rank, which `positively_spans` refuses."""
    assert max_least_weight(np.array([[1.0, 0.0, -1.0], [0.0, 1.0, -1.0]])) == pytest.approx(1 / 3, abs=1e-15)
    square = np.array([[1.0, -1.0, 1.0, -1.0], [1.0, 1.0, -1.0, -1.0]])
    assert max_least_weight(square) == pytest.approx(0.25, abs=1e-15)
    assert max_least_weight(np.array([[1.0, 0.5, 2.0], [0.1, -1.0, 1.0]])) == -math.inf
    flat = np.vstack([square, np.zeros(4)])
    assert max_least_weight(flat) == pytest.approx(0.25, abs=1e-15) and not positively_spans(flat)
    assert positively_spans(square)


def test_degenerate_programs_end() -> None:
    """Many repeated and opposite columns (every right-hand side but one is 0: the degenerate
    case where a careless pivot rule cycles) end at the optimum."""
    base = np.array([[1.0, 0.0, -1.0, 0.0], [0.0, 1.0, 0.0, -1.0]])
    w = np.hstack([base] * 6)
    assert max_least_weight(w) == pytest.approx(1 / 24, abs=1e-15)


def test_dantzig_takes_fewer_pivots_than_bland(monkeypatch) -> None:
    """On random tripod wrenches Dantzig's rule needs well under Bland's pivots (about 11 a
    program against 25 on the tripod tasks), at the same optima to 1e-12."""
    count = [0]
    pivot = lp._pivot

    def counted(*args: object) -> None:
        count[0] += 1
        pivot(*args)  # type: ignore[arg-type]

    monkeypatch.setattr(lp, "_pivot", counted)
    rng = np.random.default_rng(9)
    batches = [_tripod_wrenches(rng, mu) for mu in (0.05, 0.2, 0.5, 1.0) * 10]
    dantzig = [max_least_weight(w) for w in batches]
    pivots_dantzig = count[0]
    count[0] = 0
    monkeypatch.setattr(lp, "DEGENERATE_STREAK", 0)
    bland = [max_least_weight(w) for w in batches]
    assert pivots_dantzig < 0.7 * count[0]
    for a, b in zip(dantzig, bland, strict=True):
        assert a == b or abs(a - b) < 1e-12


def test_a_degenerate_streak_hands_over_to_bland(monkeypatch) -> None:
    """The degenerate program above, with the hand-over after every degenerate pivot, ends
    at the same optimum."""
    monkeypatch.setattr(lp, "DEGENERATE_STREAK", 1)
    base = np.array([[1.0, 0.0, -1.0, 0.0], [0.0, 1.0, 0.0, -1.0]])
    assert max_least_weight(np.hstack([base] * 6)) == pytest.approx(1 / 24, abs=1e-15)

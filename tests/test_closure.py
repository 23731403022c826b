"""The compiled least friction of three or more spatial contacts (crmgrasp.kernels.closure)
against the readable rule, bit for bit, and the tripod kernel that uses it."""

from __future__ import annotations

import math

import numpy as np
import pytest

from crmgrasp.kernels import kernel_for
from crmgrasp.kernels.closure import compiled_least_friction
from crmgrasp.model import lp
from crmgrasp.model.quality3d import least_friction_3d
from crmgrasp.model.spatial import Grip3D
from crmgrasp.model.spatial_model import contact3d
from crmgrasp.tasks import make_task


def _grip(points: np.ndarray, normals: np.ndarray) -> Grip3D:
    return Grip3D(*(contact3d(p, n) for p, n in zip(points, normals, strict=True)))


def _random_grips(seed: int, count: int) -> list[Grip3D]:
    """Three or four contacts, normals roughly inward and some exactly through one point
    (frictionless equilibria, where the program is nearly degenerate)."""
    rng = np.random.default_rng(seed)
    out = []
    for i in range(count):
        n = 3 + (i % 5 == 0)
        points = rng.normal(size=(n, 3))
        toward = points.mean(axis=0) - points
        normals = toward + (0.0 if i % 4 == 0 else 0.6) * rng.normal(size=(n, 3))
        out.append(_grip(points, normals / np.linalg.norm(normals, axis=1, keepdims=True)))
    return out


@pytest.mark.parametrize("seed", range(3))
@pytest.mark.slow
def test_compiled_least_friction_equals_the_readable_rule(seed: int) -> None:
    """Random grips, equilibria among them: the same float, bit for bit (or both inf)."""
    compiled = compiled_least_friction()
    for grip in _random_grips(seed, 40):
        want = least_friction_3d([c.x for c in grip], [c.n for c in grip])
        got = compiled(grip)
        assert got == want or (math.isinf(got) and math.isinf(want)), (grip, got, want)


@pytest.mark.slow
def test_compiled_least_friction_on_the_tripod_tasks_episodes() -> None:
    """Along random episodes of both tripod tasks the compiled kernel's steps equal the
    readable kernel's: configurations, observations, rewards and least friction."""
    for name in ("cup-3d-3f", "box-3d-3f"):
        task = make_task(name)
        fast, slow = kernel_for(task, "auto"), kernel_for(task, "reference")
        assert fast.name == "family" and fast.current.name == "numba-spatial-fingers-fused"
        rng_f, rng_s = np.random.default_rng(5), np.random.default_rng(5)
        acts = np.random.default_rng(6).integers(len(task.actions), size=60).tolist()
        a, b = fast.begin(fast.sample_start(rng_f), rng_f), slow.begin(slow.sample_start(rng_s), rng_s)
        for action in acts:
            assert a == b
            if a.terminated or a.truncated:
                a, b = fast.begin(fast.sample_start(rng_f), rng_f), slow.begin(slow.sample_start(rng_s), rng_s)
            else:
                a, b = fast.step_one(a.state, action, rng_f), slow.step_one(b.state, action, rng_s)
        assert a == b


def test_a_changed_tolerance_reaches_the_compiled_rule(monkeypatch) -> None:
    """The tolerances are read when the rule is made: with a phase-1 tolerance of -1 every
    program is infeasible, so nothing closes, readable and compiled alike."""
    grip = _random_grips(0, 1)[0]
    assert math.isfinite(compiled_least_friction()(grip))
    monkeypatch.setattr(lp, "FEASIBILITY_TOL", -1.0)
    assert math.isinf(least_friction_3d([c.x for c in grip], [c.n for c in grip]))
    assert math.isinf(compiled_least_friction()(grip))


@pytest.mark.parametrize(("name", "value"), [("GUIDE_MAX", 0), ("FIRST_PROBE", 0.0), ("FIRST_PROBE", 0.3)])
def test_the_search_constants_reach_the_compiled_rule(monkeypatch, name: str, value: float) -> None:
    """The search's constants are read when the rule is made: with no guesses allowed, or the
    first probe elsewhere (the midpoint, friction 0.3), both rules still agree bit for bit; on
    several grips that moves the answer within its bracket."""
    from crmgrasp.model import quality3d

    monkeypatch.setattr(quality3d, "TRIPOD_EXACT", False)  # three contacts search too, as four do
    grips = _random_grips(7, 12)
    guided = [compiled_least_friction()(grip) for grip in grips]
    monkeypatch.setattr(quality3d, name, value)
    plain = [compiled_least_friction()(grip) for grip in grips]
    for grip, got in zip(grips, plain, strict=True):
        want = least_friction_3d([c.x for c in grip], [c.n for c in grip])
        assert got == want or (math.isinf(got) and math.isinf(want))
    assert sum(g != p for g, p in zip(guided, plain, strict=True) if math.isfinite(g)) >= 3


def test_the_references_take_the_compiled_rule(monkeypatch) -> None:
    """`compiled_rules` leaves a planar task as it is and hands a tripod task's model the
    compiled least friction; the references computed with it equal the readable ones."""
    from crmgrasp.kernels import compiled_rules
    from crmgrasp.planners import references, sampled

    box = make_task("paper-box")
    assert compiled_rules(box) is box
    task = make_task("cup-3d-3f")
    assert compiled_rules(task).model.least_friction is not None and task.model.least_friction is None
    starts = references.sample_starts(task, 6, 3)
    fast = (references.belief_optimum(task, starts), references.clairvoyant_bound(task, starts))
    monkeypatch.setattr(sampled, "compiled_rules", lambda t: t)
    assert (references.belief_optimum(task, starts), references.clairvoyant_bound(task, starts)) == fast


def _wrench_batches(seed: int) -> list[np.ndarray]:
    """Primitive wrenches of random grips at frictions from 1e-4 to 10, the spatial model's
    own (3 or 4 contacts, 8 edges), some of them from frictionless equilibria."""
    from crmgrasp.model.quality3d import primitive_wrenches

    rng = np.random.default_rng(seed)
    out = []
    for grip in _random_grips(seed, 15):
        for mu in (1e-4, *rng.uniform(0.01, 10.0, size=3)):
            out.append(primitive_wrenches([c.x for c in grip], [c.n for c in grip], float(mu)))
    return out


@pytest.mark.parametrize("seed", range(2))
def test_the_compiled_program_equals_the_readable_one(seed: int) -> None:
    """`max_least_weight` compiled (it leaves the never-read artificial columns stale) returns
    the readable simplex method's optimum bit for bit, -inf and NaN included."""
    import crmgrasp.kernels._closure_jit as jit
    from crmgrasp.kernels.closure import closure_params

    tol = closure_params()
    for w in _wrench_batches(seed):
        want, got = lp.max_least_weight(w), jit.max_least_weight(w, tol)
        assert got == want or (math.isnan(got) and math.isnan(want)), (got, want)


@pytest.mark.parametrize("streak", [0, 1])
def test_the_pivot_rule_reaches_the_compiled_program(monkeypatch, streak: int) -> None:
    """With Bland's rule throughout (``DEGENERATE_STREAK`` 0, the rule before Dantzig's) and
    with Bland's after every degenerate pivot (1), the compiled program still equals the
    readable one bit for bit; Bland's rule throughout changes some optima in the last bits."""
    import crmgrasp.kernels._lp_jit as jit
    from crmgrasp.kernels.closure import closure_params

    batches = _wrench_batches(5)
    dantzig = [jit.max_least_weight(w, closure_params()) for w in batches]
    monkeypatch.setattr(lp, "DEGENERATE_STREAK", streak)
    tol = closure_params()
    assert tol[jit.DEGENERATE_STREAK] == streak
    got = [jit.max_least_weight(w, tol) for w in batches]
    for w, value in zip(batches, got, strict=True):
        want = lp.max_least_weight(w)
        assert value == want or (math.isnan(value) and math.isnan(want)), (value, want)
    if streak == 0:
        assert sum(a != b for a, b in zip(dantzig, got, strict=True) if math.isfinite(a)) >= 3


def test_the_rank_shortcut_decides_as_the_singular_values() -> None:
    """The Cholesky certificate and numpy's rank agree on full-rank wrenches, on wrenches of
    rank 5 (one row a copy of another: the certificate fails, the singular values decide),
    on nearly dependent rows just above and below the rank tolerance, and with a rank
    tolerance too large for the certificate (the singular values alone)."""
    import crmgrasp.kernels._closure_jit as jit
    from crmgrasp.kernels.closure import CERTIFIED_RANK_TOL, closure_params

    tol, g = closure_params(), np.empty((6, 6))
    cases = _wrench_batches(3)
    rng = np.random.default_rng(4)
    for w in list(cases):
        low = w.copy()
        low[5] = low[4]
        cases.append(low)
        for gap in (1e-11, 1e-9, 1e-3):
            near = w.copy()
            near[5] = near[4] + gap * rng.normal(size=w.shape[1])
            cases.append(near)
    kinds = set()
    for w in cases:
        want = np.linalg.matrix_rank(w, tol=tol[jit.RANK_TOL]) == 6
        assert jit._full_rank(w, tol, g) == want
        kinds.add(want)
    assert kinds == {True, False}
    coarse = tol.copy()
    coarse[jit.RANK_TOL] = 10 * CERTIFIED_RANK_TOL
    for w in cases[:20]:
        assert jit._full_rank(w, coarse, g) == (np.linalg.matrix_rank(w, tol=coarse[jit.RANK_TOL]) == 6)


@pytest.mark.parametrize("seed", range(2))
def test_the_early_decision_equals_the_comparison(seed: int) -> None:
    """`above` (the search stopped once its bracket decides ``least friction > mu_goal``)
    answers as the comparison of the full least friction does, for goals far from it, at it
    to the last bit, one unit in the last place either side, and 0; both answers occur."""
    import crmgrasp.kernels._closure_jit as jit
    from crmgrasp.kernels.closure import closure_params

    tol = closure_params()
    answers = set()
    for grip in _random_grips(10 + seed, 30):
        p, n = np.array([c.x for c in grip]), np.array([c.n for c in grip])
        lf = jit.least_friction(p, n, 8, tol)
        goals = [0.0, 0.05, 0.15, 0.5, 2.0]
        if math.isfinite(lf):
            goals += [lf, math.nextafter(lf, 0.0), math.nextafter(lf, math.inf), lf * (1 + 1e-9), lf * (1 - 1e-9)]
        for goal in goals:
            want = not (lf <= goal)
            assert jit.above(p, n, 8, tol, goal) == want, (grip, goal, lf)
            answers.add(want)
            decided = jit.decided_friction(p, n, 8, tol, goal)  # a bound on the side of the goal lf is on
            assert (decided <= goal) == (lf <= goal) and (decided >= lf if lf <= goal else decided <= lf)
    assert answers == {True, False}

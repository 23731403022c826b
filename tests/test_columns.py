"""The convex-polygon column kernels (crmgrasp._columns) against the scalar rules."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from crmgrasp import CRM, Config, Contact, Polygon, Rectangle, regular_polygon
from crmgrasp._columns import ConvexColumns, pair_checks
from crmgrasp._corners import _corner_boxes, _corner_candidates, _corner_proposal
from crmgrasp._scalar import LINE_TOL, contains, convex_edge, convex_entry, first_entry
from crmgrasp.batch import crm_arrays, execute_batch
from crmgrasp.hand import execute_crm, feasible
from crmgrasp.quality import min_friction, observe_mu_columns
from crmgrasp.sensing import Discretizer, Error, observe

from .strategies import use_backend

convex_objects = st.one_of(
    st.builds(Rectangle, st.floats(0.05, 0.4), st.floats(0.03, 0.2)),
    st.builds(regular_polygon, st.integers(3, 16), st.floats(0.03, 0.15), rotation=st.floats(0, 2 * math.pi)),
)


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


@settings(max_examples=60, deadline=None)
@given(convex_objects, st.integers(0, 2**32 - 1))
def test_column_entry_edge_and_contains_equal_the_scalar_rules(obj, seed):
    """Per row, the table (and, for over 12 edges, the argmax) path gives the scalar
    rule's edge; the specialised inside test the plain one."""
    rng = np.random.default_rng(seed)
    ox, oy, dx, dy, _ = _rays(obj, rng, 300)
    cc = obj._columns
    idx = cc.entry_edge(ox, oy, dx, dy)
    for r in range(len(ox)):
        i = convex_edge(float(ox[r]), float(oy[r]), float(dx[r]), float(dy[r]), obj.edges)
        assert idx[r] == (i if i >= 0 else cc.n)
    inside = cc.contains(ox, oy)
    assert inside.tolist() == [contains(x, y, obj.edges, True) for x, y in zip(ox.tolist(), oy.tolist())]


def test_lines_through_vertices_and_along_edges_enter_at_the_vertex():
    """A ray along a side (either way), through a corner, or missing it by less than
    LINE_TOL enters at the corner; one missing it by more does not enter. The
    batched path (scalar fallback rows) agrees."""
    box = Rectangle(0.30, 0.10)  # vertices (-0.15, -0.05), (0.15, -0.05), (0.15, 0.05), (-0.15, 0.05)
    cases = [
        ((0.3, -0.05), (-1.0, 0.0), (0.15, -0.05), (-1.0, 0.0)),  # along the bottom, leftward: right side
        ((-0.3, -0.05), (1.0, 0.0), (-0.15, -0.05), (1.0, 0.0)),  # along the bottom, rightward: left side
        ((-0.3, -0.05 - 0.1 * LINE_TOL), (1.0, 0.0), (-0.15, -0.05 - 0.1 * LINE_TOL), (1.0, 0.0)),
        ((-0.25, -0.15), (math.sqrt(0.5), math.sqrt(0.5)), (-0.15, -0.05), None),  # through the corner
    ]
    for o, d, point, normal in cases:
        e = box.ray_entry(o, d, 1.0)
        assert e is not None and e.point == pytest.approx(point, abs=1e-15)
        if normal is not None:
            assert e.normal == normal
    assert box.ray_entry((-0.3, -0.05 - 1e-9), (1.0, 0.0), 1.0) is None  # misses by 1 nm
    o = np.array([c[0] for c in cases] + [(-0.3, -0.05 - 1e-9)])
    d = np.array([c[1] for c in cases] + [(1.0, 0.0)])
    u, pts, _ = box.ray_entry_batch(o, d, np.ones(len(o)))
    for i in range(len(o)):
        e = box.ray_entry(tuple(o[i]), tuple(d[i]), 1.0)
        assert (u[i] == np.inf) if e is None else (tuple(pts[i]) == e.point)


def test_corner_seeking_crms_match_scalar_in_batch(task):
    """CRMs whose goal line runs exactly along a box side (as the grasp controller
    issues them) give the scalar outcome in the batched kernel, both backends."""
    a = Contact(-0.15, 0.023360090626670917, 1.0, 0.0)
    b = Contact(-0.13013644553857112, -0.05, -0.0, 1.0)
    cfg = Config(a, b)
    crms = [CRM("a", "a", 0.023360090626670917 + 0.05), CRM("b", "a", 0.0), CRM("b", "b", 0.02), CRM("a", "b", 0.0)]
    for backend in ("numpy", "numba"):
        with use_backend(backend):
            new, err = execute_batch(task.obj, task.hand, [cfg] * len(crms), *crm_arrays(crms))
        for i, crm in enumerate(crms):
            out = execute_crm(task.obj, task.hand, cfg, crm)
            assert int(err[i]) == int(out.error)
            assert tuple(new[i]) == tuple(np.asarray(out.config).ravel())


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2**32 - 1), st.booleans())
def test_observe_mu_columns_equals_scalar(seed, noisy):
    rng = np.random.default_rng(seed)
    obj = Rectangle(0.3, 0.1)
    s = rng.random((2, 50)) * obj.perimeter
    cfgs = [
        Config(*(Contact(*obj.boundary(float(v)).point, *obj.boundary(float(v)).normal) for v in col)) for col in s.T
    ]
    cfg = np.array([np.asarray(c).ravel() for c in cfgs]).T.copy()
    sen = cfg + rng.normal(0, 0.01, cfg.shape) if noisy else cfg
    with np.errstate(all="ignore"):
        rho, m_a, m_b, mu = observe_mu_columns(cfg, sen)
    for j, c in enumerate(cfgs):
        sc = Config(Contact(*sen[:4, j].tolist()), Contact(*sen[4:, j].tolist()))
        assert (rho[j], m_a[j], m_b[j]) == tuple(observe(sc))
        assert mu[j] == min_friction(c)


@pytest.mark.parametrize(
    "disc",
    [
        Discretizer(),
        Discretizer((0.5, 1.5), (0.02, 0.1, 0.2), ()),
        Discretizer((1.0,), tuple(np.linspace(-0.2, 0.2, 9)), (0.1,), abs_moments=False),
    ],
)
def test_index_columns_equals_index_of(disc):
    rng = np.random.default_rng(0)
    rho, m_a, m_b = rng.uniform(0, 4, 500), rng.normal(0, 0.15, 500), rng.normal(0, 0.15, 500)
    err = rng.integers(0, 3, 500).astype(np.int8)
    got = disc.index_columns(rho, m_a, m_b, err)
    assert got.dtype == np.int64
    assert got.tolist() == [disc.index_of(*map(float, v), int(e)) for *v, e in zip(rho, m_a, m_b, err)]


def test_pair_checks_equal_feasible_for_both_labelings(task):
    rng = np.random.default_rng(3)
    obj, hand = task.obj, task.hand
    s = rng.random((2, 400)) * obj.perimeter
    p1 = np.array([[*obj.boundary(float(v)).point, *obj.boundary(float(v)).normal] for v in s[0]]).T
    p2 = np.array([[*obj.boundary(float(v)).point, *obj.boundary(float(v)).normal] for v in s[1]]).T
    q = np.where(rng.random(400) < 0.5, 1.0, -1.0)
    with np.errstate(all="ignore"):
        dist, palm = pair_checks(obj.contains_xy, hand.palm_depth, hand.palm_normal_tol, p1, p2, q)
    for j in range(400):
        a, b = (p1[:, j], p2[:, j]) if q[j] > 0 else (p2[:, j], p1[:, j])
        want = feasible(obj, hand, Config(Contact(*a.tolist()), Contact(*b.tolist())))
        got = Error.APERTURE if dist[j] > hand.aperture else (Error.PALM if palm[j] else Error.NONE)
        assert got == want


def test_corner_filters_agree_across_backends(task):
    """The numpy and the compiled corner-start filters accept the same candidates."""
    rng = np.random.default_rng(5)
    cum, c_in, c_out = _corner_boxes(task.obj, task.hand.aperture)
    u = _corner_proposal(rng.random((4, 4000)), cum, c_in, c_out)
    with use_backend("numpy"):
        a = _corner_candidates(task.obj, task.hand, task.mu_goal, u)
    with use_backend("numba"):
        b = _corner_candidates(task.obj, task.hand, task.mu_goal, u)
    assert a.shape == b.shape and np.array_equal(a, b)


@pytest.mark.parametrize("n", [3, 4, 8, 9, 12, 13, 20])
def test_every_code_width_gives_the_scalar_edge(n):
    """Byte codes (up to 8 edges), 16-bit codes (up to 12) and the argmax path (beyond)."""
    poly = regular_polygon(n, 0.1, rotation=0.3)
    ox, oy, dx, dy, _ = _rays(poly, np.random.default_rng(n), 2000)
    idx = poly._columns.entry_edge(ox, oy, dx, dy)
    want = [convex_edge(*map(float, v), poly.edges) for v in zip(ox, oy, dx, dy)]
    assert idx.tolist() == [i if i >= 0 else n for i in want]
    assert 0.5 < np.mean(idx < n) < 0.99  # both entering and missing rays occur


def test_regular_polygon_with_many_edges_uses_the_argmax_path():
    poly = regular_polygon(20, 0.1)
    cc = ConvexColumns(poly.edges)
    assert cc.table is None and poly._columns.table is None
    assert len(ConvexColumns(regular_polygon(10, 0.1).edges).table) == 1 << 10


def test_tasks_stay_picklable_after_the_column_constants_are_built(task):
    import pickle

    with np.errstate(all="ignore"):
        task.obj.contains_xy(np.zeros(3), np.zeros(3))
    again = pickle.loads(pickle.dumps(task))
    assert again.obj == task.obj
    assert again.obj.contains_xy(np.array([0.0, 1.0]), np.array([0.0, 0.0])).tolist() == [True, False]

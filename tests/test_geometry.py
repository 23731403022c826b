import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from crmgrasp import CrmgraspError, Disc, Polygon, Rectangle, regular_polygon
from crmgrasp.model.geometry import EPS

from .strategies import objects

U_SHAPE = [(0, 0), (0.3, 0), (0.3, 0.2), (0.2, 0.2), (0.2, 0.05), (0.1, 0.05), (0.1, 0.2), (0, 0.2)]


def test_rectangle_vertices_and_normals():
    r = Rectangle(0.30, 0.10)
    assert r.vertices == ((-0.15, -0.05), (0.15, -0.05), (0.15, 0.05), (-0.15, 0.05))
    normals = [e[5:7] for e in r.edges]
    assert normals == [(-0.0, 1.0), (-1.0, 0.0), (-0.0, -1.0), (1.0, 0.0)]
    assert r.perimeter == pytest.approx(0.8)
    assert r.area == pytest.approx(0.03)


def test_clockwise_input_is_reoriented():
    cw = Polygon([(0, 0), (0, 1), (1, 1), (1, 0)])
    assert cw.area > 0
    assert cw.vertices[0] == (1.0, 0.0) or cw.vertices == ((1.0, 0.0), (1.0, 1.0), (0.0, 1.0), (0.0, 0.0))
    assert cw.project((0.5, -1)).normal == (0.0, 1.0) or cw.project((0.5, -1)).normal == (-0.0, 1.0)


@pytest.mark.parametrize(
    "verts, msg",
    [
        ([(0, 0), (1, 0)], "at least 3"),
        ([(0, 0), (1, 0), (2, 0)], "zero area"),
        ([(0, 0), (1, 0), (float("nan"), 1)], "finite"),
        ([(0, 0), (2, 2), (2, 0), (0, 1)], "not simple"),
        ([(0, 0), (1, 0), (1, 0), (0, 1)], "repeated vertex"),
        ([(0, 0), (1, 0), (1, 1, 1), (0, 1)], "2 coordinates"),
        ("abc", "vertex 0"),
        (5, "sequence"),
    ],
)
def test_bad_polygons_raise_one_line(verts, msg):
    with pytest.raises(CrmgraspError, match=msg) as info:
        Polygon(verts)
    assert "\n" not in str(info.value)


@pytest.mark.parametrize("bad", [0, -1, float("inf"), float("nan"), "x"])
def test_bad_disc_and_rectangle(bad):
    with pytest.raises(CrmgraspError):
        Disc(bad)
    with pytest.raises(CrmgraspError):
        Rectangle(bad, 0.1)


def test_regular_polygon_validation():
    assert len(regular_polygon(6, 0.1).vertices) == 6
    for n in (2, 3.5, True):
        with pytest.raises(CrmgraspError, match=r"n in \[3, 512\]"):
            regular_polygon(n, 0.1)


def test_strict_inside():
    r = Rectangle(0.3, 0.1)
    assert r.contains((0.0, 0.0))
    assert not r.contains((0.15, 0.0))  # on the boundary
    assert not r.contains((0.15 - EPS / 2, 0.0))  # within tolerance of it
    assert r.contains((0.15 - 10 * EPS, 0.0))
    assert not r.contains((-0.15, -0.05))  # vertex
    u = Polygon(U_SHAPE)
    assert not u.contains((0.15, 0.15))  # in the gap of the U
    assert u.contains((0.05, 0.15)) and u.contains((0.15, 0.02))
    d = Disc(0.05, (0.1, 0.0))
    assert d.contains((0.1, 0.0)) and not d.contains((0.15, 0.0)) and not d.contains((0.2, 0.0))


def test_project_and_vertex_error():
    r = Rectangle(0.3, 0.1)
    bp = r.project((-0.15, -0.02))
    assert bp.point == (-0.15, -0.02) and bp.normal == (1.0, 0.0)
    assert r.project((0.0, 0.0)).point == (0.0, -0.05)  # nearest of the two long sides (first edge wins ties)
    with pytest.raises(CrmgraspError, match="vertex"):
        r.project((-0.2, -0.1))
    with pytest.raises(CrmgraspError, match="centre"):
        Disc(0.05).project((0.0, 0.0))
    assert Disc(0.05).project((0.0, -1.0)).normal == pytest.approx((0.0, 1.0))


def test_ray_entry_polygon_first_entry_in_u():
    u = Polygon(U_SHAPE)
    # along y = 0.15 from the right going left: enters the right arm first at x = 0.3
    e = u.ray_entry((0.4, 0.15), (-1.0, 0.0), 1.0)
    assert e.point == pytest.approx((0.3, 0.15)) and e.normal == (-1.0, 0.0)
    # starting in the gap: enters the left arm's inner face at x = 0.1
    e = u.ray_entry((0.16, 0.15), (-1.0, 0.0), 1.0)
    assert e.point == pytest.approx((0.1, 0.15)) and e.normal == (-1.0, 0.0)
    # exits do not count; too short a segment finds nothing
    assert u.ray_entry((0.16, 0.15), (-1.0, 0.0), 0.05) is None
    assert u.ray_entry((0.0, 0.3), (1.0, 0.0), 1.0) is None


def test_ray_entry_disc():
    d = Disc(0.05)
    e = d.ray_entry((0.03, 0.2), (0.0, -1.0), 1.0)
    assert e.point == pytest.approx((0.03, 0.04)) and e.normal == pytest.approx((-0.6, -0.8))
    assert d.ray_entry((0.05, 0.2), (0.0, -1.0), 1.0) is None  # tangent: grazes
    assert d.ray_entry((0.0, 0.2), (0.0, 1.0), 1.0) is None  # moving away


@given(objects, st.floats(0, 1, exclude_max=True))
def test_boundary_points_are_on_boundary_with_unit_inward_normal(obj, frac):
    bp = obj.boundary(frac * obj.perimeter)
    assert obj.distance(bp.point) < 1e-12
    assert math.hypot(*bp.normal) == pytest.approx(1.0)
    step = 1e-6
    inner = (bp.point[0] + step * bp.normal[0], bp.point[1] + step * bp.normal[1])
    outer = (bp.point[0] - step * bp.normal[0], bp.point[1] - step * bp.normal[1])
    near_vertex = isinstance(obj, Polygon) and min(math.dist(bp.point, v) for v in obj.vertices) < 1e-4
    if not near_vertex:  # at a vertex (convex or reflex) either side may cross the adjacent edge
        assert obj.contains(inner) and not obj.contains(outer)


def _all_pairs_check(pts):
    """The simplicity check on every pair of edges (the definition the grid must match)."""
    from crmgrasp.model.polygon import _segments_cross

    n = len(pts)
    for i in range(n):
        if pts[i] == pts[(i + 1) % n]:
            return f"polygon has a repeated vertex {pts[i]} (zero-length edge {i})"
    for i in range(n):
        p, q, r = pts[i], pts[(i + 1) % n], pts[(i + 2) % n]
        ux, uy, wx, wy = q[0] - p[0], q[1] - p[1], r[0] - q[0], r[1] - q[1]
        if ux * wy - uy * wx == 0.0 and ux * wx + uy * wy < 0.0:
            return f"polygon is not simple: edges {i} and {(i + 1) % n} fold back"
        for j in range(i + 2, n):
            if not (i == 0 and j == n - 1) and _segments_cross(p, q, pts[j], pts[(j + 1) % n]):
                return f"polygon is not simple: edges {i} and {j} intersect"
    return None


@settings(max_examples=400, deadline=None)
@given(st.lists(st.tuples(st.integers(0, 6), st.integers(0, 6)), min_size=3, max_size=14))
def test_grid_simplicity_check_decides_as_all_pairs(raw):
    """Small integer grids give many touching, collinear and crossing edges."""
    from crmgrasp.model.polygon import _check_simple

    pts = [(float(x), float(y)) for x, y in raw]
    try:
        _check_simple(list(pts))
        got = None
    except CrmgraspError as exc:
        got = str(exc)
    assert got == _all_pairs_check(pts)


def test_a_moved_polygon_is_the_polygon_of_the_moved_vertices():
    """`Polygon.moved` skips the checks a rigid motion cannot break: the result equals the
    checked construction on the same vertices, and a motion beyond the bound is refused."""
    poly = Polygon([(0.0, 0.0), (0.3, 0.0), (0.3, 0.1), (0.1, 0.05), (0.0, 0.1)])
    moved = poly.moved(1.1, 0.02, -0.03)
    assert moved == Polygon(moved.vertices) and moved.convex is False
    assert moved.edges == Polygon(moved.vertices).edges
    for dx in (math.nan, math.inf, 2e6):
        with pytest.raises(CrmgraspError, match="not finite or beyond"):
            poly.moved(0.0, dx, 0.0)


def test_a_nan_vertex_is_refused_wherever_it_is():
    for i in range(4):
        pts = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
        pts[i] = (pts[i][0], math.nan)
        with pytest.raises(CrmgraspError, match="not finite"):
            Polygon(pts, _simple=True)

"""Closed triangle meshes in the spatial model: checks on construction, agreement with the
convex polyhedron they outline, a non-convex prism, and a task on a mesh."""

from __future__ import annotations

import numpy as np
import pytest

from crmgrasp import CrmgraspError
from crmgrasp.kernels import kernel_for
from crmgrasp.kernels.spatial import SpatialKernel
from crmgrasp.model.hand import Error
from crmgrasp.model.mesh import TriangleMesh
from crmgrasp.model.solids import Cylinder, box3d, surface_point
from crmgrasp.model.spatial import CRM3D, Config3D, Contact3D, Hand3D, execute_crm3d
from crmgrasp.tasks import SpatialTask, spatial_crms

HAND = Hand3D(aperture=0.16, palm_depth=0.12, backoff=0.01)


def _prism(outline: list[tuple[float, float]], height: float) -> TriangleMesh:
    """A prism over a simple counter-clockwise polygon (fan-triangulated caps: the outline
    must be star-shaped about its first corner)."""
    n = len(outline)
    v = [(x, y, 0.0) for x, y in outline] + [(x, y, height) for x, y in outline]
    faces = []
    for i in range(1, n - 1):
        faces.append((0, i + 1, i))  # bottom, seen from below: clockwise from above
        faces.append((n, n + i, n + i + 1))  # top
    for i in range(n):
        j = (i + 1) % n
        faces += [(i, j, n + j), (i, n + j, n + i)]
    return TriangleMesh(tuple(v), tuple(faces))


CUBE = _prism([(-0.15, -0.05), (0.15, -0.05), (0.15, 0.05), (-0.15, 0.05)], 0.10)
BOX = box3d((-0.15, -0.05, 0.0), (0.15, 0.05, 0.10))
L_SHAPE = _prism([(0.0, 0.0), (0.12, 0.0), (0.12, 0.04), (0.04, 0.04), (0.04, 0.12), (0.0, 0.12)], 0.05)


def test_a_box_mesh_gives_the_polyhedrons_outcomes() -> None:
    rng = np.random.default_rng(0)
    crms = spatial_crms()
    checked = 0
    for _ in range(150):
        cfg = Config3D(
            *(Contact3D(*(tuple(v.tolist()) for v in surface_point(BOX, rng.standard_normal(3)))) for _ in range(2))
        )
        for crm in crms:
            a = execute_crm3d(BOX, HAND, cfg, crm, table=0.0)
            b = execute_crm3d(CUBE, HAND, cfg, crm, table=0.0)
            assert a.error is b.error
            assert np.allclose(np.array(a.config.a.x + a.config.b.x), np.array(b.config.a.x + b.config.b.x), atol=1e-12)
            checked += a.error is Error.NONE
    assert checked > 100
    assert np.allclose(CUBE.centre, BOX.centre) and CUBE.support((0, 0, 1)) == 0.0


def test_the_inside_test_and_first_entry_on_a_non_convex_prism() -> None:
    assert L_SHAPE.contains((0.02, 0.1, 0.02)) and L_SHAPE.contains((0.1, 0.02, 0.02))
    assert not L_SHAPE.contains((0.08, 0.08, 0.02))  # in the notch
    assert not L_SHAPE.contains((0.0, 0.05, 0.02))  # on the surface
    hit = L_SHAPE.ray_entry((0.08, 0.2, 0.02), (0.0, -1.0, 0.0), 1.0)  # down through the notch onto the inner side
    assert hit is not None and np.allclose(hit[0], (0.08, 0.04, 0.02)) and np.allclose(hit[1], (0, -1, 0))
    assert L_SHAPE.ray_entry((0.2, 0.08, 0.02), (1.0, 0.0, 0.0), 1.0) is None
    assert L_SHAPE.gap((0.08, 0.04, 0.02)) == pytest.approx(0.0, abs=1e-12) and L_SHAPE.gap((0.02, 0.1, 0.02)) < 0


@pytest.mark.parametrize(
    ("build", "message"),
    [
        (lambda: TriangleMesh(CUBE.vertices, CUBE.faces[:-1]), "open"),
        (lambda: TriangleMesh(CUBE.vertices, (*CUBE.faces, CUBE.faces[0])), "used twice"),
        (lambda: TriangleMesh(CUBE.vertices, tuple((a, c, b) for a, b, c in CUBE.faces)), "point inward"),
        (lambda: TriangleMesh(CUBE.vertices, ((0, 0, 1), *CUBE.faces[1:])), "degenerate"),
        (lambda: TriangleMesh(CUBE.vertices, ((0, 1, 99), *CUBE.faces[1:])), "outside 0..7"),
        (lambda: TriangleMesh(((0.0, 0.0, float("nan")),) * 4, CUBE.faces), "finite"),
    ],
)
def test_bad_meshes_get_one_line_errors(build, message: str) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(CrmgraspError, match=message) as err:
        build()
    assert "\n" not in str(err.value)


def test_a_task_on_a_mesh_runs_compiled_and_equals_the_readable_rules() -> None:
    """A non-convex prism: the compiled kernel (the default) steps it as the readable rules
    do, bit for bit, and training is the same on both backends."""
    from crmgrasp.agents.training import train_trials
    from crmgrasp.kernels.spatial import FusedSpatialKernel
    from crmgrasp.sim import TaskSteps

    task = SpatialTask(name="l-prism", obj=L_SHAPE, hand=HAND, actions=spatial_crms())  # type: ignore[arg-type]
    assert type(kernel_for(task)) is FusedSpatialKernel and type(kernel_for(task, "numba")) is FusedSpatialKernel
    assert type(kernel_for(task, "reference")) is SpatialKernel
    fast, ref = FusedSpatialKernel(task), TaskSteps(task)
    seen = set()
    for w in range(30):
        r1, r2, acts = np.random.default_rng(w), np.random.default_rng(w), np.random.default_rng(w + 50)
        start = task.sample_start(r1)
        assert task.sample_start(r2, fast.start_filter) == start  # the same decisions from the same draws
        a, b = ref.begin(start, r1), fast.begin(start, r2)
        for _ in range(8):
            assert a == b
            act = int(acts.integers(len(task.actions)))
            a, b = ref.step_one(a.state, act, r1), fast.step_one(b.state, act, r2)
            seen.add(a.error)
    assert a == b and seen == {Error.NONE, Error.APERTURE, Error.PALM}
    kw = {"trials": 1, "episodes": 20, "seed": 0, "k": 1, "eval_episodes": 10}
    res = train_trials(task, "sarsa", **kw)
    assert res.steps.shape == (1, 20) and (res.steps >= 1).all()
    assert np.array_equal(res.steps, train_trials(task, "sarsa", backend="reference", **kw).steps)


def test_the_compiled_inside_test_and_entry_equal_the_meshs_own() -> None:
    """`_mesh_jit.contains` and `entry` against `TriangleMesh.contains` and `ray_entry` on
    random points and rays around the L prism and an open cup (the cavity, the opening,
    the wall), and on the surface itself."""
    from crmgrasp.kernels import _mesh_jit
    from crmgrasp.kernels.spatial import solid_params
    from crmgrasp.model.mesh import open_cup
    from crmgrasp.model.solids import SURFACE, TIE

    rng = np.random.default_rng(3)
    for mesh in (L_SHAPE, open_cup(0.04, 0.10, wall=0.005, segments=16)):
        tri, ray = solid_params(mesh, np.zeros(32), np.zeros(8, dtype=np.int64))
        lo, hi = np.min(mesh.corner_array, axis=0) - 0.02, np.max(mesh.corner_array, axis=0) + 0.02
        inside = entered = 0
        for _ in range(400):
            x = rng.uniform(lo, hi)
            if rng.random() < 0.2:  # a point on the surface: a corner's neighbourhood
                x = mesh.corner_array[rng.integers(len(mesh.vertices))] + rng.normal(0.0, 1e-9, 3)
            got = _mesh_jit.contains(tri, ray, *x, SURFACE)
            assert got == mesh.contains(x)
            inside += got
            d = rng.standard_normal(3)
            d /= np.linalg.norm(d)
            hit = mesh.ray_entry(x, d, 0.3)
            out = _mesh_jit.entry(x, d, 0.3, tri, SURFACE, TIE)
            assert out[0] == (hit is not None)
            if hit is not None:
                assert out[1:] == (*hit[0].tolist(), *hit[1].tolist())
                entered += 1
        assert inside > 20 and entered > 50


def test_an_open_cup_has_an_opening_and_an_inner_wall() -> None:
    from crmgrasp.model.mesh import open_cup

    cup = open_cup(0.04, 0.10, wall=0.005, segments=24)
    assert not cup.contains((0.0, 0.0, 0.05)) and cup.contains((0.0375, 0.0, 0.05))  # the cavity; the wall
    d = np.array([0.035, 0.0, -0.25]) / np.linalg.norm([0.035, 0.0, -0.25])
    point, normal = cup.ray_entry((0.0, 0.0, 0.30), d, 1.0)  # in through the opening: the inner wall
    assert point[2] == pytest.approx(0.05, abs=1e-3) and normal[0] > 0.99
    point, normal = cup.ray_entry((0.0, 0.0, 0.30), (0.0, 0.0, -1.0), 1.0)  # straight down: the inner bottom
    assert np.allclose(point, (0, 0, 0.005)) and np.allclose(normal, (0, 0, -1))
    for bad, message in (
        ((0.04, 0.1, 0.05), "thinner"),
        ((0.04, -0.1, 0.005), "height"),
        ((0.04, 0.1, 0.005, 3), "segments"),
    ):
        with pytest.raises(CrmgraspError, match=message):
            open_cup(*bad)


@pytest.mark.parametrize(
    ("build", "message"),
    [
        (lambda: Cylinder((0, 0, 0), (0, 0, 0), 0.05, 0.1), "axis"),
        (lambda: Cylinder((0, 0, 0), (0, 0, 1), 0.0, 0.1), "radius"),
        (lambda: Cylinder((0, 0, 0), (0, 0, 1), 0.05, -1.0), "height"),
        (lambda: box3d((0, 0, 0), (0.1, 0.0, 0.1)), "lo < hi"),
        (lambda: HAND.check_crm(CRM3D("a", "a", (0.2, 0.0))), "r_max"),
        (lambda: HAND.check_crm(CRM3D("a", "a", (float("nan"), 0.0))), "finite"),
    ],
)
def test_degenerate_solids_and_far_offsets_get_one_line_errors(build, message: str) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(CrmgraspError, match=message) as err:
        build()
    assert "\n" not in str(err.value)


def test_an_open_cups_convex_pieces_make_up_the_solid() -> None:
    """The union of the pieces' convex hulls is the cup: every point strictly inside the cup is in
    some hull, and every point in a hull is not outside the cup (random points, and points
    near the rim, the inner bottom and the cavity; a point within 1e-6 m of the surface is
    left out); posed, the cup keeps its pieces."""
    from scipy.spatial import Delaunay

    from crmgrasp.model.mesh import open_cup

    cup = open_cup(0.04, 0.10, wall=0.005, segments=12)
    corners = cup.corner_array
    hulls = [Delaunay(corners[list(p)]) for p in cup.pieces]
    rng = np.random.default_rng(2)
    points = np.vstack(
        [
            rng.uniform((-0.045, -0.045, -0.005), (0.045, 0.045, 0.105), (1200, 3)),
            rng.normal((0.0, 0.036, 0.004), 0.004, (400, 3)),
        ]
    )
    inside = 0
    for x in points:
        gap = cup.gap(x)
        if abs(gap) < 1e-6:
            continue
        in_hull = any(h.find_simplex(x) >= 0 for h in hulls)
        assert in_hull == (gap < 0), (x, gap)
        inside += gap < 0
    assert inside > 120
    moved = cup.moved(np.eye(3), (0.1, 0.0, 0.0))
    assert moved.pieces == cup.pieces and len(cup.pieces) == 13


def test_mesh_pieces_are_checked_and_written_to_task_files(tmp_path) -> None:
    from crmgrasp.model.mesh import open_cup
    from crmgrasp.tasks.files import load_task_file

    for pieces, message in (
        (((0, 1, 2),), "piece 0 must be 4 or more distinct"),
        (((0, 1, 2, 2),), "piece 0 must be 4 or more distinct"),
        (((0, 1, 2, 99),), "outside 0..7"),
        ("0123", "list of corner-index lists"),
    ):
        with pytest.raises(CrmgraspError, match=message):
            TriangleMesh(CUBE.vertices, CUBE.faces, pieces)  # type: ignore[arg-type]
    cube = TriangleMesh(CUBE.vertices, CUBE.faces, (tuple(range(8)),))
    text = "\n".join(
        [
            'name = "cube"',
            'model = "spatial"',
            "[hand]",
            "aperture = 0.16",
            "palm_depth = 0.12",
            "[[crm]]",
            'c = "a"',
            'f = "b"',
            "[solid]",
            f"mesh = {{ vertices = {[list(v) for v in cube.vertices]}, faces = {[list(f) for f in cube.faces]}, "
            f"pieces = {[list(p) for p in cube.pieces]} }}",
        ]
    )
    path = tmp_path / "cube.toml"
    path.write_text(text)
    task = load_task_file(path)
    assert task.obj == cube and task.obj.describe()["pieces"] == [list(range(8))]
    assert open_cup(0.04, 0.1).describe()["pieces"][0][:3] == [0, 1, 2]


def test_a_posed_open_cup_is_the_moved_one() -> None:
    """`open_cup(..., rotation, translation)` builds the mesh `open_cup(...).moved(...)` gives,
    corner for corner (the families pose their cups this way, building each once)."""
    from crmgrasp.model.mesh import open_cup
    from crmgrasp.model.solid_families import rotation_z

    for rot, t in (
        (rotation_z(0.7), (0.01, -0.02, 0.0)),
        (rotation_z(2.0) @ [[0, 0, 1], [0, 1, 0], [-1, 0, 0]], (0.0, 0.0, 0.05)),
    ):
        posed = open_cup(0.05, 0.12, 0.004, 16, rot, t)
        assert posed == open_cup(0.05, 0.12, 0.004, 16).moved(rot, t) and posed.pieces

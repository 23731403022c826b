"""Hypothesis strategies and helpers shared by the tests."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import assume
from hypothesis import strategies as st

from crmgrasp import CRM, Config, Contact, Disc, Hand, Polygon, Rectangle, regular_polygon


def on_boundary(obj, s: float) -> Contact:
    bp = obj.boundary(s)
    return Contact(*bp.point, *bp.normal)


@st.composite
def star_polygons(draw) -> Polygon:
    """Star-shaped (generally non-convex) simple polygons around the origin."""
    n = draw(st.integers(5, 10))
    radii = draw(st.lists(st.floats(0.03, 0.12), min_size=n, max_size=n))
    jitter = draw(st.lists(st.floats(-0.3, 0.3), min_size=n, max_size=n))
    angles = [2 * math.pi * (k + j) / n for k, j in enumerate(jitter)]
    return Polygon([(r * math.cos(a), r * math.sin(a)) for r, a in zip(radii, angles)])


objects = st.one_of(
    st.builds(Rectangle, st.floats(0.05, 0.4), st.floats(0.03, 0.2)),
    st.builds(regular_polygon, st.integers(3, 9), st.floats(0.03, 0.15), rotation=st.floats(0, 2 * math.pi)),
    st.builds(Disc, st.floats(0.02, 0.12), st.tuples(st.floats(-0.1, 0.1), st.floats(-0.1, 0.1))),
    star_polygons(),
)

hands = st.builds(Hand, st.floats(0.08, 0.4), st.floats(0.0, 0.2), st.floats(0.0, 0.02))


@st.composite
def scenes(draw):
    """(object, hand, config, crm) with contacts at random boundary points."""
    obj = draw(objects)
    hand = draw(hands)
    fa, fb = draw(st.floats(0, 1, exclude_max=True)), draw(st.floats(0, 1, exclude_max=True))
    cfg = Config(on_boundary(obj, fa * obj.perimeter), on_boundary(obj, fb * obj.perimeter))
    if isinstance(obj, Polygon):  # contacts are never placed on a vertex (docs/model.md section 1)
        assume(all(math.dist(c.point, v) > 1e-6 for c in cfg for v in obj.vertices))
    crm = CRM(draw(st.sampled_from("ab")), draw(st.sampled_from("ab")), draw(st.floats(-hand.aperture, hand.aperture)))
    return obj, hand, cfg, crm


def mirror_x(obj):
    """Reflect an object through the y axis (x -> -x)."""
    if isinstance(obj, Disc):
        return Disc(obj.radius, (-obj.center[0], obj.center[1]))
    return Polygon([(-x, y) for x, y in obj.vertices])


def mirror_contact(c: Contact) -> Contact:
    return Contact(-c.x, c.y, -c.nx, c.ny)


def mirror_swap(cfg: Config) -> Config:
    return Config(mirror_contact(cfg.b), mirror_contact(cfg.a))


def assert_close_config(c1: Config, c2: Config, tol: float = 1e-9) -> None:
    np.testing.assert_allclose(np.asarray(c1).ravel(), np.asarray(c2).ravel(), atol=tol, rtol=0)


BACKENDS = ["reference", "numba"]
"""The kernel backends every equality test runs on (:func:`crmgrasp.kernels.kernel_for`)."""

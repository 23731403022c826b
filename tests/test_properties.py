"""Property tests over random objects, hands, configurations and CRMs."""

import math

import numpy as np
import pytest
from hypothesis import assume, given
from hypothesis import strategies as st

from crmgrasp import CRM, Config, Contact, Disc, Error, force_closure, min_friction, observe
from crmgrasp.model.hand import feasible

from .strategies import assert_close_config, mirror_swap, mirror_x, scenes


def _normal_at(obj, contact):
    if isinstance(obj, Disc):
        vx, vy = obj.center[0] - contact.x, obj.center[1] - contact.y
        n = math.hypot(vx, vy)
        return (vx / n, vy / n)
    return obj.edges[obj.edge_index(contact.point)][5:7]


@given(scenes())
def test_crm_outcome_invariants(scene):
    obj, hand, cfg, crm = scene
    assume(feasible(obj, hand, cfg) is Error.NONE)
    out = hand.execute(obj, cfg, crm)
    if out.error is Error.NONE:
        for c in out.config:
            assert obj.distance(c.point) < 1e-9
            if isinstance(obj, Disc) or min(math.dist(c.point, v) for v in obj.vertices) > 1e-9:
                assert c.normal == pytest.approx(_normal_at(obj, c), abs=1e-9)
            else:  # landed on a vertex (e.g. opposite an edge midpoint of an odd polygon): an adjacent edge's normal
                assert any(c.normal == pytest.approx(e[5:7], abs=1e-9) for e in obj.edges)
        assert feasible(obj, hand, out.config) is Error.NONE
        assert out.config[crm.c if crm.c == "a" else "b"] is not None
        assert out.config["b" if crm.c == "a" else "a"] == cfg["b" if crm.c == "a" else "a"]
    else:
        assert out.config is cfg
    rho = observe(out.config).rho
    assert 0.0 <= rho <= 4.0 + 1e-12


@given(scenes())
def test_mirror_and_label_swap_commute_with_crm(scene):
    """Reflecting the world (x -> -x) flips handedness; swapping labels a <-> b puts the
    palm back on the right. CRM (c, f, r) then corresponds to (c', f', -r)."""
    obj, hand, cfg, crm = scene
    assume(feasible(obj, hand, cfg) is Error.NONE)
    out = hand.execute(obj, cfg, crm)
    swap = {"a": "b", "b": "a"}
    mobj, mcfg = mirror_x(obj), mirror_swap(cfg)
    assert feasible(mobj, hand, mcfg) is Error.NONE
    mout = hand.execute(mobj, mcfg, CRM(swap[crm.c], swap[crm.f], -crm.r))
    # skip razor-edge cases where rounding legitimately flips the outcome
    assume(_margin(obj, hand, cfg, crm) > 1e-7)
    assert mout.error == out.error
    assert_close_config(mout.config, mirror_swap(out.config), tol=1e-9)
    o, mo = observe(out.config), observe(mout.config)
    assert mo.rho == pytest.approx(o.rho, abs=1e-12)
    assert (mo.m_a, mo.m_b) == pytest.approx((-o.m_b, -o.m_a), abs=1e-12)


def _margin(obj, hand, cfg, crm):
    """Distance of a CRM from a decision boundary (perturb r; same outcome both ways?)."""
    base = hand.execute(obj, cfg, crm).error
    for dr in (-1e-7, 1e-7):
        r = max(-hand.aperture, min(hand.aperture, crm.r + dr))
        if hand.execute(obj, cfg, CRM(crm.c, crm.f, r)).error != base:
            return 0.0
    return 1.0


@given(
    st.tuples(st.floats(-1, 1), st.floats(-1, 1)),
    st.floats(0, 2 * math.pi),
    st.floats(1e-3, 1.0),
)
def test_min_friction_zero_for_antipodal(p, angle, length):
    n = (math.cos(angle), math.sin(angle))
    q = (p[0] + length * n[0], p[1] + length * n[1])
    cfg = Config(Contact(*p, *n), Contact(*q, -n[0], -n[1]))
    assert min_friction(cfg) == 0.0
    assert min_friction(cfg.swapped()) == 0.0


@given(
    st.lists(st.floats(-0.2, 0.2), min_size=4, max_size=4),
    st.floats(0, 2 * math.pi),
    st.floats(0, 2 * math.pi),
    st.floats(0.0, 2.0),
)
def test_min_friction_agrees_with_lp_force_closure(xs, ta, tb, mu):
    pa, pb = (xs[0], xs[1]), (xs[2], xs[3])
    assume(math.dist(pa, pb) > 1e-3)
    cfg = Config(Contact(*pa, math.cos(ta), math.sin(ta)), Contact(*pb, math.cos(tb), math.sin(tb)))
    m = min_friction(cfg)
    assume(abs(m - mu) > 1e-6 * (1.0 + mu))
    # the LP also accepts expanding (internal) grasps: the same test with normals flipped
    flipped = Config(cfg.a._replace(nx=-cfg.a.nx, ny=-cfg.a.ny), cfg.b._replace(nx=-cfg.b.nx, ny=-cfg.b.ny))
    m_expand = min_friction(flipped)
    assume(abs(m_expand - mu) > 1e-6 * (1.0 + mu))
    lp = force_closure([pa, pb], [cfg.a.normal, cfg.b.normal], mu)
    assert lp == (m < mu or m_expand < mu)


def test_three_contact_force_closure():
    # three contacts on an equilateral triangle's edges, normals to the centre: closure even without friction? no
    pts = [(math.cos(a), math.sin(a)) for a in (0, 2 * math.pi / 3, 4 * math.pi / 3)]
    normals = [(-x, -y) for x, y in pts]
    assert not force_closure(pts, normals, 0.0)  # concurrent frictionless normals cannot resist torque
    assert force_closure(pts, normals, 0.3)
    assert not np.isnan(min_friction(Config(Contact(0, 0, 1, 0), Contact(1, 0, -1, 0))))

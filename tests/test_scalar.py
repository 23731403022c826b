"""The fused plain-Python step equals the scalar CRM path bit for bit."""

from __future__ import annotations

from collections import Counter

import numpy as np
from hypothesis import given, settings

from crmgrasp import Config, Polygon
from crmgrasp._scalar import crm_step, observe_mu
from crmgrasp.hand import execute_crm
from crmgrasp.quality import min_friction
from crmgrasp.sensing import observe

from .strategies import on_boundary, scenes


def _fused(obj, hand, cfg, crm):
    args = (obj.edges, obj.convex, hand.aperture, hand.palm_depth, hand.palm_normal_tol)
    return crm_step((*cfg.a, *cfg.b), crm.ci == 1, crm.fi == 1, crm.r, *args)


@settings(max_examples=400, deadline=None)
@given(scenes())
def test_fused_step_equals_execute_crm(scene):
    obj, hand, cfg, crm = scene
    if not isinstance(obj, Polygon):
        return
    code, v = _fused(obj, hand, cfg, crm)
    out = execute_crm(obj, hand, cfg, crm)
    assert code == int(out.error)
    assert v == (*out.config.a, *out.config.b)
    assert observe_mu(v) == (*observe(out.config), min_friction(out.config))


def test_fused_step_sees_every_outcome_on_convex_and_non_convex_objects(task):
    """Random CRMs from random boundary pairs on the box and a U: all three error
    codes occur on each and every result equals the scalar path exactly."""
    u_shape = Polygon([(0, 0), (0.3, 0), (0.3, 0.2), (0.2, 0.2), (0.2, 0.08), (0.1, 0.08), (0.1, 0.2), (0, 0.2)])
    rng = np.random.default_rng(0)
    for obj in (task.obj, u_shape):
        codes: Counter[int] = Counter()
        for _ in range(3000):
            s = rng.random(2) * obj.perimeter
            cfg = Config(on_boundary(obj, s[0]), on_boundary(obj, s[1]))
            crm = task.actions[int(rng.integers(4))]
            code, v = _fused(obj, task.hand, cfg, crm)
            out = execute_crm(obj, task.hand, cfg, crm)
            assert (code, v) == (int(out.error), (*out.config.a, *out.config.b))
            assert observe_mu(v) == (*observe(out.config), min_friction(out.config))
            codes[code] += 1
        assert set(codes) == {0, 1, 2}, codes

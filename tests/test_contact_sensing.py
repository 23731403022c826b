"""Intrinsic contact sensing, the high-pass filter and the contact detector."""

import math

import numpy as np
import pytest

from crmgrasp import CrmgraspError
from crmgrasp.hardware.contact_sensing import (
    Circle,
    ContactDetector,
    Flat,
    HighPass,
    NoContact,
    SensedContact,
    Sphere,
    contact_from_wrench,
)


def _planar_wrench(point, force):
    return force, point[0] * force[1] - point[1] * force[0]


@pytest.mark.parametrize("angle_deg", [-90.0, -60.0, -20.0, 0.0, 35.0, 160.0])
@pytest.mark.parametrize("tilt_deg", [0.0, 15.0, -25.0])  # friction: force off the normal
def test_circle_tip_recovers_contact(angle_deg, tilt_deg):
    tip = Circle(0.012, (0.003, -0.002))
    a = math.radians(angle_deg)
    out = (math.cos(a), math.sin(a))
    point = (tip.center[0] + tip.radius * out[0], tip.center[1] + tip.radius * out[1])
    t = math.radians(tilt_deg)  # force pushes into the tip, tilted by t from the inward normal
    fin = (-out[0], -out[1])
    force = (3.0 * (math.cos(t) * fin[0] - math.sin(t) * fin[1]), 3.0 * (math.sin(t) * fin[0] + math.cos(t) * fin[1]))
    res = contact_from_wrench(tip, *_planar_wrench(point, force))
    assert isinstance(res, SensedContact)
    assert res.point == pytest.approx(point, abs=1e-12)
    assert res.normal == pytest.approx(out, abs=1e-9)
    assert res.force == pytest.approx(3.0)


def test_flat_pad_and_sphere():
    pad = Flat((0.0, -1.0), offset=0.01)  # pad surface y = -0.01, facing down
    res = contact_from_wrench(pad, *_planar_wrench((0.004, -0.01), (0.5, 2.0)))
    assert res.point == pytest.approx((0.004, -0.01)) and res.normal == pytest.approx((0.0, -1.0))
    assert isinstance(contact_from_wrench(pad, (0.0, -2.0), 0.0), NoContact)  # pulling, not pushing
    tip = Sphere(0.01, (0.0, 0.0, 0.02))
    p = np.array([0.0, 0.006, 0.02 - 0.008])  # on the sphere
    f = -2.0 * (p - np.array(tip.center)) / 0.01 + np.array([0.3, 0.0, 0.0])
    res = contact_from_wrench(tip, f, np.cross(p, f))
    assert res.point == pytest.approx(tuple(p), abs=1e-12)
    assert res.normal == pytest.approx(tuple((p - np.array(tip.center)) / 0.01), abs=1e-9)


def test_noisy_readings_degrade_gracefully():
    rng = np.random.default_rng(0)
    tip = Circle(0.01)
    errs = []
    for _ in range(500):
        a = rng.uniform(-math.pi, math.pi)
        p = (0.01 * math.cos(a), 0.01 * math.sin(a))
        f = (-2.0 * math.cos(a), -2.0 * math.sin(a))
        fn, m = _planar_wrench(p, f)
        res = contact_from_wrench(tip, np.add(fn, rng.normal(0, 0.02, 2)), m + rng.normal(0, 2e-5))
        errs.append(math.dist(res.point, p))
    assert np.median(errs) < 1e-3  # 1% force noise, 20 uN m torque noise: sub-millimetre


def test_threshold_and_bad_input():
    assert isinstance(contact_from_wrench(Circle(0.01), (0.01, 0.0), 0.0), NoContact)
    with pytest.raises(CrmgraspError, match="finite"):
        contact_from_wrench(Circle(0.01), (np.nan, 1.0), 0.0)
    with pytest.raises(CrmgraspError, match="planar fingertip"):
        contact_from_wrench(Circle(0.01), (0.0, 1.0, 0.0), 0.0)
    with pytest.raises(CrmgraspError, match="radius must be > 0"):
        Circle(0.0)
    for threshold in (0.0, -1.0, float("nan"), float("inf")):  # NaN took every reading for a contact
        with pytest.raises(CrmgraspError, match=r"contact threshold \(N\) must be"):
            contact_from_wrench(Circle(0.01), (0.0, 1.0), 0.0, threshold)


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda: contact_from_wrench(None, (0.0, 1.0), 0.0), "fingertip must be a Circle, Flat or Sphere"),
        (lambda: contact_from_wrench(Circle(0.01), "x", 0.0), "force reading must be numbers"),
        (lambda: contact_from_wrench(Circle(0.01), (0.0, 2.0), 1e308), "torque reading must be at most 1e"),
        (lambda: contact_from_wrench(Sphere(0.01), (0, 0, 1), {"a": 1}), "torque reading must be numbers"),
        (lambda: Sphere(0.01, center="xyz"), "sphere center"),
        (lambda: HighPass(0.5, 0.01)("x"), "filter sample must be numbers"),
        (lambda: ContactDetector(0.5, 0.01, on=None), r"onset threshold on \(N\) must be a number"),
        (lambda: ContactDetector(0.5, 0.01)(2.0), "force sample must be a vector"),
        (lambda: ContactDetector(0.5, 0.01)(np.inf), "force sample must be finite"),
    ],
)
def test_sensing_input_is_checked_in_one_line(call, message):
    """A fingertip, a wrench, a filter sample or a threshold that is not what it must be:
    one line naming it (before, numpy's and Python's own errors, and an overflow warning)."""
    with pytest.raises(CrmgraspError, match=message):
        call()


def test_high_pass_keeps_its_channels():
    """A sample with another number of channels than the first is refused, not broadcast."""
    hp = HighPass(0.5, 0.01)
    hp((0.0, 1.0))
    with pytest.raises(CrmgraspError, match=r"shape \(3,\); the earlier samples had \(2,\)"):
        hp((0.0, 1.0, 2.0))
    assert hp((0.0, 1.0)).shape == (2,)


def test_high_pass_removes_drift_and_passes_steps():
    dt, tau = 0.001, 0.05
    hp = HighPass(tau, dt)
    t = np.arange(0, 2.0, dt)
    signal = 5.0 + 0.5 * t + np.where(t >= 1.0, 2.0, 0.0)  # offset + drift 0.5 N/s + a 2 N step at 1 s
    out = np.array([hp(x) for x in signal])
    before = out[(t > 0.5) & (t < 0.999)]
    assert np.all(np.abs(before - 0.5 * tau) < 0.01)  # drift leaves ~ slope * tau, offset gone
    assert out[int(1.0 / dt)] > 1.9  # the step passes
    assert abs(out[-1] - 0.5 * tau) < 0.01  # and decays


def test_contact_detector_fires_once_per_onset():
    dt, tau = 0.001, 0.05
    det = ContactDetector(tau, dt, on=0.5, off=0.1)
    t = np.arange(0, 3.0, dt)
    force = np.stack([np.zeros_like(t), 0.3 * t + np.where((t >= 1.0) & (t < 2.0), 2.0, 0.0)], axis=1)
    fired = [i for i, f in enumerate(force) if det(f)]
    assert [round(i * dt, 2) for i in fired] == [1.0]  # the onset; not the drift, not the release

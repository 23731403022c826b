import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from crmgrasp import Config, Contact, CrmgraspError, Discretizer, Error, Observation, SensorNoise, observe

CFG = Config(Contact(-0.15, -0.02, 1.0, 0.0), Contact(-0.10, -0.05, 0.0, 1.0))


def test_paper_bins_roundtrip_all_24():
    d = Discretizer()
    assert d.size == 24
    seen = set()
    for rho in (0.5, 2.0):
        for ma in (0.05, -0.2):
            for mb in (-0.01, 0.3):
                for err in Error:
                    i = d.index(Observation(rho, ma, mb), err)
                    seen.add(i)
                    assert d.decode(i) == ((int(rho >= 1), int(abs(ma) >= 0.1), int(abs(mb) >= 0.1)), err)
    assert seen == set(range(24))
    assert d.label(0) == "rho<1 |m_a|<0.1 |m_b|<0.1 error=none"
    assert d.label(23) == "rho>=1 |m_a|>=0.1 |m_b|>=0.1 error=palm"


def test_threshold_is_inclusive():
    d = Discretizer()
    assert d.bins(Observation(1.0, 0.10, -0.10)) == (1, 1, 1)


def test_custom_bins():
    d = Discretizer(rho=(0.5, 1.5, 3.0), m_a=(), m_b=(-0.05, 0.05), abs_moments=False)
    assert d.size == 4 * 1 * 3 * 3
    obs = np.array([[0.1, 0.3, -0.1], [2.0, -0.3, 0.0], [3.5, 0.0, 0.06]])
    err = np.array([0, 1, 2])
    expect = [d.index(Observation(*o), e) for o, e in zip(obs, err)]
    assert expect == [(0 * 3 + 0) * 3 + 0, (2 * 3 + 1) * 3 + 1, (3 * 3 + 2) * 3 + 2]
    assert "m_a:any" in d.label(expect[0])
    assert "-0.05<=m_b<0.05" in d.label(expect[1])


@pytest.mark.parametrize(
    "kwargs, msg",
    [
        ({"rho": (2.0, 1.0)}, "increasing"),
        ({"m_a": ("x",)}, "number"),
        ({"m_b": (math.nan,)}, "finite"),
        (  # 1,001 bins each: once refused only by the history encoder, naming n_obs
            {q: tuple(range(1, 1001)) for q in ("rho", "m_a", "m_b")},
            r"3,009,009,003 discrete observations \(1001 x 1001 x 1001 bins x 3 error flags\); a history takes",
        ),
    ],
)
def test_bad_discretizer(kwargs, msg):
    with pytest.raises(CrmgraspError, match=msg):
        Discretizer(**kwargs)


def test_decode_out_of_range():
    with pytest.raises(CrmgraspError, match="outside"):
        Discretizer().decode(24)


@given(st.integers(0, 2**32 - 1))
def test_noise_is_deterministic_and_preserves_unit_normals(seed):
    noise = SensorNoise(math.radians(3), 0.002)
    s1 = noise.sense(CFG, np.random.default_rng(seed))
    s2 = noise.sense(CFG, np.random.default_rng(seed))
    assert s1 == s2
    for c in s1:
        assert math.hypot(c.nx, c.ny) == pytest.approx(1.0, abs=1e-15)
    assert 0.0 <= observe(s1).rho <= 4.0


def test_noise_statistics():
    noise = SensorNoise(0.1, 0.01)
    rng = np.random.default_rng(0)
    readings = [noise.sense(CFG, rng) for _ in range(4000)]
    ang = np.array([math.atan2(r.a.ny, r.a.nx) for r in readings])
    dx = np.array([r.a.x - CFG.a.x for r in readings])
    assert np.std(ang) == pytest.approx(0.1, rel=0.05)
    assert np.std(dx) == pytest.approx(0.01, rel=0.05)
    assert SensorNoise().sense(CFG, rng) is CFG


def test_bad_noise():
    with pytest.raises(CrmgraspError, match="sigma_n must be >= 0"):
        SensorNoise(-1.0, 0.0)

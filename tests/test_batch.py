"""The vectorised CRM path agrees with the scalar path bit for bit."""

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from crmgrasp import CrmgraspError, SensorNoise
from crmgrasp.batch import crm_arrays, execute_batch, feasible_batch
from crmgrasp.contacts import array_to_configs, configs_to_array
from crmgrasp.hand import execute_crm, feasible
from crmgrasp.quality import min_friction, min_friction_batch
from crmgrasp.sensing import observe, observe_batch

from .strategies import BACKENDS, scenes, use_backend


@pytest.mark.parametrize("backend", BACKENDS)
@given(st.lists(scenes(), min_size=1, max_size=1), st.integers(2, 12), st.booleans(), st.integers(0, 2**32 - 1))
def test_batch_matches_scalar(backend, first, n, noisy, seed):
    with use_backend(backend):
        _check_batch_matches_scalar(first, n, noisy, seed)


def _check_batch_matches_scalar(first, n, noisy, seed):
    obj, hand, cfg0, _ = first[0]
    rng = np.random.default_rng(seed)
    # n random configurations on the same object, random CRMs
    configs, crms = [cfg0], []
    for _ in range(n - 1):
        s = rng.random(2) * obj.perimeter
        pa, pb = obj.boundary(float(s[0])), obj.boundary(float(s[1]))
        configs.append(type(cfg0)(type(cfg0.a)(*pa.point, *pa.normal), type(cfg0.a)(*pb.point, *pb.normal)))
    from crmgrasp import CRM

    for _ in range(n):
        crms.append(
            CRM("ab"[rng.integers(2)], "ab"[rng.integers(2)], float(rng.uniform(-hand.aperture, hand.aperture)))
        )
    noise = SensorNoise(math.radians(5), 0.003) if noisy else SensorNoise()
    sensed = [noise.sense(c, np.random.default_rng(seed + i)) for i, c in enumerate(configs)]
    arr, sarr = configs_to_array(configs), configs_to_array(sensed)
    new, err = execute_batch(obj, hand, arr, *crm_arrays(crms), sensed=sarr)
    for i, (cfg, crm) in enumerate(zip(configs, crms)):
        out = execute_crm(obj, hand, cfg, crm, sensed[i])
        assert int(err[i]) == int(out.error)
        assert tuple(new[i]) == tuple(np.asarray(out.config).ravel())
    assert feasible_batch(obj, hand, arr).tolist() == [int(feasible(obj, hand, c)) for c in configs]
    assert observe_batch(arr).tolist() == [list(observe(c)) for c in configs]
    assert min_friction_batch(arr).tolist() == [min_friction(c) for c in configs]


def test_batch_noise_stream_equals_scalar_stream(task):
    noise = SensorNoise(0.05, 0.002)
    cfgs = [task.sample_start(np.random.default_rng(i)) for i in range(5)]
    batch = noise.sense_batch(configs_to_array(cfgs), np.random.default_rng(9))
    rng = np.random.default_rng(9)
    scalar = configs_to_array([noise.sense(c, rng) for c in cfgs])
    np.testing.assert_array_equal(batch, scalar)
    assert array_to_configs(batch)[0] == noise.sense(cfgs[0], np.random.default_rng(9))


@pytest.mark.parametrize("backend", BACKENDS)
def test_batch_worked_cases(task, backend):
    with use_backend(backend):
        _worked(task)


def _worked(task):
    near = task.hand.contact(task.obj, a=(-0.15, -0.02), b=(-0.10, -0.05))
    far = task.hand.contact(task.obj, a=(-0.15, -0.02), b=(0.00, -0.05))
    cfgs = configs_to_array([near, near, far, far])
    new, err = execute_batch(task.obj, task.hand, cfgs, *crm_arrays([task.actions[i] for i in (0, 1, 0, 3)]))
    assert err.tolist() == [0, 1, 2, 0]
    assert new[0, :4].tolist() == [-0.10, 0.05, 0.0, -1.0]
    assert new[3, 4:6].tolist() == [-0.08, -0.05]


def test_batch_input_errors(task):
    arr = configs_to_array([task.sample_start(np.random.default_rng(0))])
    with pytest.raises(CrmgraspError, match=r"shape \(N, 8\)"):
        execute_batch(task.obj, task.hand, arr[:, :6], 0, 1, 0.0)
    with pytest.raises(CrmgraspError, match="0 \\(a\\) or 1 \\(b\\)"):
        execute_batch(task.obj, task.hand, arr, 2, 1, 0.0)
    with pytest.raises(CrmgraspError, match="r_max"):
        execute_batch(task.obj, task.hand, arr, 0, 1, 1.0)
    with pytest.raises(CrmgraspError, match="finite"):
        execute_batch(task.obj, task.hand, arr * np.nan, 0, 1, 0.0)


def _odd_task():
    """A hexagon, other bins (more than three thresholds, signed moments) and CRMs."""
    from crmgrasp import CRM, Discretizer, Hand, Task, regular_polygon

    disc = Discretizer((0.5, 1.0, 2.0, 3.0), tuple(np.linspace(-0.1, 0.1, 5)), (), abs_moments=False)
    crms = (CRM("a", "b", 0.0), CRM("b", "a", 0.01), CRM("a", "a", 0.05), CRM("b", "b", -0.05))
    return Task("hexagon", regular_polygon(6, 0.08), Hand(0.2, 0.05), crms, discretizer=disc)


@pytest.mark.parametrize("which", ["paper-box", "hexagon", "noisy"])
def test_backends_agree_on_vector_env_and_starts(which):
    """Results do not depend on whether the optional compiled kernel is installed
    (the noise-free polygon step runs as one compiled pass)."""
    from dataclasses import replace

    from crmgrasp import make_task
    from crmgrasp.vector import CRMGraspVectorEnv

    task = _odd_task() if which == "hexagon" else make_task("paper-box")
    if which == "noisy":
        task = replace(task, noise=SensorNoise(0.05, 0.002))

    def run():
        env = CRMGraspVectorEnv(256, task)
        out = [env.reset(seed=9)[1]["config"]]
        rng = np.random.default_rng(9)
        for _ in range(20):
            obs, rew, term, trunc, info = env.step(rng.integers(4, size=256))
            out += [*obs.values(), rew, term, trunc, *info.values()]
        return out

    with use_backend("numpy"):
        a = run()
    with use_backend("numba"):
        b = run()
    for x, y in zip(a, b):
        assert x.dtype == y.dtype and x.shape == y.shape
        np.testing.assert_array_equal(x, y)

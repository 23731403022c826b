"""The MuJoCo stand-in with three fingertips (needs the extra ``crmgrasp[mujoco]``; skipped without it)."""

import numpy as np
import pytest

pytest.importorskip("mujoco", reason="MuJoCo stand-in tests need the extra: pip install 'crmgrasp[mujoco]'")

from crmgrasp import make_task
from crmgrasp.hardware.conformance import CHECKS, check_hand
from crmgrasp.hardware.mujoco import hardware_task
from crmgrasp.hardware.mujoco.model import mjcf
from crmgrasp.hardware.mujoco.spatial import mujoco_hand
from crmgrasp.hardware.mujoco.steps import MujocoSteps
from crmgrasp.model.contacts import Grip
from crmgrasp.model.hand import Error
from crmgrasp.sim import run_episode


@pytest.fixture(scope="module")
def world():
    base = make_task("triangles-3f")
    return base.sample_world(np.random.default_rng(0))


def test_the_scene_has_one_fingertip_per_contact(world):
    text = mjcf(world.task, labels=("a", "b", "c"))
    assert all(f'name="tip_{x}"' in text and f'name="force_{x}"' in text for x in "abc")
    assert 'name="tip_d"' not in text and 'name="tip_c"' not in mjcf(world.task)


def test_three_fingertips_sense_their_contacts(world):
    task = hardware_task(world.task)
    hand = mujoco_hand(task, world.config, np.random.default_rng(1))
    sensed, true = hand.sense(), hand.true_config()
    assert isinstance(sensed, Grip) and isinstance(true, Grip) and len(sensed) == 3
    for s, t, start in zip(sensed, true, world.config):
        assert np.hypot(s.x - t.x, s.y - t.y) < 1e-3 and np.hypot(s.x - start.x, s.y - start.y) < 3e-3
        assert s.nx * t.nx + s.ny * t.ny > np.cos(np.radians(2.0))
    assert set(hand.raw_reading()) == {"a", "b", "c"}


def test_a_three_finger_crm_runs_and_keeps_contact(world):
    task = hardware_task(world.task)
    hand = mujoco_hand(task, world.config, np.random.default_rng(2))
    hand.sense()
    error = hand.execute(task.actions[0])
    assert isinstance(error, Error)
    after = hand.sense()
    assert isinstance(after, Grip) and hand.true_config() is not None


def test_the_three_fingertip_hand_conforms():
    task = hardware_task(make_task("triangles-3f"))
    assert check_hand(mujoco_hand, task, worlds=1) == list(CHECKS)


def test_learning_steps_run_on_three_fingertips():
    task = make_task("triangles-3f")
    steps = MujocoSteps(task)

    class First:
        def begin(self, first):
            pass

        def act(self):
            return 2

        def tell(self, percept):
            pass

    episode = run_episode(task, First(), np.random.default_rng(4), kernel=steps, trace=True)
    assert 1 <= episode.steps <= task.max_steps and steps.episodes == 1
    assert episode.success == bool(episode.trace[-1].after.min_friction <= task.mu_goal)


# ---------------------------------------------------------------- the tripod in 3-D
@pytest.fixture(scope="module")
def tripod_world():
    return make_task("cup-3d-3f").sample_world(np.random.default_rng(3))


def test_the_spatial_scene_has_one_fingertip_per_contact(tripod_world):
    from crmgrasp.hardware.mujoco.spatial import spatial_mjcf

    text = spatial_mjcf(tripod_world.task)
    assert all(f'name="tip_{x}"' in text and f'name="torque_{x}"' in text for x in "abc")
    assert 'name="tip_c"' not in spatial_mjcf(make_task("cup-3d").sample_world(np.random.default_rng(0)).task)


def test_three_fingertips_sense_their_contacts_in_space(tripod_world):
    from crmgrasp.model.spatial import Grip3D

    task = hardware_task(tripod_world.task, 10.0)
    hand = mujoco_hand(task, tripod_world.config, np.random.default_rng(1))
    sensed, true = hand.sense(), hand.true_config()
    assert isinstance(sensed, Grip3D) and isinstance(true, Grip3D) and len(sensed) == 3
    for s, t in zip(sensed, true):
        assert np.linalg.norm(np.subtract(s.x, t.x)) < 1e-3 and np.dot(s.n, t.n) > np.cos(np.radians(2.0))
    assert set(hand.raw_reading()) == {"a", "b", "c"}
    error = hand.execute(task.actions[0])  # oppose a onto b: its chord within the aperture of b and c
    assert isinstance(error, Error) and isinstance(hand.sense(), Grip3D) and hand.true_config() is not None


def test_the_tripod_hand_conforms():
    task = hardware_task(make_task("cup-3d-3f"), 10.0)
    assert check_hand(mujoco_hand, task, worlds=1) == list(CHECKS)

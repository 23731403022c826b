"""The MuJoCo stand-in's parts that need no MuJoCo: parameters, MJCF text, errors."""

import math
import sys
import xml.etree.ElementTree as ET

import pytest

from crmgrasp import make_task
from crmgrasp._validation import CrmgraspError
from crmgrasp.hardware.mujoco import hardware_task, mujoco_available, require_mujoco
from crmgrasp.hardware.mujoco.model import PhysicsParams, mjcf
from crmgrasp.model.disc import Disc
from crmgrasp.model.geometry import Polygon


def test_require_mujoco_names_the_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "mujoco", None)  # makes `import mujoco` fail
    assert not mujoco_available()
    with pytest.raises(CrmgraspError, match=r"crmgrasp\[mujoco\]") as err:
        require_mujoco()
    assert "\n" not in str(err.value)


def test_hardware_task_sets_the_fingertip_tolerance():
    task = hardware_task(make_task("paper-box"), 10.0, mu_goal=0.15)
    assert task.hand.palm_normal_tol == pytest.approx(math.sin(math.radians(10.0)))
    assert task.mu_goal == 0.15 and task.actions == make_task("paper-box").actions


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"kp": 0.0}, "kp must be > 0"),
        ({"force_noise": -1.0}, "force_noise must be >= 0"),
        ({"timestep": float("nan")}, "timestep must be finite"),
        ({"control_steps": 0}, "control_steps must be an integer >= 1"),
        ({"contact_off": 0.5, "contact_on": 0.3}, "contact_off must be <= contact_on"),
    ],
)
def test_physics_params_validate(kwargs, match):
    with pytest.raises(CrmgraspError, match=match):
        PhysicsParams(**kwargs)


def test_mjcf_is_well_formed_with_both_fingertip_sensors():
    root = ET.fromstring(mjcf(make_task("paper-box")))
    sensors = {(s.tag, s.get("site")) for s in root.find("sensor")}
    assert sensors == {("force", "tip_a"), ("torque", "tip_a"), ("force", "tip_b"), ("torque", "tip_b")}
    assert len(root.find("actuator")) == 6
    mesh = root.find("asset/mesh")
    assert len(mesh.get("vertex").split()) == 4 * 2 * 3  # 4 corners, top and bottom


def test_mjcf_object_kinds():
    import dataclasses

    base = make_task("paper-box")
    disc = dataclasses.replace(base, obj=Disc(0.05))
    assert 'type="cylinder"' in mjcf(disc)
    concave = Polygon([(0, 0), (0.2, 0), (0.2, 0.2), (0.1, 0.05), (0, 0.2)])
    with pytest.raises(CrmgraspError, match="convex"):
        mjcf(dataclasses.replace(base, obj=concave))

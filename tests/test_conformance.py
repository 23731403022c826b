"""The hand conformance test: the kinematic and MuJoCo hands pass it; broken hands fail it, named."""

import pytest

from crmgrasp import make_task
from crmgrasp._validation import CrmgraspError
from crmgrasp.hardware.conformance import CHECKS, check_hand
from crmgrasp.hardware.runner import KinematicHand
from crmgrasp.model.hand import Error


@pytest.mark.parametrize("name", ["paper-box", "box-family", "box-3d", "triangles-3f"])
def test_the_kinematic_hand_conforms(name):
    assert check_hand(KinematicHand, make_task(name)) == [c for c in CHECKS]


@pytest.mark.parametrize("name", ["paper-box", "cup-3d"])
def test_the_mujoco_hands_conform(name):
    pytest.importorskip("mujoco", reason="needs the extra crmgrasp[mujoco]")
    from crmgrasp.hardware.mujoco import hardware_task
    from crmgrasp.hardware.mujoco.spatial import mujoco_hand

    assert check_hand(mujoco_hand, hardware_task(make_task(name)), worlds=1) == list(CHECKS)


class _Broken(KinematicHand):
    def __init__(self, task, start, rng, fault):
        super().__init__(task, start, rng)
        self.fault = fault

    def sense(self):
        reading = super().sense()
        return "a reading" if self.fault == "sense" else reading

    def execute(self, crm):
        if self.fault == "refuse":  # executes whatever it is given, unchecked
            return Error.NONE
        error = super().execute(crm)
        return int(error) if self.fault == "execute" else error


@pytest.mark.parametrize("fault", ["sense", "execute", "refuse"])
def test_a_broken_hand_fails_the_named_check(fault):
    def make(task, start, rng):
        return _Broken(task, start, rng, fault)

    with pytest.raises(CrmgraspError, match=f"^hand conformance: {fault}: ") as info:
        check_hand(make, make_task("paper-box"), worlds=1)
    assert "\n" not in str(info.value)

"""A hand's answers are checked where the runner receives them: a malformed one is a one-line
error naming the method, and no step log is written."""

import csv
import json
import math

import numpy as np
import pytest

from crmgrasp import make_task
from crmgrasp._validation import CrmgraspError
from crmgrasp.agents.policy import GreedyPolicy
from crmgrasp.hardware.answers import checked_pose, checked_reading, checked_time
from crmgrasp.hardware.contact_sensing import NoContact
from crmgrasp.hardware.runner import KinematicHand, PolicyRunner
from crmgrasp.model.contacts import Config, Contact
from crmgrasp.model.spatial import Config3D, Contact3D


class _Hand(KinematicHand):
    """A kinematic hand whose answer ``slot`` is ``value`` (a reading: the first one)."""

    def __init__(self, task, slot, value, raw=None):
        world = task.sample_world(np.random.default_rng(0))
        super().__init__(world.task, world.config, np.random.default_rng(0))
        self.slot, self.value, self.raw, self.readings = slot, value, raw or {"a": [1.0, 2.0, 0.1]}, 0

    def sense(self):
        real = super().sense()
        self.readings += 1
        return self.value if self.slot == "sense" and self.readings == 1 else real

    def execute(self, crm):
        error = super().execute(crm)
        return self.value if self.slot == "execute" else error

    def raw_reading(self):
        return self.value if self.slot == "raw_reading" else self.raw

    @property
    def time(self):
        return self.value if self.slot == "time" else float(self.readings)

    def object_pose(self):
        return self.value if self.slot == "object_pose" else None


def _run(task, hand, log=None):
    return PolicyRunner(GreedyPolicy(task, 1, {})).run(hand, np.random.default_rng(1), log)


@pytest.mark.parametrize(
    "slot, value, message",
    [
        ("sense", "x", r"^the hand's sense\(\) before the first CRM returned 'x', not a planar configuration of 2"),
        ("sense", (0.1, 0.2), r"not a planar configuration of 2 contacts \(8 finite numbers\)$"),
        (
            "execute",
            "PALM",
            r"^the hand's execute\(\(\w,\w,[-.\d]+\)\) returned 'PALM', not an Error \(NONE, APERTURE, PALM\)$",
        ),
        ("execute", 2, r"returned 2, not an Error"),
        ("raw_reading", [1, 2], r"^the hand's raw_reading\(\) returned \[1, 2\], not a dict with string keys$"),
        ("raw_reading", {"v": object()}, r"^the hand's raw_reading\(\) returned a dict that JSON cannot hold"),
        ("time", "x", r"^the hand's time is 'x', not a number of seconds in \[0, 1e\+09\]$"),
        ("time", -1.0, r"not a number of seconds"),
        (
            "object_pose",
            (1.0, 2.0),
            r"^the hand's object_pose\(\) returned \(1.0, 2.0\), not None or 3 finite numbers$",
        ),
    ],
)
def test_a_malformed_answer_is_one_line_naming_the_method_and_writes_no_log(tmp_path, slot, value, message):
    task = make_task("paper-box")
    for name in ("run.csv", "run.mcap"):
        if name.endswith(".mcap"):
            pytest.importorskip("mcap", reason="needs the extra crmgrasp[mcap]")
        with pytest.raises(CrmgraspError, match=message) as info:
            _run(task, _Hand(task, slot, value), tmp_path / name)
        assert "\n" not in str(info.value) and len(str(info.value)) < 400
        assert list(tmp_path.iterdir()) == []


def test_a_reading_off_the_model_object_runs_but_not_one_of_another_kind():
    """A sensed configuration lies where the hand senses it (the object is unknown); its kind,
    count, finiteness and normals are checked."""
    task = make_task("paper-box")
    far = Config(Contact(5.0, 5.0, 1.0, 0.0), Contact(5.2, 5.0, -1.0, 0.0))
    assert checked_reading(task, far) == (far, task.observe(far)) and task.model.check_reading(far) is far
    with pytest.raises(CrmgraspError, match="off the object"):
        task.check_config(far)
    spatial = Config3D(Contact3D((0.0, 0.0, 0.0), (1.0, 0.0, 0.0)), Contact3D((0.1, 0.0, 0.0), (-1.0, 0.0, 0.0)))
    with pytest.raises(CrmgraspError, match=r"not a planar configuration of 2 contacts"):
        checked_reading(task, spatial, "now")
    cup = make_task("cup-3d")
    assert cup.model.check_reading(spatial) is spatial
    with pytest.raises(CrmgraspError, match=r"^reading must be a Config3D of 2 Contact3D"):
        cup.model.check_reading(list(spatial))
    tripod = make_task("box-3d-3f")
    with pytest.raises(CrmgraspError, match=r"not a spatial configuration of 3 contacts \(18 finite numbers\)$"):
        checked_reading(tripod, spatial)
    assert checked_reading(task, NoContact("tip a is free")) == (NoContact("tip a is free"), None)
    huge = Config3D(Contact3D((1e308, 0.0, 0.0), (1.0, 0.0, 0.0)), Contact3D((-1e308, 0.0, 0.0), (0.0, 1.0, 0.0)))
    with pytest.raises(CrmgraspError, match=r"the observation .* is not finite$"):
        checked_reading(cup, huge)  # no overflow warning on the way (the suite raises warnings as errors)


def test_times_and_poses():
    assert checked_time(0) == 0.0 and checked_time(np.float32(2.5)) == 2.5
    for bad in (True, math.nan, 2e9, None):
        with pytest.raises(CrmgraspError, match="the hand's time is"):
            checked_time(bad)
    plane, space = make_task("paper-box"), make_task("cup-3d")
    assert checked_pose(plane, None) is None and checked_pose(plane, np.zeros(3)) == (0.0, 0.0, 0.0)
    assert checked_pose(space, (0, 0, 0, 1, 0, 0, 0)) == (0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0)
    with pytest.raises(CrmgraspError, match=r"the quaternion \(0.0, 0.0, 0.0, 0.0\), not a unit one$"):
        checked_pose(space, np.zeros(7))
    with pytest.raises(CrmgraspError, match="not None or 7 finite numbers"):
        checked_pose(space, (0.0, 0.0, 0.0))


def test_raw_values_are_logged_whatever_they_hold(tmp_path):
    """A raw entry that is not a contact's wrench goes to the CSV as JSON and to the MCAP record's
    /raw topic; a non-finite number is written as null."""
    task = make_task("paper-box")
    raw = {"a": [1.0, 2.0, 0.1], "temperature": 31.5, "flag": math.nan}
    result = _run(task, _Hand(task, None, None, raw), tmp_path / "run.csv")
    with open(tmp_path / "run.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == len(result.rows) and json.loads(rows[0]["raw"]) == {**raw, "flag": None}
    pytest.importorskip("mcap", reason="needs the extra crmgrasp[mcap]")
    from mcap.reader import make_reader

    _run(task, _Hand(task, None, None, raw), tmp_path / "run.mcap")
    with open(tmp_path / "run.mcap", "rb") as fh:
        topics = [channel.topic for _, channel, _ in make_reader(fh).iter_messages()]
    assert topics.count("/raw") == len(result.rows) and topics.count("/wrench/a") == len(result.rows)


def test_the_hand_fuzz_passes_and_catches_an_unchecked_answer(monkeypatch):
    import importlib.util
    from pathlib import Path

    path = Path(__file__).resolve().parents[1] / "benchmarks" / "hand_fuzz.py"
    spec = importlib.util.spec_from_file_location("hand_fuzz", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    out = mod.main(["--task", "paper-box"])
    assert out["failed"] == 0 and out["runs"] == 80 * len(out["logs"])  # 80 hostile answers, each with every log
    import crmgrasp.hardware.runner as runner

    monkeypatch.setattr(runner, "checked_error", lambda value, crm: value)
    out = mod.main(["--task", "paper-box"])
    assert out["failed"] > 0 and all(f["slot"] == "execute" for f in out["failures"])

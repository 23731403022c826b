"""MCAP records of runs on a hand (needs the extra ``crmgrasp[mcap]``; skipped without it)."""

import csv
import json

import numpy as np
import pytest

pytest.importorskip("mcap", reason="MCAP records need the extra: pip install 'crmgrasp[mcap]'")
pytest.importorskip("foxglove", reason="MCAP records need the extra: pip install 'crmgrasp[mcap]'")

from mcap.reader import make_reader

from crmgrasp import make_task
from crmgrasp._validation import CrmgraspError
from crmgrasp.agents import GreedyPolicy, train_trials
from crmgrasp.cli.main import main
from crmgrasp.hardware import records
from crmgrasp.hardware.records import contact_frames
from crmgrasp.hardware.runner import KinematicHand, PolicyRunner

A, B = "-0.15,-0.02", "-0.01,-0.05"


@pytest.fixture(scope="module")
def policy(tmp_path_factory):
    task = make_task("paper-box")
    res = train_trials(
        task, "pooled-vi", trials=1, episodes=40, seed=0, k=1, eval_episodes=0, params={"symmetric": True}
    )
    path = tmp_path_factory.mktemp("pol") / "policy.json"
    GreedyPolicy.from_agent(task, 1, res.agents[0]).save(path)
    return path


def _read(path):
    out = []
    with open(path, "rb") as fh:
        for schema, channel, message in make_reader(fh).iter_messages():
            body = json.loads(message.data) if channel.message_encoding == "json" else message.data
            out.append((channel.topic, schema.name, message.log_time, body))
    return out


def test_contact_frames_read_the_models_row():
    task = make_task("paper-box")
    cfg = task.place((-0.15, -0.02), (-0.10, -0.05))
    frames = contact_frames(task.model, cfg)
    assert frames["a"] == ((-0.15, -0.02, 0.0), (1.0, 0.0, 0.0)) and frames["b"][1] == (0.0, 1.0, 0.0)
    spatial = make_task("box-3d")
    world = spatial.sample_world(np.random.default_rng(0))
    point, normal = contact_frames(spatial.model, world.config)["a"]
    assert len(point) == 3 and abs(sum(v * v for v in normal) - 1.0) < 1e-9


def test_kinematic_run_records_the_same_steps_as_its_csv(policy, tmp_path):
    assert main(["run", "--policy", str(policy), "--a", A, "--b", B, "--log", str(tmp_path / "r.csv")]) == 0
    assert main(["run", "--policy", str(policy), "--a", A, "--b", B, "--log", str(tmp_path / "r.mcap")]) == 0
    with open(tmp_path / "r.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    got = _read(tmp_path / "r.mcap")
    steps = [body for topic, _, _, body in got if topic == "/crm"]
    assert [s["step"] for s in steps] == [int(r["step"]) for r in rows]
    assert [s["crm"] or "" for s in steps] == [r["crm"] for r in rows]
    assert [s["error"] or "" for s in steps] == [r["error"] for r in rows]
    assert all(abs(s["observation"]["rho"] - float(r["rho"])) < 1e-12 for s, r in zip(steps, rows))
    schemas = {topic: name for topic, name, _, _ in got}
    assert schemas == {"/contacts": "foxglove.SceneUpdate", "/crm": "crmgrasp.CRMStep", "/log": "foxglove.Log"}
    assert [t for topic, _, t, _ in got if topic == "/crm"] == [i * 10**9 for i in range(len(rows))]


def test_mujoco_run_records_wrenches_and_the_object(policy, tmp_path):
    pytest.importorskip("mujoco", reason="needs the extra crmgrasp[mujoco]")
    log = tmp_path / "m.mcap"
    assert main(["run", "--policy", str(policy), "--a", A, "--b", B, "--hand", "mujoco", "--log", str(log)]) == 0
    got = _read(log)
    topics = {topic: name for topic, name, _, _ in got}
    assert topics["/object"] == "foxglove.PoseInFrame" and topics["/wrench/a"] == "crmgrasp.Wrench"
    wrench = next(body for topic, _, _, body in got if topic == "/wrench/b")
    assert set(wrench) == {"force", "torque"} and abs(wrench["force"]["y"]) > 0.5  # b presses up with ~2 N
    times = [t for topic, _, t, _ in got if topic == "/crm"]
    assert times == sorted(times) and times[0] > 0


def test_a_failed_write_leaves_nothing(tmp_path, monkeypatch):
    task = make_task("paper-box")
    hand = KinematicHand(task, task.place((-0.15, -0.02), (-0.10, -0.05)), np.random.default_rng(0))
    policy = GreedyPolicy.from_agent(
        task, 1, train_trials(task, "pooled-vi", trials=1, episodes=5, seed=0, k=1, eval_episodes=0).agents[0]
    )

    def broken(*args, **kwargs):
        raise RuntimeError("disk full")

    monkeypatch.setattr(records, "_log_all", broken)
    with pytest.raises(RuntimeError):
        PolicyRunner(policy).run(hand, np.random.default_rng(0), log=tmp_path / "x.mcap")
    assert list(tmp_path.iterdir()) == []


def test_missing_extra_is_one_line(hide_module):
    hide_module("foxglove")
    with pytest.raises(CrmgraspError, match=r"pip install 'crmgrasp\[mcap\]'"):
        records.require_mcap()


def _record(**change):
    frames = {"a": ((-0.15, -0.02, 0.0), (1.0, 0.0, 0.0)), "b": ((-0.1, -0.05, 0.0), (0.0, 1.0, 0.0))}
    rec = records.StepRecord(0.0, 0, frames, {"rho": 0.0, "m_a": 0.0, "m_b": 0.0}, 0, "a")
    for name, value in change.items():
        setattr(rec, name, value)
    return rec


@pytest.mark.parametrize(
    ("given", "message"),
    [
        (None, "records must be a list of StepRecord"),
        ([1], "record 0 cannot be written: it is no StepRecord"),
        ([_record(), _record(time=float("nan"))], "record 1 cannot be written: its time is nan"),
        ([_record(contacts={"a": ((0.0, 0.0), (1.0, 0.0, 0.0))})], "its contacts is"),
        ([_record(raw={"a": [1j]})], "its raw is"),
        ([_record(pose=(0.0, 0.0))], "its pose is"),
        ([_record(step=True)], "its step is True, not an integer >= 0"),
    ],
)
def test_a_malformed_record_is_one_line_and_nothing_is_written(tmp_path, given, message):
    """What ``write_mcap`` is given is checked before the file is opened (before, a record's
    field of the wrong kind failed inside the Foxglove SDK with its own error)."""
    with pytest.raises(CrmgraspError, match=message):
        records.write_mcap(tmp_path / "x.mcap", given, "paper-box")
    assert list(tmp_path.iterdir()) == []
    assert records.write_mcap(tmp_path / "y.mcap", [_record(raw={"a": [0.0, 1.0, 0.0]})], "paper-box").exists()

"""The MuJoCo stand-in hand (needs the extra ``crmgrasp[mujoco]``; skipped without it)."""

import csv
import json
import math

import numpy as np
import pytest

pytest.importorskip("mujoco", reason="MuJoCo stand-in tests need the extra: pip install 'crmgrasp[mujoco]'")

from crmgrasp import make_task
from crmgrasp._validation import CrmgraspError
from crmgrasp.agents import GreedyPolicy, train_trials
from crmgrasp.cli.main import main
from crmgrasp.experiments.mujoco import (
    MujocoFigure4Config,
    MujocoFigure9Config,
    figure_4_mujoco,
    figure_9_mujoco,
)
from crmgrasp.hardware.contact_sensing import NoContact
from crmgrasp.hardware.mujoco import hardware_task
from crmgrasp.hardware.mujoco.hand import MujocoHand
from crmgrasp.hardware.mujoco.model import PhysicsParams
from crmgrasp.hardware.runner import HandInterface, PolicyRunner
from crmgrasp.model.contacts import Config, Contact
from crmgrasp.model.hand import CRM
from crmgrasp.model.quality import min_friction
from crmgrasp.model.sensing import Error

NEAR = Config(Contact(-0.15, -0.02, 1.0, 0.0), Contact(-0.10, -0.05, 0.0, 1.0))  # docs/model.md section 7 worked cases
FAR = Config(Contact(-0.15, -0.02, 1.0, 0.0), Contact(0.0, -0.05, 0.0, 1.0))


@pytest.fixture(scope="module")
def task():
    return hardware_task(make_task("paper-box"))


def _close(contact: Contact, point: tuple[float, float], tol: float = 1e-3) -> bool:
    return math.dist(contact.point, point) < tol


def test_it_is_a_hand(task):
    assert isinstance(MujocoHand(task, NEAR, np.random.default_rng(0)), HandInterface)


def test_opposition_lands_on_the_expected_side(task):
    hand = MujocoHand(task, NEAR, np.random.default_rng(0))
    assert hand.execute(task.actions[0]) == Error.NONE  # C1: a -> (-0.10, 0.05)
    true = hand.true_config()
    assert true is not None and _close(true.a, (-0.10, 0.05)) and _close(true.b, (-0.10, -0.05))
    assert true.a.normal == pytest.approx((0.0, -1.0), abs=0.01)
    assert min_friction(true) < 0.05


def test_palm_collision_is_a_palm_error(task):
    hand = MujocoHand(task, FAR, np.random.default_rng(0))
    assert hand.execute(task.actions[0]) == Error.PALM  # C1 from the far start: palm inside the box
    true = hand.true_config()
    assert true is not None and _close(true.a, (-0.15, -0.02), 2e-3) and _close(true.b, (0.0, -0.05), 2e-3)


def test_line_out_of_reach_is_an_aperture_error(task):
    hand = MujocoHand(task, NEAR, np.random.default_rng(0))
    assert hand.execute(task.actions[1]) == Error.APERTURE  # C2: the line through a misses b's reach
    true = hand.true_config()
    assert true is not None and _close(true.a, (-0.15, -0.02), 2e-3) and _close(true.b, (-0.10, -0.05), 2e-3)


def test_crm_in_own_frame_moves_toward_the_corner(task):
    hand = MujocoHand(task, FAR, np.random.default_rng(0))
    assert hand.execute(task.actions[3]) == Error.NONE  # C4: b -> (-0.08, -0.05)
    true = hand.true_config()
    assert true is not None and _close(true.b, (-0.08, -0.05))


def test_sensing_matches_mujoco_contacts(task):
    rng = np.random.default_rng(3)
    for _ in range(5):
        hand = MujocoHand(task, task.sample_start(rng), rng)
        sensed, true = hand.sense(), hand.true_config()
        assert isinstance(sensed, Config) and true is not None
        for s, t in zip(sensed, true):
            assert math.dist(s.point, t.point) < 1e-3
            assert math.degrees(math.acos(min(1.0, s.nx * t.nx + s.ny * t.ny))) < 2.0


def test_high_pass_detection_survives_bias_and_drift(task):
    params = PhysicsParams(force_bias=1.0, force_drift=0.2)
    hand = MujocoHand(task, FAR, np.random.default_rng(1), params)
    hand.execute(CRM("b", "b", -0.08))
    free_reading = np.linalg.norm(hand._bias[:, :2], axis=1)  # what a raw-level detector would see untouched
    assert free_reading.max() > params.contact_on  # so a raw threshold would fire in free space
    true = hand.true_config()
    assert true is not None and _close(true.b, (-0.08, -0.05))


def test_same_seed_same_readings(task):
    runs = [MujocoHand(task, NEAR, np.random.default_rng(7)) for _ in range(2)]
    for hand in runs:
        hand.execute(task.actions[0])
    assert runs[0].sense() == runs[1].sense()


def test_cannot_execute_without_contact(task):
    hand = MujocoHand(task, NEAR, np.random.default_rng(0))
    hand._move(0, hand._centre(0) + np.array([-0.03, 0.0, 0.0]), 0.25)  # pull fingertip a off the box
    got = hand.sense()
    assert isinstance(got, NoContact) and "fingertip a" in got.reason and hand.true_config() is None
    with pytest.raises(CrmgraspError, match="without contact"):
        hand.execute(task.actions[0])


@pytest.fixture(scope="module")
def policy_file(tmp_path_factory):
    base = make_task("paper-box")
    res = train_trials(base, "sarsa", trials=3, episodes=2000, seed=0, eval_episodes=200)
    best = int(np.argmin(res.greedy_steps.mean(axis=1)))
    path = tmp_path_factory.mktemp("policy") / "policy.json"
    GreedyPolicy.from_agent(base, 2, res.agents[best]).save(path)
    return path


def test_policy_runner_grasps_on_mujoco(task, policy_file, tmp_path):
    policy = GreedyPolicy.load(policy_file, make_task("paper-box"))
    far = Config(Contact(-0.15, -0.02, 1.0, 0.0), Contact(-0.01, -0.05, 0.0, 1.0))
    hand = MujocoHand(task, far, np.random.default_rng(0))
    res = PolicyRunner(policy, task).run(hand, np.random.default_rng(0), log=tmp_path / "log.csv")
    assert res.grasped and res.crms == 2
    with open(tmp_path / "log.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert [r["crm"] for r in rows] == ["(b,b,-0.08)", "(a,b,0)", ""]
    assert set(json.loads(rows[0]["raw"])) == {"a", "b"}
    assert min_friction(hand.true_config()) < 0.05


def test_cli_run_and_show_on_mujoco(policy_file, tmp_path, capsys):
    log = tmp_path / "run.csv"
    argv = ["run", "--hand", "mujoco", "--policy", str(policy_file), "--a=-0.15,-0.02", "--b=-0.01,-0.05"]
    assert main([*argv, "--log", str(log)]) == 0
    assert "grasp sensed after 2 CRMs" in capsys.readouterr().out
    assert (
        main(["show", "--hand", "mujoco", "--a=-0.15,-0.02", "--b=-0.1,-0.05", "--out", str(tmp_path / "x.pdf")]) == 2
    )
    assert "must end in .png or .gif" in capsys.readouterr().err


def _render_or_skip(fn):
    try:
        return fn()
    except CrmgraspError as exc:
        if "rendering failed" in str(exc):
            pytest.skip(f"no headless OpenGL here: {exc}")
        raise


def test_headless_render(task, tmp_path):
    from crmgrasp.hardware.mujoco.render import render, show

    hand = MujocoHand(task, NEAR, np.random.default_rng(0))
    frame = _render_or_skip(lambda: render(hand, 160, 120))
    assert frame.shape == (120, 160, 3) and frame.dtype == np.uint8 and frame.std() > 5
    msg = _render_or_skip(lambda: show(task, NEAR, task.actions[0], tmp_path / "c1.gif", np.random.default_rng(0)))
    assert "-> none" in msg and (tmp_path / "c1.gif").stat().st_size > 1000
    msg = _render_or_skip(lambda: show(task, NEAR, task.actions[0], tmp_path / "c1.png", np.random.default_rng(0)))
    import matplotlib.image as mpimg

    picture = mpimg.imread(tmp_path / "c1.png")
    assert picture.shape[0] == 320 + 26  # the render and its caption band above it
    band = picture[:26]
    assert band.max() == 1.0 and band.min() < 0.5  # a white band with dark text (the label)
    from PIL import Image

    with Image.open(tmp_path / "c1.gif") as gif:  # the motion at the still's resolution, labelled
        assert gif.size == (picture.shape[1], picture.shape[0]) and gif.n_frames > 10


def test_show_retries_with_osmesa_when_egl_fails(monkeypatch, tmp_path):
    import subprocess

    from crmgrasp.hardware.mujoco import render

    def broken(*args, **kwargs):
        raise CrmgraspError("headless MuJoCo rendering failed with MUJOCO_GL=egl: no EGL")

    calls = []
    monkeypatch.delenv("MUJOCO_GL", raising=False)
    monkeypatch.setattr(render, "show", broken)
    monkeypatch.setattr(
        subprocess, "run", lambda cmd, env, check: calls.append((cmd, env)) or subprocess.CompletedProcess(cmd, 0)
    )
    argv = ["show", "--hand", "mujoco", "--a=-0.15,-0.02", "--b=-0.1,-0.05", "--out", str(tmp_path / "s.png")]
    assert main(argv) == 0
    ((cmd, env),) = calls
    assert env["MUJOCO_GL"] == "osmesa" and cmd[-len(argv) :] == argv


def test_figure_experiments_smoke(policy_file, tmp_path):
    s9 = figure_9_mujoco(tmp_path / "f9", MujocoFigure9Config(trials=2, policy=str(policy_file), animate=False))
    assert s9["successes"] == 2 and s9["max_extra_crms"] <= 1
    assert (tmp_path / "f9" / "figure9_mujoco.png").exists() and (tmp_path / "f9" / "logs" / "trial01.csv").exists()
    s4 = figure_4_mujoco(tmp_path / "f4", MujocoFigure4Config(trials=3, extra_starts=2))
    assert s4["failures"] == 0 and s4["contact_sensing"]["contacts"] == 4 * 3 + 4 * 2
    assert s4["contact_sensing"]["median_position_error_mm"] < 1.0


@pytest.mark.parametrize("kind", ["hexagon", "disc"])
def test_other_convex_objects(kind):
    import dataclasses

    from crmgrasp.model.disc import Disc
    from crmgrasp.model.geometry import regular_polygon
    from crmgrasp.model.hand import execute_crm
    from crmgrasp.tasks import UniformStarts

    obj = regular_polygon(6, 0.06) if kind == "hexagon" else Disc(0.05)
    base = make_task("paper-box")
    task = hardware_task(dataclasses.replace(base, name=kind, obj=obj, starts=UniformStarts()))
    rng = np.random.default_rng(0)
    agree = 0
    for k in range(4):
        start = task.sample_start(rng)
        hand = MujocoHand(task, start, rng)
        sensed, true = hand.sense(), hand.true_config()
        assert isinstance(sensed, Config) and true is not None
        assert max(math.dist(s.point, t.point) for s, t in zip(sensed, true)) < 1e-3
        crm = task.actions[k]
        agree += hand.execute(crm) == execute_crm(task.obj, task.hand, start, crm).error
        assert hand.true_config() is not None  # contact re-established or kept
    assert agree >= 3

"""The MuJoCo stand-in in 3-D (needs the extra ``crmgrasp[mujoco]``; skipped without it):
docs/model-3d.md's worked cases as real motions, sensing, the policy transfer."""

import csv
import math

import numpy as np
import pytest

pytest.importorskip("mujoco", reason="MuJoCo stand-in tests need the extra: pip install 'crmgrasp[mujoco]'")

from crmgrasp import make_task
from crmgrasp._validation import CrmgraspError
from crmgrasp.agents import GreedyPolicy, train_trials
from crmgrasp.experiments.mujoco_spatial import SpatialMujocoConfig, spatial_mujoco
from crmgrasp.hardware.mujoco import hardware_task
from crmgrasp.hardware.mujoco.spatial import MujocoHand3D, spatial_mjcf
from crmgrasp.hardware.runner import HandInterface, KinematicHand, PolicyRunner
from crmgrasp.model.mesh import TriangleMesh, open_cup
from crmgrasp.model.sensing import Error
from crmgrasp.model.solids import box3d
from crmgrasp.model.spatial import CRM3D, Config3D, Contact3D

BOX = box3d((-0.15, -0.05, 0.0), (0.15, 0.05, 0.10))  # docs/model-3d.md sections 3 and 6
START = Config3D(Contact3D((-0.15, -0.02, 0.05), (1.0, 0.0, 0.0)), Contact3D((-0.10, -0.05, 0.05), (0.0, 1.0, 0.0)))
ON_TOP = Config3D(Contact3D((-0.12, 0.0, 0.10), (0.0, 0.0, -1.0)), Contact3D((-0.12, -0.05, 0.05), (0.0, 1.0, 0.0)))


@pytest.fixture(scope="module")
def task():
    return hardware_task(make_task("box-3d").with_object(BOX))


def _close(c: Contact3D, point: tuple[float, float, float], tol: float = 1.5e-3) -> bool:
    return math.dist(c.x, point) < tol


def test_it_is_a_hand(task):
    assert isinstance(MujocoHand3D(task, START, np.random.default_rng(0)), HandInterface)


@pytest.mark.parametrize(
    ("start", "crm", "error", "moved"),
    [
        (START, CRM3D("a", "b"), Error.NONE, (-0.10, 0.05, 0.05)),  # section 3: the opposition grasps
        (START, CRM3D("b", "a"), Error.APERTURE, None),  # section 3: the start is inside the box
        (START, CRM3D("a", "a", (0.0, 0.03)), Error.NONE, (-0.15, -0.02, 0.08)),  # section 3: slide up
        (ON_TOP, CRM3D("b", "a"), Error.PALM, None),  # section 6: b would come from under the table
        (ON_TOP, CRM3D("a", "b"), Error.NONE, (-0.12, 0.05, 0.05)),  # section 6: a grasp
    ],
)
def test_worked_cases_as_real_motions(task, start, crm, error, moved):
    hand = MujocoHand3D(task, start, np.random.default_rng(0))
    assert hand.execute(crm) == error
    assert error == task.execute(start, crm, start).error  # the kinematic model agrees
    true = hand.true_config()
    assert true is not None
    mover = 0 if crm.c == "a" else 1
    expected = moved if moved is not None else start[mover].x
    assert _close(true[mover], expected)
    assert _close(true[1 - mover], start[1 - mover].x)
    if crm == CRM3D("a", "b"):
        assert true.a.n == pytest.approx((0.0, -1.0, 0.0), abs=0.02)
        assert task.quality(true) < 0.05


def test_sensing_matches_mujoco_contacts():
    base = make_task("cup-3d")
    rng = np.random.default_rng(3)
    for _ in range(6):
        world = base.sample_world(rng)
        hand = MujocoHand3D(hardware_task(world.task), world.config, rng)
        sensed, true = hand.sense(), hand.true_config()
        assert isinstance(sensed, Config3D) and true is not None
        for s, t in zip(sensed, true):
            assert math.dist(s.x, t.x) < 1e-3
            assert math.degrees(math.acos(min(1.0, float(np.dot(s.n, t.n))))) < 2.0


def test_same_seed_same_readings(task):
    runs = [MujocoHand3D(task, START, np.random.default_rng(7)) for _ in range(2)]
    for hand in runs:
        hand.execute(CRM3D("a", "b"))
    assert runs[0].sense() == runs[1].sense() and len(runs[0].crm_seconds) == 1


def test_bad_input_is_one_line(task):
    family = hardware_task(make_task("cup-3d"))
    with pytest.raises(CrmgraspError, match="one solid"):
        MujocoHand3D(family, START, np.random.default_rng(0))
    with pytest.raises(CrmgraspError, match="spatial task"):
        MujocoHand3D(make_task("paper-box"), START, np.random.default_rng(0))  # type: ignore[arg-type]
    cup = open_cup(0.04, 0.1, 0.005)
    bare = TriangleMesh(cup.vertices, cup.faces)  # no convex pieces
    with pytest.raises(CrmgraspError, match="meshes with convex pieces, not a TriangleMesh without convex pieces"):
        spatial_mjcf(task.with_object(bare))  # type: ignore[arg-type]
    short = TriangleMesh(cup.vertices, cup.faces, cup.pieces[:-1])  # one block of the wall missing
    with pytest.raises(CrmgraspError, match=r"convex pieces hold .* m\^3 of its .* m\^3: they miss part of it"):
        spatial_mjcf(task.with_object(short))  # type: ignore[arg-type]
    with pytest.raises(CrmgraspError, match="off the object"):
        MujocoHand3D(task, Config3D(START.a, Contact3D((0.0, 0.0, 0.3), (0.0, 0.0, -1.0))), np.random.default_rng(0))
    with pytest.raises(CrmgraspError, match="r_max"):
        MujocoHand3D(task, START, np.random.default_rng(0)).execute(CRM3D("a", "b", (0.5, 0.0)))


@pytest.fixture(scope="module")
def cup_policy():
    base = make_task("cup-3d")
    res = train_trials(base, "model-vi", trials=1, episodes=300, seed=0, k=1, eval_episodes=0)
    return GreedyPolicy.from_agent(base, 1, res.agents[0])


def test_policy_runs_on_both_hands_from_the_same_world(cup_policy, tmp_path):
    base = make_task("cup-3d")
    world = base.sample_world(np.random.default_rng(5))
    task = hardware_task(world.task)
    hand = MujocoHand3D(task, world.config, np.random.default_rng(0))
    res = PolicyRunner(cup_policy, task).run(hand, np.random.default_rng(0), log=tmp_path / "log.csv")
    kinematic = KinematicHand(task, world.config, np.random.default_rng(0))
    kin = PolicyRunner(cup_policy, task).run(kinematic, np.random.default_rng(0))
    with open(tmp_path / "log.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert {"az", "anz", "bz", "bnz", "rho"} <= set(rows[0]) and len(rows) == res.crms + 1
    assert res.grasped and kin.grasped
    assert task.quality(hand.true_config()) <= task.mu_goal


def test_cli_run_and_show_on_mujoco(cup_policy, tmp_path, capsys):
    from crmgrasp.cli.main import main

    path = tmp_path / "cup.json"
    cup_policy.save(path)
    argv = ["run", "--hand", "mujoco", "--policy", str(path), "--a=0.1,0,0.05", "--b=0,0.1,0.12"]
    assert main([*argv, "--log", str(tmp_path / "run.csv")]) == 0
    out = capsys.readouterr().out
    assert "grasp sensed after 1 CRM (" in out and "true min_friction 0.0" in out
    show = ["show", "--task", "cup-3d", "--hand", "mujoco", "--a=0.1,0,0.05", "--b=0,0.1,0.12", "--crm", "C1"]
    code = main([*show, "--out", str(tmp_path / "s.png")])
    got = capsys.readouterr()
    if code != 0 and "rendering failed" in got.err:
        pytest.skip(f"no headless OpenGL here: {got.err}")
    assert code == 0 and "-> none" in got.out and (tmp_path / "s.png").stat().st_size > 1000


def test_experiment_smoke(cup_policy, tmp_path):
    path = tmp_path / "cup.json"
    cup_policy.save(path)
    cfg = SpatialMujocoConfig(tasks=("cup-3d",), trials=2, policies=(str(path),), random_crms=3, animate=False)
    s = spatial_mujoco(tmp_path / "run", cfg)
    row = s["tasks"]["cup-3d"]
    assert row["trials"] == 2 and 0 <= row["successes"] <= 2 and row["max_crm_seconds"] > 0
    assert s["contact_sensing"]["contacts"] == 2 * 2 * 2 + 3 * 2
    assert row["random_crms_same_error_as_kinematic"].endswith("of 3")
    for name in ("data.csv", "spatial_mujoco.png", "summary.json", "logs/cup-3d-trial01.csv"):
        assert (tmp_path / "run" / name).exists()


def test_rolling_friction_keeps_lying_cups_in_place():
    from crmgrasp.hardware.contact_sensing import NoContact
    from crmgrasp.hardware.mujoco.model import PhysicsParams

    base = make_task("cup-3d")
    rng = np.random.default_rng(0)
    worlds = [base.sample_world(rng) for _ in range(40)]

    def lost(rolling: float) -> int:
        params = PhysicsParams(rolling_friction=rolling)
        hands = (
            MujocoHand3D(hardware_task(w.task), w.config, np.random.default_rng(i), params)
            for i, w in enumerate(worlds)
        )
        return sum(isinstance(hand.sense(), NoContact) for hand in hands)

    assert lost(PhysicsParams().rolling_friction) == 0
    assert lost(1e-4) >= 5  # docs/hardware.md: 14 of these 40 cups roll out of the placed grasp


def test_an_open_cup_is_its_convex_pieces_and_its_wall_can_be_pinched():
    """An open cup (a non-convex mesh) in MuJoCo is its convex pieces, the object's mass shared
    by their volumes; two fingertips pinching its wall, one outside and one inside the
    opening, sense what MuJoCo's contacts say, and the pinch needs no friction."""
    from crmgrasp.hardware.mujoco.model import PhysicsParams

    cup = open_cup(0.05, 0.10, 0.005)
    task = hardware_task(make_task("open-cup-3d").with_object(cup))
    half, side = math.radians(7.5), (1.0 + math.cos(math.radians(15.0))) / 2.0

    def on_facet(r: float, inward: float) -> Contact3D:  # the middle of the first side's facet, at 6 cm
        point = (r * side, r * math.sin(2.0 * half) / 2.0, 0.06)
        return Contact3D(point, (inward * math.cos(half), inward * math.sin(half), 0.0))

    start = Config3D(on_facet(0.05, -1.0), on_facet(0.045, 1.0))  # outer wall, inner wall
    assert task.feasible(start) is Error.NONE and task.quality(start) < 1e-9
    hand = MujocoHand3D(task, start, np.random.default_rng(0))
    m = hand.model
    assert len(hand._objects) == len(cup.pieces) == 25
    assert float(m.body_mass[m.geom_bodyid[hand._objects[0]]]) == pytest.approx(PhysicsParams().object_mass)
    sensed, true = hand.sense(), hand.true_config()
    assert isinstance(sensed, Config3D) and true is not None
    for s, t, k in zip(sensed, true, start):
        assert math.dist(s.x, t.x) < 1e-3 and math.dist(t.x, k.x) < 1e-3
    assert true.b.n[0] > 0.99 and task.quality(true) < task.mu_goal  # b presses the inner wall outward

"""Hostile or careless input gets one line and exit status 2 (CLI) or a one-line
CrmgraspError (API), never a traceback, a hang or an allocation that cannot succeed."""

from __future__ import annotations

import json
import re
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from crmgrasp import CRM, Config, Contact, CrmgraspError, make_task
from crmgrasp.agents import train_trials
from crmgrasp.cli.main import main
from crmgrasp.envs import CRMGraspEnv
from crmgrasp.model.history import KOrderEncoder

from .signals import default_sigint

NEAR = ["--a", "-0.15,-0.02", "--b", "-0.10,-0.05"]
HUGE = "9" * 5000  # longer than Python's integer conversion limit


def _one_line_exit_2(argv, capsys, tmp_path, monkeypatch) -> str:
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit) as info:
        sys.exit(main(argv))
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    assert len(err) < 300, err
    return err


SEEDED = [
    ["crm", *NEAR, "--crm", "C1"],
    ["show", *NEAR, "--out", "x.png"],
    ["reproduce", "figure4"],
    ["learn", "--out", "x"],
    ["evaluate", "--policy", "p.json"],
    ["bench", "--smoke"],
    ["references"],
    ["compare", "--out", "x"],
    ["pomdp", "--out", "x.pomdp"],
    ["run", "--policy", "p.json", *NEAR, "--log", "x.csv"],
]


@pytest.mark.parametrize(
    "argv",
    [
        ["crm", "--start-preset", HUGE, *NEAR, "--crm", "C1"],  # argparse's "invalid choice"
        ["crm", "--a", HUGE, "--b", "-0.10,-0.05", "--crm", "C1"],  # a point option's message
        ["references", "--task", HUGE],  # the system's "File name too long"
        ["status", HUGE],
    ],
    ids=["choice", "point", "file-name", "run-folder"],
)
def test_an_error_echoing_a_huge_value_stays_one_short_line(argv, capsys, tmp_path, monkeypatch):
    """Each of these echoed all 5,000 digits (found by benchmarks/cli_fuzz.py); the echo is cut
    to its ends around a count (`crmgrasp.cli.options.fit_line`)."""
    err = _one_line_exit_2(argv, capsys, tmp_path, monkeypatch)
    assert " characters)..." in err  # the run of digits, with whatever quotes or path it sits in


@pytest.mark.parametrize("argv", SEEDED, ids=[a[0] for a in SEEDED])
@pytest.mark.parametrize("seed", ["-1", str(2**63), HUGE, "1.5", "1e3", "٣"])
def test_every_seed_is_checked_before_any_work(argv, seed, capsys, tmp_path, monkeypatch):
    err = _one_line_exit_2([*argv, "--seed", seed], capsys, tmp_path, monkeypatch)
    assert "--seed: value must be an integer in [0, 9223372036854775807]" in err


@pytest.mark.parametrize(
    "argv, msg",
    [
        (
            ["learn", "--episodes", "1000000000000", "--out", "x"],
            "--episodes: value must be an integer in [1, 10000000]",
        ),
        (["learn", "--trials", HUGE, "--out", "x"], "--trials: value must be an integer"),
        (["learn", "--k", "100000", "--out", "x"], "--k: value must be an integer in [0, 10]"),
        (["learn", "--trials", "100000", "--episodes", "10000", "--out", "x"], "episodes exceed the 200,000,000"),
        (["evaluate", "--policy", "p.json", "--episodes", "1e9"], "--episodes: value must be an integer"),
        (["references", "--starts", "1000000000"], "--starts: value must be an integer in [1, 1000000]"),
        (["bench", "--rounds", "1e9"], "--rounds: value must be an integer in [1, 1000]"),
        (["crm", *NEAR, "--crm", ""], "CRM must be written c,f,r"),
        (["crm", *NEAR, "--crm", "C" + "\u0661"], "CRM must be written c,f,r"),
        (["crm", *NEAR, "--crm", "a,b,\u0663"], "ASCII digits"),
        (["crm", *NEAR, "--crm", "C" + HUGE], "has actions C1..C4"),
        (["crm", *NEAR, "--crm", "C1", "--sigma-n-deg", HUGE], "finite"),
        (["reproduce", "figure4", "figure4"], "'figure4' is named more than once"),
    ],
)
def test_bad_numbers_and_names(argv, msg, capsys, tmp_path, monkeypatch):
    assert msg in _one_line_exit_2(argv, capsys, tmp_path, monkeypatch)


def test_sigint_ends_a_run_with_one_line_and_status_130(tmp_path):
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "crmgrasp",
            "learn",
            "--trials",
            "50",
            "--episodes",
            "100000",
            "--quiet",
            "--out",
            str(tmp_path),
        ],
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=default_sigint,
    )
    time.sleep(3)  # past the imports, inside training
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130
    assert err.strip() == "crmgrasp learn: interrupted"
    from crmgrasp.experiments.runs import read_status

    assert read_status(tmp_path) == "interrupted"


def test_api_budgets_and_history_orders_are_bounded(task):
    with pytest.raises(CrmgraspError, match="episodes exceed the 200,000,000"):
        train_trials(task, "sarsa", trials=10**6, episodes=10**6, seed=0)
    with pytest.raises(CrmgraspError, match=r"history order k must be an integer in \[0, 10\], got 1000000"):
        KOrderEncoder(24, 4, 1_000_000)
    with pytest.raises(CrmgraspError, match="trials must be an integer"):
        train_trials(task, "sarsa", trials=2.5, episodes=10, seed=0)  # type: ignore[arg-type]


def test_api_configurations_and_generators_are_checked(task):
    good = task.sample_start(np.random.default_rng(0))
    crm = CRM("a", "b", 0.0)
    with pytest.raises(CrmgraspError, match=re.escape("rng must be a numpy.random.Generator, got 3")):
        task.hand.execute(task.obj, good, crm, rng=3)  # type: ignore[arg-type]
    bad = {
        "abc": "must be a Config of two Contacts, got 'abc'",
        Config(Contact(np.nan, 0.0, 1.0, 0.0), good.b): "contact a must be finite",
        Config(good.a, Contact(0.0, -0.05, 0.0, 2.0)): "contact b's normal must be a unit vector",
        Config(Contact(-0.5, 0.0, 1.0, 0.0), good.b): "is 0.35 m off the object",
    }
    env = CRMGraspEnv(task)
    for config, msg in bad.items():
        with pytest.raises(CrmgraspError, match=re.escape(msg)):
            task.hand.execute(task.obj, config, crm)  # type: ignore[arg-type]
        with pytest.raises(CrmgraspError, match=re.escape(msg)):
            env.reset(options={"config": config})
    assert env.reset(options={"config": good})[1]["config"] == good
    for options, msg in (
        ({"confg": good}, "unknown reset option(s) confg; known: config, world"),
        ({"config": good, "world": None}, "options['config'] or options['world'], not both"),
        ("config", "reset options must be a dict, got 'config'"),
    ):
        with pytest.raises(CrmgraspError, match=re.escape(msg)):
            env.reset(options=options)  # type: ignore[arg-type]


def test_the_episode_loop_checks_its_policy_learner_and_generators(task):
    """What the loop is handed is checked where it arrives: before, a policy without
    ``begin``, a learner with fewer actions than its encoder, or a seed of text reached
    Python or Gymnasium as an ``AttributeError``, an ``IndexError`` or Gymnasium's error."""
    from crmgrasp import sim
    from crmgrasp.agents import encoder_for, evaluate, make_agent, run_episode

    rng = np.random.default_rng(0)
    with pytest.raises(CrmgraspError, match="a policy needs the methods begin, act, tell; 3 has no begin"):
        sim.run_episode(task, 3, rng)  # type: ignore[arg-type]
    with pytest.raises(CrmgraspError, match=re.escape("run_episode needs a Task (crmgrasp.make_task(name)), got None")):
        sim.run_episode(None, 3, rng)  # type: ignore[arg-type]
    agent = make_agent("sarsa", 3)
    with pytest.raises(CrmgraspError, match="the agent has 3 actions, the encoder 4"):
        run_episode(task, agent, encoder_for(task, 1), rng, rng)
    with pytest.raises(CrmgraspError, match="a learner acts through a KOrderEncoder"):
        run_episode(task, make_agent("sarsa", 4), 1, rng, rng)  # type: ignore[arg-type]
    with pytest.raises(CrmgraspError, match=r"episodes must be an integer in \[0, 200000000\], got -1"):
        evaluate(task, make_agent("sarsa", 4), encoder_for(task, 1), -1, rng)
    for seed in (-1, "x", 1.5):
        with pytest.raises(CrmgraspError, match="seed must be an integer"):
            CRMGraspEnv(task).reset(seed=seed)  # type: ignore[arg-type]
    assert CRMGraspEnv(task).reset(seed=np.int64(3))[0] == CRMGraspEnv(task).reset(seed=3)[0]


def test_helpers_that_build_tasks_and_actions_check_their_arguments():
    from crmgrasp.agents import episodes_to_within
    from crmgrasp.envs.continuous import PairOffsetActions, flat_action
    from crmgrasp.envs.vector import vector_env
    from crmgrasp.model.families import BoxFamily
    from crmgrasp.tasks import default_crms, family_task

    with pytest.raises(CrmgraspError, match=r"CRM offsets must be a list, got 0\.04"):
        default_crms(0.04)  # type: ignore[arg-type]
    assert default_crms(np.array([0.04])) == default_crms((0.04,))
    with pytest.raises(CrmgraspError, match=r"a task family must be a ShapeFamily \(BoxFamily\(\), ...\), got None"):
        family_task("f", None)  # type: ignore[arg-type]
    with pytest.raises(CrmgraspError, match=r"expected a CRM, got \[1.0, 2.0\]"):  # not the mirror's TypeError
        family_task("f", BoxFamily(), actions=[[1.0, 2.0]])
    with pytest.raises(CrmgraspError, match="CRMGraspVectorEnv needs a Task"):
        vector_env(2, None)  # type: ignore[arg-type]
    ranges = PairOffsetActions(make_task("paper-box")).ranges
    with pytest.raises(CrmgraspError, match=r"the flat action must have shape \(2,\), got \(3,\)"):
        flat_action(ranges, np.zeros(3))
    with pytest.raises(CrmgraspError, match="ranges must be a non-empty list of CRMRange"):
        flat_action([], np.zeros(2))
    with pytest.raises(CrmgraspError, match="a learning curve must be a 1-D sequence of finite numbers"):
        episodes_to_within([1.0, np.nan], 1.0)
    with pytest.raises(CrmgraspError, match=r"window must be an integer in \[1, 200000000\], got 0"):
        episodes_to_within([1.0, 1.0], 1.0, window=0)


def test_spatial_rules_grids_and_figures_check_their_arguments(capsys, tmp_path, monkeypatch):
    """The 3-D rules, CRM grids and figures refuse what they cannot use in one line; before,
    text reached numpy, ``None`` reached an attribute, and a grid of 1,000 offsets per
    coordinate on a 3-D task (4,000,000 CRMs, deduplicated by a list scan) ran for good."""
    from crmgrasp.model.actions import grid_points
    from crmgrasp.model.spatial import Config3D, Contact3D, box3d, execute_crm3d, observe3d
    from crmgrasp.plotting import friction_histogram, scene_figure
    from crmgrasp.tasks.offsets import grid_crms

    cup = make_task("cup-3d")
    world = cup.sample_world(np.random.default_rng(0))
    bad = Config3D(Contact3D(("x", 0.0, 0.0), (1.0, 0.0, 0.0)), world.config.b)
    with pytest.raises(CrmgraspError, match="observe3d: contact a must be finite 3-vectors"):
        observe3d(bad)
    with pytest.raises(CrmgraspError, match="a spatial object must be a ConvexPolyhedron, Cylinder or TriangleMesh"):
        execute_crm3d(None, cup.hand, world.config, cup.actions[0])  # type: ignore[arg-type]
    with pytest.raises(CrmgraspError, match="table height must be a number, got 'x'"):
        execute_crm3d(world.task.obj, cup.hand, world.config, cup.actions[0], table="x")  # type: ignore[arg-type]
    with pytest.raises(CrmgraspError, match="a box's lo corner must be numbers, got 'abc'"):
        box3d("abc", (1.0, 1.0, 1.0))
    with pytest.raises(CrmgraspError, match=r"offsets per coordinate must be an integer in \[1, 1000\]"):
        grid_points(-0.1, 0.1, 10**100)
    with pytest.raises(CrmgraspError, match="make 4,000,000 CRMs on task 'cup-3d'; at most 100,000"):
        grid_crms(cup, 1000)
    err = _one_line_exit_2(["references", "--task", "cup-3d", "--offset-grid", "1000"], capsys, tmp_path, monkeypatch)
    assert "4,000,000 CRMs" in err
    box = make_task("paper-box")
    cfg = box.sample_start(np.random.default_rng(0))
    with pytest.raises(CrmgraspError, match="a scene's object must be a Shape or a solid, got None"):
        scene_figure(None, box.hand, cfg)  # type: ignore[arg-type]
    with pytest.raises(CrmgraspError, match="a scene of a Polygon needs a Hand, got None"):
        scene_figure(box.obj, None, cfg)  # type: ignore[arg-type]
    with pytest.raises(CrmgraspError, match="friction values must be numbers"):
        friction_histogram("x", 0, "t")  # type: ignore[arg-type]


def test_the_fused_kernel_refuses_an_action_out_of_range(task):
    from crmgrasp.kernels import kernel_for
    from crmgrasp.sim import SimState

    good = task.sample_start(np.random.default_rng(0))
    k = kernel_for(make_task("paper-box"), "numba")
    for action in (-1, 4, 10**9):
        with pytest.raises(CrmgraspError, match=r"action must be an integer in \[0, 4\)"):
            k.step_one(SimState(good, good, 0), action, np.random.default_rng(0))


# ------------------------------------------------------------------ policy files
@pytest.fixture
def saved_policy(tmp_path):
    from crmgrasp.agents import GreedyPolicy

    task = make_task("paper-box")
    res = train_trials(task, "sarsa", trials=1, episodes=30, seed=0, eval_episodes=0)
    path = GreedyPolicy.from_agent(task, 2, res.agents[0]).save(tmp_path / "p.json")
    return task, path


def _load_error(task, path) -> str:
    from crmgrasp.agents import GreedyPolicy

    with pytest.raises(CrmgraspError) as info:
        GreedyPolicy.load(path, task)
    msg = str(info.value)
    assert "\n" not in msg and len(msg) < 300, msg
    return msg


def test_policy_reader_refuses_files_that_are_not_small_regular_json(saved_policy, tmp_path, monkeypatch):
    import json
    import os

    import crmgrasp.agents.policy_file as policy_module

    task, good = saved_policy
    doc = json.loads(good.read_text())
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    assert "is not a regular file" in _load_error(task, fifo)  # refused without opening: no hang
    assert "is not a regular file" in _load_error(task, "/dev/zero")
    assert "is not a regular file" in _load_error(task, tmp_path)
    monkeypatch.setattr(policy_module, "MAX_BYTES", 100)
    assert "larger than 100 bytes" in _load_error(task, good)
    monkeypatch.undo()
    cases = {
        "nested.json": "[" * 100_000 + "]" * 100_000,
        "bigint.json": '{"format": "crmgrasp-policy", "version": ' + "9" * 5000 + "}",
        "nan.json": '{"format": NaN}',
        "dupes.json": '{"format": "a", "format": "b"}',
    }
    expected = {
        "nested.json": "nested too deeply",
        "bigint.json": "has more than 20 digits",
        "nan.json": "NaN is not standard JSON",
        "dupes.json": "'format' appears more than once",
    }
    for name, text in cases.items():
        (tmp_path / name).write_text(text)
        assert expected[name] in _load_error(task, tmp_path / name)
    for key in ("7_813", "+5", "05", " 5", "\u0665"):
        d = json.loads(json.dumps(doc))
        d["greedy"][key] = [0]
        from crmgrasp.agents.policy import policy_digest

        d["sha256"] = policy_digest(d)
        (tmp_path / "key.json").write_text(json.dumps(d))
        assert "is not a canonical non-negative integer" in _load_error(task, tmp_path / "key.json")


def test_cli_reads_policies_through_the_bounded_reader(tmp_path, capsys, monkeypatch):
    for argv in (["evaluate", "--policy", "/dev/zero"], ["run", "--policy", "/dev/zero", *NEAR, "--log", "x.csv"]):
        assert "is not a regular file" in _one_line_exit_2(argv, capsys, tmp_path, monkeypatch)


# ------------------------------------------------------------------ output paths
def test_outputs_never_replace_devices_folders_or_symlinks_to_them(saved_policy, tmp_path, capsys, monkeypatch):
    import os

    _, good = saved_policy
    link = tmp_path / "link"
    os.symlink("/dev/null", link)
    (tmp_path / "folder").mkdir()
    for target in ("/dev/null", str(link), str(tmp_path / "folder")):
        argv = ["run", "--policy", str(good), *NEAR, "--log", target]
        assert "refusing to replace it" in _one_line_exit_2(argv, capsys, tmp_path, monkeypatch)
        argv = ["pomdp", "--out", target]
        assert "refusing to replace it" in _one_line_exit_2(argv, capsys, tmp_path, monkeypatch)
    assert link.is_symlink() and os.readlink(link) == "/dev/null"
    for argv in (["learn", "--out", ""], ["reproduce", "--out", ""], ["show", *NEAR, "--out", ""]):
        assert "the path is empty" in _one_line_exit_2(argv, capsys, tmp_path, monkeypatch)
    (tmp_path / "file").write_text("keep")
    assert "exists and is not a folder" in _one_line_exit_2(
        ["learn", "--out", str(tmp_path / "file")], capsys, tmp_path, monkeypatch
    )
    assert (tmp_path / "file").read_text() == "keep"


def test_writes_use_short_temporary_names_the_umask_and_standard_json(tmp_path):
    import json
    import os
    import stat

    from crmgrasp._io import write_json

    long_name = tmp_path / ("x" * 250 + ".json")  # legal; a temporary name built from it would not be
    write_json(long_name, {"nan": float("nan"), "inf": float("inf"), "ok": 1.5})
    assert json.loads(long_name.read_text()) == {"nan": None, "inf": None, "ok": 1.5}
    old = os.umask(0o027)
    try:
        write_json(tmp_path / "u.json", {})
    finally:
        os.umask(old)
    assert stat.S_IMODE((tmp_path / "u.json").stat().st_mode) == 0o640
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []


def test_write_errors_name_the_users_path(tmp_path):
    from crmgrasp._io import write_json

    (tmp_path / "plain").write_text("a file, not a folder")
    target = tmp_path / "plain" / "x.json"
    with pytest.raises(CrmgraspError, match=re.escape(f"output file {str(target)!r} cannot be written")):
        write_json(target, {})


def test_noise_and_coordinates_have_stated_ranges():
    from crmgrasp import Polygon, SensorNoise
    from crmgrasp.model.sensing import MAX_SIGMA_N, MAX_SIGMA_P

    SensorNoise(MAX_SIGMA_N, MAX_SIGMA_P)  # the bounds themselves are valid
    for bad in ((MAX_SIGMA_N * 1.01, 0.0), (0.0, 0.2)):
        with pytest.raises(CrmgraspError, match="beyond the valid range"):
            SensorNoise(*bad)
    with pytest.raises(CrmgraspError, match=re.escape("vertex 1 (1e+200, 0) is beyond +-1e+06 m")):
        Polygon([(0, 0), (1e200, 0), (0, 1e200)])


def test_every_object_and_pose_is_within_reach(tmp_path, capsys, monkeypatch):
    """Discs, solids, meshes and family poses beyond +-MAX_COORD are one-line errors: a cup
    placed 1e7 m out once gave NaN normals (a RuntimeWarning, then garbage) instead."""
    from crmgrasp import Disc
    from crmgrasp.model.family_base import Pose
    from crmgrasp.model.mesh import TriangleMesh
    from crmgrasp.model.shape import MAX_COORD
    from crmgrasp.model.solids import ConvexPolyhedron, Cylinder, box3d

    far = 10 * MAX_COORD
    cases = [
        (lambda: Disc(0.1, (far, 0.0)), "a disc's radius or center"),
        (lambda: Disc(far), "a disc's radius or center"),
        (lambda: Cylinder((0.0, far, 0.0), (0.0, 0.0, 1.0), 0.05, 0.1), "a cylinder's origin"),
        (lambda: Cylinder((0.0, 0.0, 0.0), (0.0, 0.0, 1.0), 0.05, far), "a cylinder's origin"),
        (lambda: box3d((far, 0.0, 0.0), (far + 1.0, 1.0, 1.0)), "a box's corner"),
        (lambda: ConvexPolyhedron([(1, 0, 0, far), (-1, 0, 0, 0), (0, 1, 0, 1), (0, -1, 0, 0)]), "a polyhedron's"),
        (
            lambda: TriangleMesh(
                [(0, 0, 0), (far, 0, 0), (0, 1, 0), (0, 0, 1)], [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)]
            ),
            "a mesh's corner",
        ),
        (lambda: Pose(offset=(-far, 0.0)), "pose offset"),
    ]
    for make, what in cases:
        with pytest.raises(CrmgraspError, match=re.escape(what)):
            make()
    Disc(0.1, (MAX_COORD - 0.1, 0.0))  # within reach: fine
    box3d((0.0, 0.0, 0.0), (MAX_COORD, 1.0, 1.0))
    path = tmp_path / "far-cups.toml"
    path.write_text(
        'name = "far-cups"\nmodel = "spatial"\n[hand]\naperture = 0.16\npalm_depth = 0.12\n[[crm]]\nc = "a"\n'
        'f = "b"\n[family]\nkind = "cylinder"\npose = { offset = [1e7, 1e7] }\n'
    )
    err = _one_line_exit_2(["references", "--task", str(path), "--starts", "5"], capsys, tmp_path, monkeypatch)
    assert "pose offset is beyond +-1e+06 m" in err


_json_values = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats(allow_nan=False) | st.text(max_size=8),
    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=6), inner, max_size=4),
    max_leaves=20,
)


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(
    st.one_of(
        st.binary(max_size=200),
        _json_values.map(lambda v: json.dumps(v).encode()),
        st.fixed_dictionaries(
            {"format": st.just("crmgrasp-policy"), "version": st.integers(0, 3), "task": st.just("paper-box")},
            optional={"k": _json_values, "greedy": _json_values, "sha256": st.text(max_size=5)},
        ).map(lambda v: json.dumps(v).encode()),
    )
)
def test_fuzzed_policy_files_load_or_fail_in_one_line(tmp_path, data):
    from crmgrasp.agents import GreedyPolicy

    path = tmp_path / "fuzz.json"
    path.write_bytes(data)
    try:
        GreedyPolicy.load(path, make_task("paper-box"))
    except CrmgraspError as exc:
        assert "\n" not in str(exc) and len(str(exc)) < 400


def test_near_coincident_contacts_after_a_noisy_crm_are_a_palm_error(task):
    """At 30 degrees of normal noise an opposition sometimes lands the moving contact
    within a millimetre of the other: with min_separation the model calls it a palm
    error (the fingertips collide), and no accepted CRM ends closer than that."""
    import math
    from dataclasses import replace

    from crmgrasp import SensorNoise
    from crmgrasp.model.hand import Error, execute_crm

    noise = SensorNoise(math.radians(30), 0.002)
    hand = replace(task.hand, min_separation=0.01)
    rng = np.random.default_rng(0)
    close = reclassified = 0
    for _ in range(3000):
        cfg = task.sample_start(rng)
        sensed = noise.sense(cfg, rng)
        plain = execute_crm(task.obj, task.hand, cfg, task.actions[0], sensed)
        strict = execute_crm(task.obj, hand, cfg, task.actions[0], sensed)
        if strict.error is Error.NONE:
            assert strict.config.separation > 0.01
        if plain.error is Error.NONE and plain.config.separation <= 0.01:
            close += 1
            reclassified += strict.error is Error.PALM
    assert close > 0 and reclassified == close
    with pytest.raises(CrmgraspError, match="min_separation must be below the aperture"):
        replace(task.hand, min_separation=1.0)


def test_crossed_contacts_are_a_palm_error_and_no_noisy_crm_ends_in_one(task):
    """Two contacts on one side whose order is reversed put the palm on the object's side
    (the surfaces face the palm): the model calls that a palm error. Under the largest
    noise allowed, every CRM that reports no error ends in a feasible configuration,
    crossed or coincident contacts included."""
    import math

    from crmgrasp import SensorNoise
    from crmgrasp.model.hand import Error, execute_crm, feasible

    hand, obj = task.hand, task.obj
    side_by_side = Config(Contact(-0.10, -0.05, 0.0, 1.0), Contact(-0.05, -0.05, 0.0, 1.0))
    crossed = Config(side_by_side.b, side_by_side.a)
    assert feasible(obj, hand, side_by_side) is Error.NONE
    assert feasible(obj, hand, crossed) is Error.PALM
    assert feasible(obj, hand, Config(side_by_side.a, side_by_side.a)) is Error.PALM  # coincident
    rng = np.random.default_rng(1)
    seen = {Error.NONE: 0, Error.PALM: 0, Error.APERTURE: 0}
    for sigma in (math.radians(30), math.radians(45)):
        noise = SensorNoise(sigma, 0.01)
        for _ in range(1500):
            cfg = task.sample_start(rng)
            for crm in task.actions:
                out = execute_crm(obj, hand, cfg, crm, noise.sense(cfg, rng))
                seen[out.error] += 1
                if out.error is Error.NONE:
                    assert feasible(obj, hand, out.config) is Error.NONE
                    assert out.config.separation > 0.0
    assert min(seen.values()) > 0  # every outcome occurs at this noise


def test_public_functions_check_configurations(task):
    from crmgrasp import min_friction, observe

    good = task.sample_start(np.random.default_rng(0))
    nan = Config(Contact(np.nan, 0.0, 1.0, 0.0), good.b)
    long = Config(good.a, Contact(0.0, -0.05, 0.0, 2.0))
    for fn in (min_friction, observe):
        with pytest.raises(CrmgraspError, match="contact a must be finite"):
            fn(nan)
        with pytest.raises(CrmgraspError, match="contact b's normal must be a unit vector"):
            fn(long)
        with pytest.raises(CrmgraspError, match="must be a Config of two Contacts"):
            fn("abc")  # type: ignore[arg-type]
    with pytest.raises(CrmgraspError, match=re.escape("is 0.35 m off the object")):
        task.hand.feasible(task.obj, Config(Contact(-0.5, 0.0, 1.0, 0.0), good.b))
    with pytest.raises(CrmgraspError, match="contact a"):
        task.hand.contact(task.obj, (np.nan, 0.0), (0.0, -0.05))
    with pytest.raises(CrmgraspError, match="contact b"):
        task.hand.contact(task.obj, (0.0, 0.05), (1.0, 2.0, 3.0))


@pytest.mark.parametrize(
    ("family", "message"),
    [
        (
            {"kind": "regular-polygon", "sides": [3, 1_000_000]},
            "regular polygon sides range (3, 1000000) must end at 512",
        ),
        ({"kind": "star", "points": [4, 100_000]}, "star points range (4, 100000) must end at 256"),
        (
            {"kind": "convex-polygon", "vertices": [3, 100_000]},
            "convex polygon vertices range (3, 100000) must end at 512",
        ),
        (
            {"kind": "polygon", "vertices": [[i * 1e-6, (i % 2) * 1e-6] for i in range(1_000_000)]},
            "a polygon may have at most 512 vertices, got 1000000",
        ),
    ],
)
def test_family_counts_are_bounded_with_the_limit_named(family, message):
    """A hostile count is refused at once, in one line naming the limit (not a hang or MemoryError)."""
    from crmgrasp.tasks import make_task, task_from_dict, task_to_dict

    doc = {**task_to_dict(make_task("u-handle")), "family": family, "symmetry": None}
    with pytest.raises(CrmgraspError) as err:
        task_from_dict(doc)
    assert message in str(err.value) and "\n" not in str(err.value)


SWALLOWED = """
import os, signal, sys
import crmgrasp.experiments.learning as learning
from crmgrasp.cli import main

real = learning.learn


class Finaliser:
    def __del__(self):  # Ctrl-C lands here: Python prints "Exception ignored" and carries on
        os.kill(os.getpid(), signal.SIGINT)


def learn(*args, **kwargs):
    Finaliser()
    return real(*args, **kwargs)


learning.learn = learn
sys.exit(main(sys.argv[1:]))
"""


def test_a_ctrl_c_that_python_swallows_still_stops_the_run(tmp_path):
    """SIGINT raised inside a finaliser is lost to Python (it prints the traceback and goes
    on); the command remembers it and stops at the next progress step, interrupted."""
    import subprocess
    import sys

    from tests.signals import default_sigint

    argv = ["learn", "--trials", "2", "--episodes", "20000", "--quiet", "--out", str(tmp_path)]
    proc = subprocess.run(
        [sys.executable, "-c", SWALLOWED, *argv],
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=default_sigint,
        timeout=120,
    )
    assert "Exception ignored" in proc.stderr  # Python did swallow it
    assert proc.returncode == 130 and proc.stderr.strip().endswith("crmgrasp learn: interrupted")
    from crmgrasp.experiments.runs import read_status

    assert read_status(tmp_path) == "interrupted"


@pytest.mark.parametrize("text", ["beta", "=1", "beta=", "beta=nan", "beta=inf", "beta=x", "beta=--5", "beta=+-5"])
def test_a_malformed_setting_names_the_item(text):
    from crmgrasp._validation import setting

    with pytest.raises(CrmgraspError) as err:
        setting(text)
    msg = str(err.value)
    assert "\n" not in msg and ("beta" in msg or repr(text) in msg)


def test_a_setting_keeps_integers_whole():
    from crmgrasp._validation import setting

    assert setting(" explore = 2 ") == ("explore", 2) and isinstance(setting("explore=2")[1], int)
    assert setting("beta=-0.25") == ("beta", -0.25) and setting("sample=TRUE") == ("sample", True)


def test_an_experiments_parameters_are_checked_when_built(tmp_path):
    """Each field of an experiment's config is checked against its type where the config is
    built; before, ``Figure4Config(trials="x")`` was accepted and the run failed inside with a
    ``TypeError``, and ``GeneralizationConfig(families="t-shape")`` held the families "t",
    "-", "s", ... (a string is a sequence)."""
    from crmgrasp.experiments.figure4 import Figure4Config, figure_4_opposition_quality
    from crmgrasp.experiments.generalization import GeneralizationConfig
    from crmgrasp.experiments.third_contact import ThirdContactConfig

    for kwargs, message in [
        ({"trials": "x"}, "Figure4Config.trials must be an integer, got 'x'"),
        ({"seed": -1}, r"Figure4Config.seed must be an integer in \[0, 9223372036854775807\], got -1"),
        ({"sigma_p": float("nan")}, "Figure4Config.sigma_p must be finite, got nan"),
        ({"task": None}, "Figure4Config.task must be text, got None"),
    ]:
        with pytest.raises(CrmgraspError, match=message):
            Figure4Config(**kwargs)
    with pytest.raises(CrmgraspError, match=r"GeneralizationConfig\.families must be a list, got .t-shape."):
        GeneralizationConfig(families="t-shape")  # type: ignore[arg-type]
    assert GeneralizationConfig(families=["t-shape"]).families == ("t-shape",)  # stored as a tuple
    with pytest.raises(CrmgraspError, match=r"ThirdContactConfig.pairs\[0\] must have 2 items, got 3"):
        ThirdContactConfig(pairs=(("a", "b", "c"),))  # type: ignore[arg-type]
    with pytest.raises(CrmgraspError, match="the experiment's parameters must be a Figure4Config, got None"):
        figure_4_opposition_quality(tmp_path / "out", None)  # type: ignore[arg-type]
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("name", ["paper-box", "triangles-3f", "cup-3d", "box-3d-3f"])
def test_a_kernel_checks_what_its_compiled_code_would_read(name):
    """A configuration reaches compiled code only as a configuration of the task's model:
    before, ``kernel_for(paper-box).successors([[1.0, 2.0]])`` handed a row of 2 numbers to
    code that reads 8, and repeated it crashed the process (a segmentation fault)."""
    from crmgrasp.kernels import kernel_for

    task = make_task(name)
    kernel = kernel_for(task, "auto")
    rng = np.random.default_rng(0)
    if task.family is not None:
        world = task.sample_world(rng)
        kernel.use(world.task)
        good = world.config
    else:
        good = task.sample_start(rng)
    for bad in ([[1.0, 2.0]], None, (good[0],), np.array([np.nan])):
        with pytest.raises(CrmgraspError, match="configuration"):
            kernel.successors(bad)
        with pytest.raises(CrmgraspError, match="configuration"):
            kernel.begin(bad, rng)
    with pytest.raises(CrmgraspError, match="a step needs the SimState of the episode's last step, got None"):
        kernel.step_one(None, 0, rng)
    first = kernel.begin(good, rng)
    assert kernel.step_one(first.state, 0, rng).state.steps == 1  # a checked start steps as before


def test_execute_batch_checks_its_rows_indices_and_offsets(task):
    from crmgrasp.kernels import execute_batch

    rows = np.array([[-0.15, -0.02, 1.0, 0.0, -0.10, -0.05, 0.0, 1.0]])
    for kwargs, message in [
        ({"c": "x"}, "c must be numbers, got 'x'"),
        ({"c": 0.5}, r"contact indices c and f must be integers in \[0, 1\]"),
        ({"f": [0, 1]}, r"f must be one number or 1, got shape \(2,\)"),
        ({"r": 1e308}, "CRM offsets r must be finite and within r_max"),
        ({"configs": "abc"}, "configs must be numbers, got 'abc'"),
    ]:
        args = {"configs": rows, "c": 0, "f": 1, "r": 0.0, **kwargs}
        with pytest.raises(CrmgraspError, match=message):
            execute_batch(task.obj, task.hand, args["configs"], args["c"], args["f"], args["r"])


def test_a_kernels_action_table_row_is_checked_unless_its_caller_did(task):
    """``step_row`` reads ``2 + offset_dim`` numbers of its row, contact indices among them:
    a row of another shape, an index past the hand's contacts or a NaN offset is one line
    (before, compiled code read them as they were). The continuous environments check the
    pair and offset themselves and say so (``checked=True``)."""
    from crmgrasp.kernels import kernel_for

    kernel = kernel_for(task, "auto")
    rng = np.random.default_rng(0)
    state = kernel.begin(task.sample_start(rng), rng).state
    good = kernel.crm_row(task.actions[1])
    for row, message in [
        (np.zeros((1, 2)), r"must be a float64 array of shape \(1, 3\), got \(\(1, 2\), 'float64'\)"),
        (np.array([[0.0, 5.0, 0.0]]), r"contact indices in \[0, 1\] and finite offsets"),
        (np.array([[0.0, 1.0, np.nan]]), "finite offsets"),
        ([[0.0, 1.0, 0.0]], "must be a float64 array"),
    ]:
        with pytest.raises(CrmgraspError, match=message):
            kernel.step_row(state, row, rng)
    assert kernel.step_row(state, good, rng) == kernel.step_row(state, good, rng, checked=True)


def test_the_learners_helpers_check_names_tasks_and_features(task):
    """A preset, an agent or a deep learner named by something other than text, and features
    of the wrong kind, are one line (before: ``TypeError: unhashable type`` from a dict lookup,
    and a ``TypeError`` or ``IndexError`` from inside ``features``)."""
    from crmgrasp.agents import deep, deep_trials, presets

    with pytest.raises(CrmgraspError, match=r"unknown preset array\(\[nan\]\); known: "):
        presets.apply_preset(np.array([np.nan]), task)
    with pytest.raises(CrmgraspError, match=r"agent must be a learner's name, got \[\]"):
        presets.apply_preset("fastest", task, agent=[])  # type: ignore[arg-type]
    with pytest.raises(CrmgraspError, match="apply_preset needs a Task"):
        presets.apply_preset("fastest", None)  # type: ignore[arg-type]
    with pytest.raises(CrmgraspError, match="deep learner parameters must be a dict, got 3"):
        deep_trials.deep_config("ppo", 3)  # type: ignore[arg-type]
    bounds = deep.bounds_of(task)
    with pytest.raises(CrmgraspError, match=r"features need one number per bound .* error code in \[0, 3\)"):
        deep.features([1.0, 0.0, 0.0], 7, bounds)
    with pytest.raises(CrmgraspError, match="a model's discrete action must be an integer, got nan"):
        deep.crm_of_action(task, np.nan)
    assert deep.features([1.0, 0.0, 0.0], 0, bounds)[3] == 1.0  # the error flag's one-hot


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda s: s["bootstrap_ci"]("x"), "values must be numbers"),
        (lambda s: s["bootstrap_ci"]([1.0] * 5, seed=float("nan")), r"seed must be an integer in \[0, "),
        (lambda s: s["bootstrap_ci"]([1.0] * 5, confidence=1e-320), r"confidence must be in \[0.5, 1\)"),
        (lambda s: s["bootstrap_ci"]([1.0] * 5, resamples=10**100), r"resamples must be an integer in \[100, "),
        (lambda s: s["normal_ci"]([]), "a normal interval needs at least one value, got none"),
        (lambda s: s["iqm"]({"a": 1}), "values must be numbers"),
        (lambda s: s["ci_text"]("x", 1.7), "an interval's ends must be numbers"),
    ],
)
def test_the_interval_helpers_check_their_values(call, message):
    """The statistics a user applies to results: one line for values, a seed, a confidence or a
    number of resamples of the wrong kind (before, numpy's, scipy's and Python's own errors)."""
    from crmgrasp.experiments import stats

    with pytest.raises(CrmgraspError, match=message):
        call(vars(stats))
    assert stats.bootstrap_ci([1.0, 2.0, 3.0, 4.0, 5.0], seed=np.int64(3)) == stats.bootstrap_ci(
        [1.0, 2.0, 3.0, 4.0, 5.0], seed=3
    )


def test_the_pomdp_helpers_hand_check_and_controller_check_their_arguments(tmp_path):
    """``belief_update``, ``build_task_pomdp``, ``policy_costs``, ``check_hand``, ``load_policy``
    and ``run_controller``: one line naming the argument (before, attribute, type and index
    errors from inside, and a ``worlds`` of 10**100 ran until stopped)."""
    from crmgrasp.agents.controller import run_controller
    from crmgrasp.agents.loading import load_policy
    from crmgrasp.hardware.conformance import check_hand
    from crmgrasp.hardware.runner import KinematicHand
    from crmgrasp.planners import references as refs
    from crmgrasp.planners.pomdp import belief_update
    from crmgrasp.planners.pomdp_task import build_task_pomdp
    from crmgrasp.planners.realizable import policy_costs

    box = make_task("paper-box")
    m = build_task_pomdp(box, samples=2, n_starts=20, max_states=2000).model
    cases = [
        (lambda: belief_update(m, m.b0[:-1], 0, 0), f"belief must be a distribution over the {m.n_states} states"),
        (lambda: belief_update(m, m.b0, m.n_actions, 0), r"action must be an integer in \[0, 3\]"),
        (lambda: belief_update(m, m.b0, 0, -1), "observation must be an integer"),
        (lambda: build_task_pomdp(None), "build_task_pomdp needs a Task"),
        (lambda: build_task_pomdp(box, samples=None), "samples per cell must be an integer"),
        (lambda: policy_costs(None, []), "policy_costs needs a BeliefPolicy, got None"),
        (
            lambda: policy_costs(refs.BeliefPolicy(box, refs.sample_starts(box, 2, 0)), [], advance=1.0),
            "advance must be a function or None",
        ),
        (lambda: check_hand(None, box), "make_hand must make a hand"),
        (lambda: check_hand(KinematicHand, box, worlds=10**100), r"worlds must be an integer in \[1, 1000\]"),
        (lambda: check_hand(KinematicHand, None), "check_hand needs a Task"),
        (lambda: load_policy(None), "policy file path must be text or a path"),
        (lambda: load_policy(tmp_path / "p.json", task=float("nan")), "load_policy needs a Task"),
        (lambda: run_controller(box, None, np.random.default_rng(0)), "episodes must be an integer"),
        (lambda: run_controller(None, 3, np.random.default_rng(0)), "run_controller needs a Task"),
    ]
    for call, message in cases:
        with pytest.raises(CrmgraspError, match=message):
            call()
    o = int(np.flatnonzero(m.Z[0].T @ (m.T[0].T @ m.b0))[0])  # an observation the first action can give
    assert np.array_equal(belief_update(m, m.b0, np.int64(0), np.int64(o)), belief_update(m, m.b0, 0, o))

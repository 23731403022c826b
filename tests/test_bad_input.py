"""Hostile or careless input gets one line and exit status 2 (CLI) or a one-line
CrmgraspError (API), never a traceback, a hang or an allocation that cannot succeed."""

from __future__ import annotations

import re
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from crmgrasp import CRM, Config, Contact, CrmgraspError, make_task
from crmgrasp.agents import train_trials
from crmgrasp.cli.main import main
from crmgrasp.envs import CRMGraspEnv
from crmgrasp.model.history import KOrderEncoder

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
        (["crm", *NEAR, "--crm", "C1", "--sigma-n", HUGE], "finite"),
        (["reproduce", "figure4", "figure4"], "'figure4' is named more than once"),
    ],
)
def test_bad_numbers_and_names(argv, msg, capsys, tmp_path, monkeypatch):
    assert msg in _one_line_exit_2(argv, capsys, tmp_path, monkeypatch)


def test_sigint_ends_a_run_with_one_line_and_status_130(tmp_path):
    proc = subprocess.Popen(
        [sys.executable, "-m", "crmgrasp", "learn", "--trials", "50", "--episodes", "100000", "--out", str(tmp_path)],
        stderr=subprocess.PIPE,
        text=True,
    )
    time.sleep(3)  # past the imports, inside training
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130
    assert err.strip() == "crmgrasp learn: interrupted"


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


def test_the_fused_kernel_refuses_an_action_out_of_range(task):
    from crmgrasp.kernels import kernel_for
    from crmgrasp.sim import SimState

    good = task.sample_start(np.random.default_rng(0))
    k = kernel_for(make_task("paper-box"), "numba")
    for action in (-1, 4, 10**9):
        with pytest.raises(CrmgraspError, match=r"action must be an integer in \[0, 4\)"):
            k.step_one(SimState(good, good, 0), action, np.random.default_rng(0))

"""The crmgrasp command: outputs, and one-line errors with exit status 2."""

import json
import subprocess
import sys

import numpy as np
import pytest

from crmgrasp.cli.main import main

NEAR = ["--a", "-0.15,-0.02", "--b", "-0.10,-0.05"]


def test_crm_text(capsys):
    assert main(["crm", *NEAR, "--crm", "a,b,0"]) == 0
    out = capsys.readouterr().out
    assert "error=none" in out and "a: x=(-0.1, 0.05)  n=(0, -1)" in out and "success=True" in out


def test_crm_json_and_action_names(capsys):
    assert main(["crm", "--a", "-0.15,-0.02", "--b", "0,-0.05", "--crm", "C4", "--json"]) == 0
    res = json.loads(capsys.readouterr().out)
    assert res["error"] == "none" and res["config"]["b"]["point"] == [-0.08, -0.05]
    assert res["crm"] == {"c": "b", "f": "b", "r": -0.08}
    assert main(["crm", "--a", "-0.15,-0.02", "--b", "0,-0.05", "--crm", "C1", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["error"] == "palm"


def test_crm_with_noise_is_seeded(capsys):
    args = ["crm", *NEAR, "--crm", "C1", "--json", "--sigma-n-deg", "3", "--sigma-p", "0.002", "--seed", "7"]
    main(args)
    first = capsys.readouterr().out
    main(args)
    assert capsys.readouterr().out == first


@pytest.mark.parametrize(
    "argv, msg",
    [
        (["crm", *NEAR, "--crm", "a,c,0"], "names contact 'c', but the hand has contacts a, b"),
        (["crm", *NEAR, "--crm", "a,q,0"], "unknown contact label 'q'"),
        (["crm", *NEAR, "--crm", "a,a,0.5"], "beyond r_max"),
        (["crm", *NEAR, "--crm", "C9"], "C1..C4"),
        (["crm", *NEAR, "--crm", "a,b"], "c,f,r"),
        (["crm", "--a", "-0.15", "--b", "0,0", "--crm", "C1"], "expected X,Y"),
        (["crm", "--a", "nan,0", "--b", "0,0", "--crm", "C1"], "finite"),
        (["crm", "--task", "nope", *NEAR, "--crm", "C1"], "unknown task 'nope'"),
        (["crm", "--a", "-0.2,-0.1", "--b", "0,-0.05", "--crm", "C1"], "vertex"),
        (["crm", "--a", "-0.15,0.0", "--b", "0.15,0.0", "--crm", "C1"], "infeasible"),
        (["crm", *NEAR], "required: --crm"),
        (["crm", *NEAR, "--crm", "C1", "--sigma-n-deg", "inf"], "finite"),
        (["show", *NEAR, "--out", "x.txt"], ".png, .pdf or .svg"),
        (["reproduce", "figure99"], "unknown experiment 'figure99'"),
        (["frobnicate"], "invalid choice"),
        (["learn", "--agent", "nope", "--out", "x"], "invalid choice: 'nope'"),
        (["learn", "--trials", "0", "--out", "x"], "--trials: value must be an integer in [1, 100000], got 0"),
        (["learn", "--alpha", "2", "--trials", "1", "--episodes", "1", "--out", "x"], "alpha must be in"),
        (["learn", "--k", "-1", "--out", "x"], "--k: value must be an integer in [0, 10], got -1"),
        (["references", "--starts", "0"], "--starts: value must be an integer in [1, 1000000]"),
        (["evaluate", "--policy", "missing.json"], "does not exist"),
        (
            ["evaluate", "--policy", "missing.json", "--episodes", "0"],
            "--episodes: value must be an integer in [1, 10000000]",
        ),
    ],
)
def test_bad_input_is_one_line_exit_2(argv, msg, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit) as info:
        sys.exit(main(argv))
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert msg in err and err.count("\n") == 1, err


def test_show_writes_image(tmp_path, capsys):
    out = tmp_path / "sub" / "scene.png"
    assert main(["show", *NEAR, "--crm", "C1", "--out", str(out)]) == 0
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert main(["show", *NEAR, "--out", str(tmp_path / "s.svg")]) == 0
    capsys.readouterr()
    before = out.read_bytes()
    assert main(["show", *NEAR, "--out", str(out)]) == 2  # an existing image is the user's: kept
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "exists; --overwrite replaces it" in err and out.read_bytes() == before
    assert main(["show", *NEAR, "--out", str(out), "--overwrite"]) == 0 and out.read_bytes() != before


def test_installed_entry_point_help():
    res = subprocess.run([sys.executable, "-m", "crmgrasp", "crm", "--help"], capture_output=True, text=True)
    assert res.returncode == 0 and "--crm" in res.stdout


def test_tasks_listing(capsys):
    assert main(["tasks"]) == 0
    assert "paper-box" in capsys.readouterr().out


def test_learn_then_evaluate(tmp_path, capsys):
    out = tmp_path / "run"
    args = [
        "learn",
        "--agent",
        "sarsa",
        "--trials",
        "2",
        "--episodes",
        "300",
        "--eval-episodes",
        "50",
        "--seed",
        "3",
        "--out",
        str(out),
    ]
    assert main(args) == 0
    for name in ("curve.csv", "checkpoints.csv", "summary.json", "policy.json", "learning_curve.png"):
        assert (out / name).exists()
    summary = json.loads((out / "summary.json").read_text())
    for key in (
        "agent",
        "task",
        "trials",
        "episodes",
        "seed",
        "final_mean_steps",
        "greedy_mean_steps",
        "episodes_to_5pct",
    ):
        assert key in summary
    assert (out / "curve.csv").read_text().splitlines()[0] == "episode,mean_steps,sem_steps"
    capsys.readouterr()
    assert main(["evaluate", "--policy", str(out / "policy.json"), "--episodes", "100", "--json"]) == 0
    res = json.loads(capsys.readouterr().out)
    assert res["task"] == "paper-box" and 1.0 <= res["mean_steps"] <= 10.0
    assert res["ci95"][0] <= res["mean_steps"] <= res["ci95"][1]
    assert (
        main(
            [
                "learn",
                "--agent",
                "dyna-q",
                "--planning",
                "sweep",
                "--k",
                "1",
                "--trials",
                "1",
                "--episodes",
                "20",
                "--eval-episodes",
                "10",
                "--out",
                str(tmp_path / "d"),
            ]
        )
        == 0
    )


def test_references_command(capsys):
    assert main(["references", "--starts", "300", "--seed", "2", "--json"]) == 0
    res = json.loads(capsys.readouterr().out)
    assert 1.0 <= res["clairvoyant_bound"] <= res["belief_optimum"] <= 2.5
    assert res["aliasing_price"] == pytest.approx(res["belief_optimum"] - res["clairvoyant_bound"])


def test_references_blocks(capsys):
    """``--blocks``: the optimum over disjoint blocks of the starts, never above the optimum
    over all of them (a policy for the union is one for each block); a count that does not
    divide the starts is a one-line error before any work."""
    from crmgrasp._validation import CrmgraspError
    from crmgrasp.planners.references import block_optima, sample_starts
    from crmgrasp.tasks import make_task

    assert main(["references", "--task", "u-handle", "--starts", "60", "--blocks", "4", "--json", "--quiet"]) == 0
    res = json.loads(capsys.readouterr().out)
    task = make_task("u-handle")
    assert res["block_optima"] == block_optima(task, sample_starts(task, 60, 0), 4) and res["blocks"] == 4
    assert res["block_optimum_mean"] <= res["belief_optimum"] + 1e-12
    lo, hi = res["block_optimum_ci95"]
    assert lo <= res["block_optimum_mean"] <= hi
    assert main(["references", "--starts", "60", "--blocks", "7", "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--blocks 7 must divide --starts 60" in err
    with pytest.raises(CrmgraspError, match="divides the 60 starts"):
        block_optima(task, sample_starts(task, 60, 0), 7)


def test_pomdp_command(tmp_path, capsys):
    out = tmp_path / "box.pomdp"
    assert (
        main(["pomdp", "--cell", "0.02", "--samples", "5", "--starts", "300", "--episodes", "100", "--out", str(out)])
        == 0
    )
    assert "model value" in capsys.readouterr().out and out.read_text().startswith("# crmgrasp POMDP")
    assert main(["pomdp", "--cell", "-1", "--out", str(out)]) == 2
    text, again = out.read_text(), ["pomdp", "--cell", "0.02", "--samples", "5", "--starts", "300", "--out", str(out)]
    assert main([*again, "--episodes", "10"]) == 2 and out.read_text() == text  # refused before any work
    assert "exists; --overwrite replaces it" in capsys.readouterr().err
    assert main([*again, "--episodes", "10", "--seed", "1", "--overwrite"]) == 0 and out.read_text() != text


def test_run_command(tmp_path, capsys):
    pol = tmp_path / "p"
    assert main(["learn", "--trials", "2", "--episodes", "1500", "--eval-episodes", "50", "--out", str(pol)]) == 0
    capsys.readouterr()
    log = tmp_path / "run.csv"
    assert (
        main(
            ["run", "--policy", str(pol / "policy.json"), "--a", "-0.15,-0.02", "--b", "-0.01,-0.05", "--log", str(log)]
        )
        == 0
    )
    out = capsys.readouterr().out
    assert out.startswith("grasp sensed after 2 CRMs") and log.read_text().startswith("step,ax,ay")
    again = ["run", "--policy", str(pol / "policy.json"), "--a", "-0.15,-0.02", "--b", "-0.01,-0.05", "--log", str(log)]
    log.write_text("an earlier run")
    assert main(again) == 2 and "exists (the log of an earlier run)" in capsys.readouterr().err
    assert log.read_text() == "an earlier run"
    assert main([*again, "--overwrite"]) == 0 and log.read_text().startswith("step,ax,ay")
    assert main(["run", "--policy", str(tmp_path / "nope.json"), "--a", "0,0", "--b", "0,0", "--log", str(log)]) == 2


def test_run_draws_its_readings(tmp_path, capsys):
    """--figure: one panel per reading (the runner keeps each reading's sensed contacts and the
    CRM after it); a bad or taken path is refused before the run, and nothing is written."""
    from crmgrasp.agents.loading import load_policy
    from crmgrasp.hardware.runner import KinematicHand, PolicyRunner

    pol = tmp_path / "p"
    learn = ["learn", "--preset", "fastest", "--trials", "1", "--episodes", "100", "--quiet"]
    assert main([*learn, "--out", str(pol)]) == 0
    policy = load_policy(pol / "policy.json")
    task = policy.task
    start = task.hand.contact(task.obj, a=(-0.15, -0.02), b=(-0.01, -0.05))
    res = PolicyRunner(policy).run(KinematicHand(task, start, np.random.default_rng(0)), np.random.default_rng(0))
    assert len(res.readings) == res.crms + 1 and res.readings[0][0] == start and res.readings[-1][1:] == ("", "")
    assert [crm for _, crm, _ in res.readings[:-1]] == [row[-3] for row in res.rows[:-1]]  # the log's CRMs
    capsys.readouterr()
    log, figure = tmp_path / "run.csv", tmp_path / "run.png"
    argv = ["run", "--policy", str(pol / "policy.json"), "--a", "-0.15,-0.02", "--b", "-0.01,-0.05", "--log", str(log)]
    assert main([*argv, "--figure", str(figure)]) == 0
    assert figure.read_bytes().startswith(b"\x89PNG") and f"wrote {figure.resolve()}" in capsys.readouterr().out
    other = tmp_path / "other.csv"
    bad = [
        (["--figure", str(tmp_path / "x.gif")], "--figure must end in .png, .pdf or .svg"),
        (["--figure", str(figure)], "exists; --overwrite replaces it"),
    ]
    for extra, message in bad:
        assert main(["run", *argv[1:-1], str(other), *extra]) == 2
        err = capsys.readouterr().err
        assert message in err and err.count("\n") == 1
        assert not other.exists()  # refused before the run: no log either
    same = ["run", *argv[1:-1], str(tmp_path / "s.png"), "--figure", str(tmp_path / "s.png")]
    assert main(same) == 2 and "name the same file" in capsys.readouterr().err


def test_run_from_a_drawn_start(tmp_path, capsys):
    """Without --a, --b: a start drawn from the task's own starts with --seed, printed, the same
    for the same seed; some points but not all, or an infeasible start: one line, nothing written."""
    pol = tmp_path / "p"
    learn = ["learn", "--preset", "fastest", "--trials", "1", "--episodes", "50", "--quiet", "--out", str(pol)]
    assert main(learn) == 0
    capsys.readouterr()
    runs = {}
    for name, seed in (("a", "3"), ("b", "3"), ("c", "4")):
        log = tmp_path / f"{name}.csv"
        assert main(["run", "--policy", str(pol / "policy.json"), "--log", str(log), "--seed", seed]) == 0
        first = capsys.readouterr().out.splitlines()[0]
        assert first.startswith("start drawn from paper-box's starts (seed ") and ": a (" in first
        runs[name] = (first, log.read_text())
    assert runs["a"] == runs["b"] and runs["c"][0] != runs["a"][0]
    base = ["run", "--policy", str(pol / "policy.json"), "--log", str(tmp_path / "x.csv")]
    for extra, message in (
        (["--a", "-0.15,-0.02"], "task 'paper-box' has 2 fingers: give --a --b (got --a)"),
        (["--a", "-0.15,0.02", "--b", "0.1,0.05"], "the start configuration is infeasible: an aperture error"),
    ):
        assert main([*base, *extra]) == 2
        err = capsys.readouterr().err
        assert message in err and err.count("\n") == 1
    assert not (tmp_path / "x.csv").exists()


def test_learn_gives_the_same_curve_on_every_kernel_backend(tmp_path):
    """--lockstep on each --backend, and sequential training, write the same curve."""
    base = ["learn", "--agent", "sarsa", "--trials", "3", "--episodes", "40", "--eval-episodes", "10", "--seed", "2"]
    runs = {
        "sequential": [],
        "auto": ["--lockstep"],
        "numba": ["--lockstep", "--backend", "numba"],
        "reference": ["--lockstep", "--backend", "reference"],
    }
    curves = {}
    for name, extra in runs.items():
        assert main([*base, *extra, "--out", str(tmp_path / name)]) == 0
        curves[name] = (tmp_path / name / "curve.csv").read_text()
    assert len(set(curves.values())) == 1
    with pytest.raises(SystemExit):
        main([*base, "--lockstep", "--backend", "gpu", "--out", str(tmp_path / "x")])


def test_the_command_line_shows_what_the_library_knows():
    """Choices, presets and defaults come from the registries, not from copies in the CLI."""
    from crmgrasp.agents.deep import DEEP_AGENTS
    from crmgrasp.agents.presets import PRESETS
    from crmgrasp.agents.training import AGENTS, parameter_defaults
    from crmgrasp.cli.parser import build_parser
    from crmgrasp.experiments.registry import EXPERIMENTS
    from crmgrasp.tasks.presets import START_PRESETS

    sub = next(a for a in build_parser()._actions if a.dest == "command").choices
    learn = {a.dest: a for a in sub["learn"]._actions}
    assert tuple(learn["agent"].choices) == (*AGENTS, *DEEP_AGENTS) and tuple(learn["preset"].choices) == tuple(PRESETS)
    assert all(a.description in learn["agent"].help for a in DEEP_AGENTS.values())
    assert "recurrent-ppo, ppo, sac: default 0.9" in learn["gamma"].help
    assert tuple(learn["start_preset"].choices) == tuple(START_PRESETS)
    assert all(p.description in learn["preset"].help for p in PRESETS.values())
    assert parameter_defaults("lam") == {"sarsa-lambda": 0.9} and "sarsa-lambda: default 0.9" in learn["lam"].help
    assert all(name in sub["reproduce"]._actions[1].help for name in EXPERIMENTS)
    jobs = {a.default for p in sub.values() for a in p._actions if a.dest == "jobs"}
    assert jobs == {1}  # one default for --jobs across commands
    backends = {tuple(a.choices) for p in sub.values() for a in p._actions if "--backend" in a.option_strings}
    assert backends == {("auto", "numba", "reference")}  # --backend means the kernel, in every command


def test_every_option_shows_its_default_or_choices():
    import argparse

    from crmgrasp.cli.options import _Help
    from crmgrasp.cli.parser import build_parser

    parser = build_parser()
    subs = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    for name, sub in subs.choices.items():
        for action in sub._actions:
            if isinstance(action, (argparse._HelpAction, argparse._StoreTrueAction)) or not action.option_strings:
                continue
            text = _Help("crmgrasp")._get_help_string(action) or ""
            shown = "default" in text or action.choices or action.required or action.default is None
            assert shown, f"{name} {action.option_strings}: {text!r}"
            if action.default is not None and action.choices is None:
                assert "default" in text, f"{name} {action.option_strings}: {text!r}"
        assert "usage:" in sub.format_help()


def test_learn_preset_fastest_learns_from_scratch_and_a_prior_only_when_named(tmp_path, capsys):
    out = tmp_path / "fast"
    base = ["learn", "--trials", "2", "--episodes", "40", "--eval-episodes", "200", "--quiet"]
    assert main([*base, "--preset", "fastest", "--out", str(out)]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["agent"] == "pooled-vi" and summary["k"] == 1 and summary["params"]["symmetric"] is True
    assert "prior_task" not in summary["params"] and summary["prior"] is None  # no prior unless asked for
    assert json.loads((out / "run.json").read_text())["config"]["prior"] is None
    assert summary["greedy_mean_steps"] < 1.05 * 1.66 + 0.05  # 40 episodes from scratch: near the optimum
    family = tmp_path / "family"
    assert main([*base, "--task", "cup-family", "--preset", "fastest", "--out", str(family)]) == 0
    assert json.loads((family / "summary.json").read_text())["prior"] is None
    assert main([*base, "--preset", "fastest", "--agent", "sarsa", "--out", str(tmp_path / "s")]) == 0
    assert json.loads((tmp_path / "s" / "summary.json").read_text())["agent"] == "sarsa"
    prior = tmp_path / "prior"
    extra = ["--prior-task", "box-family", "--prior-episodes", "100", "--out", str(prior)]
    capsys.readouterr()
    assert main([*base, "--preset", "fastest", *extra]) == 0
    said = capsys.readouterr()
    assert "prior: 100 episodes on box-family" in said.err and "after a prior of 100 episodes on box-family" in said.out
    recorded = {"task": "box-family", "episodes": 100, "weight": 1.0, "seed": 0}
    assert json.loads((prior / "summary.json").read_text())["prior"] == recorded
    assert json.loads((prior / "run.json").read_text())["config"]["prior"] == recorded
    for agent in ("sarsa", "dyna-q"):
        assert main([*base, "--agent", agent, "--prior-task", "box-family", "--out", str(tmp_path / agent)]) == 2
        assert f"--prior-task does not apply to --agent {agent}" in capsys.readouterr().err


def test_learn_says_when_no_interval_is_given(tmp_path, capsys):
    """Fewer than 5 trials: the text says no interval is given (not 'n/a-n/a')."""
    argv = ["learn", "--trials", "1", "--episodes", "20", "--eval-episodes", "10", "--quiet"]
    assert main([*argv, "--out", str(tmp_path / "r")]) == 0
    out = capsys.readouterr().out
    assert "no interval: fewer than 5 trials" in out and "n/a" not in out


def test_learn_without_evaluation_says_so(tmp_path, capsys):
    """--eval-episodes 0: the greedy line says the policy was not evaluated (no 'nan%', no
    'fewer than 5 trials' for 5 trials)."""
    argv = ["learn", "--trials", "5", "--episodes", "5", "--eval-episodes", "0", "--quiet"]
    assert main([*argv, "--out", str(tmp_path / "r")]) == 0
    out = capsys.readouterr().out
    assert "greedy policy: not evaluated (--eval-episodes 0)" in out
    assert "nan" not in out and "fewer than" not in out


HEXAGON = """name = "wide-hexagon"
[object]
polygon = [[0.2, 0.0], [0.1, 0.1732], [-0.1, 0.1732], [-0.2, 0.0], [-0.1, -0.1732], [0.1, -0.1732]]
[hand]
aperture = 0.16
palm_depth = 0.12
[[crm]]
c = "a"
f = "b"
[[crm]]
c = "b"
f = "a"
[starts]
kind = "uniform"
"""


def test_learn_warns_before_training_an_ungraspable_task(tmp_path, capsys):
    """A hexagon 0.35 m wide for a 0.16 m aperture: no start can be grasped, and learn says so first."""
    task = tmp_path / "hex.toml"
    task.write_text(HEXAGON)
    argv = ["learn", "--trials", "1", "--episodes", "5", "--eval-episodes", "5", "--quiet"]
    assert main([*argv, "--task", str(task), "--out", str(tmp_path / "a")]) == 0
    err = capsys.readouterr().err
    assert "warning: task 'wide-hexagon': none of 50 sampled starts can be grasped" in err
    assert main([*argv, "--out", str(tmp_path / "b")]) == 0  # paper-box: no warning
    assert "warning" not in capsys.readouterr().err


def test_episodes_to_5pct_lead_with_the_greedy_policy_and_flag_a_noise_bound_curve():
    from crmgrasp.cli.learning import _to_5pct_lines

    s = {
        "reference_mean_steps": 1.66,
        "converged": True,
        "trials": 20,
        "episodes": 20_000,
        "checkpoint_episodes": 100,
        "greedy_episodes_to_5pct": 1500,
        "episodes_to_5pct": 19_841,
    }
    greedy, curve = _to_5pct_lines(s)
    assert greedy.endswith("within 5% of 1.66: from episode 1,500")
    assert "19,841 (in the budget's last tenth: bound by the episodes' noise" in curve
    s.update(episodes_to_5pct=1726, converged=True)
    assert _to_5pct_lines(s)[1].endswith("from episode 1,726")
    s.update(episodes_to_5pct=None, converged=False, greedy_episodes_to_5pct=None, checkpoint_episodes=0)
    (only,) = _to_5pct_lines(s)
    assert only.endswith("never (not converged at 20 trials x 20,000 episodes)")

"""Studies: parsing, identical results for any number of workers, failures kept apart,
resume, tables and the report."""

from __future__ import annotations

import csv
import json
import re
from pathlib import Path

import pytest

from crmgrasp._validation import CrmgraspError
from crmgrasp.cli import main
from crmgrasp.experiments import sweep as sweep_mod
from crmgrasp.experiments.runs import read_status
from crmgrasp.experiments.study import cell_id, load_study, study_from_dict

from .signals import default_sigint

STUDY = """
name = "tiny"
trials = 3
episodes = 40
eval_episodes = 10
seeds = [0, 1]
[grid]
agent = ["sarsa", "q"]
alpha = [0.3, 0.6]
[[cell]]
agent = "backoff-vi"
k = 1
"""


def _write(tmp_path, text=STUDY):
    p = tmp_path / "study.toml"
    p.write_text(text)
    return p


def test_grid_and_cells_are_expanded(tmp_path):
    study = load_study(_write(tmp_path))
    assert len(study.cells) == 5 and study.seeds == (0, 1)
    assert study.cells[0] == {"task": "paper-box", "agent": "sarsa", "k": 2, "alpha": 0.3}
    assert len({cell_id(c) for c in study.cells}) == 5


@pytest.mark.parametrize(
    ("doc", "message"),
    [
        ({"grid": {"agent": ["sarsa"]}, "foo": 1}, "unknown key 'foo'"),
        ({"grid": {"alpah": [0.1]}}, r"unknown key 'alpah' \(did you mean 'alpha'\?\); every cell takes task, "),
        (
            {"cell": [{"agent": "pooled-vi", "bata": 1}]},
            r"'bata' \(did you mean 'beta'\?\); .* agent 'pooled-vi' takes beta",
        ),
        ({"cell": [3]}, "[[cell]] number 1 must be a table of cell keys, got 3"),
        ({"cell": [{"agent": "sarsa"}], "eval_episodes": 0}, "eval_episodes must be an integer in [1, "),
        ({"grid": {"agent": []}}, "must be a non-empty list"),
        ({}, "needs a [grid]"),
        ({"grid": {"agent": ["sarsa"]}, "seeds": [1, 1]}, "must not repeat"),
        ({"grid": {"agent": ["sarsa"]}, "seeds": [-1]}, "seed"),
        ({"grid": {"agent": ["sarsa"]}, "trials": 0}, "trials"),
        ({"cell": [{"agent": ["sarsa"]}]}, "must be a single value"),
        ({"cell": [{"agent": "sarsa"}, {"agent": "sarsa"}]}, "the same"),
        ({"cell": [{"agent": "random", "alpha": 0.5}]}, "agent 'random' takes no alpha"),
        ({"cell": [{"agent": "nope"}]}, "unknown agent 'nope'"),
        ({"grid": {"agent": ["sarsa"]}, "name": "x/../../../ESCAPED"}, "name must be 1-64 letters"),
        ({"grid": {"agent": ["sarsa"]}, "name": "a\nb"}, "name must be 1-64 letters"),
        ({"grid": {"agent": ["sarsa"]}, "seeds": ["0"]}, "seeds must be a non-empty list of integers"),
        ({"grid": {"agent": ["sarsa"]}, "seeds": [True]}, "seeds must be a non-empty list of integers"),
        ({"cell": [{"agent": "model-vi", "symmetric": "no"}]}, "symmetric must be true or false, got 'no'"),
        ({"cell": [{"agent": "model-vi", "symmetric": 0.5}]}, "symmetric must be true or false, got 0.5"),
        ({"cell": [{"agent": "sarsa", "k": 1.5}]}, "k must be an integer, got 1.5"),
        ({"cell": [{"agent": "sarsa", "alpha": "0.3"}]}, "alpha must be a finite number, got '0.3'"),
        ({"cell": [{"agent": "sarsa", "alpha": True}]}, "alpha must be a finite number, got True"),
        ({"cell": [{"agent": "sarsa", "alpha": float("inf")}]}, "alpha must be finite, got inf"),
        ({"cell": [{"agent": "sarsa", "task": 3}]}, "task must be a string, got 3"),
        ({"cell": [{"agent": "pooled-vi", "mean_after": 10}]}, "agent 'pooled-vi' takes no mean_after"),
        ({"cell": [{"agent": "backoff-vi", "mean_after": 1.5}]}, "mean_after must be an integer, got 1.5"),
        ({"cell": [{"agent": "backoff-vi", "skip_errored": 1}]}, "skip_errored must be true or false, got 1"),
        ({"cell": [{"agent": "fixed", "sequence": 1}]}, "unknown key 'sequence'"),  # not a scalar parameter
    ],
)
def test_bad_studies_are_one_line(doc, message):
    with pytest.raises(CrmgraspError, match=message.replace("[", r"\[")) as err:
        study_from_dict(doc)
    assert "\n" not in str(err.value)


def test_every_agents_scalar_parameters_are_cell_keys_and_columns(tmp_path, capsys):
    """A study sets any registered agent's parameters (backoff-vi's ``beta`` and
    ``mean_after`` here), which reach the agent and become columns after the first
    learners' ones."""
    from crmgrasp.agents.training import AGENTS, agent_parameters
    from crmgrasp.experiments.study import BASE_KEYS, TABLE_PARAMS, agent_params, table_keys

    wanted = {p for a in AGENTS for p in agent_parameters(a)} - {"sequence"}  # fixed's CRM list
    assert set(agent_params()) == wanted
    text = 'name = "b"\ntrials = 1\nepisodes = 30\neval_episodes = 5\n[grid]\nagent = ["backoff-vi"]\n'
    text += "beta = [0.5, 1.0]\nmean_after = [10]\n"
    study = load_study(_write(tmp_path, text))
    assert table_keys(study) == [*BASE_KEYS, *TABLE_PARAMS, "beta", "mean_after"]
    assert main(["sweep", str(tmp_path / "study.toml"), "--quiet", "--out", str(tmp_path / "out")]) == 0
    with open(tmp_path / "out" / "cells.csv") as fh:
        cells = list(csv.DictReader(fh))
    assert [(c["beta"], c["mean_after"], c["status"]) for c in cells] == [("0.5", "10", "ok"), ("1.0", "10", "ok")]
    units = sorted((tmp_path / "out" / "units").iterdir())
    params = [json.loads(u.read_text())["summary"]["params"] for u in units]
    assert sorted((p["beta"], p["mean_after"]) for p in params) == [(0.5, 10), (1.0, 10)]


@pytest.mark.parametrize(
    ("cell", "message"),
    [
        ('task = "missing.toml"', "cell task '"),
        ('task = "nonexistent"', "cell task 'nonexistent': unknown task 'nonexistent'"),
        ('start_preset = "bogus"', "cell task 'paper-box': unknown start preset 'bogus'"),
    ],
)
def test_a_task_that_does_not_resolve_is_refused_before_any_run(tmp_path, cell, message):
    path = _write(tmp_path, f'name = "t"\n[[cell]]\nagent = "sarsa"\n{cell}\n')
    with pytest.raises(CrmgraspError, match=re.escape(message)) as err:
        load_study(path)
    assert "\n" not in str(err.value) and "study file" in str(err.value)


def test_a_cells_relative_task_file_is_read_beside_the_study(tmp_path, monkeypatch):
    from crmgrasp.tasks import TEMPLATE

    (tmp_path / "studies").mkdir()
    (tmp_path / "studies" / "my-u.toml").write_text(TEMPLATE)
    study_file = tmp_path / "studies" / "s.toml"
    study_file.write_text('name = "s"\n[[cell]]\ntask = "my-u.toml"\n[[cell]]\ntask = "paper-box"\n')
    monkeypatch.chdir(tmp_path)  # the working directory holds no my-u.toml
    study = load_study("studies/s.toml")
    assert study.cells[0]["task"] == str((tmp_path / "studies" / "my-u.toml").resolve())
    assert study.cells[1]["task"] == "paper-box"


def test_sweep_runs_tables_report_and_resume(tmp_path, capsys, monkeypatch):
    path = _write(tmp_path)
    one, two = tmp_path / "one", tmp_path / "two"
    assert main(["sweep", str(path), "--quiet", "--jobs", "1", "--out", str(one)]) == 1  # backoff-vi, k = 1, fails
    assert "8 runs ok, 2 failed" in capsys.readouterr().out
    assert main(["sweep", str(path), "--quiet", "--jobs", "2", "--out", str(two)]) == 1
    assert (one / "results.csv").read_bytes() == (two / "results.csv").read_bytes()
    with open(one / "results.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == 4 * 2 * 3 and {r["agent"] for r in rows} == {"sarsa", "q"}
    with open(one / "cells.csv") as fh:
        cells = list(csv.DictReader(fh))
    failed = [c for c in cells if c["status"] == "failed"]
    assert len(failed) == 2 and "needs long histories" in failed[0]["error"]
    assert '"failed": 2' in (one / "study.json").read_text()
    assert read_status(one) == "complete"
    calls = []
    monkeypatch.setattr(sweep_mod._Unit, "__call__", lambda self: calls.append(1) or {"status": "failed", "error": "x"})
    assert main(["sweep", str(path), "--quiet", "--resume", "--out", str(one)]) == 1
    assert calls == []  # every unit was recorded: nothing runs again
    assert main(["sweep", "report", str(one)]) == 0
    report = (one / "report.md").read_text()
    assert "| task | cell | agent | k | alpha | trials | mean CRMs | vs optimum |" in report and "failed" in report
    assert re.search(r"\| paper-box \| sarsa-k2-\w+ \| sarsa \| 2 \| 0\.\d \| 6 \| [\d.]+ \| \+\d+\.\d% \|", report)
    for name in ("profile.png", "param_agent.png", "param_k.png", "param_alpha.png"):
        assert (one / name).exists()


def test_sweep_cli_errors(tmp_path, capsys):
    assert main(["sweep", "report"]) == 2
    assert "needs the study's run folder" in capsys.readouterr().err
    assert main(["sweep", str(_write(tmp_path, "name = 3\n[grid]\nagent=['sarsa']"))]) == 2
    assert "name must be 1-64 letters, digits" in capsys.readouterr().err
    study = _write(tmp_path)
    assert main(["sweep", str(study), "--address", "127.0.0.1:1", "--out", str(tmp_path / "o")]) == 2
    assert "--address names a Ray cluster: it needs --executor ray" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()
    assert main(["sweep", "report", str(tmp_path)]) == 2


def test_parquet_tables(tmp_path):
    pq = pytest.importorskip("pyarrow.parquet", reason="needs the extra: pip install 'crmgrasp[sweep]'")
    out = tmp_path / "run"
    assert main(["sweep", str(_write(tmp_path)), "--quiet", "--out", str(out)]) == 1
    assert pq.read_table(out / "results.parquet").num_rows == 24
    assert pq.read_table(out / "cells.parquet").num_rows == 10


@pytest.mark.slow
def test_ray_gives_the_local_results_on_one_and_two_nodes(tmp_path, capsys):
    ray = pytest.importorskip("ray", reason="needs the extra: pip install 'crmgrasp[ray]'")
    from ray.cluster_utils import Cluster

    path = _write(tmp_path)
    local, on_ray, on_cluster = tmp_path / "local", tmp_path / "ray", tmp_path / "cluster"
    assert main(["sweep", str(path), "--quiet", "--jobs", "1", "--out", str(local)]) == 1
    assert main(["sweep", str(path), "--quiet", "--jobs", "2", "--executor", "ray", "--out", str(on_ray)]) == 1
    assert (on_ray / "results.csv").read_bytes() == (local / "results.csv").read_bytes()
    cluster = Cluster(initialize_head=True, head_node_args={"num_cpus": 1})
    cluster.add_node(num_cpus=1)
    try:
        argv = ["sweep", str(path), "--quiet", "--executor", "ray", "--address", cluster.address]
        assert main([*argv, "--out", str(on_cluster)]) == 1
    finally:
        ray.shutdown()
        cluster.shutdown()
    assert (on_cluster / "results.csv").read_bytes() == (local / "results.csv").read_bytes()


@pytest.mark.parametrize(("signame", "code", "word"), [("SIGINT", 130, "interrupted"), ("SIGTERM", 143, "terminated")])
def test_ctrl_c_or_a_kill_leaves_a_resumable_study_and_no_workers(tmp_path, signame, code, word):
    import os
    import signal
    import subprocess
    import sys
    import time

    path = _write(
        tmp_path, STUDY.replace("episodes = 40", "episodes = 20000").replace("seeds = [0, 1]", "seeds = [0, 1, 2, 3]")
    )
    out = tmp_path / "run"
    argv = [sys.executable, "-m", "crmgrasp", "sweep", str(path), "--quiet", "--jobs", "2", "--out", str(out)]
    proc = subprocess.Popen(argv, stderr=subprocess.PIPE, text=True, preexec_fn=default_sigint)
    children = Path(f"/proc/{proc.pid}/task/{proc.pid}/children")
    workers: list[int] = []
    for _ in range(100):  # until both workers run (at most 10 s)
        time.sleep(0.1)
        workers = [int(p) for p in children.read_text().split()] if children.exists() else []
        if len(workers) >= 2:
            break
    time.sleep(1)
    proc.send_signal(getattr(signal, signame))
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == code and err.strip().endswith(f"crmgrasp sweep: {word}"), err
    assert read_status(out) == "interrupted"
    assert not (out / "results.csv").exists()  # tables are written only when every unit has run
    assert len(workers) >= 2
    for _ in range(50):  # the workers were stopped with the parent (reaped by init once gone)
        alive = [w for w in workers if Path(f"/proc/{w}").exists() and "Z" not in _state(w)]
        if not alive:
            break
        time.sleep(0.1)
    assert alive == [], f"workers outlived the parent: {alive}"
    assert os.getpid() not in workers


def _state(pid: int) -> str:
    """A process's state letter from /proc (``Z`` for a zombie; empty once gone)."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (OSError, IndexError):
        return "Z"


def test_unreachable_ray_address_is_one_line(tmp_path, capsys):
    pytest.importorskip("ray", reason="needs the extra: pip install 'crmgrasp[ray]'")
    argv = ["sweep", str(_write(tmp_path)), "--quiet", "--executor", "ray", "--address", "127.0.0.1:9"]
    assert main([*argv, "--out", str(tmp_path / "run")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Ray address 127.0.0.1:9 is unreachable" in err
    assert main([*argv[:-1], "nowhere", "--out", str(tmp_path / "run2")]) == 2
    assert "must be auto or HOST:PORT" in capsys.readouterr().err


def test_the_example_study_loads():
    from pathlib import Path

    study = load_study(Path(__file__).resolve().parents[1] / "examples" / "sarsa-alpha-q0.toml")
    assert len(study.cells) == 8 and len(study.seeds) == 10


def test_report_on_a_damaged_study_folder_is_one_line_and_reads_only_inside(tmp_path, capsys):
    tiny = 'name = "tiny"\ntrials = 2\nepisodes = 10\neval_episodes = 5\nseeds = [0]\n[[cell]]\nagent = "sarsa"\n'
    out = tmp_path / "s"
    assert main(["sweep", str(_write(tmp_path, tiny)), "--quiet", "--out", str(out)]) == 0
    capsys.readouterr()
    record = json.loads((out / "run.json").read_text())
    (unit,) = record["completed"]
    good = (out / "units" / f"{unit.replace(' ', '_')}.json").read_text()

    def damaged(change) -> str:
        rec = json.loads(json.dumps(record))
        change(rec)
        (out / "run.json").write_text(json.dumps(rec))
        assert main(["sweep", "report", str(out)]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "internal error" not in err
        return err

    outside = tmp_path / "secret.json"
    outside.write_text(good)  # a unit path in the record must not lead here
    assert "holds no readable study" in damaged(lambda r: r["config"]["study"].pop("cells"))
    assert "holds no readable study" in damaged(lambda r: r["config"]["study"].update(seeds="x"))
    (out / "units" / f"{unit.replace(' ', '_')}.json").unlink()
    assert "unit result" in damaged(lambda r: r["completed"][unit].update(file=str(outside)))
    (out / "units" / f"{unit.replace(' ', '_')}.json").write_text('{"trials": 3}')
    assert "is damaged" in damaged(lambda r: None)
    for field, value in (("summary.greedy_ci95_over_trials", 3), ("trials.greedy_mean_steps", ["x"])):
        part, key = field.split(".")
        doc = json.loads(good)
        doc[part][key] = value  # an internal error before (a TypeError, a ValueError)
        (out / "units" / f"{unit.replace(' ', '_')}.json").write_text(json.dumps(doc))
        assert f"is damaged ({field})" in damaged(lambda r: None)
    (out / "units" / f"{unit.replace(' ', '_')}.json").write_text(good)
    assert "holds no readable study" in damaged(lambda r: r.pop("config"))  # a KeyError before
    record["status"], record["pid"] = "running", 2**22 + 12345  # a study whose process is gone
    (out / "run.json").write_text(json.dumps(record))
    assert main(["sweep", "report", str(out)]) == 0
    assert "Status: killed." in (out / "report.md").read_text()


def test_a_ray_address_that_accepts_but_speaks_no_ray_is_bounded(tmp_path):
    """A loopback port that accepts TCP and never answers: one line within the bound, no hang."""
    pytest.importorskip("ray", reason="needs the extra: pip install 'crmgrasp[ray]'")
    import socket
    import subprocess
    import sys
    import threading
    import time

    server = socket.create_server(("127.0.0.1", 0))
    port, held = server.getsockname()[1], []

    def accept() -> None:
        server.settimeout(0.5)
        end = time.monotonic() + 60
        while time.monotonic() < end:
            try:
                held.append(server.accept()[0])  # accept, never speak
            except OSError:
                if server.fileno() == -1:
                    return

    threading.Thread(target=accept, daemon=True).start()
    code = (
        "import functools, crmgrasp.experiments.parallel as p\n"
        "p.RAY_TIMEOUT = 3.0\n"
        f"list(p.run_parallel([(0, functools.partial(abs, -1))], 1, 'ray', '127.0.0.1:{port}'))\n"
    )
    t0 = time.monotonic()
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    server.close()
    for conn in held:
        conn.close()
    assert res.returncode != 0 and time.monotonic() - t0 < 60
    assert f"Ray at 127.0.0.1:{port} did not answer within 3 s" in res.stderr


@pytest.mark.parametrize("info", [-1, "x", [], {"status": []}, {"status": "ok", "error": 3}, {}])
def test_a_resumed_study_with_a_damaged_unit_is_refused_in_one_line(tmp_path, capsys, info):
    """A unit of the record that is not what the sweep records (an internal error before: an
    AttributeError or an unhashable status) is one line, before any run; the report of a
    study none of whose units has an evaluation draws no legend (a warning before)."""
    import warnings

    tiny = 'name = "tiny"\ntrials = 1\nepisodes = 5\neval_episodes = 2\nseeds = [0]\n[[cell]]\nagent = "sarsa"\n'
    study, out = _write(tmp_path, tiny), tmp_path / "s"
    assert main(["sweep", str(study), "--quiet", "--out", str(out)]) == 0
    record = json.loads((out / "run.json").read_text())
    (unit,) = record["completed"]
    for name in (unit, "another unit"):
        rec = json.loads(json.dumps(record))
        rec["completed"][name] = info
        (out / "run.json").write_text(json.dumps(rec))
        capsys.readouterr()
        assert main(["sweep", str(study), "--quiet", "--out", str(out), "--resume"]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and f"is damaged (unit '{name}')" in err, err
    record["completed"][unit]["status"] = "failed"
    (out / "run.json").write_text(json.dumps(record))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert main(["sweep", "report", str(out)]) == 0


def test_the_python_api_of_a_sweep_checks_its_arguments(tmp_path):
    """``run_study`` and ``report`` called from Python with something else than a study, a run
    folder or a path: one line each (before, an ``AttributeError`` or ``TypeError``)."""
    from crmgrasp.experiments.runs import RunFolder
    from crmgrasp.experiments.study import study_from_dict

    study = study_from_dict({"trials": 1, "episodes": 2, "eval_episodes": 1, "cell": [{"task": "paper-box"}]})
    with pytest.raises(CrmgraspError, match="run_study takes a Study and a RunFolder, got None"):
        sweep_mod.run_study(None, RunFolder(tmp_path / "s", "sweep", "study", study.to_dict()))
    with pytest.raises(CrmgraspError, match="run_study takes a Study and a RunFolder, got Study"):
        sweep_mod.run_study(study, str(tmp_path / "s"))
    with pytest.raises(CrmgraspError, match="study folder path must be text or a path"):
        sweep_mod.report(None)

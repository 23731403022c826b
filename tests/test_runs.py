"""Run folders (run.json, refusal, --overwrite, --resume, statuses) and progress."""

from __future__ import annotations

import io
import json
import os
import subprocess
import sys

import numpy as np
import pytest

from crmgrasp._progress import Progress, Quiet
from crmgrasp._validation import CrmgraspError
from crmgrasp.cli import main
from crmgrasp.experiments.runs import RunFolder, default_run_dir, leftovers, read_status

from .signals import default_sigint

LEARN = ["learn", "--trials", "3", "--episodes", "40", "--eval-episodes", "10", "--quiet"]


def test_run_json_records_what_ran(tmp_path):
    out = tmp_path / "r"
    assert main([*LEARN, "--out", str(out)]) == 0
    rec = json.loads((out / "run.json").read_text())
    assert rec["status"] == "complete" and rec["command"] == "learn" and rec["task"] == "paper-box"
    assert rec["seed"] == 0 and rec["argv"][0] == "learn" and rec["ended"] >= rec["started"]
    assert {"numpy", "gymnasium"} <= set(rec["dependencies"]) and rec["config"]["trials"] == 3
    assert read_status(out) == "complete"
    assert main(["status", str(out)]) == 0


def test_files_respect_the_umask(tmp_path):
    old = os.umask(0o022)
    try:
        assert main([*LEARN, "--out", str(tmp_path / "r")]) == 0
    finally:
        os.umask(old)
    assert (tmp_path / "r" / "summary.json").stat().st_mode & 0o777 == 0o644


def test_default_folder_is_under_runs_and_never_reused(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(LEARN) == 0 and main(LEARN) == 0
    made = sorted(p.name for p in (tmp_path / "runs").iterdir())
    assert len(made) == 2 and all(n.startswith("learn-paper-box-") for n in made)
    assert default_run_dir("learn", "paper-box", tmp_path / "runs").name not in made


def test_existing_folder_is_refused_then_overwritten_or_resumed(tmp_path, capsys):
    out = tmp_path / "r"
    assert main([*LEARN, "--out", str(out)]) == 0
    before = (out / "curve.csv").read_bytes()
    assert main([*LEARN, "--out", str(out)]) == 2
    assert "already holds a complete learn run" in capsys.readouterr().err
    assert (out / "curve.csv").read_bytes() == before
    assert main([*LEARN, "--out", str(out), "--resume"]) == 0
    assert "was already complete; --resume reran nothing" in capsys.readouterr().err
    assert (out / "curve.csv").read_bytes() == before
    (out / "stray.txt").write_text("x")
    assert main([*LEARN, "--out", str(out), "--overwrite"]) == 0
    assert not (out / "stray.txt").exists() and (out / "curve.csv").read_bytes() == before


def test_foreign_folders_are_never_deleted(tmp_path, capsys):
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "thesis.tex").write_text("precious")
    for flag in ([], ["--overwrite"], ["--resume"]):
        assert main([*LEARN, "--out", str(mine), *flag]) == 2
        err = capsys.readouterr().err
        assert "not a crmgrasp run folder" in err or "not empty" in err, err
    assert (mine / "thesis.tex").read_text() == "precious"


def test_resume_refuses_other_settings_and_damaged_records(tmp_path, capsys):
    out = tmp_path / "r"
    assert main([*LEARN, "--out", str(out)]) == 0
    assert main([*LEARN[:2], "5", *LEARN[3:], "--out", str(out), "--resume"]) == 2
    assert "trials = 3" in capsys.readouterr().err
    (out / "run.json").write_text("{not json")
    assert main([*LEARN, "--out", str(out), "--resume"]) == 2
    assert "damaged" in capsys.readouterr().err
    assert main([*LEARN, "--out", str(tmp_path / "empty"), "--resume"]) == 2


@pytest.mark.parametrize("score", ["x", None, [], True, 1e309])
def test_a_complete_run_with_a_damaged_unit_is_refused_in_one_line(tmp_path, capsys, score):
    """A resumed run that was complete says so only once it has ended well: a damaged unit
    found after the record was claimed (a ``score`` that is not a finite number: an internal
    error before) is one line, with no notice before it."""
    out = tmp_path / "r"
    assert main([*LEARN, "--out", str(out)]) == 0
    record = json.loads((out / "run.json").read_text())
    unit = next(iter(record["completed"]))
    record["completed"][unit]["score"] = score
    (out / "run.json").write_text(json.dumps(record))
    capsys.readouterr()
    assert main([*LEARN, "--out", str(out), "--resume"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"is damaged ({unit}: score)" in err, err


@pytest.mark.parametrize(
    ("array", "change"),
    [
        ("steps", lambda a: a.astype(str)),
        ("success", lambda a: np.array(3)),
        ("greedy_steps", lambda a: a[:, :0]),
        ("greedy_success", lambda a: a[..., None]),
        ("checkpoints", lambda a: a * np.nan),
        ("checkpoint_steps", lambda a: a[..., None]),
        ("steps", lambda a: -a),
    ],
)
def test_a_damaged_trials_file_is_refused_in_one_line(tmp_path, capsys, array, change):
    """An array of a saved group of trials that training would not write (an internal error
    before, or, for negative CRM counts, results resumed from garbage) is one line naming it."""
    out = tmp_path / "r"
    assert main([*LEARN, "--out", str(out)]) == 0
    path = sorted((out / "trials").glob("*.npz"))[0]
    with np.load(path) as z:
        arrays = {k: z[k] for k in z.files}
    arrays[array] = change(arrays[array])
    with open(path, "wb") as fh:
        np.savez(fh, **arrays)
    capsys.readouterr()
    assert main([*LEARN, "--out", str(out), "--resume"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"is damaged ({array})" in err, err


def test_interrupted_run_resumes_to_identical_results(tmp_path, monkeypatch):
    import crmgrasp.experiments.learning as learning

    full, cut = tmp_path / "full", tmp_path / "cut"
    argv = ["learn", "--trials", "6", "--episodes", "60", "--eval-episodes", "10", "--quiet"]
    assert main([*argv, "--out", str(full)]) == 0
    real, calls = learning._save_part, []

    def save_then_stop(*a, **k):
        real(*a, **k)
        calls.append(1)
        if len(calls) == 3:
            raise KeyboardInterrupt

    monkeypatch.setattr(learning, "_save_part", save_then_stop)
    assert main([*argv, "--out", str(cut)]) == 130
    assert read_status(cut) == "interrupted"
    assert len(json.loads((cut / "run.json").read_text())["completed"]) == 3
    monkeypatch.setattr(learning, "_save_part", real)
    assert main([*argv, "--out", str(cut), "--resume"]) == 0
    for name in ("curve.csv", "checkpoints.csv", "policy.json"):
        assert (cut / name).read_bytes() == (full / name).read_bytes(), name


def test_a_killed_run_is_not_complete(tmp_path):
    run = RunFolder(tmp_path / "r", "learn", "paper-box", {"a": 1})
    rec = json.loads((run.path / "run.json").read_text())
    assert rec["status"] == "running" and read_status(run.path) == "running"  # this process is alive
    rec["pid"] = 2**22 + 12345  # a pid that does not exist
    (run.path / "run.json").write_text(json.dumps(rec))
    assert read_status(run.path) == "killed"
    assert main(["status", str(run.path)]) == 1
    run._unlock()  # what the process's death does to its lock
    again = RunFolder(run.path, "learn", "paper-box", {"a": 1}, resume=True)
    assert again.resumed


def test_a_folder_is_claimed_by_one_run_at_a_time(tmp_path):
    first = RunFolder(tmp_path / "r", "learn", "paper-box", {"a": 1})
    with pytest.raises(CrmgraspError, match="is in use by another crmgrasp run"):
        RunFolder(tmp_path / "r", "learn", "paper-box", {"a": 1})
    with pytest.raises(CrmgraspError, match="is in use by another crmgrasp run"):
        RunFolder(tmp_path / "r", "learn", "paper-box", {"a": 1}, overwrite=True)
    assert json.loads((tmp_path / "r" / "run.json").read_text())["pid"] == os.getpid()
    first.finish("complete")  # finishing releases the folder
    RunFolder(tmp_path / "r", "learn", "paper-box", {"a": 1}, overwrite=True).finish("complete")
    with pytest.raises(CrmgraspError, match="holds no run to resume"):
        RunFolder(tmp_path / "new", "learn", "paper-box", {}, resume=True)
    assert not (tmp_path / "new").exists()  # a refused claim leaves no folder behind


def test_two_learn_processes_into_one_folder_one_is_refused(tmp_path):
    """Started together into one empty --out: one run completes, the other is refused in one line."""
    out = tmp_path / "r"
    out.mkdir()
    cmd = [sys.executable, "-m", "crmgrasp", *LEARN, "--out", str(out)]
    procs = [subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True) for _ in range(2)]
    errors = [p.communicate(timeout=120)[1] for p in procs]  # communicate closes the pipes
    results = [(p.returncode, err) for p, err in zip(procs, errors)]
    codes = sorted(code for code, _ in results)
    assert codes == [0, 2], results
    refused = next(err for code, err in results if code == 2)
    assert refused.count("\n") == 1 and ("in use by" in refused or "already holds a complete" in refused)
    assert read_status(out) == "complete"


def test_cut_short_writes_are_named_by_status_and_swept_by_resume(tmp_path, capsys):
    run = RunFolder(tmp_path / "r", "learn", "paper-box", {"a": 1})
    (run.path / "sub").mkdir()
    (run.path / "sub" / ".crmgrasp-x1y2.tmp").write_text("half a file")
    run.finish("interrupted")
    assert leftovers(run.path) == ["sub/.crmgrasp-x1y2.tmp"]
    assert main(["status", str(run.path)]) == 1
    assert "1 temporary file(s) of cut-short writes: sub/.crmgrasp-x1y2.tmp" in capsys.readouterr().out
    RunFolder(run.path, "learn", "paper-box", {"a": 1}, resume=True).finish("complete")
    assert leftovers(run.path) == [] and (run.path / "sub").is_dir()


def test_failed_run_says_why(tmp_path):
    with pytest.raises(CrmgraspError):
        with RunFolder(tmp_path / "r", "learn", "paper-box", {}):
            raise CrmgraspError("boom")
    rec = json.loads((tmp_path / "r" / "run.json").read_text())
    assert rec["status"] == "failed" and rec["error"] == "boom"


def test_progress_lines_and_quiet():
    buf = io.StringIO()
    p = Progress(buf, live=False, interval=0.0)
    with p.stage("learn", 200, "episodes"):
        p.advance(100)
        p.advance(100)
    text = buf.getvalue()
    assert "100/200 episodes" in text and "learn: done 200/200 episodes" in text
    live = io.StringIO()
    q = Progress(live, live=True)
    q.stage("x", 4, "steps")
    q.advance(2)
    assert "50%" in q.line() and "2/4 steps" in q.line()
    q.end()
    assert live.getvalue().startswith("\rx  [") and live.getvalue().endswith("\r")  # redrawn, then cleared
    silent = Quiet()
    silent.stage("x", 3)
    silent.advance(3)
    silent.end()  # nothing to check but that it is silent and does not fail


def test_worker_processes_give_the_same_results(tmp_path):
    from crmgrasp.experiments.learning import LearnerSpec, learn
    from crmgrasp.experiments.parallel import usable_jobs
    from crmgrasp.tasks import paper_box

    task = paper_box()
    kw = dict(trials=6, episodes=50, seed=2, eval_episodes=10, checkpoint_episodes=5)
    one = learn(task, LearnerSpec("sarsa", 2), **kw)
    two = learn(task, LearnerSpec("sarsa", 2), jobs=2, **kw)
    for name in ("steps", "success", "greedy_steps", "checkpoint_steps"):
        assert (getattr(one.result, name) == getattr(two.result, name)).all(), name
    assert one.policy.to_dict() == two.policy.to_dict()
    assert usable_jobs(0) >= 1 and usable_jobs(3) == 3
    with pytest.raises(CrmgraspError, match="jobs must be an integer >= 0"):
        usable_jobs(-1)
    out = tmp_path / "r"
    argv = ["learn", "--trials", "4", "--episodes", "30", "--eval-episodes", "5", "--quiet", "--jobs", "2"]
    assert main([*argv, "--out", str(out)]) == 0 and read_status(out) == "complete"


def test_ctrl_c_with_workers_is_one_line_and_interrupted(tmp_path):
    import signal
    import subprocess
    import sys
    import time

    argv = ["learn", "--trials", "8", "--episodes", "200000", "--jobs", "2", "--quiet", "--out", str(tmp_path / "r")]
    proc = subprocess.Popen(
        [sys.executable, "-m", "crmgrasp", *argv], stderr=subprocess.PIPE, text=True, preexec_fn=default_sigint
    )
    time.sleep(4)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130 and err.strip() == "crmgrasp learn: interrupted", err
    assert read_status(tmp_path / "r") == "interrupted"


def test_the_record_names_the_code_it_ran_without_git(tmp_path):
    """run.json holds a digest of the installed source, which pip-installed copies have too."""
    from crmgrasp.experiments.runs import source_digest

    run = RunFolder(tmp_path / "r", "learn", "paper-box", {})
    run.finish("complete")
    rec = json.loads((run.path / "run.json").read_text())
    assert rec["source_sha256"] == source_digest() and len(rec["source_sha256"]) == 64
    assert rec["version"] != "unknown"


def test_more_jobs_than_calls_start_one_worker_per_call(monkeypatch):
    """--jobs beyond the number of units starts only as many workers as there are units."""
    import functools

    from crmgrasp.experiments import parallel

    started = []
    real = parallel.ProcessPoolExecutor

    def recording(*args, max_workers, **kwargs):
        started.append(max_workers)
        return real(*args, max_workers=max_workers, **kwargs)

    monkeypatch.setattr(parallel, "ProcessPoolExecutor", recording)
    calls = [(i, functools.partial(abs, -i)) for i in range(3)]
    assert dict(parallel.run_parallel(calls, jobs=16)) == {0: 0, 1: 1, 2: 2}
    assert started == [3]


def test_units_go_to_an_append_only_journal_folded_in_at_the_end(tmp_path):
    """A unit done appends one line; run.json is written at the start and the end only, and
    a killed run's journal (its last line cut short by the kill) still says what was done."""
    from crmgrasp.experiments.runs import JOURNAL

    run = RunFolder(tmp_path / "r", "sweep", "t", {})
    before = (run.path / "run.json").read_bytes()
    for i in range(50):
        run.complete(f"unit {i}", {"status": "ok", "value": float("nan") if i == 3 else i})
    assert (run.path / "run.json").read_bytes() == before  # not rewritten per unit
    assert len((run.path / JOURNAL).read_text().splitlines()) == 50
    with open(run.path / JOURNAL, "a") as fh:
        fh.write('{"unit": "unit 50", "info": {"sta')  # the append a kill cut short
    from crmgrasp.experiments.runs import _read

    rec = _read(run.path)
    assert len(rec["completed"]) == 50 and rec["completed"]["unit 3"]["value"] is None
    run._unlock()  # the kill: its lock goes, and its pid with it
    killed = json.loads((run.path / "run.json").read_text())
    (run.path / "run.json").write_text(json.dumps({**killed, "pid": 2**22 + 12345}))
    again = RunFolder(run.path, "sweep", "t", {}, resume=True)
    assert again.done("unit 49") == {"status": "ok", "value": 49} and again.done("unit 50") is None
    assert not (run.path / JOURNAL).exists()  # folded into run.json when the resumed run started
    again.complete("unit 50", "ok")
    again.finish("complete")
    assert not (run.path / JOURNAL).exists()
    assert len(json.loads((run.path / "run.json").read_text())["completed"]) == 51


def test_a_journal_damaged_before_its_last_line_is_one_line(tmp_path, capsys):
    from crmgrasp.experiments.runs import JOURNAL

    run = RunFolder(tmp_path / "r", "learn", "paper-box", {})
    run.complete("a")
    run.finish("interrupted")
    (run.path / JOURNAL).write_text('{"unit": "a", "info": true}\nnot json\n{"unit": "b", "info": true}\n')
    assert main(["status", str(run.path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "run journal" in err and "is damaged (line 2)" in err


def test_workers_are_spawned_once_torch_is_loaded(monkeypatch):
    """A forked worker inherits torch's thread pool broken and hangs (seen: ``reproduce(...,
    jobs=2)`` after a torch matrix product never finished); with torch loaded, workers spawn."""
    import multiprocessing
    import types

    from crmgrasp.experiments.parallel import FORK_UNSAFE, start_method

    forkable = "fork" in multiprocessing.get_all_start_methods()
    for name in FORK_UNSAFE:
        monkeypatch.delitem(sys.modules, name, raising=False)
    assert start_method() == ("fork" if forkable else "spawn")
    monkeypatch.setitem(sys.modules, "torch", types.ModuleType("torch"))
    assert start_method() == "spawn"


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda p: RunFolder(p / "r", "learn", "paper-box", {"x": 1j}), "a run's config must be JSON data"),
        (lambda p: RunFolder(p / "r", None, "paper-box", {}), "a run's command name must be text, got None"),
        (lambda p: default_run_dir("learn", 3, root=p), "a run's task name must be text, got 3"),
        (lambda p: default_run_dir("learn", "t", root=None), "runs folder path must be text or a path"),
        (lambda p: read_status(None), "run folder path must be text or a path"),
        (lambda p: leftovers(b"x"), "run folder path must be text or a path"),
    ],
)
def test_a_run_folder_of_the_wrong_kind_is_one_line_and_makes_nothing(tmp_path, call, message):
    """Names, a config JSON cannot hold and folder paths are checked before a folder is made."""
    with pytest.raises(CrmgraspError, match=message):
        call(tmp_path)
    assert list(tmp_path.iterdir()) == []

"""Hostile run records, at scale: every field of a run folder's ``run.json`` set to every value of a hostile list.

It makes two small run folders with the command line, a ``learn`` run (paper-box, 2 trials of
10 episodes) and a ``sweep`` run (a study of 2 cells x 2 seeds), both complete. For every leaf of
each folder's ``run.json`` (a key, or an item of a list: ``benchmarks/task_file_fuzz.py``'s
``leaves``) and every value of its ``HOSTILE`` list, plus deleting the leaf, it copies the
folder, writes the changed record into the copy and runs on it what a user runs on a folder:
``crmgrasp status``, the same command again with ``--resume``, and for the study ``crmgrasp
sweep report``, each in this process with warnings raised as errors and 20 s at most
(``benchmarks/cli_fuzz.py``'s ``run_case``). A command passes if it ends with status 0, with
status 2 and one line on standard error, or with status 1 and nothing on standard error where
that status means something (``status``: the run is not complete; ``sweep``: a cell failed);
anything else (an internal error, a second line, the time limit) is reported with the leaf,
value and command. It prints one JSON object and exits 1 if a command failed.

``tests/test_runs.py`` checks chosen damaged folders; this runs every field. Measured
2026-12-07: 10,143 commands (5,658 on the learn run, 4,485 on the study) in 736 s on one core
beside other work, none failed. A first version of this script, at d15454e before the fixes
it led to, reported 2,449 of them: a resumed run that was already complete said so before it
checked the record, so every refusal of a damaged record came after that notice (two lines); a
unit's ``score`` that was not a number and a record without ``config`` were internal errors; and
``sweep report`` on a record whose cells had no evaluation drew an empty legend (a warning).

``--kind sweep-unit`` changes the study's first unit result (``units/*.json``) instead, leaf by
leaf the same way, and runs ``sweep report`` and the resumed study on it: 2,070 commands in 305 s,
none failed. Before its fix (at fd7d8e5, a first version that left out the curve's items but the
first: 1,886 commands), 41 were internal errors: a unit whose interval, mean or trial values were
not numbers, or whose summary lacked a key.

Usage: ``python benchmarks/run_record_fuzz.py [--kind learn|sweep|sweep-unit ...]``.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import math
import shutil
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))
import cli_fuzz
import task_file_fuzz

SECONDS = 20.0
"""Most seconds one command may take on a variant."""

STUDY = 'name = "s"\ntrials = 1\nepisodes = 5\neval_episodes = 3\nseeds = [0, 1]\n[grid]\nagent = ["sarsa", "q"]\n'
"""The study of the ``sweep`` folder."""


KINDS = ("learn", "sweep", "sweep-unit")
"""What is changed: the record of the learn run, the record of the study, the first unit result of
the study (``units/*.json``: what its tables and report read)."""


def commands(kind: str, root: Path) -> tuple[list[str], list[list[str]]]:
    """The command line that makes ``kind``'s folder (``--out`` to be added) and the commands run
    on each variant (``{d}`` standing for the folder)."""
    if kind == "learn":
        make = ["learn", "--task", "paper-box", "--trials", "2", "--episodes", "10", "--eval-episodes", "3", "--quiet"]
        return make, [["status", "{d}"], [*make, "--out", "{d}", "--resume"]]
    study = root / "study.toml"
    study.write_text(STUDY)
    make = ["sweep", str(study), "--quiet"]
    runs = [["sweep", "report", "{d}"], [*make, "--out", "{d}", "--resume"]]
    return make, runs if kind == "sweep-unit" else [["status", "{d}"], *runs]


def target(kind: str, folder: Path) -> Path:
    """The file of ``folder`` that ``kind``'s variants change."""
    return min((folder / "units").iterdir()) if kind == "sweep-unit" else folder / "run.json"


def passes(argv: list[str], outcome: str, problem: str | None) -> bool:
    """Whether a command's outcome (``cli_fuzz.run_case``) is what a user should see: it ran,
    was refused in one line, or ended with status 1 silently where status 1 means something."""
    if outcome in ("ran", "refused"):
        return True
    meaningful = argv[0] == "status" or (argv[0] == "sweep" and argv[1] != "report")
    return outcome == "failed" and meaningful and problem is not None and problem.startswith("status 1, 0 lines")


def fuzz(kind: str, root: Path) -> dict[str, Any]:
    """Every variant of ``kind``'s run record, each command on it: counts and failures."""
    from crmgrasp.cli import main

    make, runs = commands(kind, root)
    pristine = root / kind
    with contextlib.redirect_stdout(io.StringIO()):
        assert main([*make, "--out", str(pristine)]) == 0, kind
    doc = json.loads(target(kind, pristine).read_text())
    count, failures = 0, []
    for path in task_file_fuzz.leaves(doc):
        for value in (*task_file_fuzz.HOSTILE, task_file_fuzz.DELETE):
            folder = root / "variant"
            shutil.rmtree(folder, ignore_errors=True)
            shutil.copytree(pristine, folder)
            target(kind, folder).write_text(json.dumps(task_file_fuzz.mutated(doc, path, value)))
            for run in runs:
                argv = [part.format(d=folder) for part in run]
                count += 1
                outcome, problem = cli_fuzz.run_case(argv, SECONDS)
                if not passes(argv, outcome, problem):
                    shown = "delete" if value is task_file_fuzz.DELETE else repr(value)
                    text = (problem or outcome).replace(str(folder), "DIR")
                    leaf = ".".join(map(str, path))
                    failures.append({"leaf": leaf, "value": shown, "command": " ".join(run[:2]), "problem": text})
    return {"kind": kind, "commands": count, "failed": len(failures), "failures": failures[:20]}


def main(argv: list[str] | None = None) -> dict[str, Any]:
    from crmgrasp.kernels import compiling

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--kind", action="append", choices=KINDS, help="(default: every kind)")
    args = parser.parse_args(argv)
    t0, after = time.perf_counter(), compiling.AFTER
    compiling.AFTER = math.inf  # the notice while numba compiles would be a second line
    rows = []
    try:
        with tempfile.TemporaryDirectory(prefix="crmgrasp-record-fuzz-") as tmp:
            for kind in args.kind or KINDS:
                rows.append(fuzz(kind, Path(tmp)))
                print(f"{kind}: {rows[-1]['commands']} commands, {rows[-1]['failed']} failed", file=sys.stderr)
    finally:
        compiling.AFTER = after
    out = {
        "commands": sum(r["commands"] for r in rows),
        "failed": sum(r["failed"] for r in rows),
        "seconds": round(time.perf_counter() - t0, 1),
        "kinds": rows,
    }
    print(json.dumps(out, indent=1))
    return out


if __name__ == "__main__":
    sys.exit(1 if main()["failed"] else 0)

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

``--kind learn-trials`` damages each array of the learn run's first saved group of trials
(``trials/*.npz``) in each of 10 ways (deleted, a scalar, empty, a row more, an axis more,
text, NaN, negative, booleans, objects) and resumes the run: 60 commands, none failed (58
refused in one line; the 2 that ran turned booleans into booleans). Before its fix (at 4600dce)
16 were internal errors (an array of the wrong shape or kind met in concatenation or
arithmetic) and 26 more resumed from the damaged arrays without a word (NaN or negative CRM
counts, a row too many, empty checkpoints).

Usage: ``python benchmarks/run_record_fuzz.py [--kind learn|sweep|sweep-unit|learn-trials ...]``.
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
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import cli_fuzz
import task_file_fuzz

SECONDS = 20.0
"""Most seconds one command may take on a variant."""

STUDY = 'name = "s"\ntrials = 1\nepisodes = 5\neval_episodes = 3\nseeds = [0, 1]\n[grid]\nagent = ["sarsa", "q"]\n'
"""The study of the ``sweep`` folder."""


KINDS = ("learn", "sweep", "sweep-unit", "learn-trials")
"""What is changed: the record of the learn run, the record of the study, the first unit result of
the study (``units/*.json``: what its tables and report read), the learn run's first saved group
of trials (``trials/*.npz``: its arrays, each changed by each of [`ARRAY_CHANGES`][])."""

ARRAY_CHANGES: dict[str, Callable[[np.ndarray], np.ndarray | None]] = {
    "delete": lambda a: None,
    "a scalar": lambda a: np.array(3),
    "empty": lambda a: a[:0],
    "one row more": lambda a: np.concatenate([a, a[:1]]) if a.ndim else a,
    "one axis more": lambda a: a[..., None],
    "text": lambda a: a.astype(str),
    "NaN": lambda a: a * np.nan,
    "negative": lambda a: -np.abs(a.astype(float)) - 1,
    "booleans": lambda a: a.astype(bool),
    "objects": lambda a: np.array([None] * max(a.size, 1), dtype=object),
}
"""How each array of a saved group of trials is damaged, in turn."""


def commands(kind: str, root: Path) -> tuple[list[str], list[list[str]]]:
    """The command line that makes ``kind``'s folder (``--out`` to be added) and the commands run
    on each variant (``{d}`` standing for the folder)."""
    if kind.startswith("learn"):
        make = ["learn", "--task", "paper-box", "--trials", "2", "--episodes", "10", "--eval-episodes", "3", "--quiet"]
        resume = [*make, "--out", "{d}", "--resume"]
        return make, [resume] if kind == "learn-trials" else [["status", "{d}"], resume]
    study = root / "study.toml"
    study.write_text(STUDY)
    make = ["sweep", str(study), "--quiet"]
    runs = [["sweep", "report", "{d}"], [*make, "--out", "{d}", "--resume"]]
    return make, runs if kind == "sweep-unit" else [["status", "{d}"], *runs]


def target(kind: str, folder: Path) -> Path:
    """The file of ``folder`` that ``kind``'s variants change."""
    if kind == "learn-trials":
        return min((folder / "trials").glob("*.npz"))
    return min((folder / "units").iterdir()) if kind == "sweep-unit" else folder / "run.json"


def variants(kind: str, pristine: Path) -> Iterator[tuple[str, str, Callable[[Path], Any]]]:
    """``(leaf, value shown, write)`` of every variant of ``kind``, ``write(folder)`` putting it
    into a copy of ``pristine``."""
    if kind == "learn-trials":
        with np.load(target(kind, pristine)) as z:
            arrays = {name: z[name] for name in z.files}
        for name, array in arrays.items():
            for label, change in ARRAY_CHANGES.items():
                changed = {**arrays, name: change(array)}
                kept = {k: v for k, v in changed.items() if v is not None}
                yield name, label, lambda folder, kept=kept: np.savez(target(kind, folder), **kept)
        return
    doc = json.loads(target(kind, pristine).read_text())
    for path in task_file_fuzz.leaves(doc):
        for value in (*task_file_fuzz.HOSTILE, task_file_fuzz.DELETE):
            text = json.dumps(task_file_fuzz.mutated(doc, path, value))
            shown = "delete" if value is task_file_fuzz.DELETE else repr(value)
            yield ".".join(map(str, path)), shown, lambda folder, text=text: target(kind, folder).write_text(text)


def passes(argv: list[str], outcome: str, problem: str | None) -> bool:
    """Whether a command's outcome (``cli_fuzz.run_case``) is what a user should see: it ran,
    was refused in one line, or ended with status 1 silently where status 1 means something."""
    if outcome in ("ran", "refused"):
        return True
    meaningful = argv[0] == "status" or (argv[0] == "sweep" and argv[1] != "report")
    return outcome == "failed" and meaningful and problem is not None and problem.startswith("status 1, 0 lines")


def fuzz(kind: str, root: Path) -> dict[str, Any]:
    """Every variant of ``kind``, each command on it: the commands, those that ran (status 0: a
    damaged file that a command reads without a word shows here, not as a failure) and the
    failures."""
    from crmgrasp.cli import main

    make, runs = commands(kind, root)
    pristine = root / kind
    with contextlib.redirect_stdout(io.StringIO()):
        assert main([*make, "--out", str(pristine)]) == 0, kind
    count, ran, failures = 0, 0, []
    for leaf, shown, write in variants(kind, pristine):
        folder = root / "variant"
        shutil.rmtree(folder, ignore_errors=True)
        shutil.copytree(pristine, folder)
        write(folder)
        for run in runs:
            argv = [part.format(d=folder) for part in run]
            count += 1
            outcome, problem = cli_fuzz.run_case(argv, SECONDS)
            ran += outcome == "ran"
            if not passes(argv, outcome, problem):
                text = (problem or outcome).replace(str(folder), "DIR")
                failures.append({"leaf": leaf, "value": shown, "command": " ".join(run[:2]), "problem": text})
    return {"kind": kind, "commands": count, "ran": ran, "failed": len(failures), "failures": failures[:20]}


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

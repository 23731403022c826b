"""Hostile command lines, at scale: every option of every ``crmgrasp`` command given every value
of a hostile list.

For each command it starts from a short, working command line ([`BASES`][]: tiny budgets,
``--quiet``, a fresh output path) and, for each of the command's options and positional
arguments that takes a value, replaces or adds that one value for each of [`HOSTILE`][]
(empty and blank strings, signs, zero, NaN and infinities, overflowing, underflowing and
5,000-digit numbers, other scripts' digits, underscores and hexadecimal, unknown names,
wrong point formats, missing, unreadable and malformed files, modules that are not task
factories). Each command line runs in this process through ``crmgrasp.cli.main``, in a
scratch folder of its own, with Python's warnings raised as errors and a time limit
(``--seconds``, 3 by default: a command still running then has passed its checks and begun
its work). A command line passes if it exits 0 (``ran``), exits 2 with one line on standard
error of under 400 characters (``refused``: the message a user sees) or reaches the time
limit; anything else (status 1, the CLI's "internal error", an exception escaping ``main``, a
warning, a message of several lines, another status) is reported with the command line. It
prints one JSON object and exits 1 if a command line failed. (Run as root, a value such as
``/tmp/x`` given to ``--out`` writes there: the values here name no place a run could create.)

The tests of bad input check chosen cases; this runs every option. Measured 2026-12-07 on the
2-core machine beside other work: 4,658 command lines of the 15 commands in 205 s; 240 ran,
4,393 were refused in one line, 25 reached the time limit, none failed. (Which values run and
which are refused depends on what the earlier cases wrote: ``--out a`` is refused once a case
has made the run folder ``a``.) With ``--command learn --command pomdp --command compare
--seconds 40`` every command line of those three finishes within the limit: 1,972 command lines
in 8 minutes, 146 ran, 1,826 refused, none failed. Before the fixes of
that day three kinds failed: a cell of 1e-320 m (``pomdp --cell``) and a ``backoff-vi`` decay
of 1e-320 (``learn --decay``) raised OverflowError (status 1, "internal error"), and 11
messages echoed a 5,000-digit value whole (a choice, a point, a file name, a run folder).

Usage: ``python benchmarks/cli_fuzz.py [--command NAME ...] [--seconds S]``.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import io
import json
import math
import os
import signal
import sys
import tempfile
import time
import warnings
from collections.abc import Iterator
from pathlib import Path
from typing import Any

HOSTILE: tuple[str, ...] = (
    "",
    " ",
    "-1",
    "0",
    "1",
    "0.5",
    "-0.0",
    "1e-320",
    "1e309",
    "nan",
    "inf",
    "-inf",
    "9" * 5000,
    "1_000",
    "0x10",
    "\u0661\u0662",  # Arabic-Indic digits
    "\uff11",  # a full-width 1
    "a",
    "C9",
    "x,y",
    "0,0",
    "0,0,0",
    "1e9,1e9",
    "nan,0",
    "-0.15,-0.02",
    "missing.toml",
    "bad.toml",
    "garbage.json",
    "/dev/null",
    "/dev/null/file",  # not a folder, even for root
    ".",
    "os:getcwd",
    "math:pi",
    "no_such_module:factory",
)
"""The values every option and positional argument takes, in turn."""

NEAR = ["--a", "-0.15,-0.02", "--b", "-0.10,-0.05"]

BASES: dict[str, list[str]] = {
    "crm": [*NEAR, "--crm", "C1"],
    "show": [*NEAR, "--out", "{out}/scene.png"],
    "reproduce": ["figure4", "--quick", "--quiet", "--out", "{out}/r"],
    "learn": ["--trials", "1", "--episodes", "3", "--eval-episodes", "3", "--quiet", "--out", "{out}/r"],
    "evaluate": ["--policy", "{policy}", "--episodes", "3", "--quiet"],
    "bench": ["--smoke", "--rounds", "1"],
    "references": ["--starts", "8", "--quiet"],
    "plan": ["--worlds", "4", "--heldout", "4", "--quiet", "--out", "{out}/r"],
    "compare": ["--quick", "--quiet", "--out", "{out}/r"],
    "pomdp": [
        "--cell",
        "0.05",
        "--samples",
        "20",
        "--starts",
        "10",
        "--episodes",
        "2",
        "--quiet",
        "--out",
        "{out}/m.pomdp",
    ],
    "run": ["--policy", "{policy}", *NEAR, "--log", "{out}/log.jsonl"],
    "sweep": ["{study}", "--quiet", "--out", "{out}/r"],
    "tasks": [],
    "task-template": [],
    "status": ["{run}"],
}
"""A short command line of each command that works: ``{out}`` is the case's scratch folder,
``{policy}``, ``{run}`` and ``{study}`` files the setup writes."""

FIRST_POSITIONAL = ("experiments", "target", "run")
"""The positional arguments that are the first word of their command's base line."""

STUDY = """name = "fuzz"
trials = 1
episodes = 3
eval_episodes = 3
seeds = [0]

[grid]
task = ["paper-box"]
agent = ["sarsa"]
alpha = [0.3]
"""


class _TimeUp(BaseException):
    """The case's time limit (a BaseException, so that the CLI's own handlers let it pass)."""


def _alarm(signum: int, frame: Any) -> None:
    raise _TimeUp


def options(command: str) -> list[tuple[str | None, str]]:
    """``(option string or None for a positional, dest)`` of every argument of ``command``
    that takes a value."""
    from crmgrasp.cli.parser import build_parser

    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    out: list[tuple[str | None, str]] = []
    for action in sub.choices[command]._actions:
        if isinstance(action, argparse._HelpAction) or action.nargs == 0:
            continue
        out.append((action.option_strings[0] if action.option_strings else None, action.dest))
    return out


def agent_for(dest: str) -> list[str]:
    """For ``learn``: the options that choose an agent taking parameter ``dest`` (the first
    registered one; the prior's options take ``model-vi``), so that the value reaches the
    agent's own checks and not only "does not apply"; none for the default agent's own."""
    from crmgrasp.agents.training import AGENTS, agent_parameters

    if dest in ("prior_task", "prior_episodes"):
        return ["--agent", "model-vi"]
    if dest in agent_parameters("sarsa"):
        return []
    for name in AGENTS:
        if dest in agent_parameters(name):
            return ["--agent", name, *(["--offset-grid", "9"] if name == "refine-vi" else [])]
    return []


def command_line(command: str, option: str | None, dest: str, value: str, fill: dict[str, str]) -> list[str]:
    """The base command line of ``command`` with ``option`` (or the positional ``dest``) set to
    ``value`` (and, for ``learn``, an agent that takes it: [`agent_for`][])."""
    base = [part.format(**fill) for part in BASES[command]]
    if command == "learn" and option not in ("--agent", "--offset-grid"):
        base += agent_for(dest)
    if option is not None:
        if option in base:
            i = base.index(option)
            return [command, *base[:i], option, value, *base[i + 2 :]]
        return [command, *base, option, value]
    if dest in FIRST_POSITIONAL:  # the base's first word
        return [command, value, *base[1:]]
    return [command, *base, value]  # sweep's folder, after its target


def run_case(argv: list[str], seconds: float) -> tuple[str, str | None]:
    """Run ``crmgrasp argv`` here: ``(outcome, problem)``, the outcome one of ``ran`` (status
    0), ``refused`` (status 2 in one line), ``time limit`` (still running after ``seconds``)
    and ``failed``, with what went wrong (module docstring); the problem is None unless it
    failed."""
    from crmgrasp.cli import main

    err, out = io.StringIO(), io.StringIO()
    previous = signal.signal(signal.SIGALRM, _alarm)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        with warnings.catch_warnings(), contextlib.redirect_stderr(err), contextlib.redirect_stdout(out):
            warnings.simplefilter("error")
            try:
                status = main(argv)
            except SystemExit as exc:  # argparse's usage errors
                status = exc.code if isinstance(exc.code, int) else 2
    except _TimeUp:
        return "time limit", None
    except Exception as exc:  # what this script looks for
        return "failed", f"{type(exc).__name__} escaped main: {str(exc)[:200]}"
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)
    text = err.getvalue()
    if status == 0:
        return "ran", None
    if status == 2 and text.count("\n") == 1 and text.endswith("\n") and len(text) < 400:
        return "refused", None
    return "failed", f"status {status}, {text.count(chr(10))} lines on stderr: {text[:300]!r}"


HEAVY = (
    "torch",
    "torch._dynamo",
    "stable_baselines3",
    "sb3_contrib",
    "mujoco",
    "pomdp_py",
    "ray",
    "pyarrow",
    "matplotlib.pyplot",
)
"""Modules imported before the first case where installed: the time limit interrupts a command
wherever it is, and one interrupted inside a module's first import leaves the module half
imported for every later case (seen: torch, after which the deep peer's cases failed; then
``torch._dynamo``, which torch imports only when first needed: 10 of ``compare``'s cases in
the full run of 2026-12-08)."""


@contextlib.contextmanager
def scratch() -> Iterator[dict[str, str]]:
    """A scratch folder to work in, with the files the base command lines name (and the
    [`HEAVY`][] modules imported)."""
    from crmgrasp.cli import main

    for name in HEAVY:
        with contextlib.suppress(ImportError):
            importlib.import_module(name)

    here = os.getcwd()
    with tempfile.TemporaryDirectory(prefix="crmgrasp-cli-fuzz-") as root:
        os.chdir(root)
        try:
            Path("bad.toml").write_text("x = [\n")
            Path("garbage.json").write_text("{not json")
            Path("study.toml").write_text(STUDY)
            with contextlib.redirect_stdout(io.StringIO()):
                assert main([*["learn"], *BASES["learn"][:-1], "setup"]) == 0
            yield {
                "policy": str(Path(root, "setup", "policy.json")),
                "run": str(Path(root, "setup")),
                "study": "study.toml",
            }
        finally:
            os.chdir(here)


def fuzz(commands: list[str], seconds: float) -> dict[str, Any]:
    """Every hostile value of every option of each of ``commands``: counts and failures."""
    from crmgrasp.kernels import compiling

    rows, t0, n, after = [], time.perf_counter(), 0, compiling.AFTER
    compiling.AFTER = math.inf  # the notice while numba compiles would be a second line
    try:
        with scratch() as fill:
            for command in commands:
                warm = [command, *(p.format(**fill, out="warm") for p in BASES[command])]
                run_case(warm, 60.0)  # imports and compilation before the cases are timed
                outcomes: dict[str, int] = {"ran": 0, "refused": 0, "time limit": 0, "failed": 0}
                failures = []
                for option, dest in options(command):
                    for value in HOSTILE:
                        n += 1
                        argv = command_line(command, option, dest, value, {**fill, "out": f"case{n}"})
                        outcome, problem = run_case(argv, seconds)
                        outcomes[outcome] += 1
                        if problem is not None:
                            shown = argv if len(value) < 100 else [*argv[:1], option or dest, "<long>"]
                            failures.append({"argv": shown, "problem": problem})
                rows.append({"command": command, **outcomes, "failures": failures[:20]})
                print(f"{command}: {outcomes}", file=sys.stderr, flush=True)
    finally:
        compiling.AFTER = after
    return {
        "cases": n,
        **{k: sum(r[k] for r in rows) for k in ("ran", "refused", "time limit", "failed")},
        "seconds": round(time.perf_counter() - t0, 1),
        "commands": rows,
    }


def main(argv: list[str] | None = None) -> dict[str, Any]:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--command", action="append", choices=tuple(BASES), help="(default: every command)")
    parser.add_argument("--seconds", type=float, default=3.0, help="time limit of one command line")
    args = parser.parse_args(argv)
    out = fuzz(args.command or list(BASES), args.seconds)
    print(json.dumps(out, indent=1))
    return out


if __name__ == "__main__":
    sys.exit(1 if main()["failed"] else 0)

"""Hostile study files, at scale: every key of a sweep's study file set to every value of a hostile list.

For each registered agent it makes a study of one cell on paper-box that sets every scalar
parameter the agent takes (each at its default), k = 1, with 1 trial of 3 episodes and 2
evaluation episodes, seed 0. For every leaf of that document (a key, or an item of a list:
``benchmarks/task_file_fuzz.py``'s ``leaves``) and every value of its ``HOSTILE`` list, plus
deleting the leaf, it writes the study as a TOML file and runs it as ``crmgrasp sweep`` does:
``load_study`` (parse, check, and build the cells' tasks), ``run_study`` into a run folder
(every (cell, seed) unit; a unit that fails is recorded with its message and the others go on)
and ``report`` (tables and figures), with Python's warnings raised as errors and 20 s at most
per variant. A variant passes if it runs, or if the study is refused with a ``CrmgraspError``
of one line under 400 characters, and every failed unit's recorded message is such a line;
anything else (another exception, a warning, a message of several lines, a unit failed
without one) is reported with the leaf and value that caused it. It prints one JSON object and
exits 1 if a variant failed.

``tests/test_sweep.py`` checks chosen bad studies; this runs every leaf. Measured 2026-12-07:
the 12 agents, 4,577 variants in 155 s on one core, none failed. At 388bc46, before the fixes it
led to, 346 failed (179 s): per agent, ``eval_episodes = 0`` ran and then failed its report with
a TypeError, and a ``[[cell]]`` that is not a table (28 or 29 variants) got a 410-character
message about an unknown key ``'?'`` listing every agent's parameters.

Usage: ``python benchmarks/study_file_fuzz.py [--agent NAME ...]``.
"""

from __future__ import annotations

import argparse
import json
import math
import signal
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))
import task_file_fuzz

SECONDS = 20.0
"""Most seconds one variant may take (the budgets are tiny; a variant that runs longer is a
failure: a hostile value made the study far larger than its file says)."""


def toml_value(value: Any) -> str:
    """``value`` as a TOML value (inline arrays and tables; NaN and infinities as TOML writes them)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float) and not math.isfinite(value):
        return "nan" if math.isnan(value) else ("inf" if value > 0 else "-inf")
    if isinstance(value, (int, float, str)):
        return json.dumps(value)
    if isinstance(value, list):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{json.dumps(k)} = {toml_value(v)}" for k, v in value.items()) + "}"
    raise TypeError(f"no TOML for {value!r}")


def study_document(agent: str) -> dict[str, Any]:
    """The base study of ``agent``: one paper-box cell setting every scalar parameter the agent
    takes at its default, k = 1, the smallest budgets."""
    from crmgrasp.agents.training import agent_parameters, parameter_defaults
    from crmgrasp.experiments.study import agent_params

    cell: dict[str, Any] = {"task": "paper-box", "agent": agent, "k": 1}
    scalar = set(agent_params())
    cell |= {p: parameter_defaults(p)[agent] for p in agent_parameters(agent) if p in scalar}
    return {"name": "fuzz", "trials": 1, "episodes": 3, "eval_episodes": 2, "seeds": [0], "cell": [cell]}


class TimeLimitError(Exception):
    """A variant ran past ``SECONDS`` (reported as its problem)."""


def _alarm(signum: int, frame: Any) -> None:
    raise TimeLimitError(f"still running after {SECONDS:g} s")


def run_study_file(doc: dict[str, Any], root: Path) -> None:
    """Write ``doc`` as ``root/study.toml`` and run it as ``crmgrasp sweep`` and ``sweep report``
    do, into a new folder under ``root``; raises ``CrmgraspError`` where the study is refused
    and ``AssertionError`` for a failed unit whose message is not one short line."""
    from crmgrasp.experiments.runs import RunFolder
    from crmgrasp.experiments.sweep import load_study, report, run_study

    path = root / "study.toml"
    path.write_text("".join(f"{json.dumps(k)} = {toml_value(v)}\n" for k, v in doc.items()))
    study = load_study(path)
    with RunFolder(tempfile.mkdtemp(dir=root), "sweep", study.name, {"study": study.to_dict()}, argv=[]) as run:
        run_study(study, run)
    for unit, info in run.record["completed"].items():
        error = info.get("error")
        if info["status"] != "ok":
            assert isinstance(error, str) and "\n" not in error and len(error) < 400, f"{unit}: {error!r}"
    if any(info["status"] == "ok" for info in run.record["completed"].values()):
        report(run.path)


def run_variant(doc: dict[str, Any], root: Path) -> str | None:
    """``None`` if the study runs or is refused in one line (``task_file_fuzz.attempt``), else
    what went wrong; ``SECONDS`` at most."""
    previous = signal.signal(signal.SIGALRM, _alarm)
    signal.setitimer(signal.ITIMER_REAL, SECONDS)
    try:
        return task_file_fuzz.attempt(lambda: run_study_file(doc, root))
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


def fuzz(agent: str, root: Path) -> dict[str, Any]:
    """Every variant of ``agent``'s study: the count and the failures."""
    doc = study_document(agent)
    assert run_variant(doc, root) is None, agent  # the base study runs
    count, failures = 0, []
    for path in task_file_fuzz.leaves(doc):
        for value in (*task_file_fuzz.HOSTILE, task_file_fuzz.DELETE):
            count += 1
            problem = run_variant(task_file_fuzz.mutated(doc, path, value), root)
            if problem is not None:
                shown = "delete" if value is task_file_fuzz.DELETE else repr(value)
                failures.append({"leaf": ".".join(map(str, path)), "value": shown, "problem": problem})
    return {"agent": agent, "variants": count, "failed": len(failures), "failures": failures[:20]}


def main(argv: list[str] | None = None) -> dict[str, Any]:
    from crmgrasp.agents.training import AGENTS

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--agent", action="append", choices=tuple(AGENTS), help="(default: every agent)")
    args = parser.parse_args(argv)
    t0 = time.perf_counter()
    rows = []
    with tempfile.TemporaryDirectory(prefix="crmgrasp-study-fuzz-") as tmp:
        for agent in args.agent or list(AGENTS):
            rows.append(fuzz(agent, Path(tmp)))
            print(f"{agent}: {rows[-1]['variants']} variants, {rows[-1]['failed']} failed", file=sys.stderr, flush=True)
    out = {
        "variants": sum(r["variants"] for r in rows),
        "failed": sum(r["failed"] for r in rows),
        "seconds": round(time.perf_counter() - t0, 1),
        "agents": rows,
    }
    print(json.dumps(out, indent=1))
    return out


if __name__ == "__main__":
    sys.exit(1 if main()["failed"] else 0)

"""``crmgrasp reproduce``: run the registered experiments into one folder and write an
index ``README.md`` with every figure and our numbers beside the paper's."""

from __future__ import annotations

import json
import time
from functools import partial
from pathlib import Path
from typing import Any

from crmgrasp._io import atomic_write_text, json_safe, write_json
from crmgrasp._progress import Progress
from crmgrasp._validation import CrmgraspError
from crmgrasp.experiments.parallel import run_parallel, usable_jobs
from crmgrasp.experiments.registry import EXPERIMENTS, GROUPS, IMAGES, NEEDS_MUJOCO, QUICK_BUDGETS
from crmgrasp.experiments.runs import RunFolder
from crmgrasp.experiments.stats import fmt
from crmgrasp.kernels import BACKENDS

__all__ = ["reproduce", "select"]


def _cell(value: object) -> str:
    """Markdown table cell: numbers rounded ([`fmt`][crmgrasp.experiments.stats.fmt]),
    pipes escaped."""
    return fmt(value).replace("|", "\\|")


FULL_RUN = Path(__file__).with_name("full_run.json")
"""The index rows of a full ``crmgrasp reproduce --seed 0`` (all extras), shown beside a
quick run's numbers; rewritten by ``python scripts/record_full_run.py RUN_DIR``."""


def full_run_rows() -> dict[str, str]:
    """``"figure | quantity" -> ours`` of the recorded full run (empty if none)."""
    try:
        doc = json.loads(FULL_RUN.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    return {str(k): str(v) for k, v in doc.get("rows", {}).items()} if isinstance(doc, dict) else {}


def record_full_run(run_dir: str | Path) -> Path:
    """Update [`FULL_RUN`][] with the rows of a complete full-budget reproduce run folder
    (rows of experiments it did not run are kept)."""
    from crmgrasp.experiments.runs import _read

    rec = _read(Path(run_dir))
    if rec.get("command") != "reproduce" or rec["status"] != "complete" or rec["config"].get("quick"):
        raise CrmgraspError(f"{str(run_dir)!r} is not a complete full-budget reproduce run")
    rows = {f"{name} | {row[0]}": _cell(row[1]) for name, done in rec["completed"].items() for row in done["rows"]}
    try:
        old = json.loads(FULL_RUN.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        old = {}
    source = {"experiments": list(rec["completed"]), "git_commit": rec.get("git_commit"), "version": rec.get("version")}
    doc = {
        "seed": rec["config"]["seed"],
        "sources": [*old.get("sources", []), source],
        "rows": {**old.get("rows", {}), **rows},  # a run of some experiments updates their rows only
    }
    return write_json(FULL_RUN, doc)


def select(names: list[str] | None) -> tuple[list[str], list[str]]:
    """The experiments to run, in registry order, and those skipped: all by default
    (without the MuJoCo ones when the extra is missing), else ``names`` checked."""
    from crmgrasp.hardware.mujoco import mujoco_available, require_mujoco

    if not names:
        names = list(EXPERIMENTS)
        skipped = [] if mujoco_available() else [n for n in names if n in NEEDS_MUJOCO]
        return [n for n in names if n not in skipped], skipped
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise CrmgraspError(f"experiment {twice[0]!r} is named more than once")
    unknown = [n for n in names if n not in EXPERIMENTS]
    if unknown:
        raise CrmgraspError(f"unknown experiment {unknown[0]!r}; known: {', '.join(EXPERIMENTS)}")
    if any(n in NEEDS_MUJOCO for n in names):
        require_mujoco()
    return sorted(names, key=list(EXPERIMENTS).index), []


def _groups(names: list[str]) -> list[tuple[str, ...]]:
    """``names`` in groups that must run in one process, in order (`GROUPS`: an
    experiment using another's result runs after it), longest expected first."""
    out: list[tuple[str, ...]] = []
    for group in GROUPS:
        chosen = tuple(n for n in group if n in names)
        if chosen:
            out.append(chosen)
    grouped = {n for g in out for n in g}
    return out + [(n,) for n in names if n not in grouped]


def _run_one(
    name: str, out: Path, seed: int, quick: bool, ctx: dict[str, Any], progress: Progress | None = None
) -> tuple[str, dict[str, Any], list[Any], dict[str, Any]]:
    """Run one experiment; its summary (with ``seconds``), rows and what it added to ``ctx``."""
    if progress:
        progress.note(f"reproduce: {name} ...")
    before = {k: v for k, v in ctx.items() if k not in ("progress", "jobs")}
    t0 = time.perf_counter()
    summary, rows = EXPERIMENTS[name][1](out / name, seed, quick, ctx)
    summary["seconds"] = round(time.perf_counter() - t0, 3)
    added = {k: v for k, v in ctx.items() if k not in ("progress", "jobs") and before.get(k) != v}
    return name, summary, rows, added


def _run_group(
    names: tuple[str, ...], out: str, seed: int, quick: bool, shared: dict[str, Any]
) -> list[tuple[str, dict[str, Any], list[Any], dict[str, Any]]]:
    """The experiments of one group, in order, in one (worker) process."""
    ctx = {**shared, "progress": None, "jobs": 1}
    return [_run_one(name, Path(out), seed, quick, ctx) for name in names]


def reproduce(
    out_dir: str | Path,
    names: list[str] | None = None,
    *,
    seed: int = 0,
    quick: bool = False,
    backend: str = "auto",
    store: RunFolder | None = None,
    progress: Progress | None = None,
    jobs: int = 1,
) -> dict[str, dict[str, Any]]:
    """Run the named experiments (all by default) into ``out_dir/<name>/`` and write
    ``out_dir/README.md`` with every figure and our numbers beside the paper's.
    Episodes step through the kernel ``backend`` (every backend gives the same results).

    With a run folder ``store``, each finished experiment is recorded there, and one
    recorded already (a resumed run) is not run again. ``progress`` shows the
    experiments and the training inside them. With ``jobs`` > 1 the experiments run in
    worker processes, in groups (`GROUPS`) whose
    members depend on each other; with one group left, its learners' trials use the
    workers ([`learn`][crmgrasp.experiments.learning.learn]). The results are the same."""
    if backend not in BACKENDS:
        raise CrmgraspError(f"unknown backend {backend!r}; choose one of {', '.join(BACKENDS)}")
    names, skipped = select(names)
    out = Path(out_dir)
    ctx: dict[str, Any] = {"backend": backend, "progress": progress, "jobs": jobs}
    stage = progress.stage("reproduce", len(names), "experiments") if progress else None
    outcomes = _recorded(names, store, ctx, stage)
    pending = [n for n in names if n not in outcomes]
    groups = _groups(pending)
    shared = {k: v for k, v in ctx.items() if k not in ("progress", "jobs")}
    if usable_jobs(jobs) > 1 and len(groups) > 1:
        calls = [(g, partial(_run_group, g, str(out), seed, quick, shared)) for g in groups]
        finished = (item for _, items in run_parallel(calls, min(usable_jobs(jobs), len(groups))) for item in items)
    else:
        finished = (_run_one(name, out, seed, quick, ctx, progress) for name in pending)
    for name, summary, rows, added in finished:
        outcomes[name] = summary, rows
        if store is not None:
            store.complete(name, json_safe({"summary": summary, "rows": rows, "context": added}))
        if stage:
            stage.advance()
    if stage:
        stage.end()
    atomic_write_text(out / "README.md", _index(out, names, skipped, outcomes, seed, quick))
    return {name: outcomes[name][0] for name in names}


def _recorded(
    names: list[str], store: RunFolder | None, ctx: dict[str, Any], stage: Progress | None
) -> dict[str, tuple[dict[str, Any], list[Any]]]:
    """The experiments of ``names`` that the run folder ``store`` records as finished (a
    resumed run): their summaries and index rows; their recorded context joins ``ctx``."""
    outcomes: dict[str, tuple[dict[str, Any], list[Any]]] = {}
    for name in names:
        done = store.done(name) if store is not None else None
        if isinstance(done, dict) and {"summary", "rows"} <= set(done):
            outcomes[name] = done["summary"], [tuple(r) for r in done["rows"]]
            ctx.update(done.get("context", {}))
            if stage:
                stage.advance()
    return outcomes


def _index(
    out: Path,
    names: list[str],
    skipped: list[str],
    outcomes: dict[str, tuple[dict[str, Any], list[Any]]],
    seed: int,
    quick: bool,
) -> str:
    """The run's ``README.md``: how to regenerate it, one table of every experiment's numbers
    beside the paper's (and, in a quick run, beside a full run's), then each experiment's
    figures."""
    which = "" if set(names) == set(select(None)[0]) else "".join(f" {n}" for n in names)  # if not all
    lines = [
        "# crmgrasp reproduction",
        "",
        f"seed {seed}, {'quick budgets' if quick else 'full budgets'}. "
        f"Regenerate with `crmgrasp reproduce{which}{' --quick' if quick else ''} --seed {seed}`.",
        "",
    ]
    if quick:
        lines += [
            "A quick run learns on small budgets: its learned numbers have not converged (marked with their "
            "budget); the column *full run* shows the same quantity from a full run with seed 0.",
            "",
            "| figure | quantity | ours | full run | paper |",
            "| --- | --- | --- | --- | --- |",
        ]
    else:
        lines += ["| figure | quantity | ours | paper |", "| --- | --- | --- | --- |"]
    full = full_run_rows() if quick else {}
    body: list[str] = []
    for name in names:
        summary, rows = outcomes[name]
        for q, ours, paper in rows:
            if quick:
                small, learned = QUICK_BUDGETS.get(name, ("", ()))
                mark = f" (not converged at {small})" if q.startswith(tuple(learned)) and learned else ""
                ref = full.get(f"{name} | {q}", "-")
                lines.append(f"| {name} | {_cell(q)} | {_cell(ours)}{mark} | {ref} | {_cell(paper)} |")
            else:
                lines.append(f"| {name} | {_cell(q)} | {_cell(ours)} | {_cell(paper)} |")
        body += [f"## {name}", "", EXPERIMENTS[name][0], ""] + [
            f"![{name}]({name}/{img})" for img in IMAGES[name] if (out / name / img).exists()
        ]
        body += ["", f"Data and config: `{name}/` ({summary['seconds']} s).", ""]
    dash = " - |" * (3 if quick else 2)
    lines += [f"| {name} | skipped: needs `pip install 'crmgrasp[mujoco]'` |{dash}" for name in skipped]
    return "\n".join([*lines, "", *body])

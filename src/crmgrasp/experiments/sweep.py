"""Studies: many learning runs (tasks x learners x parameters x seeds), one tidy table.

A study file ([`crmgrasp.experiments.study`][]: its format, keys and checks) lists cells, each
a task, a learner and its parameters, and the seeds to run each cell with. Each (cell, seed) is one
[`learn`][crmgrasp.experiments.learning.learn] run; its results depend only on the cell and
the seed, so any number of worker processes gives the same table. A cell that fails
(a parameter its agent does not take, say) is recorded with its error; the others go
on. The run folder holds ``run.json`` (the study, the status of every (cell, seed)),
``units/`` (one file per finished unit, which ``--resume`` keeps), ``results.csv`` (one
row per cell, seed and trial: the cell's settings and the trial's greedy CRMs per
episode, success rate and CRMs per episode over the last 10 training episodes),
``cells.csv`` (one row per cell and seed: the summary) and, when ``pyarrow`` is
installed, the same tables as Parquet. [`report`][] turns a study folder into
``report.md`` and figures ([`crmgrasp.experiments.stats`][] conventions: bootstrap
intervals over trials, interquartile means, a performance profile).
"""

from __future__ import annotations

import json
import math
import textwrap
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from crmgrasp._io import as_path, atomic_write_text, read_bounded, save_figure, write_csv, write_json
from crmgrasp._progress import Progress
from crmgrasp._validation import CrmgraspError, is_finite_number, shown
from crmgrasp.experiments.learning import LearnerSpec, learn
from crmgrasp.experiments.parallel import run_parallel
from crmgrasp.experiments.runs import RunFolder
from crmgrasp.experiments.stats import bootstrap_ci, fmt, iqm
from crmgrasp.experiments.study import Study, agent_params, cell_id, load_study, study_from_dict, table_keys

__all__ = ["Study", "load_study", "run_study", "report"]


@dataclass(frozen=True)
class _Unit:
    """One (cell, seed) run; picklable, so it runs in a worker process too."""

    cell: dict[str, Any]
    seed: int
    trials: int
    episodes: int
    eval_episodes: int
    backend: str

    def __call__(self) -> dict[str, Any]:
        from crmgrasp.tasks.files import resolve_reading

        c = self.cell
        try:
            task = resolve_reading(c["task"], starts=c.get("start_preset"), grasp_reward=c.get("grasp_reward"))
            params = {k: c[k] for k in agent_params() if k in c}
            if c.get("symmetric"):
                params["symmetric"] = True
            run = learn(
                task,
                LearnerSpec(c["agent"], c["k"], params),
                trials=self.trials,
                episodes=self.episodes,
                seed=self.seed,
                eval_episodes=self.eval_episodes,
                checkpoint_episodes=0,
                backend=self.backend,
            )
        except CrmgraspError as exc:
            return {"status": "failed", "error": str(exc)}
        res = run.result
        greedy = res.greedy_steps.mean(axis=1) if self.eval_episodes else np.full(self.trials, np.nan)
        success = res.greedy_success.mean(axis=1) if self.eval_episodes else np.full(self.trials, np.nan)
        return {
            "status": "ok",
            "summary": run.summary,
            "trials": {
                "greedy_mean_steps": greedy.tolist(),
                "greedy_success_rate": success.tolist(),
                "final_mean_steps": res.steps[:, -10:].mean(axis=1).tolist(),
            },
            "curve": res.curve.tolist(),
        }


def run_study(
    study: Study,
    store: RunFolder,
    *,
    jobs: int = 1,
    backend: str = "auto",
    progress: Progress | None = None,
    executor: str = "local",
    address: str | None = None,
) -> dict[str, int]:
    """Run every (cell, seed) not yet recorded in ``store`` (``jobs`` at once, in local
    worker processes or as Ray tasks: ``crmgrasp.experiments.parallel.run_parallel``),
    then write the tables. Returns the number of units ok and failed."""
    if not isinstance(study, Study) or not isinstance(store, RunFolder):
        raise CrmgraspError(f"run_study takes a Study and a RunFolder, got {shown(study)} and {shown(store)}")
    units = [
        (f"{cell_id(c)} seed {s}", _Unit(c, s, study.trials, study.episodes, study.eval_episodes, backend))
        for c in study.cells
        for s in study.seeds
    ]
    _checked_units(store.record["completed"], store.path)  # a resumed record, before any run
    todo = [(name, unit) for name, unit in units if store.done(name) is None]
    stage = progress.stage(f"sweep {study.name}", len(units), "runs") if progress else None
    if stage:
        stage.advance(len(units) - len(todo))

    failed = [0]

    def record(name: str, result: dict[str, Any]) -> None:
        file = _unit_file(name)
        if result["status"] == "ok":
            write_json(store.path / file, result)
        store.complete(name, {"status": result["status"], "error": result.get("error"), "file": file})
        if stage:
            stage.advance()
            if result["status"] == "failed":
                failed[0] += 1
                stage.note(f"sweep: {name} failed: {result['error']}")
                stage.relabel(f"sweep {study.name} ({failed[0]} failed)")

    for name, result in run_parallel(todo, jobs, executor, address):
        record(name, result)
    if stage:
        stage.end()
    return write_tables(study, store.path, store.record["completed"])


_CELL_COLUMNS = ("greedy_mean_steps", "ci95_low", "ci95_high", "greedy_iqm_steps", "episodes_to_5pct", "seconds")


def _checked_units(completed: dict[str, Any], out: Path) -> dict[str, Any]:
    """``completed``, the units a study folder's record holds, if each is what [`run_study`][]
    records (``status`` ``ok`` or ``failed``, ``error`` text or null); else a one-line error
    naming the first that is not."""
    for name, info in completed.items():
        status, error = (info.get("status"), info.get("error")) if isinstance(info, dict) else (None, None)
        if status not in ("ok", "failed") or not isinstance(error, (str, type(None))):
            raise CrmgraspError(f"run record of {str(out)!r} is damaged (unit {shown(name)})")
    return completed


def write_tables(study: Study, out: Path, completed: dict[str, Any]) -> dict[str, int]:
    """``results.csv`` (cell x seed x trial), ``cells.csv`` (cell x seed) and Parquet copies."""
    keys = table_keys(study)
    rows, cells, counts = [], [], {"ok": 0, "failed": 0}
    for c in study.cells:
        for s in study.seeds:
            name = f"{cell_id(c)} seed {s}"
            info = completed.get(name) or {}
            status = info.get("status", "missing")
            counts[status] = counts.get(status, 0) + 1
            settings = [cell_id(c), *(c.get(k) for k in keys), s]
            if status != "ok":
                cells.append([*settings, status, info.get("error"), None, None, None, None, None, None])
                continue
            doc = _unit_doc(out, name)
            t = doc["trials"]
            for i, (g, ok, fin) in enumerate(
                zip(t["greedy_mean_steps"], t["greedy_success_rate"], t["final_mean_steps"])
            ):
                rows.append([*settings, i, g, ok, fin])
            sm = doc["summary"]
            lo, hi = sm["greedy_ci95_over_trials"]
            ok = [sm["greedy_mean_steps"], lo, hi, sm["greedy_iqm_steps"], sm["episodes_to_5pct"], sm["seconds"]]
            cells.append([*settings, "ok", None, *ok])
    head = ["cell", *keys, "seed"]
    write_csv(
        out / "results.csv", [*head, "trial", "greedy_mean_steps", "greedy_success_rate", "final_mean_steps"], rows
    )
    write_csv(
        out / "cells.csv",
        [*head, "status", "error", *_CELL_COLUMNS],
        cells,
    )
    _parquet(out, ("results", "cells"))
    units = {name: {k: v for k, v in info.items() if k != "file"} for name, info in completed.items()}
    write_json(out / "study.json", {"study": study.to_dict(), "units": units, "counts": counts, "run": "run.json"})
    return counts


def _parquet(out: Path, names: Sequence[str]) -> None:
    """Parquet copies of the CSV tables when ``pyarrow`` is installed."""
    try:
        import pyarrow.csv as pacsv
        import pyarrow.parquet as pq
    except ImportError:
        return
    from crmgrasp._io import atomic_path

    for name in names:
        table = pacsv.read_csv(out / f"{name}.csv")
        with atomic_path(out / f"{name}.parquet") as tmp:
            pq.write_table(table, tmp)


def _unit_file(name: str) -> str:
    """Where a unit's result lives in the study folder: derived from its name, never read
    from the record (a damaged record cannot point outside the folder)."""
    return f"units/{name.replace(' ', '_')}.json"


def _unit_doc(out: Path, name: str) -> dict[str, Any]:
    """The result file of unit ``name`` in the study folder ``out``, checked (one-line
    errors for a missing or damaged file)."""
    path = out / _unit_file(name)
    try:
        doc = json.loads(read_bounded(path, 64 * 2**20, "unit result").decode("utf-8"))
        _check_unit(doc)
    except (UnicodeDecodeError, json.JSONDecodeError, RecursionError) as exc:
        raise CrmgraspError(f"unit result {str(path)!r} is damaged ({type(exc).__name__})") from None
    except (KeyError, TypeError, ValueError) as exc:
        raise CrmgraspError(f"unit result {str(path)!r} is damaged ({str(exc).strip(chr(39))})") from None
    return doc  # type: ignore[no-any-return]


_TRIAL_KEYS = ("greedy_mean_steps", "greedy_success_rate", "final_mean_steps")
_SUMMARY_NUMBERS = ("greedy_mean_steps", "greedy_iqm_steps", "seconds")


def _check_unit(doc: Any) -> None:
    """What the tables and the report read of a unit's result, as ``_Unit`` writes it: equal,
    non-empty lists of finite numbers per trial; the summary's mean, interquartile mean and
    time finite, its interval two numbers or nulls, its episodes to 5% a count or null. Raises
    ``ValueError`` naming the first field that is not (``KeyError`` for a missing one)."""
    if not isinstance(doc, dict):
        raise ValueError("not a table")
    trials, summary = doc["trials"], doc["summary"]
    if not isinstance(trials, dict) or not isinstance(summary, dict):
        raise ValueError("trials or summary not a table")
    for key in _TRIAL_KEYS:
        values = trials[key]
        same = isinstance(values, list) and len(values) == len(trials[_TRIAL_KEYS[0]]) and values
        if not same or not all(is_finite_number(v) for v in values):
            raise ValueError(f"trials.{key}")
    for key in _SUMMARY_NUMBERS:
        if not is_finite_number(summary[key]):
            raise ValueError(f"summary.{key}")
    ci, to5 = summary["greedy_ci95_over_trials"], summary["episodes_to_5pct"]
    if not (isinstance(ci, list) and len(ci) == 2 and all(v is None or is_finite_number(v) for v in ci)):
        raise ValueError("summary.greedy_ci95_over_trials")
    if not (to5 is None or (isinstance(to5, int) and not isinstance(to5, bool) and to5 >= 0)):
        raise ValueError("summary.episodes_to_5pct")


def _recorded_study(rec: dict[str, Any], out: Path) -> Study:
    """The study a sweep's run record holds, checked as a study file is."""
    doc = rec.get("config", {}).get("study")  # a record may lack its config (a one-line error below)
    try:
        keys = ("name", "trials", "episodes", "eval_episodes", "seeds")
        top = {k: doc[k] for k in keys}  # type: ignore[index]
        return study_from_dict({**top, "cell": list(doc["cells"])})  # type: ignore[index]
    except (KeyError, TypeError, AttributeError, CrmgraspError) as exc:
        raise CrmgraspError(f"run record of {str(out)!r} holds no readable study ({exc})") from None


def _cell_results(
    rec: dict[str, Any], out: Path, study: Study
) -> tuple[dict[str, np.ndarray], dict[str, list[Any]], dict[str, float]]:
    """Per cell of a study folder's record: the greedy CRMs of every trial of its completed
    runs, each run's episodes to 5%, and its task's optimum as the runs recorded it
    (``reference_mean_steps``; absent where the task states none)."""
    per_cell: dict[str, np.ndarray] = {}
    to5: dict[str, list[Any]] = {}
    optimum: dict[str, float] = {}
    for c in study.cells:
        vals: list[float] = []
        for s in study.seeds:
            name = f"{cell_id(c)} seed {s}"
            info = rec["completed"].get(name) or {}
            if isinstance(info, dict) and info.get("status") == "ok":
                doc = _unit_doc(out, name)
                vals += [float(v) for v in doc["trials"]["greedy_mean_steps"]]
                to5.setdefault(cell_id(c), []).append(doc["summary"].get("episodes_to_5pct"))
                ref = doc["summary"].get("reference_mean_steps")
                if isinstance(ref, (int, float)) and ref > 0:
                    optimum[cell_id(c)] = float(ref)
        per_cell[cell_id(c)] = np.asarray(vals, dtype=float)
    return per_cell, to5, optimum


def _cell_row(c: dict[str, Any], v: np.ndarray, swept: list[str], to5: list[Any], ref: float | None) -> str:
    """One cell's row of ``report.md``: its settings, trials, mean CRMs, gap to the optimum
    ``ref``, bootstrap 95% interval, interquartile mean and median episodes to 5% over ``to5``."""
    lo, hi = bootstrap_ci(v, 0)
    mean = fmt(float(v.mean())) if v.size else "failed"
    settings = " | ".join(str(c.get(k)) for k in swept)
    middle = fmt(iqm(v)) if v.size else "-"
    seeds_to5 = sorted(math.inf if not isinstance(x, (int, float)) else x for x in to5)
    med = seeds_to5[len(seeds_to5) // 2] if seeds_to5 else None
    shown_to5 = "-" if med is None else ("never" if med == math.inf else f"{int(med):,}")
    ci = f"{fmt(lo)}-{fmt(hi)}" if math.isfinite(lo) else "-"
    gap = f"{float(v.mean()) / ref - 1.0:+.1%}" if ref and v.size else "-"
    row = f"| {c.get('task')} | {cell_id(c)} | {settings}{' | ' if swept else ''}{v.size} | {mean} | {gap} | {ci} | "
    return f"{row}{middle} | {shown_to5} |"


def report(folder: str | Path) -> Path:
    """``report.md``, ``profile.png`` and one ``param_<key>.png`` per swept key, from a
    study folder: per cell, the mean greedy CRMs per episode with a bootstrap 95%
    interval over all its trials (every seed), the interquartile mean, and a performance
    profile (the share of a cell's trials whose greedy CRMs are at most tau). It reads
    only inside the folder; a damaged record or unit file is a one-line error."""
    from crmgrasp.experiments.runs import _read, read_status

    out = as_path(folder, "study folder")
    rec = _read(out)
    if rec.get("command") != "sweep":
        raise CrmgraspError(f"{str(out)!r} is not a study folder (command {shown(rec.get('command'))})")
    study = _recorded_study(rec, out)
    per_cell, to5, optimum = _cell_results(rec, out, study)
    swept = [k for k in table_keys(study) if k != "task" and len({json.dumps(c.get(k)) for c in study.cells}) > 1]
    lines = [
        f"# Study {study.name}: {len(study.cells)} cells x {len(study.seeds)} seeds x {study.trials} trials",
        "",
        f"{study.episodes:,} training episodes per trial, greedy evaluation on {study.eval_episodes:,} episodes; "
        "mean over all trials of the cell with a percentile-bootstrap 95% interval over trials, and the "
        "interquartile mean; episodes to 5%: first training episode after which the 10-episode average "
        "stays within 5% of the task's optimum (median of the seeds' runs; never = beyond the budget). "
        "Cells are grouped by task (CRMs of different tasks do not compare); *vs optimum* is the mean over the "
        "task's belief-space optimum as its runs recorded it (`reference_mean_steps`; - where the task states none). "
        f"Status: {read_status(out)}.",
        "",
        "| task | cell | " + " | ".join(swept) + " | trials | mean CRMs | vs optimum | 95% CI | IQM | episodes to 5% "
        "(median of seeds) |",
        "| --- | --- | " + " | ".join("---" for _ in swept) + " | --- | --- | --- | --- | --- | --- |",
    ]

    def order(c: dict[str, Any]) -> tuple[str, float]:
        v = per_cell[cell_id(c)]
        return str(c.get("task")), float(np.mean(v)) if v.size else math.inf

    for c in sorted(study.cells, key=order):
        lines.append(_cell_row(c, per_cell[cell_id(c)], swept, to5.get(cell_id(c), []), optimum.get(cell_id(c))))
    atomic_write_text(out / "report.md", "\n".join(lines) + "\n")
    _figures(out, study, per_cell, swept)
    return out / "report.md"


def _cell_label(cell: dict[str, Any], swept: list[str]) -> str:
    """A cell by its settings (``agent=sarsa, alpha=0.3``), its id when nothing is swept."""
    return ", ".join(f"{k}={cell.get(k)}" for k in ["task", *swept] if k in cell and (k != "task" or swept)) or (
        cell_id(cell)
    )


def _figures(out: Path, study: Study, per_cell: dict[str, np.ndarray], swept: list[str]) -> None:
    from matplotlib.figure import Figure

    fig = Figure(figsize=(6.5, 4.2), layout="constrained")
    ax = fig.add_subplot()
    scores = [v for v in per_cell.values() if v.size]
    if scores:
        taus = np.linspace(min(float(v.min()) for v in scores), max(float(v.max()) for v in scores), 200)
        for c in study.cells:
            v = per_cell[cell_id(c)]
            if v.size:
                ax.plot(taus, [(v <= t).mean() for t in taus], label=_cell_label(c, swept), lw=1.2)
    ax.set_xlabel("tau: greedy CRMs per episode")
    ax.set_ylabel("share of trials at or below tau")
    tasks = sorted({str(c.get("task")) for c in study.cells})
    note = f" (tasks differ: {', '.join(tasks)}; see report.md by task)" if len(tasks) > 1 else f" on {tasks[0]}"
    ax.set_title("\n".join(textwrap.wrap(f"Performance profile, study {study.name}{note}", 80)), fontsize=9)
    ax.grid(alpha=0.3)
    if scores and len(study.cells) <= 12:  # no curve, no legend: no cell has an evaluation
        ax.legend(fontsize=6)
    save_figure(fig, out / "profile.png", dpi=110)
    for key in swept:
        fig = Figure(figsize=(5.5, 4.0), layout="constrained")
        ax = fig.add_subplot()
        xs = sorted({json.dumps(c.get(key)) for c in study.cells})
        for i, x in enumerate(xs):
            v = np.concatenate(
                [per_cell[cell_id(c)] for c in study.cells if json.dumps(c.get(key)) == x] or [np.zeros(0)]
            )
            if v.size:
                lo, hi = bootstrap_ci(v, 0)
                m = float(v.mean())
                yerr = [[m - lo if math.isfinite(lo) else 0], [hi - m if math.isfinite(hi) else 0]]
                ax.errorbar([i], [m], yerr=yerr, marker="o", capsize=3, color="k")
        ax.set_xticks(range(len(xs)), [json.loads(x) if json.loads(x) is not None else "-" for x in xs])
        ax.set_xlabel(key)
        ax.set_ylabel("greedy CRMs per episode (all cells with this value)")
        others = [k for k in swept if k != key] + (["task"] if len(tasks) > 1 else [])
        pooled = f"; pooled over {', '.join(others)}" if others else ""
        ax.set_title(f"{study.name}: by {key} (mean, 95% bootstrap CI{pooled})", fontsize=9)
        save_figure(fig, out / f"param_{key}.png", dpi=110)

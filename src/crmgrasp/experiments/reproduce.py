"""``crmgrasp reproduce``: run the registered experiments into one folder and write an
index ``README.md`` with every figure and our numbers beside the paper's."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

from crmgrasp._io import atomic_write_text, json_safe
from crmgrasp._progress import Progress
from crmgrasp._validation import CrmgraspError
from crmgrasp.experiments.registry import EXPERIMENTS, IMAGES, NEEDS_MUJOCO
from crmgrasp.experiments.runs import RunFolder
from crmgrasp.kernels import BACKENDS

__all__ = ["reproduce", "select"]


def _cell(value: object) -> str:
    """Markdown table cell: pipes escaped."""
    return str(value).replace("|", "\\|")


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


def reproduce(
    out_dir: str | Path,
    names: list[str] | None = None,
    *,
    seed: int = 0,
    quick: bool = False,
    backend: str = "auto",
    store: RunFolder | None = None,
    progress: Progress | None = None,
) -> dict[str, dict[str, Any]]:
    """Run the named experiments (all by default) into ``out_dir/<name>/`` and write
    ``out_dir/README.md`` with every figure and our numbers beside the paper's.
    Episodes step through the kernel ``backend`` (every backend gives the same results).

    With a run folder ``store``, each finished experiment is recorded there, and one
    recorded already (a resumed run) is not run again. ``progress`` shows the
    experiments and the training inside them."""
    if backend not in BACKENDS:
        raise CrmgraspError(f"unknown backend {backend!r}; choose one of {', '.join(BACKENDS)}")
    names, skipped = select(names)
    out = Path(out_dir)
    results: dict[str, dict[str, Any]] = {}
    ctx: dict[str, Any] = {"backend": backend, "progress": progress}
    budget = "quick budgets (not converged; see the full run)" if quick else "full budgets"
    lines = [
        "# crmgrasp reproduction",
        "",
        f"seed {seed}, {budget}. Regenerate with `crmgrasp reproduce{' --quick' if quick else ''} --seed {seed}`.",
        "",
        "| figure | quantity | ours | paper |",
        "| --- | --- | --- | --- |",
    ]
    body: list[str] = []
    stage = progress.stage("reproduce", len(names), "experiments") if progress else None
    for name in names:
        desc, run = EXPERIMENTS[name]
        done = store.done(name) if store is not None else None
        if isinstance(done, dict) and {"summary", "rows"} <= set(done):
            summary, rows = done["summary"], [tuple(r) for r in done["rows"]]
            ctx.update(done.get("context", {}))
        else:
            if progress:
                progress.note(f"reproduce: {name} ...")
            before = {k: v for k, v in ctx.items() if k != "progress"}
            t0 = time.perf_counter()
            summary, rows = run(out / name, seed, quick, ctx)
            summary["seconds"] = round(time.perf_counter() - t0, 3)
            if store is not None:
                added = {k: v for k, v in ctx.items() if k != "progress" and before.get(k) != v}
                store.complete(name, json_safe({"summary": summary, "rows": rows, "context": added}))
        if stage:
            stage.advance()
        results[name] = summary
        lines += [f"| {name} | {_cell(q)} | {_cell(ours)} | {_cell(paper)} |" for q, ours, paper in rows]
        body += [f"## {name}", "", desc, ""] + [
            f"![{name}]({name}/{img})" for img in IMAGES[name] if (out / name / img).exists()
        ]
        body += ["", f"Data and config: `{name}/` ({summary['seconds']} s).", ""]
    if stage:
        stage.end()
    lines += [f"| {name} | skipped: needs `pip install 'crmgrasp[mujoco]'` | - | - |" for name in skipped]
    atomic_write_text(out / "README.md", "\n".join([*lines, "", *body]))
    return results

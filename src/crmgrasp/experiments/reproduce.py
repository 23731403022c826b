"""``crmgrasp reproduce``: run the registered experiments into one folder and write an
index ``README.md`` with every figure and our numbers beside the paper's."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

from crmgrasp._io import atomic_write_text
from crmgrasp._validation import CrmgraspError
from crmgrasp.experiments.registry import EXPERIMENTS, IMAGES, NEEDS_MUJOCO
from crmgrasp.kernels import BACKENDS

__all__ = ["reproduce"]


def _cell(value: object) -> str:
    """Markdown table cell: pipes escaped."""
    return str(value).replace("|", "\\|")


def reproduce(
    out_dir: str | Path,
    names: list[str] | None = None,
    *,
    seed: int = 0,
    quick: bool = False,
    backend: str = "auto",
) -> dict[str, dict[str, Any]]:
    """Run the named experiments (all by default) into ``out_dir/<name>/`` and write
    ``out_dir/README.md`` with every figure and our numbers beside the paper's.
    Episodes step through the kernel ``backend`` (every backend gives the same results)."""
    from crmgrasp.hardware.mujoco import mujoco_available, require_mujoco

    skipped: list[str] = []
    if not names:
        names = list(EXPERIMENTS)
        if not mujoco_available():
            skipped = [n for n in names if n in NEEDS_MUJOCO]
            names = [n for n in names if n not in NEEDS_MUJOCO]
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise CrmgraspError(f"experiment {twice[0]!r} is named more than once")
    unknown = [n for n in names if n not in EXPERIMENTS]
    if unknown:
        raise CrmgraspError(f"unknown experiment {unknown[0]!r}; known: {', '.join(EXPERIMENTS)}")
    if any(n in NEEDS_MUJOCO for n in names):
        require_mujoco()
    out = Path(out_dir)
    results: dict[str, dict[str, Any]] = {}
    if backend not in BACKENDS:
        raise CrmgraspError(f"unknown backend {backend!r}; choose one of {', '.join(BACKENDS)}")
    ctx: dict[str, Any] = {"backend": backend}
    lines = [
        "# crmgrasp reproduction",
        "",
        f"seed {seed}, quick={quick}. Regenerate with `crmgrasp reproduce{' --quick' if quick else ''} --seed {seed}`.",
        "",
        "| figure | quantity | ours | paper |",
        "| --- | --- | --- | --- |",
    ]
    body: list[str] = []
    for name in sorted(names, key=list(EXPERIMENTS).index):
        desc, run = EXPERIMENTS[name]
        t0 = time.perf_counter()
        summary, rows = run(out / name, seed, quick, ctx)
        summary["seconds"] = round(time.perf_counter() - t0, 3)
        results[name] = summary
        lines += [f"| {name} | {_cell(q)} | {_cell(ours)} | {_cell(paper)} |" for q, ours, paper in rows]
        body += [f"## {name}", "", desc, ""] + [
            f"![{name}]({name}/{img})" for img in IMAGES[name] if (out / name / img).exists()
        ]
        body += ["", f"Data and config: `{name}/` ({summary['seconds']} s).", ""]
    lines += [f"| {name} | skipped: needs `pip install 'crmgrasp[mujoco]'` | - | - |" for name in skipped]
    atomic_write_text(out / "README.md", "\n".join([*lines, "", *body]))
    return results

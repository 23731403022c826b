"""The paper's experiments, one function per figure, and the ``reproduce`` driver.

Each experiment writes its data (CSV), figure (PNG) and the configuration it ran
with (JSON) into its own folder; :func:`reproduce` runs them all into one output
folder and writes an index ``README.md`` beside them.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path

from .._io import atomic_write_text
from .._validation import CrmgraspError
from .figure4 import Figure4Config, figure_4_opposition_quality

__all__ = ["EXPERIMENTS", "reproduce", "figure_4_opposition_quality", "Figure4Config"]


def _figure4(out: Path, seed: int, quick: bool) -> dict[str, object]:
    return figure_4_opposition_quality(out, Figure4Config(seed=seed))


EXPERIMENTS: dict[str, tuple[str, Callable[[Path, int, bool], dict[str, object]]]] = {
    "figure4": ("Fig. 4: min-friction histogram of 30 opposition CRMs under sensing noise", _figure4),
}
"""Experiment name -> (description, runner(out_dir, seed, quick))."""

PAPER_NUMBERS = {
    "figure4": "histogram of 30 Robonaut grasps, most below 0.1 (read off the paper's Fig. 4)",
}


def reproduce(
    out_dir: str | Path, names: list[str] | None = None, *, seed: int = 0, quick: bool = False
) -> dict[str, dict[str, object]]:
    """Run the named experiments (all by default) into ``out_dir/<name>/`` and write
    ``out_dir/README.md`` indexing every figure with our numbers beside the paper's."""
    names = list(EXPERIMENTS) if not names else names
    unknown = [n for n in names if n not in EXPERIMENTS]
    if unknown:
        raise CrmgraspError(f"unknown experiment {unknown[0]!r}; known: {', '.join(EXPERIMENTS)}")
    out = Path(out_dir)
    results: dict[str, dict[str, object]] = {}
    lines = ["# crmgrasp reproduction", "", f"seed {seed}, quick={quick}", ""]
    for name in names:
        desc, run = EXPERIMENTS[name]
        t0 = time.perf_counter()
        summary = run(out / name, seed, quick)
        summary["seconds"] = round(time.perf_counter() - t0, 3)
        results[name] = summary
        lines += [
            f"## {name}",
            "",
            desc,
            "",
            f"![{name}]({name}/{name}.png)",
            "",
            "| quantity | ours | paper |",
            "| --- | --- | --- |",
        ]
        lines += [f"| {k} | {v} | |" for k, v in summary.items()]
        lines += [
            f"| (paper) | | {PAPER_NUMBERS.get(name, '')} |",
            "",
            f"Files: `{name}/data.csv`, `{name}/{name}.png`, `{name}/config.json`.",
            "",
        ]
    atomic_write_text(out / "README.md", "\n".join(lines))
    return results

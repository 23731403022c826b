"""The paper's experiments, one function per figure, and the ``reproduce`` driver.

Each experiment writes its data (CSV), figure (PNG) and the configuration it ran
with (JSON) into its own folder; [`reproduce`][] ([`crmgrasp.experiments.reproduce`][])
runs the experiments of [`crmgrasp.experiments.registry`][] into one output folder
and writes an index ``README.md`` that shows every figure and compares our numbers
with the paper's.
"""

from __future__ import annotations

import importlib
from typing import Any

from crmgrasp.experiments.registry import EXPERIMENTS
from crmgrasp.experiments.reproduce import reproduce

_HOMES = {
    "figure_4_opposition_quality": "crmgrasp.experiments.figure4",
    "Figure4Config": "crmgrasp.experiments.figure4",
    "figure_7_learning_curve": "crmgrasp.experiments.figure7",
    "Figure7Config": "crmgrasp.experiments.figure7",
    "figure_8_strategies": "crmgrasp.experiments.figure8",
    "Figure8Config": "crmgrasp.experiments.figure8",
    "figure_9_robonaut_trials": "crmgrasp.experiments.figure9",
    "Figure9Config": "crmgrasp.experiments.figure9",
}
"""Where each figure's function lives: imported on first use (PEP 562), so that the
command line reads the registry without loading plotting and every experiment."""


def __getattr__(name: str) -> Any:
    home = _HOMES.get(name)
    if home is None:
        raise AttributeError(f"module 'crmgrasp.experiments' has no attribute {name!r}")
    return getattr(importlib.import_module(home), name)


__all__ = [
    "EXPERIMENTS",
    "reproduce",
    "figure_4_opposition_quality",
    "figure_7_learning_curve",
    "figure_8_strategies",
    "figure_9_robonaut_trials",
    "Figure4Config",
    "Figure7Config",
    "Figure8Config",
    "Figure9Config",
]

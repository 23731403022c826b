"""The paper's experiments, one function per figure, and the ``reproduce`` driver.

Each experiment writes its data (CSV), figure (PNG) and the configuration it ran
with (JSON) into its own folder; :func:`reproduce` (:mod:`crmgrasp.experiments.reproduce`)
runs the experiments of :mod:`crmgrasp.experiments.registry` into one output folder
and writes an index ``README.md`` that shows every figure and compares our numbers
with the paper's.
"""

from crmgrasp.experiments.figure4 import Figure4Config, figure_4_opposition_quality
from crmgrasp.experiments.figure7 import Figure7Config, figure_7_learning_curve
from crmgrasp.experiments.figure8 import Figure8Config, figure_8_strategies
from crmgrasp.experiments.figure9 import Figure9Config, figure_9_robonaut_trials
from crmgrasp.experiments.registry import EXPERIMENTS
from crmgrasp.experiments.reproduce import reproduce

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

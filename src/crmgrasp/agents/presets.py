"""Learner presets: named settings of ``crmgrasp learn`` (and of any caller), with the
rule that fills what the user did not give.

A preset names an agent, a history order and whether to learn on the mirror quotient
where the task declares a symmetry (tabular learners). Every preset learns from scratch:
a prior learned on another task is used only when the user names that task
(``prior_task``, ``--prior-task``), and its episodes are then counted and reported.
[`apply_preset`][] is the one place that combines a preset with the user's choices; the
command line lists [`PRESETS`][] and their descriptions.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

from crmgrasp._validation import CrmgraspError, known, shown
from crmgrasp.agents.tabular import TabularAgent
from crmgrasp.agents.training import AGENTS
from crmgrasp.tasks import Task, checked_task

__all__ = ["LearnerPreset", "PRESETS", "LearnerChoice", "apply_preset"]


@dataclass(frozen=True)
class LearnerPreset:
    """A named learner setting.

    Parameters
    ----------
    agent
        A registered agent ([`crmgrasp.agents.training.AGENTS`][]).
    k
        History order.
    symmetric
        Learn on the mirror quotient where the task declares a symmetry (tabular agents only).
    description
        One line for ``--help``.
    params
        The agent's keyword parameters the preset sets, ``(name, value)`` pairs: each applies
        where the user gives no value of their own, and only when the preset's agent runs.
    """

    agent: str
    k: int
    symmetric: bool = False
    description: str = ""
    params: tuple[tuple[str, float | int | bool], ...] = ()


PRESETS: dict[str, LearnerPreset] = {
    "paper": LearnerPreset("sarsa", 2, description="the paper's SARSA, k = 2"),
    "fastest": LearnerPreset(
        "pooled-vi",
        1,
        symmetric=True,
        params=(("skip_errored", True),),
        description="pooled-vi, k = 1, on the mirror quotient where the task declares one, its greedy policy never "
        "repeating a CRM that erred since the contacts last moved (skip_errored); from scratch",
    ),
    "families": LearnerPreset(
        "backoff-vi",
        2,
        symmetric=True,
        params=(("skip_errored", True), ("mean_after", 2000)),
        description="backoff-vi, k = 2: two-CRM histories backed off to k = 1, for object families, its greedy "
        "policy never repeating a CRM that erred since the contacts last moved (skip_errored), acting on the "
        "model's posterior mean instead of a draw after episode 2,000 (mean_after); from scratch",
    ),
    "costly-errors": LearnerPreset(
        "backoff-vi",
        6,
        symmetric=True,
        params=(("explore", 2.0), ("explore_tried", 2.0)),
        description="backoff-vi, k = 6, explore = explore_tried = 2: for tasks where an errored CRM costs more "
        "(error_cost); from scratch",
    ),
}
"""The presets of ``crmgrasp learn --preset``."""


class LearnerChoice(NamedTuple):
    """What a learner run uses: agent, history order, mirror quotient, prior task (or None),
    and the preset's agent parameters (``(name, value)`` pairs) for the caller to apply
    where the user gave none."""

    agent: str
    k: int
    symmetric: bool
    prior_task: str | None
    params: tuple[tuple[str, float | int | bool], ...] = ()


def apply_preset(
    name: str,
    task: Task,
    *,
    agent: str | None = None,
    k: int | None = None,
    symmetric: bool = False,
    prior_task: str | None = None,
) -> LearnerChoice:
    """The preset ``name`` with the user's choices on top: a given ``agent`` or ``k`` wins;
    ``prior_task`` is the user's alone (no preset adds one); the mirror quotient is on if
    asked for, or if the preset wants it, the agent is tabular and the task declares a
    symmetry; the preset's parameters come along only when its own agent runs."""
    preset = PRESETS[known(name, PRESETS, "preset")]
    checked_task(task, "apply_preset")
    if agent is not None and not isinstance(agent, str):  # any learner's name: the caller resolves it
        raise CrmgraspError(f"agent must be a learner's name, got {shown(agent)}")
    chosen = preset.agent if agent is None else agent
    made = AGENTS.get(chosen)
    tabular = isinstance(made, type) and issubclass(made, TabularAgent)
    mirror = symmetric or (preset.symmetric and tabular and task.symmetry is not None)
    params = preset.params if chosen == preset.agent else ()
    return LearnerChoice(chosen, preset.k if k is None else k, mirror, prior_task, params)

"""A realizable reference: the belief-space policy planned over starts drawn apart from
the ones it is scored on.

The belief-space optimum over sampled starts ([`crmgrasp.planners.references.belief_optimum`][])
is the best policy for those very starts, so on a family of objects it is optimistic: in
expectation at most the family's own optimum ``J*``, and the more so the fewer starts.
The same planner over ``n`` *other* starts ([`BeliefPolicy`][crmgrasp.planners.references.BeliefPolicy]),
run from the starts, knows the task's distribution (it plans on draws from it) but not the
starts: its mean cost is a policy's, at least ``J*`` in expectation. Together they bracket
``J*``; how far apart they are says how far the sample size still moves the optimum.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence

import numpy as np

from crmgrasp._progress import Progress
from crmgrasp._validation import CrmgraspError, shown
from crmgrasp.model.hand import Error
from crmgrasp.model.sensing import SensorNoise
from crmgrasp.planners.references import BeliefPolicy, graspable_starts, sample_starts
from crmgrasp.planners.sampled import Start, checked_starts, expansion_kernel
from crmgrasp.sim import run_episode
from crmgrasp.tasks import Task, checked_task

__all__ = ["policy_costs", "realizable_reference"]


def policy_costs(
    policy: BeliefPolicy, starts: Sequence[Start], advance: Callable[[], None] | None = None
) -> np.ndarray:
    """The cost per start of a belief-space policy ([`BeliefPolicy`][], planned over its
    own starts) run from each of ``starts``: its CRMs, plus ``task.error_cost`` per errored
    CRM (the cost [`belief_optimum`][crmgrasp.planners.references.belief_optimum] counts), to
    the step limit where it does not grasp; noise-free, as the policy plans.

    Planned over the starts themselves, the mean is that optimum over them. Planned over
    worlds sampled apart from the starts, the policy knows the task's distribution (it plans
    on draws from it) but not the starts it runs on: its mean cost estimates a realizable
    policy's, at least the task's own optimum in expectation, where the optimum over the
    starts is at most that in expectation (it is the best policy for those very starts).
    ``advance``, if given, is called after each start (a progress display's)."""
    if not isinstance(policy, BeliefPolicy):
        raise CrmgraspError(f"policy_costs needs a BeliefPolicy, got {shown(policy)}")
    if advance is not None and not callable(advance):
        raise CrmgraspError(f"advance must be a function or None, got {shown(advance)}")
    checked_starts(starts, "policy_costs")
    task, backend = policy.task, policy.backend
    if task.noise.active:  # noise-free dynamics, as the references' own
        task = dataclasses.replace(task, noise=SensorNoise())
    kernel, counted = expansion_kernel(task, backend), task.error_cost > 0.0
    rng = np.random.default_rng(0)  # never drawn from: no sensing noise, and every start given
    costs = np.empty(len(starts))
    for i, start in enumerate(starts):
        ep = run_episode(task, policy, rng, start=start, trace=counted, kernel=kernel)
        errors = sum(t.after.error != Error.NONE for t in ep.trace)
        costs[i] = ep.steps + task.error_cost * errors
        if advance is not None:
            advance()
    return costs


def realizable_reference(
    task: Task,
    starts: Sequence[Start],
    n: int,
    seed: int,
    fallback: str = "restart",
    backend: str = "auto",
    progress: Progress | None = None,
) -> dict[str, float | int | str | None]:
    """The belief-space policy planned over ``n`` starts drawn with ``seed`` (apart from
    ``starts``), run from each of ``starts``, beside the optimum over ``starts``
    ([`policy_costs`][] of both): ``optimum`` (the value of
    [`belief_optimum`][crmgrasp.planners.references.belief_optimum], bit for bit, from the
    optimal policy's own search), ``mean`` and its ``standard_error`` over the starts,
    ``over_optimum`` (``mean / optimum - 1``), and the same on the graspable starts only
    ([`graspable_starts`][]; ``None`` where there are none), where an ungraspable start
    costs both the step limit. In expectation the task's own optimum lies between the
    optimum over ``starts`` (at most it) and ``mean`` (at least it). ``progress`` shows each
    policy's run over the starts (it plans as they run)."""
    checked_starts(starts, "realizable_reference")
    other = BeliefPolicy(task, sample_starts(checked_task(task, "realizable_reference"), n, seed), fallback, backend)
    best = BeliefPolicy(task, starts, backend=backend)
    value = best.optimum()
    optimum = _run(best, starts, progress, "the optimum over the starts")
    del best  # its memo, the largest object, goes before the other policy plans
    cost = _run(other, starts, progress, f"a policy over {n} other starts")
    graspable = graspable_starts(task, starts, backend=backend)
    k = int(graspable.sum())
    out: dict[str, float | int | str | None] = {
        "planned_starts": n,
        "seed": seed,
        "fallback": fallback,
        "optimum": value,
        "mean": float(cost.mean()),
        "standard_error": float(cost.std(ddof=1) / np.sqrt(len(cost))) if len(cost) > 1 else None,
        "over_optimum": float(cost.mean() / optimum.mean() - 1.0),
        "graspable_starts": k,
        "optimum_graspable": None,
        "mean_graspable": None,
        "over_optimum_graspable": None,
    }
    if k:
        opt, mean = float(optimum[graspable].mean()), float(cost[graspable].mean())
        out |= {"optimum_graspable": opt, "mean_graspable": mean, "over_optimum_graspable": mean / opt - 1.0}
    return out


def _run(policy: BeliefPolicy, starts: Sequence[Start], progress: Progress | None, label: str) -> np.ndarray:
    """[`policy_costs`][], shown as a stage of ``progress`` where there is one."""
    if progress is None:
        return policy_costs(policy, starts)
    with progress.stage(label, len(starts), "starts"):
        return policy_costs(policy, starts, progress.advance)

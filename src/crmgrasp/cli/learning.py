"""The ``crmgrasp`` commands that learn and score policies: ``learn`` (a learner preset, the
agent's options, a run folder) and ``evaluate`` (a saved policy on the model or a hand)."""

from __future__ import annotations

import argparse
import math
import sys
from typing import TYPE_CHECKING, Any

import numpy as np

from crmgrasp._validation import CrmgraspError
from crmgrasp.cli.common import _print_result, _progress, _run_folder, _task
from crmgrasp.cli.parser import _AGENT_FLAGS
from crmgrasp.tasks import Task, task_to_dict

if TYPE_CHECKING:
    from crmgrasp.experiments.learning import LearnerSpec


def _to_5pct_lines(s: dict[str, Any]) -> list[str]:
    """How soon a learn run came within 5% of its task's optimum: the greedy policy on the
    checkpoints' fixed starts first (robust), then the training curve's 10-episode average,
    marked when it lands in the budget's last tenth (bound by the episodes' noise there)."""
    from crmgrasp.experiments.stats import budget, fmt

    ref, lines = fmt(s["reference_mean_steps"], 2), []
    mark = "" if s["converged"] else f" (not converged at {budget(s['trials'], s['episodes'])})"

    def when(e: int | None) -> str:
        return "never" if e is None else f"from episode {e:,}"

    if s["checkpoint_episodes"]:
        greedy = when(s["greedy_episodes_to_5pct"])
        lines.append(f"  greedy policy (checkpoints on fixed starts) within 5% of {ref}: {greedy}")
    e = s["episodes_to_5pct"]
    noisy = e is not None and e > 0.9 * s["episodes"]
    note = " (in the budget's last tenth: bound by the episodes' noise more than by learning)" if noisy else ""
    lines.append(f"  training curve (10-episode average) within 5% of {ref}: {when(e)}{mark}{note}")
    return lines


def _learner_params(args: argparse.Namespace) -> dict[str, Any]:
    from crmgrasp.agents.deep import DEEP_AGENTS
    from crmgrasp.agents.deep_trials import deep_defaults
    from crmgrasp.agents.training import PRIOR_KEYS, agent_parameters, takes_prior

    params: dict[str, Any] = {}
    if args.agent in DEEP_AGENTS:
        accepted = tuple(deep_defaults(args.agent))
    else:
        accepted = agent_parameters(args.agent) + (PRIOR_KEYS[:2] if takes_prior(args.agent) else ())
    flags = {flag.lstrip("-").replace("-", "_"): flag for flag, _, _ in _AGENT_FLAGS}
    for key, flag in flags.items():
        if getattr(args, key) is not None:
            if key not in accepted:
                named = {**flags, "continuous": "--continuous"}
                takes = ", ".join(named[k] for k in accepted if k in named) or "none"
                raise CrmgraspError(f"{flag} does not apply to --agent {args.agent} (its options: {takes})")
            params[key] = getattr(args, key)
    for flag, key, applies in (("--symmetric", "symmetric", False), ("--continuous", "continuous", True)):
        if getattr(args, key):  # the mirror quotient is the tabular learners', the continuous space the deep ones'
            if (args.agent in DEEP_AGENTS) != applies:
                raise CrmgraspError(f"{flag} does not apply to --agent {args.agent}")
            params[key] = True
    return params


def _apply_preset(args: argparse.Namespace, task: Any) -> None:
    """Fill ``--agent``, ``--k``, ``--symmetric``, ``--prior-task`` and the preset's agent
    parameters (``--explore``, ...) from ``--preset`` where not given
    ([`crmgrasp.agents.presets.apply_preset`][])."""
    from crmgrasp.agents.deep import DEEP_AGENTS
    from crmgrasp.agents.presets import apply_preset

    if args.k is not None and args.agent in DEEP_AGENTS:  # it would be dropped silently
        raise CrmgraspError(f"--k does not apply to --agent {args.agent}: a deep learner keeps no k-order history")
    choice = apply_preset(
        args.preset, task, agent=args.agent, k=args.k, symmetric=args.symmetric, prior_task=args.prior_task
    )
    args.agent, args.k, args.symmetric, args.prior_task, params = choice
    for key, value in params:
        if getattr(args, key) is None:
            setattr(args, key, value)


def _warn_if_ungraspable(task: Task, seed: int, backend: str) -> None:
    """Say before training when a quick check finds no graspable start (the library's
    [`graspable_warning`][crmgrasp.planners.references.graspable_warning])."""
    from crmgrasp.planners.references import graspable_warning

    warning = graspable_warning(task, seed=seed, backend=backend)
    if warning:
        print(f"crmgrasp: warning: {warning}", file=sys.stderr)


def _cmd_learn(args: argparse.Namespace) -> int:
    from crmgrasp.agents.deep import DEEP_AGENTS
    from crmgrasp.experiments.learning import LearnerSpec, learn, write_learn_outputs

    task = _task(args)
    _apply_preset(args, task)
    deep = args.agent in DEEP_AGENTS
    spec = LearnerSpec(args.agent, args.k, _learner_params(args), args.agent if deep else "")
    checkpoint_episodes = args.checkpoint_episodes
    if checkpoint_episodes is None:
        checkpoint_episodes = 100 if args.hand == "kinematic" else 0
    prior = _check_learn(args, task, spec, deep)
    config = {
        "task": task_to_dict(task),
        "agent": spec.agent,
        "k": None if deep else spec.k,
        "params": spec.params,
        "prior": prior,
        "trials": args.trials,
        "episodes": args.episodes,
        "eval_episodes": args.eval_episodes,
        "checkpoint_episodes": checkpoint_episodes,
        "hand": args.hand,
        "seed": args.seed,
    }
    with _run_folder(args, task.name, config) as folder:
        run = learn(
            task,
            spec,
            trials=args.trials,
            episodes=args.episodes,
            seed=args.seed,
            eval_episodes=args.eval_episodes,
            lockstep=args.lockstep,
            backend=args.backend,
            store=folder,
            progress=_progress(args),
            jobs=args.jobs,
            checkpoint_episodes=checkpoint_episodes,
            hand=args.hand,
        )
        paths = write_learn_outputs(task, run, folder.path)
    _print_learned(args, task.name, run.summary, prior)
    print(f"  run folder: {folder.path.resolve()}")
    for path in paths:
        print(f"  wrote {path.name}")
    return 0


def _check_learn(args: argparse.Namespace, task: Task, spec: LearnerSpec, deep: bool) -> dict[str, Any] | None:
    """Everything ``learn`` can refuse before it makes a run folder (budget, hand, the
    learner's settings or its missing extra), the warning about ungraspable starts, and the
    prior's settings (None without one), announced on stderr."""
    from crmgrasp.agents.deep_trials import check_deep
    from crmgrasp.agents.training import build_agent, check_budget, encoder_for, prior_settings
    from crmgrasp.experiments.learning import check_hand

    check_budget(args.trials, args.episodes, args.eval_episodes)
    check_hand(args.hand, args.lockstep, spec.agent)
    if deep:
        check_deep(spec.agent, spec.params)
    else:
        build_agent(task, encoder_for(task, spec.k), spec.agent, spec.params)
    _warn_if_ungraspable(task, args.seed, args.backend)
    prior = prior_settings(spec.params)
    if prior is not None:
        print(
            f"crmgrasp: prior: {prior['episodes']:,} episodes on {prior['task']} (seed {prior['seed']}, weight "
            f"{prior['weight']}), learned once before the task episodes and counted with them",
            file=sys.stderr,
        )
    return prior


def _print_learned(args: argparse.Namespace, task_name: str, s: dict[str, Any], prior: dict[str, Any] | None) -> None:
    """The summary of a finished ``learn``: budget and time, the hand's faults, the prior,
    the last training episodes and the greedy policy with its interval over the trials."""
    from crmgrasp.experiments.stats import budget, ci_text, fmt

    lo, hi = (math.nan if v is None else v for v in s["greedy_ci95_over_trials"])
    where = "" if args.hand == "kinematic" else f" ({args.hand} hand)"
    cost = f"{budget(s['trials'], s['episodes'], s['seed'])}, {fmt(s['seconds'], 1)} s"
    print(f"{s['label']} on {task_name}{where}: {cost}")
    if args.hand != "kinematic":
        ended = ", ".join(f"{n} {kind}" for kind, n in s["faults"].items()) or "none"
        print(f"  episodes the {args.hand} hand ended early (physics faults, lost contacts): {ended}")
    if prior is not None:
        print(f"  after a prior of {prior['episodes']:,} episodes on {prior['task']} (not {task_name})")
    print(f"  CRMs per episode, last 10 training episodes: {fmt(s['final_mean_steps'])}")
    if s["eval_episodes"] == 0:
        print("  greedy policy: not evaluated (--eval-episodes 0)")
    else:
        print(
            f"  greedy policy: {fmt(s['greedy_mean_steps'])} CRMs ({ci_text(lo, hi)}, "
            f"IQM {fmt(s['greedy_iqm_steps'])}), success {s['greedy_success_rate']:.1%}"
        )
    if s["reference_mean_steps"]:
        print("\n".join(_to_5pct_lines(s)))


def _cmd_evaluate(args: argparse.Namespace) -> int:
    from crmgrasp.agents import evaluate
    from crmgrasp.agents.loading import load_policy
    from crmgrasp.agents.policy import GreedyPolicy
    from crmgrasp.hardware import hand_steps
    from crmgrasp.kernels import kernel_for

    policy = load_policy(args.policy, None if args.task is None else _task(args))
    task = policy.task
    on_hand = hand_steps(args.hand)
    if on_hand is not None and not isinstance(policy, GreedyPolicy):
        raise CrmgraspError(f"--hand {args.hand} runs tabular policies (policy.json); a deep policy runs on the model")
    kernel = kernel_for(task, args.backend) if on_hand is None else on_hand(task)
    rng = np.random.default_rng(args.seed)
    with _progress(args).stage(f"evaluate {args.policy.name} on {task.name}", 0):
        if isinstance(policy, GreedyPolicy):
            steps, success = evaluate(task, policy, policy.encoder, args.episodes, rng, kernel=kernel)
        else:
            from crmgrasp.agents.deep import evaluate_recurrent

            starts = [task.sample_world(rng) for _ in range(args.episodes)]  # sample_start's stream
            steps, success = evaluate_recurrent(policy.model, task, starts, rng)
    from crmgrasp.experiments.stats import normal_ci

    mean, lo, hi = normal_ci(steps)
    result = {
        "task": task.name,
        "policy": str(args.policy),
        "kind": "tabular" if isinstance(policy, GreedyPolicy) else "deep",
        "episodes": args.episodes,
        "seed": args.seed,
        "mean_steps": mean,
        "ci95": [lo, hi],
        "success_rate": float(success.mean()),
        "hand": args.hand,
        "faults": dict(sorted(getattr(kernel, "faults", {}).items())),
    }
    where = "" if on_hand is None else f" ({args.hand} hand; episodes ended early: {result['faults'] or 'none'})"
    return _print_result(
        args,
        result,
        f"{args.policy} on {task.name}{where}: {result['mean_steps']:.3f} CRMs per episode "
        f"(95% CI over episodes {result['ci95'][0]:.3f}-{result['ci95'][1]:.3f}), "
        f"success {result['success_rate']:.1%} over {args.episodes:,} episodes",
    )

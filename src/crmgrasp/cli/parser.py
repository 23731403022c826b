"""Argument parser of the ``crmgrasp`` command: one builder per command ([`COMMANDS`][]), on
the shared option groups of [`crmgrasp.cli.options`][]."""

from __future__ import annotations

import argparse
from collections.abc import Callable
from typing import Any

from crmgrasp import __version__
from crmgrasp.agents.deep import DEEP_AGENTS
from crmgrasp.agents.deep_trials import deep_defaults
from crmgrasp.agents.presets import PRESETS
from crmgrasp.agents.training import AGENTS, parameter_defaults
from crmgrasp.cli.options import (
    _EPISODES,
    _EVAL_EPISODES,
    _SEED,
    _STARTS,
    _TRIALS,
    _add_hand,
    _add_jobs,
    _add_kernel_backend,
    _add_noise,
    _add_points,
    _add_quiet,
    _add_run,
    _add_scene_args,
    _add_task,
    _boolean,
    _int,
    _number,
    _Parser,
    _path,
)
from crmgrasp.experiments.registry import EXPERIMENTS
from crmgrasp.model.history import MAX_K
from crmgrasp.planners.references import FALLBACKS

__all__ = ["build_parser"]


def _parser_crm(sub: Any) -> None:
    """``crmgrasp crm``."""
    p = sub.add_parser(
        "crm",
        help="execute one CRM and print the outcome",
        description="Execute one CRM from the configuration given by --a and --b.",
    )
    _add_scene_args(p, crm_required=True)
    p.add_argument("--json", action="store_true", help="print JSON instead of text")


def _parser_show(sub: Any) -> None:
    """``crmgrasp show``."""
    p = sub.add_parser(
        "show",
        help="draw the scene (and a CRM) to an image",
        description="Draw object, contacts with normals, palm point and, with --crm, the goal line and path.",
    )
    _add_scene_args(p, crm_required=False)
    _add_out_file(p, "image file (.png, .pdf, .svg; mujoco: .png or .gif)")
    _add_hand(p)


def _parser_reproduce(sub: Any) -> None:
    """``crmgrasp reproduce``."""
    p = sub.add_parser(
        "reproduce",
        help="run the paper's experiments",
        description="Run the paper's experiments into one folder with an index README.md.",
    )
    p.add_argument(
        "experiments",
        nargs="*",
        metavar="NAME",
        help=f"experiments to run: {', '.join(EXPERIMENTS)} (default: all; the MuJoCo ones need crmgrasp[mujoco])",
    )
    p.add_argument("--seed", type=_SEED, default=0, help="seed of the run (default 0; 0 to 2**63-1)")
    p.add_argument(
        "--quick",
        action="store_true",
        help="small budgets (not converged; 1.5 minutes on 2 cores in one process, under one with --jobs 0)",
    )
    _add_run(p, "reproduce")
    _add_jobs(p)
    _add_kernel_backend(p)


def _parser_learn(sub: Any) -> None:
    """``crmgrasp learn``."""
    p = sub.add_parser(
        "learn",
        help="train a learner over independent trials",
        description="Train a learner on a task; write curve.csv, summary.json, checkpoints.csv, policy.json "
        "and learning_curve.png to a run folder (with run.json: settings, versions, status).",
    )
    _add_task(p)
    p.add_argument(
        "--preset",
        default="paper",
        choices=tuple(PRESETS),
        help="learner settings: "
        + "; ".join(f"{name} ({preset.description})" for name, preset in PRESETS.items())
        + "; --agent and --k override them; no preset adds a prior (--prior-task)",
    )
    p.add_argument(
        "--agent",
        default=None,
        choices=(*AGENTS, *DEEP_AGENTS),
        help="learner or baseline (default: the preset's); deep learners (crmgrasp[deep]): "
        + "; ".join(f"{name}, {a.description}" for name, a in DEEP_AGENTS.items()),
    )
    p.add_argument(
        "--k",
        type=_int(0, MAX_K),
        default=None,
        help=f"history order of a tabular learner (default: the preset's; 0 to {MAX_K}; a deep learner has none)",
    )
    p.add_argument("--trials", type=_TRIALS, default=20, help="independent trials (default 20; 1 to 100,000)")
    p.add_argument(
        "--episodes", type=_EPISODES, default=2000, help="training episodes per trial (default 2000; 1 to 10,000,000)"
    )
    p.add_argument(
        "--eval-episodes",
        type=_EVAL_EPISODES,
        default=1000,
        help="greedy evaluation episodes per trial (default 1000; 0 to 10,000,000)",
    )
    p.add_argument("--seed", type=_SEED, default=0, help="seed of the run (default 0; 0 to 2**63-1)")
    _add_run(p, "learn")
    _add_jobs(p)
    p.add_argument(
        "--lockstep",
        action="store_true",
        help="step all trials together through the batched simulator (same results; faster from ~500 trials)",
    )
    _add_kernel_backend(p)
    _add_hand(p, "learns on (every episode: training, checkpoints, evaluation)")
    p.add_argument(
        "--checkpoint-episodes",
        type=_EVAL_EPISODES,
        default=None,
        help="greedy evaluation episodes at each checkpoint (5, 10, 15, 20, 30, ... training episodes; "
        "default 100 on the kinematic model, 0 = none on another hand, where each costs a physics episode)",
    )
    p.add_argument(
        "--symmetric",
        action="store_true",
        help="learn on the mirror quotient of the task (tabular learners; the task must declare a symmetry)",
    )
    p.add_argument(
        "--continuous",
        action="store_true",
        help="deep learners: act in the continuous action space (a contact pair and a real offset, "
        "through the flat Box action); sac always does",
    )
    for flag, kind, text in _AGENT_FLAGS:
        help_text = f"{text} ({_defaults_text(flag)})"
        if isinstance(kind, tuple):
            p.add_argument(flag, choices=kind, default=None, help=help_text)
        else:
            p.add_argument(flag, type=kind, default=None, help=help_text)


def _parser_evaluate(sub: Any) -> None:
    """``crmgrasp evaluate``."""
    p = sub.add_parser(
        "evaluate",
        help="evaluate a saved policy",
        description="Run a saved policy greedily on fresh episodes of its task.",
    )
    p.add_argument(
        "--policy",
        type=_path,
        required=True,
        help="a saved policy, carrying its task: policy.json (`crmgrasp learn`) or recurrent_ppo.zip "
        "(`crmgrasp compare`, needs crmgrasp[deep])",
    )
    p.add_argument(
        "--task", default=None, metavar="TASK", help="check the policy against this task (default: the policy's own)"
    )
    p.add_argument("--episodes", type=_EPISODES, default=1000, help="episodes (default 1000; 1 to 10,000,000)")
    p.add_argument("--seed", type=_SEED, default=0, help="seed (default 0; 0 to 2**63-1)")
    p.add_argument("--json", action="store_true", help="print JSON instead of text")
    _add_quiet(p)
    _add_kernel_backend(p)
    _add_hand(p, "runs the episodes on (a tabular policy; success from the hand's true contacts)")


def _parser_bench(sub: Any) -> None:
    """``crmgrasp bench``."""
    p = sub.add_parser(
        "bench",
        help="speed benchmarks against Gymnasium's CartPole",
        description="Time paper-box against CartPole-v1 in one process; print one JSON object.",
    )
    p.add_argument("--smoke", action="store_true", help="tiny sizes (CI): no meaningful timings")
    p.add_argument("--rounds", type=_int(1, 1000), default=15, help="alternating rounds (default 15; 1 to 1,000)")
    p.add_argument("--seed", type=_SEED, default=0, help="seed (default 0; 0 to 2**63-1)")


def _parser_references(sub: Any) -> None:
    """``crmgrasp references``."""
    p = sub.add_parser(
        "references",
        help="clairvoyant bound and belief-space optimum of a task",
        description="Exact reference values on sampled starts: the clairvoyant bound (full information) "
        "and the belief-space optimum (observations only), and the share of starts no CRM sequence grasps.",
    )
    _add_task(p)
    p.add_argument("--starts", type=_STARTS, default=4000, help="sampled starts (default 4000; 1 to 1,000,000)")
    p.add_argument("--seed", type=_SEED, default=0, help="seed of the starts (default 0; 0 to 2**63-1)")
    p.add_argument(
        "--blocks",
        type=_STARTS,
        default=1,
        help="also the belief-space optimum over each of this many disjoint blocks of the starts, their mean "
        "and a 95%% interval over the blocks: how far the sample size still moves the optimum, which on a "
        "family is optimistic and rises with more starts (default 1: none; must divide --starts)",
    )
    p.add_argument(
        "--planner",
        type=_STARTS,
        default=None,
        metavar="N",
        help="also run, from each start, the belief-space policy planned over N other sampled starts (worlds on "
        "a family): a policy that knows the task's distribution but not the starts, so its mean cost is at least "
        "the task's own optimum in expectation, as the optimum over the starts is at most that; both also on "
        "the graspable starts only (default: none; 1 to 1,000,000)",
    )
    p.add_argument(
        "--planner-seed",
        type=_SEED,
        default=None,
        metavar="SEED",
        help="seed of the planner's starts (default: --seed + 1; 0 to 2**63-1; with --planner only)",
    )
    p.add_argument(
        "--fallback",
        choices=FALLBACKS,
        default=None,
        help="the planner's belief when no planned start explains the history: restart from those with the "
        "current observation, or the nearest, those that explain all but the fewest observations (slower over "
        "many starts) (default: restart; with --planner only)",
    )
    p.add_argument("--json", action="store_true", help="print JSON instead of text")
    _add_kernel_backend(p)
    _add_quiet(p)


def _parser_plan(sub: Any) -> None:
    """``crmgrasp plan``."""
    p = sub.add_parser(
        "plan",
        help="plan a k-order policy on sampled worlds (belief-space planning), measure it on held-out ones",
        description="Search a policy of the last k CRMs and observations on sampled worlds (starting from the "
        "belief-space optimal policy, or with --init blank from nothing: then a learner from episodes, policy "
        "search on fixed worlds; improved by coordinate descent), then evaluate it greedily on held-out "
        "worlds against their belief-space optimum; writes policy.json and summary.json to the run folder.",
    )
    _add_task(p)
    p.add_argument("--worlds", type=_STARTS, default=1000, help="worlds planned on (default 1000; 1 to 1,000,000)")
    p.add_argument(
        "--heldout", type=_STARTS, default=400, help="held-out worlds evaluated on (default 400; 1 to 1,000,000)"
    )
    p.add_argument("--k", type=_int(0, 10), default=1, help="history order of the policy (default 1; 0 to 10)")
    p.add_argument(
        "--init",
        choices=("belief", "blank"),
        default="belief",
        help="start of the search: the belief-optimal policy (a planner: uses hidden states) or blank (a "
        "learner: episode costs only) (default belief)",
    )
    p.add_argument("--seed", type=_SEED, default=0, help="seed of the worlds (default 0; held-out: seed + 1)")
    _add_run(p, "plan")


def _parser_compare(sub: Any) -> None:
    """``crmgrasp compare``."""
    p = sub.add_parser(
        "compare",
        help="every method on one task, one table",
        description="Learners, baselines, the grasp controller and the exact references on one task, "
        "same seeds; writes compare.csv, compare.md and compare.png to the run folder.",
    )
    _add_task(p)
    p.add_argument("--seed", type=_SEED, default=0, help="seed (default 0; 0 to 2**63-1)")
    _add_run(p, "compare")
    _add_jobs(p)
    p.add_argument("--quick", action="store_true", help="small budgets (seconds; not converged)")
    p.add_argument(
        "--deep-steps",
        type=_int(0, 100_000_000),
        default=None,
        metavar="N",
        help="RecurrentPPO training steps (default 120000, --quick 4096; 0 leaves the deep-RL peer out)",
    )
    _add_kernel_backend(p)


def _parser_pomdp(sub: Any) -> None:
    """``crmgrasp pomdp``."""
    p = sub.add_parser(
        "pomdp",
        help="build the sampled POMDP of a task, solve it, export it",
        description="Build an explicit POMDP of a polygonal task by sampling the simulator, solve it by "
        "point-based value iteration, write it in Cassandra's .pomdp format, and run its policy.",
    )
    _add_task(p)
    p.add_argument("--cell", type=_number, default=0.01, help="cell size along each edge, m (default 0.01)")
    p.add_argument(
        "--samples",
        type=_int(1, 100_000),
        default=20,
        help="CRM samples per cell and action (default 20; 1 to 100,000)",
    )
    p.add_argument(
        "--starts",
        type=_STARTS,
        default=4000,
        help="sampled starts for the start belief (default 4000; 1 to 1,000,000)",
    )
    p.add_argument(
        "--episodes",
        type=_STARTS,
        default=1000,
        help="fresh starts to execute the policy on (default 1000; 1 to 1,000,000)",
    )
    p.add_argument(
        "--pouct",
        type=_int(1, 100_000),
        default=None,
        metavar="SIMS",
        help="also run pomdp_py's POUCT on the same model, SIMS simulations per CRM, on the same starts "
        "(extra crmgrasp[pomdp]; 1 to 100,000)",
    )
    p.add_argument("--seed", type=_SEED, default=0, help="seed (default 0; 0 to 2**63-1)")
    _add_out_file(p, "the .pomdp file to write")
    _add_quiet(p)


def _add_out_file(p: argparse.ArgumentParser, what: str) -> None:
    """``--out FILE`` (``what``) and ``--overwrite``: an existing file is refused without it."""
    p.add_argument("--out", type=_path, required=True, help=f"{what}; an existing one is refused unless --overwrite")
    p.add_argument("--overwrite", action="store_true", help="replace an existing --out")


def _parser_run(sub: Any) -> None:
    """``crmgrasp run``."""
    p = sub.add_parser(
        "run",
        help="run a saved policy on the kinematic hand, logging every step",
        description="Run a saved policy through the hand interface (the kinematic simulator, or with "
        "--hand mujoco the MuJoCo stand-in) from the configuration given by --a and --b (X,Y; on a spatial "
        "task X,Y,Z, projected to the family's nominal object from its centre), or without them from a start "
        "drawn from the task's own starts; write the step log to --log.",
    )
    p.add_argument(
        "--policy", type=_path, required=True, help="a saved policy: policy.json or recurrent_ppo.zip (deep)"
    )
    _add_points(p, "start point", default="every contact at a start drawn from the task's own starts with --seed")
    p.add_argument(
        "--log",
        type=_path,
        required=True,
        help="step log to write: CSV, or an MCAP record in Foxglove's schemas for a name ending in .mcap "
        "(extra crmgrasp[mcap]); an existing one is refused unless --overwrite",
    )
    p.add_argument(
        "--figure",
        type=_path,
        help="also draw the run to this image (.png, .pdf, .svg): one panel per reading, the sensed contacts "
        "and the CRM that followed; an existing one is refused unless --overwrite",
    )
    p.add_argument("--overwrite", action="store_true", help="replace an existing --log (and --figure)")
    _add_noise(p)
    p.add_argument("--seed", type=_SEED, default=0, help="seed (default 0; 0 to 2**63-1)")
    _add_hand(p)


def _parser_sweep(sub: Any) -> None:
    """``crmgrasp sweep``."""
    p = sub.add_parser(
        "sweep",
        help="run a study (grid of tasks, learners, parameters, seeds) or report on one",
        description="`crmgrasp sweep STUDY.toml` runs every (cell, seed) of a study into a run folder "
        "(results.csv, cells.csv, Parquet with pyarrow); `crmgrasp sweep report DIR` writes report.md and "
        "figures (bootstrap intervals over trials, interquartile means, a performance profile).",
    )
    p.add_argument("target", metavar="STUDY.toml|report", help="a study file, or the word report")
    p.add_argument("folder", nargs="?", type=_path, metavar="DIR", help="with report: the study's run folder")
    _add_run(p, "sweep")
    _add_jobs(p)
    p.add_argument(
        "--executor",
        choices=("local", "ray"),
        default="local",
        help="local worker processes, or Ray tasks (extra crmgrasp[ray]); the same results",
    )
    p.add_argument(
        "--address",
        default=None,
        metavar="auto|HOST:PORT",
        help="with --executor ray: the cluster to use (default: a local Ray instance of --jobs CPUs)",
    )
    _add_kernel_backend(p)


def _parser_tasks(sub: Any) -> None:
    """``crmgrasp tasks``."""
    sub.add_parser("tasks", help="list the built-in tasks", description="List the registered (built-in) tasks.")


def _parser_task_template(sub: Any) -> None:
    """``crmgrasp task-template``."""
    p = sub.add_parser(
        "task-template",
        help="print a commented example task file",
        description="Print a commented example task file (TOML): `crmgrasp task-template > my.toml`.",
    )
    p.add_argument("--keys", action="store_true", help="print every key a task file takes (type, default) instead")


def _parser_status(sub: Any) -> None:
    """``crmgrasp status``."""
    p = sub.add_parser(
        "status",
        help="say whether a run completed",
        description="Print the status of a run folder: running, complete, interrupted, failed, or killed "
        "(says running, but its process is gone).",
    )
    p.add_argument("run", type=_path, metavar="DIR", help="a run folder")


COMMANDS: tuple[Callable[[Any], None], ...] = (
    _parser_crm,
    _parser_show,
    _parser_reproduce,
    _parser_learn,
    _parser_evaluate,
    _parser_bench,
    _parser_references,
    _parser_plan,
    _parser_compare,
    _parser_pomdp,
    _parser_run,
    _parser_sweep,
    _parser_tasks,
    _parser_task_template,
    _parser_status,
)
"""The commands, in the order ``--help`` lists them."""


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``crmgrasp`` command: one sub-parser per command
    ([`COMMANDS`][])."""
    parser = _Parser(prog="crmgrasp", description="Grasp strategies composed of contact relative motions (Platt).")
    parser.add_argument("--version", action="version", version=f"crmgrasp {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    for add in COMMANDS:
        add(sub)
    return parser


_AGENT_FLAGS = (
    ("--alpha", _number, "learning rate"),
    ("--gamma", _number, "discount factor"),
    ("--epsilon", _number, "exploration probability (0: greedy)"),
    ("--q0", _number, "initial Q value (0: optimistic)"),
    ("--lam", _number, "trace decay lambda"),
    ("--trace", ("replacing", "accumulating"), "eligibility traces"),
    (
        "--n-planning",
        _int(0, 1_000_000),
        "planning updates (sample) or max sweeps (sweep) per step",
    ),
    ("--planning", ("sample", "sweep"), "sampled updates or value-iteration sweeps"),
    ("--q-act", _number, "acting value of an untried CRM"),
    ("--beta", _number, "weight of the prior, pseudo-counts (pooled-vi: pooled bins; backoff-vi: the k = 1 level)"),
    ("--alpha0", _number, "Dirichlet pseudo-counts per state-action pair"),
    ("--scale", _number, "exploration bonus factor"),
    ("--explore", _number, "pseudo-counts of a grasp in the posterior draw of a CRM a whole history never tried"),
    ("--explore-tried", _number, "pseudo-counts of a grasp in the posterior draw of a CRM a whole history has tried"),
    ("--plan-every", _int(1, 1_000_000), "re-plan the acting draw every N episodes (and before each of the first N)"),
    ("--mean-after", _int(0, 1_000_000_000), "act on the posterior mean after N episodes instead of a draw (0: never)"),
    ("--decay", _number, "weight factor per episode of a whole-history count, in (0, 1] (1: no forgetting)"),
    (
        "--skip-errored",
        _boolean,
        "true: the greedy policy never repeats a CRM that erred since the contacts last moved",
    ),
    ("--start-level", _int(0, 7), "the offsets open at first, 2**L + 1 per coordinate and pair"),
    ("--refine-after", _int(1, 1_000_000), "tries of a history's best CRM before finer offsets open around it"),
    ("--prior-task", str, "a task with the same CRMs and bins (e.g. box-family) to learn a prior on"),
    ("--prior-episodes", _int(1, 1_000_000), "episodes of the prior"),
)
"""The agents' keyword parameters as options of ``crmgrasp learn``: flag, type or choices,
meaning. Which agents take each, and their defaults, come from the agents themselves."""


def _defaults_text(flag: str) -> str:
    """``"sarsa, q: default 0.3"``-style text: the agents taking the parameter of ``flag``,
    grouped by their default (read from the agents' constructors)."""
    groups: dict[str, list[str]] = {}
    key = flag.lstrip("-").replace("-", "_")
    deep = {name: d[key] for name in DEEP_AGENTS if key in (d := deep_defaults(name))}
    for agent, default in {**parameter_defaults(key), **deep}.items():
        groups.setdefault(repr(default) if isinstance(default, str) else f"{default}", []).append(agent)
    return "; ".join(f"{', '.join(agents)}: default {value}" for value, agents in groups.items())

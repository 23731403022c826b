"""Argument parser of the ``crmgrasp`` command (one-line errors, negative-number values)."""

from __future__ import annotations

import argparse
import re
from collections.abc import Callable
from pathlib import Path
from typing import Any, NoReturn

from crmgrasp import __version__
from crmgrasp._validation import SEED_MAX, CrmgraspError, as_point, finite, integer, shown
from crmgrasp.agents.presets import PRESETS
from crmgrasp.agents.training import AGENTS, parameter_defaults
from crmgrasp.experiments.registry import EXPERIMENTS
from crmgrasp.model.history import MAX_K
from crmgrasp.tasks import Task
from crmgrasp.tasks.presets import START_PRESETS

__all__ = ["build_parser"]

_NUMBERISH = re.compile(r"^-[\d.]")


class _Help(argparse.HelpFormatter):
    """Help that shows every option's default (unless its text already states it)."""

    def _get_help_string(self, action: argparse.Action) -> str | None:
        text = action.help or ""
        if (
            "default" in text
            or action.default is None
            or action.default is False
            or action.default == argparse.SUPPRESS
            or action.option_strings == []
            or isinstance(action, (argparse._StoreTrueAction, argparse._VersionAction))
        ):
            return text
        return f"{text} (default: %(default)s)"


class _Parser(argparse.ArgumentParser):
    """argparse with one-line errors, defaults in the help, and values such as
    ``-0.15,-0.02``."""

    def __init__(self, *args: object, **kwargs: object) -> None:
        kwargs.setdefault("formatter_class", _Help)
        super().__init__(*args, **kwargs)  # type: ignore[arg-type]
        self._negative_number_matcher = _NUMBERISH

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message} (see --help)\n")


def _point(text: str) -> tuple[float, ...]:
    """X,Y (a planar task) or X,Y,Z (a spatial one; the task checks which it needs)."""
    parts = str(text).split(",")
    if len(parts) not in (2, 3):
        raise argparse.ArgumentTypeError(f"expected X,Y or X,Y,Z (numbers), got {text!r}")
    try:
        xy = as_point(parts[:2], "point")
        return xy if len(parts) == 2 else (*xy, finite(parts[2], "point z"))
    except CrmgraspError as exc:
        raise argparse.ArgumentTypeError(f"{exc} in {text!r}") from None


def _int(low: int, high: int) -> Callable[[str], int]:
    """An argparse type: an integer in ``[low, high]`` written in ASCII digits."""

    def parse(text: str) -> int:
        try:
            return integer(text, "value", low, high)
        except CrmgraspError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None

    parse.__name__ = "integer"
    return parse


_SEED = _int(0, SEED_MAX)
_TRIALS = _int(1, 100_000)
_EPISODES = _int(1, 10_000_000)
_EVAL_EPISODES = _int(0, 10_000_000)
_STARTS = _int(1, 1_000_000)


def _path(text: str) -> Path:
    """An argparse type: a non-empty path (``Path("")`` would silently mean ``.``)."""
    if text == "":
        raise argparse.ArgumentTypeError("the path is empty")
    return Path(text)


def _number(text: str) -> float:
    try:
        return finite(text, "value")
    except CrmgraspError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def _resolve_crm(task: Task, text: str) -> Any:
    """``C1``..``Cn`` names the task's actions; anything else is parsed as ``c,f,r``."""
    m = re.fullmatch(r"[Cc]([0-9]+)", text.strip())
    if m:
        i = int(m.group(1)) if len(m.group(1)) <= 6 else 0
        if not 1 <= i <= len(task.actions):
            raise CrmgraspError(f"task {task.name} has actions C1..C{len(task.actions)}, got {shown(text)}")
        return task.actions[i - 1]
    try:
        return task.model.parse_crm(text)
    except CrmgraspError as exc:
        raise CrmgraspError(f"{exc} (or name one of the task's actions C1..C{len(task.actions)})") from None


def _add_task(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--task",
        default="paper-box",
        metavar="TASK",
        help="a registered task (`crmgrasp tasks` lists them), a .toml task file "
        "(`crmgrasp task-template` writes one), or package.module:factory (default: paper-box)",
    )
    p.add_argument(
        "--start-preset",
        choices=tuple(START_PRESETS),
        default=None,
        help="replace the task's start distribution by a preset: corners (the paper-box rule), near-corner "
        "(both contacts within 0.10 m of a corner, like Fig. 8a), long-side (the long-side contact over 0.10 m "
        "from the corner, like Fig. 9), mixture (40%% near-corner, 60%% long-side) (default: the task's own)",
    )
    p.add_argument(
        "--grasp-reward",
        type=_number,
        default=None,
        metavar="R",
        help="reward of the grasping CRM, every other CRM -1 (default: the task's own, -1 for paper-box; "
        "0 reads the paper's reward as -1 in every non-goal state)",
    )


def _add_run(p: argparse.ArgumentParser, command: str) -> None:
    """The run-folder and progress options of a command that writes a run."""
    p.add_argument(
        "--out",
        type=_path,
        default=None,
        metavar="DIR",
        help=f"run folder (default: runs/{command}-<task>-<UTC time>); an existing non-empty one is "
        "refused unless --overwrite or --resume",
    )
    g = p.add_mutually_exclusive_group()
    g.add_argument("--overwrite", action="store_true", help="replace the run in --out (it must be a run folder)")
    g.add_argument(
        "--resume", action="store_true", help="continue the interrupted run in --out (same settings; done work is kept)"
    )
    _add_quiet(p)


JOBS_DEFAULT = 1
"""``--jobs`` of every command that runs workers: one process unless asked for more."""


def _add_jobs(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--jobs",
        type=_int(0, 1024),
        default=JOBS_DEFAULT,
        metavar="N",
        help=f"worker processes running at once, 0 for every usable core (the same results) (default {JOBS_DEFAULT})",
    )


def _add_quiet(p: argparse.ArgumentParser) -> None:
    p.add_argument("--quiet", action="store_true", help="no progress display")


def _add_scene_args(p: argparse.ArgumentParser, crm_required: bool) -> None:
    _add_task(p)
    p.add_argument(
        "--a", type=_point, required=True, metavar="X,Y", help="point projected onto the boundary for contact a (m)"
    )
    p.add_argument(
        "--b", type=_point, required=True, metavar="X,Y", help="point projected onto the boundary for contact b (m)"
    )
    p.add_argument(
        "--crm",
        required=crm_required,
        metavar="C",
        help="CRM as c,f,r (e.g. a,b,0 or b,b,-0.08) or a task action C1..Cn",
    )
    p.add_argument(
        "--sigma-n-deg",
        type=_number,
        default=0.0,
        metavar="DEG",
        help="normal sensing noise, degrees (task files state it in radians: noise.sigma_n) (default 0)",
    )
    p.add_argument(
        "--sigma-p", type=_number, default=0.0, metavar="M", help="position sensing noise, metres (default 0)"
    )
    p.add_argument("--seed", type=_SEED, default=0, help="seed of the sensing noise (default 0; 0 to 2**63-1)")


def _add_kernel_backend(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--backend",
        choices=("auto", "numba", "reference"),
        default="auto",
        help="kernel that episodes step through: compiled where one exists (auto, default), compiled "
        "(numba), or the readable rules (reference); all give the same results",
    )


def _add_hand(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--hand",
        choices=("kinematic", "mujoco"),
        default="kinematic",
        help="kinematic simulator (default) or the MuJoCo stand-in hand (extra crmgrasp[mujoco]; "
        "fingertip palm tolerance 10 degrees, its own sensor noise)",
    )


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
    p.add_argument("--out", type=_path, required=True, help="image file (.png, .pdf, .svg; mujoco: .png or .gif)")
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
    p.add_argument("--quick", action="store_true", help="small budgets (under a minute on 2 cores; not converged)")
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
        + "; --agent, --k and --prior-task override them",
    )
    p.add_argument("--agent", default=None, choices=tuple(AGENTS), help="learner or baseline (default: the preset's)")
    p.add_argument(
        "--k",
        type=_int(0, MAX_K),
        default=None,
        help=f"history order (default: the preset's; 0 to {MAX_K})",
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
    p.add_argument(
        "--symmetric",
        action="store_true",
        help="learn on the mirror quotient of the task (tabular learners; the task must declare a symmetry)",
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
    p.add_argument("--json", action="store_true", help="print JSON instead of text")
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
    p.add_argument("--seed", type=_SEED, default=0, help="seed (default 0; 0 to 2**63-1)")
    p.add_argument("--out", type=_path, required=True, help="the .pomdp file to write")
    _add_quiet(p)


def _parser_run(sub: Any) -> None:
    """``crmgrasp run``."""
    p = sub.add_parser(
        "run",
        help="run a saved policy on the kinematic hand, logging every step",
        description="Run a saved policy through the hand interface (the kinematic simulator, or with "
        "--hand mujoco the MuJoCo stand-in) from the configuration given by --a and --b (X,Y; on a spatial "
        "task X,Y,Z, projected to the family's nominal object from its centre); write the step log to --log.",
    )
    p.add_argument(
        "--policy", type=_path, required=True, help="a saved policy: policy.json or recurrent_ppo.zip (deep)"
    )
    p.add_argument("--a", type=_point, required=True, metavar="X,Y[,Z]", help="start point for contact a (m)")
    p.add_argument("--b", type=_point, required=True, metavar="X,Y[,Z]", help="start point for contact b (m)")
    p.add_argument("--log", type=_path, required=True, help="CSV step log to write")
    p.add_argument(
        "--sigma-n-deg",
        type=_number,
        default=0.0,
        metavar="DEG",
        help="normal sensing noise, degrees (task files state it in radians: noise.sigma_n) (default 0)",
    )
    p.add_argument(
        "--sigma-p", type=_number, default=0.0, metavar="M", help="position sensing noise, metres (default 0)"
    )
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
    sub.add_parser(
        "task-template",
        help="print a commented example task file",
        description="Print a commented example task file (TOML): `crmgrasp task-template > my.toml`.",
    )


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
    (:data:`COMMANDS`)."""
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
    ("--prior-task", str, "a task with the same CRMs and bins (e.g. box-family) to learn a prior on"),
    ("--prior-episodes", _int(1, 1_000_000), "episodes of the prior"),
)
"""The agents' keyword parameters as options of ``crmgrasp learn``: flag, type or choices,
meaning. Which agents take each, and their defaults, come from the agents themselves."""


def _defaults_text(flag: str) -> str:
    """``"sarsa, q: default 0.3"``-style text: the agents taking the parameter of ``flag``,
    grouped by their default (read from the agents' constructors)."""
    groups: dict[str, list[str]] = {}
    for agent, default in parameter_defaults(flag.lstrip("-").replace("-", "_")).items():
        groups.setdefault(repr(default) if isinstance(default, str) else f"{default}", []).append(agent)
    return "; ".join(f"{', '.join(agents)}: default {value}" for value, agents in groups.items())

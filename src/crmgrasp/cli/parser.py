"""Argument parser of the ``crmgrasp`` command (one-line errors, negative-number values)."""

from __future__ import annotations

import argparse
import re
from collections.abc import Callable
from pathlib import Path
from typing import Any, NoReturn

from crmgrasp import __version__
from crmgrasp._validation import SEED_MAX, CrmgraspError, as_point, finite, integer, shown
from crmgrasp.model.history import MAX_K
from crmgrasp.tasks import Task

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


START_PRESET_NAMES = ("corners", "near-corner", "long-side", "mixture")
"""The start presets (a test keeps this equal to :data:`crmgrasp.tasks.presets.START_PRESETS`)."""

AGENT_NAMES = ("sarsa", "q", "sarsa-lambda", "dyna-q", "model-vi", "random", "fixed")
"""The registered agents (a test keeps this equal to :data:`crmgrasp.agents.training.AGENTS`)."""

EXPERIMENT_NAMES = (
    "figure4",
    "figure7",
    "figure8",
    "figure9",
    "compare",
    "figure7-sensitivity",
    "cost-of-failure",
    "generalization",
    "non-convex",
    "spatial",
    "figure4-mujoco",
    "figure9-mujoco",
    "spatial-mujoco",
)
"""The experiments of ``reproduce`` (a test keeps this equal to the registry)."""


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
        choices=START_PRESET_NAMES,
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


def _add_jobs(p: argparse.ArgumentParser, default: int = 1) -> None:
    p.add_argument(
        "--jobs",
        type=_int(0, 1024),
        default=default,
        metavar="N",
        help="worker processes running at once, 0 for every usable core (the same results) "
        f"(default {default}{': every usable core' if default == 0 else ''})",
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
        "--sigma-n", type=_number, default=0.0, metavar="DEG", help="normal sensing noise, degrees (default 0)"
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


def _add_backend(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--backend",
        choices=("kinematic", "mujoco"),
        default="kinematic",
        help="kinematic simulator (default) or the MuJoCo stand-in hand (extra crmgrasp[mujoco]; "
        "fingertip palm tolerance 10 degrees, its own sensor noise)",
    )


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``crmgrasp`` command."""
    parser = _Parser(prog="crmgrasp", description="Grasp strategies composed of contact relative motions (Platt).")
    parser.add_argument("--version", action="version", version=f"crmgrasp {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)

    p = sub.add_parser(
        "crm",
        help="execute one CRM and print the outcome",
        description="Execute one CRM from the configuration given by --a and --b.",
    )
    _add_scene_args(p, crm_required=True)
    p.add_argument("--json", action="store_true", help="print JSON instead of text")

    p = sub.add_parser(
        "show",
        help="draw the scene (and a CRM) to an image",
        description="Draw object, contacts with normals, palm point and, with --crm, the goal line and path.",
    )
    _add_scene_args(p, crm_required=False)
    p.add_argument("--out", type=_path, required=True, help="image file (.png, .pdf, .svg; mujoco: .png or .gif)")
    _add_backend(p)

    p = sub.add_parser(
        "reproduce",
        help="run the paper's experiments",
        description="Run the paper's experiments into one folder with an index README.md.",
    )
    p.add_argument(
        "experiments",
        nargs="*",
        metavar="NAME",
        help=f"experiments to run: {', '.join(EXPERIMENT_NAMES)} (default: all; the MuJoCo ones need crmgrasp[mujoco])",
    )
    p.add_argument("--seed", type=_SEED, default=0, help="seed of the run (default 0; 0 to 2**63-1)")
    p.add_argument("--quick", action="store_true", help="small budgets (under a minute on 2 cores; not converged)")
    _add_run(p, "reproduce")
    _add_jobs(p)
    _add_kernel_backend(p)

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
        choices=tuple(LEARN_PRESETS),
        help="learner settings: paper (SARSA, k = 2) or fastest (model-vi, k = 1, on the mirror quotient where the "
        "task declares one; on paper-box with a prior learned in 500 episodes on box-family: from scratch, use "
        "--agent model-vi --k 1 --symmetric); --agent, --k and --prior-task override them",
    )
    p.add_argument("--agent", default=None, choices=AGENT_NAMES, help="learner or baseline (default: the preset's)")
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
        if isinstance(kind, tuple):
            p.add_argument(flag, choices=kind, default=None, help=text)
        else:
            p.add_argument(flag, type=kind, default=None, help=text)

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

    p = sub.add_parser(
        "bench",
        help="speed benchmarks against Gymnasium's CartPole",
        description="Time paper-box against CartPole-v1 in one process; print one JSON object.",
    )
    p.add_argument("--smoke", action="store_true", help="tiny sizes (CI): no meaningful timings")
    p.add_argument("--rounds", type=_int(1, 1000), default=15, help="alternating rounds (default 15; 1 to 1,000)")
    p.add_argument("--seed", type=_SEED, default=0, help="seed (default 0; 0 to 2**63-1)")

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

    p = sub.add_parser(
        "run",
        help="run a saved policy on the kinematic hand, logging every step",
        description="Run a saved policy through the hand interface (the kinematic simulator, or with "
        "--backend mujoco the MuJoCo stand-in) from the configuration given by --a and --b (X,Y; on a spatial "
        "task X,Y,Z, projected to the family's nominal object from its centre); write the step log to --log.",
    )
    p.add_argument(
        "--policy", type=_path, required=True, help="a saved policy: policy.json or recurrent_ppo.zip (deep)"
    )
    p.add_argument("--a", type=_point, required=True, metavar="X,Y[,Z]", help="start point for contact a (m)")
    p.add_argument("--b", type=_point, required=True, metavar="X,Y[,Z]", help="start point for contact b (m)")
    p.add_argument("--log", type=_path, required=True, help="CSV step log to write")
    p.add_argument(
        "--sigma-n", type=_number, default=0.0, metavar="DEG", help="normal sensing noise, degrees (default 0)"
    )
    p.add_argument(
        "--sigma-p", type=_number, default=0.0, metavar="M", help="position sensing noise, metres (default 0)"
    )
    p.add_argument("--seed", type=_SEED, default=0, help="seed (default 0; 0 to 2**63-1)")
    _add_backend(p)

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
    _add_jobs(p, default=0)
    p.add_argument(
        "--backend",
        choices=("local", "ray"),
        default="local",
        help="local worker processes, or Ray tasks (extra crmgrasp[ray]); the same results",
    )
    p.add_argument(
        "--address",
        default=None,
        metavar="auto|HOST:PORT",
        help="with --backend ray: the cluster to use (default: a local Ray instance of --jobs CPUs)",
    )
    p.add_argument(
        "--kernel",
        choices=("auto", "numba", "reference"),
        default="auto",
        help="kernel that episodes step through (as --backend of learn); all give the same results",
    )

    sub.add_parser("tasks", help="list the built-in tasks", description="List the registered (built-in) tasks.")
    sub.add_parser(
        "task-template",
        help="print a commented example task file",
        description="Print a commented example task file (TOML): `crmgrasp task-template > my.toml`.",
    )
    p = sub.add_parser(
        "status",
        help="say whether a run completed",
        description="Print the status of a run folder: running, complete, interrupted, failed, or killed "
        "(says running, but its process is gone).",
    )
    p.add_argument("run", type=_path, metavar="DIR", help="a run folder")
    return parser


LEARN_PRESETS = {"paper": ("sarsa", 2, False), "fastest": ("model-vi", 1, True)}
"""``--preset`` of ``crmgrasp learn``: agent, k, and whether to learn on the mirror quotient
(where the task declares a symmetry)."""

FASTEST_PRIORS = {"paper-box": "box-family"}
"""Tasks on which ``--preset fastest`` also gives ``model-vi`` a prior (``--prior-task``): a
family task with the same CRMs and bins of which the task's object is one member (the
paper's box is one box of ``box-family``)."""

_AGENT_FLAGS = (
    ("--alpha", _number, "learning rate (default 0.3)"),
    ("--gamma", _number, "discount factor (default 0.9)"),
    ("--epsilon", _number, "exploration probability (default 0: greedy)"),
    ("--q0", _number, "initial Q value (default 0: optimistic)"),
    ("--lam", _number, "sarsa-lambda: trace decay lambda (default 0.9)"),
    ("--trace", ("replacing", "accumulating"), "sarsa-lambda: eligibility traces (default replacing)"),
    (
        "--n-planning",
        _int(0, 1_000_000),
        "dyna-q: planning updates (sample) or max sweeps (sweep) per step (default 20)",
    ),
    ("--planning", ("sample", "sweep"), "dyna-q: sampled updates or value-iteration sweeps (default sample)"),
    ("--q-act", _number, "model-vi: acting value of an untried CRM (default -1.5)"),
    ("--prior-task", str, "model-vi: a task with the same CRMs and bins (e.g. box-family) to learn a prior on"),
    ("--prior-episodes", _int(1, 1_000_000), "model-vi: episodes of the prior (default 500)"),
)

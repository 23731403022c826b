"""The option types and option groups the ``crmgrasp`` commands share: one-line errors,
defaults in the help, negative-number values, and the task, run-folder, jobs, scene, kernel
and hand options (one meaning per flag name across commands)."""

from __future__ import annotations

import argparse
import re
from collections.abc import Callable
from pathlib import Path
from typing import Any, NoReturn

from crmgrasp._validation import SEED_MAX, CrmgraspError, as_point, finite, integer, shown
from crmgrasp.hardware import HANDS
from crmgrasp.model.actions import MAX_GRID
from crmgrasp.model.contacts import ALL_LABELS, LABELS
from crmgrasp.tasks import Task
from crmgrasp.tasks.presets import START_PRESETS

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


_LONG = re.compile(r"\S{161,}")


def fit_line(text: str) -> str:
    """``text`` with every run of over 160 non-blank characters (a pasted number of 5,000
    digits, a path someone's script built wrong) cut to its first 60 and last 20 characters
    around a count, so that an error echoing a user's value stays a line a terminal shows."""
    return _LONG.sub(lambda m: f"{m[0][:60]}...({len(m[0]):,} characters)...{m[0][-20:]}", text)


class _Parser(argparse.ArgumentParser):
    """argparse with one-line errors, defaults in the help, and values such as
    ``-0.15,-0.02``."""

    def __init__(self, *args: object, **kwargs: object) -> None:
        kwargs.setdefault("formatter_class", _Help)
        super().__init__(*args, **kwargs)  # type: ignore[arg-type]
        self._negative_number_matcher = _NUMBERISH

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {fit_line(message)} (see --help)\n")


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


def _boolean(text: str) -> bool:
    """An argparse type: ``true`` or ``false`` (any case)."""
    word = text.strip().lower()
    if word not in ("true", "false"):
        raise argparse.ArgumentTypeError(f"expected true or false, got {text!r}")
    return word == "true"


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
    p.add_argument(
        "--offset-grid",
        type=_int(1, MAX_GRID),
        default=None,
        metavar="N",
        help="replace the task's CRMs by N evenly spaced offsets per coordinate over each contact pair of its "
        "continuous action space (odd N holds r = 0) (default: the task's own CRMs)",
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


def _add_points(p: argparse.ArgumentParser, what: str, default: str = "") -> None:
    """``--a``, ``--b`` (required unless ``default`` says what stands in for them) and ``--c``,
    ``--d`` (a hand with that many fingers): one point per contact (the task's model says how
    many it takes)."""
    for label in ALL_LABELS:
        more = "" if label in LABELS else "; a hand with that many fingers only"
        more += f" (default: {default})" if default and label == "a" else ""
        p.add_argument(
            f"--{label}",
            type=_point,
            required=label in LABELS and not default,
            metavar="X,Y[,Z]",
            help=f"{what} for contact {label} (m){more}",
        )


def _add_scene_args(p: argparse.ArgumentParser, crm_required: bool) -> None:
    _add_task(p)
    _add_points(p, "point (X,Y on a planar task, projected onto the boundary; X,Y,Z on a spatial one)")
    p.add_argument(
        "--crm",
        required=crm_required,
        metavar="C",
        help="CRM as c,f,r (e.g. a,b,0 or b,b,-0.08) or a task action C1..Cn",
    )
    _add_noise(p)
    p.add_argument("--seed", type=_SEED, default=0, help="seed of the sensing noise (default 0; 0 to 2**63-1)")


def _add_noise(p: argparse.ArgumentParser) -> None:
    """The sensing noise of a scene or a run: ``--sigma-n-deg`` (degrees) and ``--sigma-p`` (m)."""
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


def _add_kernel_backend(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--backend",
        choices=("auto", "numba", "reference"),
        default="auto",
        help="kernel the rules run on: compiled where one exists (auto, default), compiled "
        "(numba), or the readable rules (reference); all give the same results",
    )


def _add_hand(p: argparse.ArgumentParser, what: str = "runs on") -> None:
    p.add_argument(
        "--hand",
        choices=tuple(HANDS),
        default="kinematic",
        help=f"the hand it {what}: " + "; ".join(f"{name}: {text}" for name, text in HANDS.items()),
    )

"""Helpers every ``crmgrasp`` command shares: the task of ``--task``, the run folder,
the progress display, printing a result."""

from __future__ import annotations

import argparse
from typing import Any

from crmgrasp._io import dumps_json
from crmgrasp.tasks import Task


def _task(args: argparse.Namespace, spec: str | None = None) -> Task:
    """The task of ``--task`` (or ``spec``) with ``--start-preset``, ``--grasp-reward`` and
    ``--offset-grid`` applied."""
    from crmgrasp.tasks.files import resolve_reading

    return resolve_reading(
        args.task if spec is None else spec,
        starts=getattr(args, "start_preset", None),
        grasp_reward=getattr(args, "grasp_reward", None),
        offset_grid=getattr(args, "offset_grid", None),
    )


def _run_folder(args: argparse.Namespace, task: str, config: dict[str, Any]) -> Any:
    """The run folder of this command (``--out``, ``--overwrite``, ``--resume``)."""
    from crmgrasp.experiments.runs import RunFolder

    return RunFolder(
        args.out,
        args.command,
        task,
        config,
        argv=args.argv,
        seed=getattr(args, "seed", None),
        overwrite=args.overwrite,
        resume=args.resume,
    )


def _progress(args: argparse.Namespace) -> Any:
    from crmgrasp._progress import make_progress

    return make_progress(args.quiet)


def _print_result(args: argparse.Namespace, result: dict[str, Any], text: str) -> int:
    """Print ``result`` as JSON with ``--json``, else the one-line ``text``; exit code 0."""
    print(dumps_json(result) if args.json else text)
    return 0

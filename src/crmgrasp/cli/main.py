"""The ``crmgrasp`` command.

Every failure caused by the user's input prints one line,
``crmgrasp <command>: error: <what is wrong>``, and exits with status 2.
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import os
import signal
import sys
from collections.abc import Sequence
from typing import Any

import numpy as np

from crmgrasp import _progress as interrupt  # the Ctrl-C a finaliser would swallow
from crmgrasp._io import check_new_output
from crmgrasp._validation import CrmgraspError
from crmgrasp.cli.common import _print_result, _progress, _run_folder, _task
from crmgrasp.cli.learning import _cmd_evaluate, _cmd_learn
from crmgrasp.cli.options import fit_line
from crmgrasp.cli.parser import build_parser
from crmgrasp.cli.scene import _cmd_crm, _cmd_run, _cmd_show
from crmgrasp.tasks import TEMPLATE, Task, make_task, task_names, task_to_dict

__all__ = ["main", "build_parser"]


def _cmd_reproduce(args: argparse.Namespace) -> int:
    from crmgrasp.experiments import reproduce
    from crmgrasp.experiments.reproduce import select

    names, _ = select(args.experiments)
    config = {"experiments": names, "seed": args.seed, "quick": args.quick}
    with _run_folder(args, "paper-box", config) as run:
        results = reproduce(
            run.path,
            args.experiments,  # as asked: all by default, and then the index lists what was skipped
            seed=args.seed,
            quick=args.quick,
            backend=args.backend,
            store=run,
            progress=_progress(args),
            jobs=args.jobs,
        )
    from crmgrasp.experiments.stats import fmt, summary_lines

    root = run.path.resolve()
    for name, summary in results.items():
        print(f"{name}: {root / name} ({fmt(summary['seconds'], 1)} s)")
        print("\n".join(summary_lines(summary)))
    print(f"index: {root / 'README.md'}")
    return 0


def _cmd_references(args: argparse.Namespace) -> int:
    from crmgrasp.experiments.stats import ci_text, normal_ci
    from crmgrasp.planners import references as refs

    if args.starts % args.blocks:
        raise CrmgraspError(f"--blocks {args.blocks} must divide --starts {args.starts}")
    for flag, given in (("--planner-seed", args.planner_seed), ("--fallback", args.fallback)):
        if given is not None and args.planner is None:
            raise CrmgraspError(f"{flag} needs --planner")
    task = _task(args)
    starts = refs.sample_starts(task, args.starts, args.seed)
    planner: dict[str, Any] | None = None
    line = ""
    if args.planner is not None:  # it finds the optimum over the starts on its way
        planner, line = _realizable(args, task, starts)
    with _progress(args).stage(f"references of {task.name}", 0):
        backend = args.backend
        clair = refs.clairvoyant_bound(task, starts, backend=backend)
        if planner is None:
            belief = refs.belief_optimum(task, starts, backend=backend)
            never = refs.ungraspable_fraction(task, starts, backend=backend)
        else:  # the same values, which the planner's run has found on its way
            belief, never = planner["optimum"], (len(starts) - planner["graspable_starts"]) / len(starts)
        blocks = refs.block_optima(task, starts, args.blocks, backend=backend) if args.blocks > 1 else None
    res = {
        "task": task.name,
        "starts": args.starts,
        "seed": args.seed,
        "clairvoyant_bound": clair,
        "belief_optimum": belief,
        "aliasing_price": belief - clair,
        "ungraspable_fraction": never,
    }
    text = (
        f"{task.name}, {args.starts} starts (seed {args.seed}): clairvoyant bound {clair:.4f} CRMs, "
        f"belief-space optimum {belief:.4f} CRMs, price of aliasing {belief - clair:.4f}; "
        f"{never:.1%} of starts no CRM sequence of at most {task.max_steps} grasps"
    )
    if blocks is not None:
        mean, lo, hi = normal_ci(blocks)
        res |= {
            "blocks": args.blocks,
            "block_optima": blocks,
            "block_optimum_mean": mean,
            "block_optimum_ci95": [lo, hi],
        }
        text += (
            f"\n  over {args.blocks} blocks of {args.starts // args.blocks} starts: belief-space optimum {mean:.4f} "
            f"({ci_text(lo, hi, 'blocks')}) against {belief:.4f} over all {args.starts}"
        )
    if planner is not None:
        res["planner"] = planner
        text += line
    return _print_result(args, res, text)


def _realizable(args: argparse.Namespace, task: Task, starts: list) -> tuple[dict[str, Any], str]:
    """``references --planner``: the realizable reference and the text lines that say it."""
    from crmgrasp.planners.realizable import realizable_reference

    seed = args.seed + 1 if args.planner_seed is None else args.planner_seed
    fallback = args.fallback or "restart"
    res = realizable_reference(task, starts, args.planner, seed, fallback, args.backend, _progress(args))
    sem = res["standard_error"]
    spread = "" if sem is None else f" (standard error {sem:.4f})"  # none from a single start
    line = (
        f"\n  a belief-space policy planned over {args.planner} other starts (seed {seed}, fallback {fallback}): "
        f"{res['mean']:.4f} CRMs on these starts{spread}, "
        f"{res['over_optimum']:+.1%} over the optimum; the task's own optimum lies between the two in expectation"
    )
    if res["graspable_starts"]:
        line += (
            f"\n  on the {res['graspable_starts']} graspable starts: belief-space optimum "
            f"{res['optimum_graspable']:.4f}, the policy {res['mean_graspable']:.4f} "
            f"({res['over_optimum_graspable']:+.1%})"
        )
    return res, line


def _cmd_plan(args: argparse.Namespace) -> int:
    from crmgrasp.experiments.planning import plan_korder

    task = _task(args)
    config = {
        "task": task_to_dict(task),
        "worlds": args.worlds,
        "heldout": args.heldout,
        "k": args.k,
        "init": args.init,
        "seed": args.seed,
    }
    with _run_folder(args, task.name, config) as folder:
        _, s = plan_korder(
            task,
            worlds=args.worlds,
            k=args.k,
            heldout=args.heldout,
            seed=args.seed,
            init=args.init,
            out_dir=folder.path,
            progress=_progress(args),
        )
    how = "planned" if args.init == "belief" else f"learned from {s['episodes']:,} episodes"
    there = "" if s["planned_belief_optimum"] is None else f" (optimum {s['planned_belief_optimum']:.4f})"
    print(
        f"k = {s['k']} policy on {task.name}, {how} on {s['worlds']} worlds ({s['seconds']:.1f} s): "
        f"{s['planned_mean_cost']:.4f} CRMs there{there}; "
        f"on {s['heldout']} held-out worlds {s['heldout_mean_crms']:.4f} "
        f"(success {s['heldout_success_rate']:.1%}) against a belief-space optimum of {s['belief_optimum']:.4f} "
        f"({s['gap_to_optimum']:+.1%})"
    )
    print(f"  wrote {(folder.path / 'policy.json').resolve()}")
    return 0


def _cmd_compare(args: argparse.Namespace) -> int:
    from crmgrasp.agents.deep import RecurrentPPOConfig
    from crmgrasp.experiments.compare import CompareConfig, compare
    from crmgrasp.experiments.stats import summary_lines

    task = _task(args)
    if task.model.kind != "planar":
        raise CrmgraspError(
            f"compare's grasp controller, sampled POMDP and deep peer are planar; on the spatial task {task.name!r} "
            "use learn, evaluate and references (or reproduce spatial)"
        )
    cfg = CompareConfig.quick(task.name, args.seed) if args.quick else CompareConfig(task=task.name, seed=args.seed)
    if args.deep_steps is not None:
        if args.deep_steps < 0:
            raise CrmgraspError(f"--deep-steps must be >= 0, got {args.deep_steps}")
        deep = cfg.deep or RecurrentPPOConfig()
        cfg = dataclasses.replace(
            cfg, deep=dataclasses.replace(deep, total_steps=args.deep_steps) if args.deep_steps else None
        )
    config = {"task": task_to_dict(task), "quick": args.quick, "seed": args.seed, "deep_steps": args.deep_steps}
    with _run_folder(args, task.name, config) as run:
        summary = compare(
            run.path, cfg, backend=args.backend, progress=_progress(args), task=task, store=run, jobs=args.jobs
        )
    print((run.path / "compare.md").read_text(encoding="utf-8"))
    print("\n".join(summary_lines(summary, indent=0, skip=())))
    print(f"wrote {(run.path / 'compare.csv').resolve()}, compare.md, compare.png")
    return 0


def _cmd_pomdp(args: argparse.Namespace) -> int:
    from crmgrasp.planners.pomdp import write_cassandra
    from crmgrasp.planners.pomdp_task import POMDPAgent, build_task_pomdp
    from crmgrasp.planners.references import sample_starts

    if args.cell <= 0 or args.samples < 1 or args.episodes < 1:
        raise CrmgraspError("--cell must be > 0, and --samples and --episodes >= 1")
    check_new_output(args.out, "--out", args.overwrite)
    task = _task(args)
    if task.family is not None:
        raise CrmgraspError(
            f"pomdp: task {task.name!r} draws an object per episode; the sampled POMDP needs one object"
        )
    if args.pouct is not None:
        from crmgrasp.planners.pouct import ModelPOUCTPolicy, POUCTSettings, require_pomdp_py

        require_pomdp_py()  # before the work: a one-line error where the extra is missing
    with _progress(args).stage(f"pomdp of {task.name}: sample, solve, execute", 0):
        tp = build_task_pomdp(task, cell=args.cell, samples=args.samples, n_starts=args.starts, seed=args.seed)
        path = write_cassandra(tp.model, args.out)
        agent = POMDPAgent(tp, seed=args.seed)
        starts = sample_starts(task, args.episodes, args.seed + 1)
        runs = [agent.run(c) for c in starts]  # type: ignore[arg-type]
    counts = ", ".join(f"{k} {v}" for k, v in tp.model.counts.items())
    print(
        f"{task.name}: sampled POMDP ({counts}); model value {agent.model_value():.4f} CRMs; executed on "
        f"{args.episodes} fresh starts: {np.mean([n for n, _ in runs]):.4f} CRMs, "
        f"success {np.mean([ok for _, ok in runs]):.1%}"
    )
    if args.pouct is not None:
        pouct = ModelPOUCTPolicy(tp, np.random.default_rng(args.seed), POUCTSettings(num_sims=args.pouct))
        with _progress(args).stage(f"POUCT on the model, {args.pouct} simulations per CRM", 0):
            planned = [pouct.run(c) for c in starts]  # type: ignore[arg-type]
        print(
            f"pomdp_py's POUCT on the same model, {args.pouct} simulations per CRM, the same starts: "
            f"{np.mean([n for n, _ in planned]):.4f} CRMs, success {np.mean([ok for _, ok in planned]):.1%}"
        )
    print(f"wrote {path.resolve()}")
    return 0


def _cmd_bench(args: argparse.Namespace) -> int:
    """Run the speed benchmarks ([`crmgrasp.experiments.bench`][])."""
    from crmgrasp.experiments.bench import main as bench

    if args.rounds < 1:
        raise CrmgraspError(f"--rounds must be >= 1, got {args.rounds}")
    bench((["--smoke"] if args.smoke else []) + ["--rounds", str(args.rounds), "--seed", str(args.seed)])
    return 0


def _cmd_sweep(args: argparse.Namespace) -> int:
    from crmgrasp.experiments.sweep import load_study, report, run_study

    if args.target == "report":
        if args.folder is None:
            raise CrmgraspError("sweep report needs the study's run folder: crmgrasp sweep report DIR")
        print(f"wrote {report(args.folder).resolve()}")
        return 0
    if args.folder is not None:
        raise CrmgraspError(f"unexpected argument {str(args.folder)!r} (use --out for the run folder)")
    if args.address is not None and args.executor != "ray":
        raise CrmgraspError("--address names a Ray cluster: it needs --executor ray")
    study = load_study(args.target)
    with _run_folder(args, study.name, {"study": study.to_dict()}) as run:
        counts = run_study(
            study,
            run,
            jobs=args.jobs,
            backend=args.backend,
            progress=_progress(args),
            executor=args.executor,
            address=args.address,
        )
    print(
        f"study {study.name}: {len(study.cells)} cells x {len(study.seeds)} seeds: {counts.get('ok', 0)} runs ok, "
        f"{counts.get('failed', 0)} failed"
    )
    print(f"wrote {(run.path / 'results.csv').resolve()}, cells.csv; report: crmgrasp sweep report {run.path}")
    return 1 if counts.get("failed") else 0


def _cmd_tasks(args: argparse.Namespace) -> int:
    for name in task_names():
        print(f"{name}: {make_task(name).headline()}")
    print("(any command's --task also takes a .toml task file or package.module:factory; see `crmgrasp task-template`)")
    return 0


def _cmd_task_template(args: argparse.Namespace) -> int:
    from crmgrasp.tasks.files import key_reference

    sys.stdout.write(key_reference() if args.keys else TEMPLATE)
    return 0


def _cmd_status(args: argparse.Namespace) -> int:
    from crmgrasp.experiments.runs import leftovers, read_status

    status = read_status(args.run)
    left = leftovers(args.run)
    note = f" ({len(left)} temporary file(s) of cut-short writes: {', '.join(left[:3])}; --resume deletes them)"
    print(f"{args.run}: {status}{note if left else ''}")
    return 0 if status == "complete" else 1


_STEPS_KERNELS = frozenset(
    {"reproduce", "sweep", "learn", "evaluate", "bench", "references", "plan", "compare", "pomdp", "run"}
)
"""The commands that step the compiled kernels (the others import no numba)."""


def _compile_notice(args: argparse.Namespace) -> Any:
    """A one-line notice on standard error while numba compiles for more than 2 s
    ([`crmgrasp.kernels.compiling`][]; nothing with ``--quiet``), for the commands that step
    kernels."""
    if args.command not in _STEPS_KERNELS or getattr(args, "quiet", False):
        return contextlib.nullcontext()
    from crmgrasp._progress import Progress
    from crmgrasp.kernels.compiling import compile_notice

    return compile_notice(Progress().interject)


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point; returns the exit status."""
    parser = build_parser()
    args = parser.parse_args(argv)
    args.argv = list(sys.argv[1:] if argv is None else argv)
    handlers = {
        "crm": _cmd_crm,
        "show": _cmd_show,
        "reproduce": _cmd_reproduce,
        "tasks": _cmd_tasks,
        "task-template": _cmd_task_template,
        "sweep": _cmd_sweep,
        "status": _cmd_status,
        "learn": _cmd_learn,
        "evaluate": _cmd_evaluate,
        "bench": _cmd_bench,
        "references": _cmd_references,
        "plan": _cmd_plan,
        "compare": _cmd_compare,
        "pomdp": _cmd_pomdp,
        "run": _cmd_run,
    }
    previous = _on_sigterm(_terminate)
    inherited_ignore = signal.getsignal(signal.SIGINT) is signal.SIG_IGN  # e.g. `crmgrasp ... &`: keep it
    previous_int = None if inherited_ignore else _on_signal(signal.SIGINT, interrupt.on_sigint)
    interrupt.clear()
    try:
        with _compile_notice(args):
            result = handlers[args.command](args)
        interrupt.check()  # a Ctrl-C that Python swallowed (in a finaliser, a callback) still stops
        return result
    except Terminated:  # SIGTERM (kill, a scheduler's stop): as Ctrl-C, with the shell's status for it
        print(f"crmgrasp {args.command}: terminated", file=sys.stderr)
        return 143
    except CrmgraspError as exc:
        print(f"crmgrasp {args.command}: error: {fit_line(str(exc))}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:  # Ctrl-C: one line and the shell's status for SIGINT
        print(f"crmgrasp {args.command}: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # output piped into e.g. `head`
        sys.stderr.close()
        return 0
    except OSError as exc:
        print(
            fit_line(f"crmgrasp {args.command}: error: {exc.strerror or exc}: {exc.filename or ''}".rstrip(": ")),
            file=sys.stderr,
        )
        return 2
    except Exception as exc:  # a bug: one line for the user, the traceback with CRMGRASP_DEBUG=1
        if os.environ.get("CRMGRASP_DEBUG"):
            raise
        text = " ".join(str(exc).split())[:300]
        print(
            f"crmgrasp {args.command}: internal error ({type(exc).__name__}: {text}); please report it "
            "(CRMGRASP_DEBUG=1 shows the traceback)",
            file=sys.stderr,
        )
        return 1
    finally:
        _on_sigterm(previous)
        _on_signal(signal.SIGINT, previous_int)
        interrupt.clear()


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised where the command is: every path that stops on Ctrl-C (worker
    processes stopped, the run folder marked ``interrupted``) stops on it too."""


def _terminate(signum: int, frame: Any) -> None:
    raise Terminated


def _on_sigterm(handler: Any) -> Any:
    """Install ``handler`` for SIGTERM and return the previous one (``None`` where no
    handler can be set: not the main thread)."""
    return _on_signal(signal.SIGTERM, handler)


def _on_signal(signum: int, handler: Any) -> Any:
    """Install ``handler`` for ``signum`` and return the previous one (``None`` where no
    handler can be set: not the main thread)."""
    if handler is None:
        return None
    try:
        return signal.signal(signum, handler)
    except ValueError:  # signals are set from the main thread only
        return None


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())

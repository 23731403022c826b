"""The ``crmgrasp`` command.

Every failure caused by the user's input prints one line,
``crmgrasp <command>: error: <what is wrong>``, and exits with status 2.
"""

from __future__ import annotations

import argparse
import json
import math
import re
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import NoReturn

import numpy as np

from . import __version__
from ._io import save_figure
from ._validation import CrmgraspError, as_point, finite
from .contacts import Config
from .hand import CRM
from .quality import min_friction
from .sensing import Error, SensorNoise, observe
from .tasks import Task, make_task, task_names

__all__ = ["main"]

_NUMBERISH = re.compile(r"^-[\d.]")


class _Parser(argparse.ArgumentParser):
    """argparse with one-line errors and values such as ``-0.15,-0.02``."""

    def __init__(self, *args: object, **kwargs: object) -> None:
        super().__init__(*args, **kwargs)  # type: ignore[arg-type]
        self._negative_number_matcher = _NUMBERISH

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message} (see --help)\n")


def _point(text: str) -> tuple[float, float]:
    parts = str(text).split(",")
    if len(parts) != 2:
        raise argparse.ArgumentTypeError(f"expected X,Y (two numbers), got {text!r}")
    try:
        return as_point(parts, "point")
    except CrmgraspError as exc:
        raise argparse.ArgumentTypeError(f"{exc} in {text!r}") from None


def _number(text: str) -> float:
    try:
        return finite(text, "value")
    except CrmgraspError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def _resolve_crm(task: Task, text: str) -> CRM:
    """``C1``..``Cn`` names the task's actions; anything else is parsed as ``c,f,r``."""
    m = re.fullmatch(r"[Cc](\d+)", text.strip())
    if m:
        i = int(m.group(1))
        if not 1 <= i <= len(task.actions):
            raise CrmgraspError(f"task {task.name} has actions C1..C{len(task.actions)}, got {text!r}")
        return task.actions[i - 1]
    return task.hand.check_crm(CRM.parse(text))


def _add_scene_args(p: argparse.ArgumentParser, crm_required: bool) -> None:
    p.add_argument("--task", default="paper-box", help="registered task name (default: paper-box)")
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
    p.add_argument("--seed", type=int, default=0, help="seed of the sensing noise (default 0)")


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
    p.add_argument("--out", type=Path, required=True, help="image file (.png, .pdf or .svg)")

    p = sub.add_parser(
        "reproduce",
        help="run the paper's experiments",
        description="Run the paper's experiments into one folder with an index README.md.",
    )
    p.add_argument("experiments", nargs="*", metavar="NAME", help="experiments to run (default: all)")
    p.add_argument(
        "--out", type=Path, default=Path("crmgrasp-results"), help="output folder (default: ./crmgrasp-results)"
    )
    p.add_argument("--seed", type=int, default=0, help="seed of the run (default 0)")
    p.add_argument("--quick", action="store_true", help="small budgets (under a minute on 2 cores)")

    p = sub.add_parser(
        "learn",
        help="train a learner over independent trials",
        description="Train a learner on a task; write curve.csv, summary.json, policy.json "
        "and learning_curve.png to --out.",
    )
    p.add_argument("--task", default="paper-box", help="registered task name (default: paper-box)")
    p.add_argument("--agent", default="sarsa", help="sarsa, q, sarsa-lambda, dyna-q, random or fixed")
    p.add_argument("--k", type=int, default=2, help="history order of the state (default 2)")
    p.add_argument("--trials", type=int, default=20, help="independent trials (default 20)")
    p.add_argument("--episodes", type=int, default=2000, help="training episodes per trial (default 2000)")
    p.add_argument("--eval-episodes", type=int, default=1000, help="greedy evaluation episodes per trial")
    p.add_argument("--seed", type=int, default=0, help="seed of the run (default 0)")
    p.add_argument("--out", type=Path, required=True, help="output folder")
    p.add_argument(
        "--lockstep",
        action="store_true",
        help="step all trials together through the batched simulator (same results; faster from ~500 trials)",
    )
    for flag, kind, text in _AGENT_FLAGS:
        p.add_argument(flag, type=kind, default=None, help=text)

    p = sub.add_parser(
        "evaluate",
        help="evaluate a saved policy",
        description="Run a saved policy greedily on fresh episodes of its task.",
    )
    p.add_argument("--policy", type=Path, required=True, help="policy.json written by `crmgrasp learn`")
    p.add_argument("--task", default=None, help="task name (default: the one the policy names)")
    p.add_argument("--episodes", type=int, default=1000, help="episodes (default 1000)")
    p.add_argument("--seed", type=int, default=0, help="seed (default 0)")
    p.add_argument("--json", action="store_true", help="print JSON instead of text")

    p = sub.add_parser(
        "bench",
        help="speed benchmarks against Gymnasium's CartPole",
        description="Time paper-box against CartPole-v1 in one process; print one JSON object.",
    )
    p.add_argument("--smoke", action="store_true", help="tiny sizes (CI): no meaningful timings")
    p.add_argument("--rounds", type=int, default=15, help="alternating rounds (default 15)")
    p.add_argument("--seed", type=int, default=0)

    p = sub.add_parser(
        "references",
        help="clairvoyant bound and belief-space optimum of a task",
        description="Exact reference values on sampled starts: the clairvoyant bound (full information) "
        "and the belief-space optimum (observations only).",
    )
    p.add_argument("--task", default="paper-box", help="registered task name (default: paper-box)")
    p.add_argument("--starts", type=int, default=4000, help="sampled starts (default 4000)")
    p.add_argument("--seed", type=int, default=0, help="seed of the starts (default 0)")
    p.add_argument("--json", action="store_true", help="print JSON instead of text")

    p = sub.add_parser(
        "compare",
        help="every method on one task, one table",
        description="Learners, baselines, the grasp controller and the exact references on one task, "
        "same seeds; writes compare.csv, compare.md and compare.png to --out.",
    )
    p.add_argument("--task", default="paper-box", help="registered task name (default: paper-box)")
    p.add_argument("--seed", type=int, default=0, help="seed (default 0)")
    p.add_argument("--out", type=Path, required=True, help="output folder")
    p.add_argument("--quick", action="store_true", help="small budgets (seconds)")

    p = sub.add_parser(
        "pomdp",
        help="build the sampled POMDP of a task, solve it, export it",
        description="Build an explicit POMDP of a polygonal task by sampling the simulator, solve it by "
        "point-based value iteration, write it in Cassandra's .pomdp format, and run its policy.",
    )
    p.add_argument("--task", default="paper-box", help="registered task name (default: paper-box)")
    p.add_argument("--cell", type=_number, default=0.01, help="cell size along each edge, m (default 0.01)")
    p.add_argument("--samples", type=int, default=20, help="CRM samples per cell and action (default 20)")
    p.add_argument("--starts", type=int, default=4000, help="sampled starts for the start belief (default 4000)")
    p.add_argument("--episodes", type=int, default=1000, help="fresh starts to execute the policy on")
    p.add_argument("--seed", type=int, default=0, help="seed (default 0)")
    p.add_argument("--out", type=Path, required=True, help="the .pomdp file to write")

    p = sub.add_parser(
        "run",
        help="run a saved policy on the kinematic hand, logging every step",
        description="Run a saved policy through the hand interface (here: the kinematic simulator) from the "
        "configuration given by --a and --b; write the step log to --log.",
    )
    p.add_argument("--policy", type=Path, required=True, help="policy.json written by `crmgrasp learn`")
    p.add_argument("--a", type=_point, required=True, metavar="X,Y", help="start point for contact a (m)")
    p.add_argument("--b", type=_point, required=True, metavar="X,Y", help="start point for contact b (m)")
    p.add_argument("--log", type=Path, required=True, help="CSV step log to write")
    p.add_argument("--sigma-n", type=_number, default=0.0, metavar="DEG", help="normal sensing noise, degrees")
    p.add_argument("--sigma-p", type=_number, default=0.0, metavar="M", help="position sensing noise, metres")
    p.add_argument("--seed", type=int, default=0, help="seed (default 0)")

    sub.add_parser("tasks", help="list registered tasks", description="List the registered tasks.")
    return parser


_AGENT_FLAGS = (
    ("--alpha", _number, "learning rate (default 0.3)"),
    ("--gamma", _number, "discount factor (default 0.9)"),
    ("--epsilon", _number, "exploration probability (default 0: greedy)"),
    ("--q0", _number, "initial Q value (default 0: optimistic)"),
    ("--lam", _number, "sarsa-lambda: trace decay lambda (default 0.9)"),
    ("--trace", str, "sarsa-lambda: replacing or accumulating"),
    ("--n-planning", int, "dyna-q: planning updates (sample) or max sweeps (sweep) per step"),
    ("--planning", str, "dyna-q: sample or sweep"),
)


def _scene(args: argparse.Namespace) -> tuple[Task, Config, CRM | None, SensorNoise, np.random.Generator]:
    task = make_task(args.task)
    config = task.hand.contact(task.obj, args.a, args.b)
    crm = _resolve_crm(task, args.crm) if args.crm else None
    noise = SensorNoise(math.radians(args.sigma_n), args.sigma_p)
    return task, config, crm, noise, np.random.default_rng(args.seed)


def _cmd_crm(args: argparse.Namespace) -> int:
    task, config, crm, noise, rng = _scene(args)
    assert crm is not None
    start_err = task.hand.feasible(task.obj, config)
    if start_err is not Error.NONE:
        raise CrmgraspError(f"the start configuration is infeasible ({start_err.name.lower()} error)")
    out = task.hand.execute(task.obj, config, crm, noise=noise, rng=rng)
    obs = observe(noise.sense(out.config, rng))
    index = task.discretizer.index(obs, out.error)
    result = {
        "task": task.name,
        "crm": {"c": crm.c, "f": crm.f, "r": crm.r},
        "error": out.error.name.lower(),
        "config": out.config.to_dict(),
        "observation": {
            "rho": obs.rho,
            "m_a": obs.m_a,
            "m_b": obs.m_b,
            "index": index,
            "label": task.discretizer.label(index),
        },
        "min_friction": min_friction(out.config),
        "success": task.is_success(out.config),
        "path": [list(p) for p in out.path],
    }
    if args.json:
        print(json.dumps(result, indent=2))
        return 0
    print(f"CRM {crm} on {task.name}: error={result['error']}")
    for lab in ("a", "b"):
        c = out.config[lab]
        print(f"  {lab}: x=({c.x + 0.0:.6g}, {c.y + 0.0:.6g})  n=({c.nx + 0.0:.6g}, {c.ny + 0.0:.6g})")
    label = task.discretizer.label(index)
    print(f"  observation: rho={obs.rho:.6g} m_a={obs.m_a:.6g} m_b={obs.m_b:.6g}  [{index}: {label}]")
    print(f"  min_friction={result['min_friction']:.6g}  success={result['success']}")
    return 0


def _cmd_show(args: argparse.Namespace) -> int:
    from .plotting import scene_figure

    if args.out.suffix.lower() not in {".png", ".pdf", ".svg"}:
        raise CrmgraspError(f"--out must end in .png, .pdf or .svg, got {args.out.name!r}")
    task, config, crm, noise, rng = _scene(args)
    outcome = task.hand.execute(task.obj, config, crm, noise=noise, rng=rng) if crm else None
    title = f"{task.name}" + (f": CRM {crm} -> {outcome.error.name.lower()}" if outcome else "")
    save_figure(scene_figure(task.obj, task.hand, config, outcome, title), args.out, dpi=120)
    print(f"wrote {args.out.resolve()}")
    return 0


def _cmd_reproduce(args: argparse.Namespace) -> int:
    from .experiments import reproduce

    results = reproduce(args.out, args.experiments, seed=args.seed, quick=args.quick)
    root = args.out.resolve()
    for name, summary in results.items():
        print(f"{name}: {root / name} ({summary['seconds']} s)")
        for key, value in summary.items():
            if key != "seconds":
                print(f"  {key}: {value}")
    print(f"index: {root / 'README.md'}")
    return 0


def _cmd_learn(args: argparse.Namespace) -> int:
    from .experiments.learning import LearnerSpec, learn, write_learn_outputs

    task = make_task(args.task)
    params = {
        flag.lstrip("-").replace("-", "_"): getattr(args, flag.lstrip("-").replace("-", "_"))
        for flag, _, _ in _AGENT_FLAGS
    }
    params = {k: v for k, v in params.items() if v is not None}
    if args.k < 0:
        raise CrmgraspError(f"--k must be >= 0, got {args.k}")
    run = learn(
        task,
        LearnerSpec(args.agent, args.k, params),
        trials=args.trials,
        episodes=args.episodes,
        seed=args.seed,
        eval_episodes=args.eval_episodes,
        lockstep=args.lockstep,
    )
    paths = write_learn_outputs(task, run, args.out)
    s = run.summary
    print(f"{s['label']} on {task.name}: {s['trials']} trials x {s['episodes']} episodes in {s['seconds']} s")
    print(
        f"  final_mean_steps={s['final_mean_steps']:.3f}  greedy_mean_steps={s['greedy_mean_steps']:.3f}"
        f"  episodes_to_5pct={s['episodes_to_5pct']}"
    )
    for path in paths:
        print(f"  wrote {path.resolve()}")
    return 0


def _cmd_evaluate(args: argparse.Namespace) -> int:
    from .agents import GreedyPolicy, evaluate

    if args.episodes < 1:
        raise CrmgraspError(f"--episodes must be >= 1, got {args.episodes}")
    name = args.task
    if name is None:
        try:
            doc = json.loads(args.policy.read_text(encoding="utf-8"))
            name = doc["task"] if isinstance(doc, dict) and isinstance(doc.get("task"), str) else "paper-box"
        except (OSError, ValueError):
            name = "paper-box"  # GreedyPolicy.load reports the real problem
    task = make_task(name)
    policy = GreedyPolicy.load(args.policy, task)
    steps, success = evaluate(task, policy, policy.encoder, args.episodes, np.random.default_rng(args.seed))
    half = 1.96 * float(steps.std(ddof=1)) / math.sqrt(len(steps)) if len(steps) > 1 else 0.0
    result = {
        "task": task.name,
        "policy": str(args.policy),
        "episodes": args.episodes,
        "seed": args.seed,
        "mean_steps": float(steps.mean()),
        "ci95": [float(steps.mean()) - half, float(steps.mean()) + half],
        "success_rate": float(success.mean()),
    }
    if args.json:
        print(json.dumps(result, indent=2))
    else:
        print(
            f"{args.policy} on {task.name}: {result['mean_steps']:.3f} CRMs per episode "
            f"(95% CI {result['ci95'][0]:.3f}-{result['ci95'][1]:.3f}), success {result['success_rate']:.1%} "
            f"over {args.episodes} episodes"
        )
    return 0


def _cmd_references(args: argparse.Namespace) -> int:
    from .references import belief_optimum, clairvoyant_bound, sample_starts

    task = make_task(args.task)
    starts = sample_starts(task, args.starts, args.seed)
    clair, belief = clairvoyant_bound(task, starts), belief_optimum(task, starts)
    res = {
        "task": task.name,
        "starts": args.starts,
        "seed": args.seed,
        "clairvoyant_bound": clair,
        "belief_optimum": belief,
        "aliasing_price": belief - clair,
    }
    if args.json:
        print(json.dumps(res, indent=2))
    else:
        print(
            f"{task.name}, {args.starts} starts (seed {args.seed}): clairvoyant bound {clair:.4f} CRMs, "
            f"belief-space optimum {belief:.4f} CRMs, price of aliasing {belief - clair:.4f}"
        )
    return 0


def _cmd_compare(args: argparse.Namespace) -> int:
    from .experiments.compare import CompareConfig, compare

    make_task(args.task)  # a clear error for an unknown task before any work
    cfg = CompareConfig.quick(args.task, args.seed) if args.quick else CompareConfig(task=args.task, seed=args.seed)
    summary = compare(args.out, cfg)
    print((args.out / "compare.md").read_text(encoding="utf-8"))
    for key, value in summary.items():
        print(f"{key}: {value}")
    print(f"wrote {(args.out / 'compare.csv').resolve()}, compare.md, compare.png")
    return 0


def _cmd_pomdp(args: argparse.Namespace) -> int:
    from .pomdp import write_cassandra
    from .pomdp_task import POMDPAgent, build_task_pomdp
    from .references import sample_starts

    if args.cell <= 0 or args.samples < 1 or args.episodes < 1:
        raise CrmgraspError("--cell must be > 0, and --samples and --episodes >= 1")
    task = make_task(args.task)
    tp = build_task_pomdp(task, cell=args.cell, samples=args.samples, n_starts=args.starts, seed=args.seed)
    path = write_cassandra(tp.model, args.out)
    agent = POMDPAgent(tp, seed=args.seed)
    runs = [agent.run(c) for c in sample_starts(task, args.episodes, args.seed + 1)]
    counts = ", ".join(f"{k} {v}" for k, v in tp.model.counts.items())
    print(
        f"{task.name}: sampled POMDP ({counts}); model value {agent.model_value():.4f} CRMs; executed on "
        f"{args.episodes} fresh starts: {np.mean([n for n, _ in runs]):.4f} CRMs, "
        f"success {np.mean([ok for _, ok in runs]):.1%}"
    )
    print(f"wrote {path.resolve()}")
    return 0


def _cmd_run(args: argparse.Namespace) -> int:
    from .agents import GreedyPolicy
    from .runner import KinematicHand, PolicyRunner

    name = "paper-box"
    try:
        doc = json.loads(args.policy.read_text(encoding="utf-8"))
        name = doc["task"] if isinstance(doc, dict) and isinstance(doc.get("task"), str) else name
    except (OSError, ValueError):
        pass  # GreedyPolicy.load reports the real problem
    task = make_task(name)
    policy = GreedyPolicy.load(args.policy, task)
    start = task.hand.contact(task.obj, args.a, args.b)
    if task.hand.feasible(task.obj, start) is not Error.NONE:
        raise CrmgraspError("the start configuration is infeasible")
    rng = np.random.default_rng(args.seed)
    hand = KinematicHand(task, start, rng, SensorNoise(math.radians(args.sigma_n), args.sigma_p))
    res = PolicyRunner(policy).run(hand, rng, log=args.log)
    crms = " ".join(r[-3] for r in res.rows if r[-3])
    print(f"{res.stopped} after {res.crms} CRMs ({crms}); true min_friction {min_friction(hand.config):.4g}")
    print(f"wrote {args.log.resolve()}")
    return 0


def _cmd_bench(args: argparse.Namespace) -> int:
    from .bench import main as bench_main

    if args.rounds < 1:
        raise CrmgraspError(f"--rounds must be >= 1, got {args.rounds}")
    bench_main((["--smoke"] if args.smoke else []) + ["--rounds", str(args.rounds), "--seed", str(args.seed)])
    return 0


def _cmd_tasks(args: argparse.Namespace) -> int:
    for name in task_names():
        print(f"{name}: {make_task(name).description}")
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point; returns the exit status."""
    parser = build_parser()
    args = parser.parse_args(argv)
    handlers = {
        "crm": _cmd_crm,
        "show": _cmd_show,
        "reproduce": _cmd_reproduce,
        "tasks": _cmd_tasks,
        "learn": _cmd_learn,
        "evaluate": _cmd_evaluate,
        "bench": _cmd_bench,
        "references": _cmd_references,
        "compare": _cmd_compare,
        "pomdp": _cmd_pomdp,
        "run": _cmd_run,
    }
    try:
        return handlers[args.command](args)
    except CrmgraspError as exc:
        print(f"crmgrasp {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except BrokenPipeError:  # output piped into e.g. `head`
        sys.stderr.close()
        return 0
    except OSError as exc:
        print(
            f"crmgrasp {args.command}: error: {exc.strerror or exc}: {exc.filename or ''}".rstrip(": "), file=sys.stderr
        )
        return 2


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())

"""The ``crmgrasp`` commands that act on one scene: ``crm``, ``show`` and ``run`` (a
configuration from ``--a`` and ``--b``, planar or spatial, on the kinematic or the MuJoCo
hand)."""

from __future__ import annotations

import argparse
import dataclasses
import math
import os
import subprocess
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from crmgrasp._io import check_new_output, dumps_json, save_figure
from crmgrasp._validation import CrmgraspError
from crmgrasp.cli.common import _task
from crmgrasp.cli.options import _resolve_crm
from crmgrasp.model.contacts import ALL_LABELS
from crmgrasp.model.hand import Error
from crmgrasp.model.quality import min_friction
from crmgrasp.model.sensing import SensorNoise, observe
from crmgrasp.tasks import Task


def _scene(args: argparse.Namespace) -> tuple[Task, Any, Any, SensorNoise, np.random.Generator]:
    """The task, the configuration of --a and --b (planar or spatial), the CRM, the noise, the generator."""
    task = _task(args)
    config = _place(task, args)
    crm = _resolve_crm(task, args.crm) if args.crm is not None else None
    noise = _noise(args)
    return task, config, crm, noise, np.random.default_rng(args.seed)


def _place(task: Task, args: argparse.Namespace) -> Any:
    """The configuration of --a, --b, ... on ``task``'s object (its nominal one for a family):
    one point of the contact model's dimension per contact of the model."""
    labels, dim = task.model.labels, task.model.dim
    flags = [f"--{lab}" for lab in labels]
    given = [f"--{lab}" for lab in ALL_LABELS if getattr(args, lab, None) is not None]
    if given != flags:
        raise CrmgraspError(
            f"task {task.name!r} has {len(labels)} fingers: give {' '.join(flags)} (got {' '.join(given)})"
        )
    points = [getattr(args, lab) for lab in labels]
    if any(len(p) != dim for p in points):
        axes = ",".join("XYZ"[:dim])
        raise CrmgraspError(f"{', '.join(flags)} take {axes} on the {task.model.kind} task {task.name!r}")
    return task.place(*points)


def _noise(args: argparse.Namespace) -> SensorNoise:
    """The sensing noise of --sigma-n-deg (degrees) and --sigma-p (metres)."""
    return SensorNoise(math.radians(args.sigma_n_deg), args.sigma_p)


def _sensing(task: Task, noise: SensorNoise) -> Task:
    """``task`` read through ``noise`` (the command's --sigma-n-deg and --sigma-p)."""
    return task if noise == task.noise else dataclasses.replace(task, noise=noise)


def _observation(task: Task, obs: Sequence[float], index: int) -> dict[str, Any]:
    """An observation as JSON data: each of the model's quantities by name, its bin index and label."""
    return {
        **dict(zip(task.model.observation_names, obs, strict=True)),
        "index": index,
        "label": task.discretizer.label(index),
    }


def _observation_line(task: Task, obs: Sequence[float], index: int) -> str:
    """An observation as one line of the ``crm`` report."""
    values = " ".join(f"{n}={v:.6g}" for n, v in zip(task.model.observation_names, obs, strict=True))
    return f"  observation: {values}  [{index}: {task.discretizer.label(index)}]"


def _cmd_crm(args: argparse.Namespace) -> int:
    task, config, crm, noise, rng = _scene(args)
    assert crm is not None
    start_err = task.feasible(config)
    if start_err is not Error.NONE:
        raise CrmgraspError(f"the start configuration is infeasible ({start_err.name.lower()} error)")
    if task.model.kind != "planar":
        return _crm_spatial(args, task, config, crm, noise, rng)
    out = task.hand.execute(task.obj, config, crm, noise=noise, rng=rng)
    obs = observe(noise.sense(out.config, rng))
    index = task.discretizer.index(obs, out.error)
    result = {
        "task": task.name,
        "crm": {"c": crm.c, "f": crm.f, "r": crm.r},
        "error": out.error.name.lower(),
        "config": out.config.to_dict(),
        "observation": _observation(task, obs, index),
        "min_friction": min_friction(out.config),
        "success": task.is_success(out.config),
        "path": [list(p) for p in out.path],
    }
    if args.json:
        print(dumps_json(result))
        return 0
    print(f"CRM {crm} on {task.name}: error={result['error']}")
    for lab in task.model.labels:
        c = out.config[lab]
        print(f"  {lab}: x=({c.x + 0.0:.6g}, {c.y + 0.0:.6g})  n=({c.nx + 0.0:.6g}, {c.ny + 0.0:.6g})")
    print(_observation_line(task, obs, index))
    print(f"  min_friction={result['min_friction']:.6g}  success={result['success']}")
    return 0


def _crm_spatial(
    args: argparse.Namespace, task: Task, config: Any, crm: Any, noise: SensorNoise, rng: np.random.Generator
) -> int:
    """``crmgrasp crm`` on a spatial task: the same report with 3-D contacts."""
    t = _sensing(task, noise)
    out: Any = t.execute(config, crm, t.read(config, rng))
    obs = t.observe(t.read(out.config, rng))
    index = task.discretizer.index(obs, out.error)
    contacts = {lab: {"x": list(c.x), "n": list(c.n)} for lab, c in zip(task.model.labels, out.config, strict=True)}
    result = {
        "task": task.name,
        "crm": {"c": crm.c, "f": crm.f, "r": list(crm.r)},
        "error": out.error.name.lower(),
        "config": contacts,
        "observation": _observation(task, obs, index),
        "min_friction": task.quality(out.config),
        "success": task.is_success(out.config),
    }
    if args.json:
        print(dumps_json(result))
        return 0
    print(f"CRM {crm} on {task.name}: error={result['error']}")
    for lab, c in contacts.items():
        x, n = (", ".join(f"{v + 0.0:.6g}" for v in c[key]) for key in ("x", "n"))
        print(f"  {lab}: x=({x})  n=({n})")
    print(_observation_line(task, obs, index))
    print(f"  min_friction={result['min_friction']:.6g}  success={result['success']}")
    return 0


def _cmd_show(args: argparse.Namespace) -> int:
    from crmgrasp.plotting import scene_figure

    if args.hand == "mujoco":
        return _show_mujoco(args)
    if args.out.suffix.lower() not in {".png", ".pdf", ".svg"}:
        raise CrmgraspError(f"--out must end in .png, .pdf or .svg, got {args.out.name!r}")
    check_new_output(args.out, "--out", args.overwrite)
    task, config, crm, noise, rng = _scene(args)
    t = _sensing(task, noise)
    outcome = t.execute(config, crm, t.read(config, rng)) if crm else None
    title = f"{task.name}" + (f": CRM {crm} -> {outcome.error.name.lower()}" if outcome else "")
    save_figure(scene_figure(task.obj, task.hand, config, outcome, title), args.out, dpi=120)
    print(f"wrote {args.out.resolve()}")
    return 0


def _show_mujoco(args: argparse.Namespace) -> int:
    from crmgrasp.hardware.mujoco import hardware_task
    from crmgrasp.hardware.mujoco.render import show

    user_gl = os.environ.get("MUJOCO_GL")
    check_new_output(args.out, "--out", args.overwrite)
    task, config, crm, _, rng = _scene(args)
    try:
        print(show(hardware_task(task), config, crm, args.out, rng))
    except CrmgraspError as exc:
        if user_gl is not None or "rendering failed" not in str(exc):
            raise
        # EGL is missing: MuJoCo fixes its GL backend at import, so retry in a child with OSMesa
        env = {**os.environ, "MUJOCO_GL": "osmesa"}
        return subprocess.run([sys.executable, "-m", "crmgrasp", *args.argv], env=env, check=False).returncode
    return 0


def _cmd_run(args: argparse.Namespace) -> int:
    from crmgrasp.agents.loading import load_policy
    from crmgrasp.hardware.runner import KinematicHand, PolicyRunner

    check_new_output(args.log, "--log", args.overwrite, " (the log of an earlier run)")
    if args.figure is not None:
        if args.figure.suffix.lower() not in {".png", ".pdf", ".svg"}:
            raise CrmgraspError(f"--figure must end in .png, .pdf or .svg, got {args.figure.name!r}")
        if args.figure.resolve() == args.log.resolve():
            raise CrmgraspError("--figure and --log name the same file")
        check_new_output(args.figure, "--figure", args.overwrite)
    policy = load_policy(args.policy)
    task = policy.task
    if task.family is not None:  # the family's nominal object
        task = task.with_object(task.obj)
    start = _start(task, args)
    if (error := task.feasible(start)) is not Error.NONE:
        name = error.name.lower()
        article = "an" if name[0] in "aeiou" else "a"
        raise CrmgraspError(f"the start configuration is infeasible: {article} {name} error")
    rng = np.random.default_rng(args.seed)
    if args.hand == "mujoco":
        from crmgrasp.hardware.mujoco import hardware_task
        from crmgrasp.hardware.mujoco.spatial import mujoco_hand

        task = hardware_task(task)
        hand: Any = mujoco_hand(task, start, rng)
    else:
        hand = KinematicHand(task, start, rng, _noise(args))
    res = PolicyRunner(policy, task).run(hand, rng, log=args.log)
    crms = " ".join(r[-3] for r in res.rows if r[-3])
    true = hand.config if args.hand == "kinematic" else hand.true_config()
    mu = f"{task.quality(true):.4g}" if true is not None else "n/a (no contact)"
    after = f"{res.stopped} after {res.crms} CRM{'' if res.crms == 1 else 's'}"
    print(f"{after} ({crms}); true min_friction {mu}")
    print(f"wrote {args.log.resolve()}")
    if args.figure is not None:
        _run_figure(args.figure, task, res, f"{task.name}: {after}; true min_friction {mu}")
        print(f"wrote {args.figure.resolve()}")
    return 0


def _start(task: Task, args: argparse.Namespace) -> Any:
    """``run``'s start: the configuration of --a, --b, ... ([`_place`][]) or, with none of them,
    one drawn from ``task``'s own starts by a generator of --seed (printed)."""
    if any(getattr(args, lab, None) is not None for lab in ALL_LABELS):
        return _place(task, args)
    start = task.sample_start(np.random.default_rng([args.seed, 1]))
    nums, dim = task.model.numbers(start), task.model.dim
    points = [nums[2 * dim * i : 2 * dim * i + dim] for i in range(len(task.model.labels))]
    where = ", ".join(f"{lab} ({', '.join(f'{v:.4f}' for v in p)})" for lab, p in zip(task.model.labels, points))
    print(f"start drawn from {task.name}'s starts (seed {args.seed}): {where}")
    return start


def _run_figure(path: Path, task: Any, res: Any, title: str) -> None:
    """The run's readings drawn, one panel each ([`readings_figure`][crmgrasp.plotting.readings.readings_figure]):
    the CRM that followed a reading and its error, or after the last one how the run stopped."""
    from crmgrasp.plotting.readings import readings_figure

    panels = [
        (config, f"reading {i}: {crm} -> {error}" if crm else f"reading {i}: {res.stopped}")
        for i, (config, crm, error) in enumerate(res.readings)
    ]
    save_figure(readings_figure(task.obj, task.hand, panels, title), path, dpi=100)

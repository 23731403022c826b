"""The working calls of [`api_fuzz`][]'s input and output surfaces: fingertip sensing, step
records, sweeps and run folders, the vector environments' resets, and what a user calls on
results (intervals, a hand's conformance, saved policies, the sampled POMDP, policy costs).

Each function returns [`Example`][]s, one working call per public constructor or function,
which ``api_fuzz`` makes into its ``Call``s and gives each of their arguments every hostile value
in turn. The calls that write files write in the scratch folder ``api_fuzz`` works in.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

import crmgrasp as c
from crmgrasp.hardware.contact_sensing import Circle, ContactDetector, Flat, HighPass, Sphere, contact_from_wrench

Example = tuple[str, Callable[..., Any], tuple[Any, ...], dict[str, Any]]
"""A working call: its label, the function, the positional and the keyword arguments."""


def example(label: str, function: Callable[..., Any], *args: Any, **kwargs: Any) -> Example:
    """The [`Example`][] ``function(*args, **kwargs)``, labelled."""
    return label, function, args, kwargs


def io_examples(box: c.Task) -> list[Example]:
    """Every example of this module."""
    return [
        *sensing_examples(),
        *records_examples(box),
        *study_examples(),
        *vector_examples(),
        *analysis_examples(box),
    ]


def _filtered(tau: Any, dt: Any, first: Any, second: Any) -> Any:
    """Two samples through a ``HighPass(tau, dt)``: the second's output."""
    f = HighPass(tau, dt)
    f(first)
    return f(second)


def _detected(tau: Any, dt: Any, on: Any, off: Any, first: Any, second: Any) -> Any:
    """Two force samples through a ``ContactDetector``: whether the second is an onset."""
    d = ContactDetector(tau, dt, on=on, off=off)
    d(first)
    return d(second)


def sensing_examples() -> list[Example]:
    """Fingertip shapes, the contact from a wrench, the filter and the onset detector."""
    return [
        example("Circle", Circle, 0.01, center=(0.0, 0.0)),
        example("Flat", Flat, (0.0, 1.0), offset=0.0),
        example("Sphere", Sphere, 0.01, center=(0.0, 0.0, 0.0)),
        example("contact_from_wrench", contact_from_wrench, Circle(0.01), (0.0, 2.0), 0.0, threshold=0.05),
        example("contact_from_wrench (3-D)", contact_from_wrench, Sphere(0.01), (0.0, 0.0, 2.0), (0.0, 0.0, 0.0)),
        example("HighPass", _filtered, 0.5, 0.01, (0.0, 1.0), (0.0, 2.0)),
        example("ContactDetector", _detected, 0.5, 0.01, 0.2, 0.1, (0.0, 0.0), (0.0, 2.0)),
    ]


def _record(time: Any, step: Any, contacts: Any, observation: Any, obs_index: Any, label: Any, **more: Any) -> Any:
    """One [`StepRecord`][crmgrasp.hardware.records.StepRecord] written to ``steps.mcap``."""
    from crmgrasp.hardware.records import StepRecord, write_mcap

    record = StepRecord(time, step, contacts, observation, obs_index, label, **more)
    return write_mcap("steps.mcap", [record], "paper-box")


def records_examples(box: c.Task) -> list[Example]:
    """A step record written to an MCAP file (none without the extra ``crmgrasp[mcap]``)."""
    import importlib.util

    if importlib.util.find_spec("foxglove") is None:
        return []
    from crmgrasp.hardware.records import StepRecord, write_mcap

    contacts = {"a": ((-0.15, -0.02, 0.0), (1.0, 0.0, 0.0)), "b": ((-0.1, -0.05, 0.0), (0.0, 1.0, 0.0))}
    record = StepRecord(0.0, 0, contacts, {"rho": 0.0, "m_a": 0.0, "m_b": 0.0}, 0, "a")
    return [
        example("write_mcap", write_mcap, "steps.mcap", [record], "paper-box"),
        example(
            "StepRecord",
            _record,
            0.0,
            0,
            contacts,
            {"rho": 0.0, "m_a": 0.0, "m_b": 0.0},
            0,
            "a",
            raw={"a": [0.0, 1.0, 0.0]},
            pose=(0.0, 0.0, 0.0),
            action=1,
            crm="C1",
            error=None,
        ),
    ]


def _run_folder(path: Any, command: Any, task: Any, config: Any, **kwargs: Any) -> Any:
    """A run folder opened, one unit completed and finished ``complete``."""
    from crmgrasp.experiments.runs import RunFolder

    store = RunFolder(path, command, task, config, **kwargs)
    store.complete("unit", {"value": 1})
    store.finish("complete")
    return store


def study_examples() -> list[Example]:
    """A study read from plain data, run, reported; run folders and their status."""
    from crmgrasp.experiments.runs import RunFolder, default_run_dir, leftovers, read_status
    from crmgrasp.experiments.study import study_from_dict
    from crmgrasp.experiments.sweep import report, run_study

    doc = {"name": "s", "trials": 1, "episodes": 3, "eval_episodes": 2, "seeds": [0], "cell": [{"task": "paper-box"}]}
    study = study_from_dict(doc)
    store = RunFolder("study", "sweep", "s", study.to_dict(), seed=0)
    run_study(study, store)
    store.finish("complete")
    return [
        example("study_from_dict", study_from_dict, doc),
        example("run_study", run_study, study, RunFolder("study2", "sweep", "s", study.to_dict()), jobs=1),
        example("report", report, "study"),
        example("read_status", read_status, "study"),
        example("leftovers", leftovers, "study"),
        example("default_run_dir", default_run_dir, "learn", "paper-box", root="runs"),
        example("RunFolder", _run_folder, "run", "learn", "paper-box", {"k": 1}, argv=[], seed=0, overwrite=True),
    ]


def vector_examples() -> list[Example]:
    """The vector environments' constructors and resets (their steps are in ``loop_examples``)."""
    from crmgrasp.envs.vector import FamilyVectorEnv, continuous_vector_env, vector_env

    vec, fam = vector_env(2), FamilyVectorEnv(2, "box-family")
    fam.reset(seed=0)
    return [
        example("CRMGraspVectorEnv.reset", vec.reset, seed=0, options=None),
        example("FamilyVectorEnv", FamilyVectorEnv, 2, "box-family", backend="auto", max_episode_steps=None),
        example("FamilyVectorEnv.reset", fam.reset, seed=0, options=None),
        example("FamilyVectorEnv.step", fam.step, np.array([0, 1])),
        example("continuous_vector_env", continuous_vector_env, 2, "paper-box", exact_friction=True),
    ]


def analysis_examples(box: c.Task) -> list[Example]:
    """Intervals over trials, a hand's conformance test, loading a saved policy, the sampled
    POMDP and its belief update, a belief policy's costs, the graspable check, the controller."""
    from crmgrasp.agents.controller import run_controller
    from crmgrasp.agents.loading import load_policy
    from crmgrasp.experiments.stats import bootstrap_ci, ci_text, iqm, normal_ci
    from crmgrasp.hardware.conformance import check_hand
    from crmgrasp.hardware.runner import KinematicHand
    from crmgrasp.planners import references as refs
    from crmgrasp.planners.pomdp import belief_update
    from crmgrasp.planners.pomdp_task import build_task_pomdp
    from crmgrasp.planners.realizable import policy_costs

    values = [1.0, 2.0, 3.0, 4.0, 5.0]
    m = build_task_pomdp(box, samples=2, n_starts=20, max_states=2000).model
    starts = refs.sample_starts(box, 4, 0)
    return [
        example("bootstrap_ci", bootstrap_ci, values, seed=0, confidence=0.95, resamples=100),
        example("normal_ci", normal_ci, values),
        example("iqm", iqm, values),
        example("ci_text", ci_text, 1.6, 1.7, over="trials"),
        example("check_hand", check_hand, KinematicHand, box, seed=0, worlds=1),
        example("load_policy", load_policy, "policy.json", task=box),
        example("build_task_pomdp", build_task_pomdp, box, cell=0.01, samples=2, n_starts=20, seed=0, max_states=2000),
        example("belief_update", belief_update, m, m.b0, 0, 0),
        example("policy_costs", policy_costs, refs.BeliefPolicy(box, starts), starts, advance=None),
        example("graspable_warning", refs.graspable_warning, box, n=5, seed=0, backend="auto"),
        example("run_controller", run_controller, box, 3, np.random.default_rng(0)),
    ]

"""Hostile arguments to the Python API, at scale: every argument of every call of [`EXAMPLES`][]
given every value of [`HOSTILE`][].

A user defines objects, hands, CRM sets, bins and tasks in Python (docs/usage.md) as much as in
task files. [`EXAMPLES`][] holds one working call of each public constructor and function of
``crmgrasp`` (the top-level API, the hand's and the task's methods a user calls, and the named
tuples through the functions that read them, since a ``Contact`` is checked where it is used).
For each call and each of its arguments (positional and keyword) the script replaces that one
argument with each hostile value (``None``, NaN and infinities, negative, zero, huge, tiny and
100-digit numbers, text, ``True``, empty and nested containers, an array with a NaN, a complex
number, bytes, an object) and makes the call in this process with Python's warnings raised as
errors and a time limit. A call passes if it returns or raises a ``CrmgraspError`` of one line
under 400 characters; any other exception, a warning, a longer message or a call still running
after ``--seconds`` (5) is reported with the call, the argument and the value. It prints one JSON
object and exits 1 if a call failed.

Measured 2026-12-08 on the 2-core machine: 170 calls, 12,180 variants in 5 s, none failed (with
MuJoCo, the MCAP and the deep extras installed).
The first 24 calls on the code before their fixes (46c3eef): 227 of 1,460 failed. A ``Contact`` of text,
``None`` or containers reached ``observe`` and ``min_friction`` as a ``TypeError`` (88); a hand
given no ``Shape`` failed inside ``contact`` and ``execute`` (40); ``Task`` took actions that
are no sequence and a text ``reference_mean_steps`` (22); ``KOrderHistory`` wrapped anything
(20, Gymnasium's ``TypeError``); a ``Rectangle`` pose that is no triple (19); ``force_closure``
and the spatial ``place`` given text (24); ``Discretizer`` names that are no sequence of text
(13); and ``regular_polygon(10**100, r)`` built its vertices until the time limit (1). The 10 calls
added next (sampling a start, executing with noise or a given reading, ``UniformStarts``,
``CRMRange``, ``train_trials``, and a greedy policy's ``from_agent``, ``predict``, ``save`` and
``load``) on the code of db0d784: 274 of 680 failed, as an ``AttributeError`` or ``TypeError``
from deep inside (a generator, a sensor, a reading, a task, an agent, parameters, checkpoints
or a path of the wrong kind). The 34 calls of the planners, the references, the episode loop,
the environments' steps and the family helpers ([`planning_examples`][], [`loop_examples`][])
on the code of 411076d: 934 of 2,140 failed. Something other than a ``Task`` reached 15
functions as an ``AttributeError`` (298); the episode loop took a policy, a learner, an encoder
or a generator of the wrong kind (154); the explicit POMDP's helpers took anything (168);
starts that are no list (90); seeds of text, floats or negative (44, the environment's through
Gymnasium's own error); offsets, labels, families and CRM sets of the family helpers (92);
``episodes_to_within`` (47) and ``flat_action`` (39); and 10**100 sampled starts ran until the
time limit (2). The 30 calls of the spatial model, the hardware runner, CRM grids, task files
and figures ([`spatial_examples`][], [`hardware_examples`][]) on the code of c589ca7: 475 of
1,680 failed. Figures took any object, hand, configuration, outcome or curve (118); CRM grids
and ranges took anything, and 10**100 offsets ran until the time limit (84); 3-vectors of text
reached numpy in the 3-D hand, solids and quality (72); ``execute_crm3d`` and ``observe3d``
took anything as an object, a hand, contacts or a table (102); something other than a
``Task`` reached ``KinematicHand``, ``log_columns`` and ``task_to_dict`` (60); and the CRM
sets of the spatial helpers (21) and a task file's path (18). The 16 experiments' configs
([`config_examples`][]) on the code of fbe9770: 4 of 2,640 failed (a ``ThirdContactConfig``
preset of the wrong kind), but only because a config took anything: ``Figure4Config(trials="x")``
was built, and its run failed inside with a ``TypeError``. Each field is now checked against
its type where the config is built (``crmgrasp.experiments.configs``). The 8 calls of the
kernel seam ([`kernel_examples`][]) on the code of f605494: 192 of 420 failed, and the run
crashed the process at its end ("corrupted double-linked list", a segmentation fault in
other orders): ``Kernel.successors([[1.0, 2.0]])`` handed a row of 2 numbers to compiled code
that reads 8 (repeated alone, it crashed Python too). A kernel now checks a configuration
before its compiled code reads it (``Kernel.trust``), and a step its state. The kernels'
batched methods (``execute``, ``execute_crms``, ``observe``, ``read_rows``) on the code of
7f3340f: 99 of 260 failed, and rows of the wrong width were read past their ends without a
word (``observe`` and ``read_rows`` of ``(4, 2)`` rows returned numbers); they now check their
arrays' shapes, indices and offsets (``Kernel.check_batch``), and ``step_row`` its row
(``Kernel.check_row``: 40 of 60 variants failed at 1bad162). The MuJoCo stand-in's
``MujocoHand``, ``MujocoSteps`` and ``hardware_task`` ([`mujoco_examples`][]) on the code of
05bd926: 142 of 200 failed (something other than a ``Task``, a start, a generator or physics
parameters reached an attribute; a palm tolerance of text reached ``math.radians``). The learners' helpers
([`learner_examples`][]) on the code of 86c3c34: 148 of 620 failed (``features`` took any
values, error code and bounds: 56; a preset, a deep learner or an agent named by something
that is not text reached a dict lookup; ``bounds_of`` and ``apply_preset`` took non-tasks).
The 21 calls of fingertip sensing, MCAP step records, sweeps and run folders, and the vector
environments' resets ([`api_examples_io`][]) on the code of a8d4749: 414 of 1,320 failed. A
``write_mcap`` record with a field of the wrong kind failed inside the Foxglove SDK (156); the
fingertip, force, torque, filter sample and thresholds of the contact sensing reached numpy
(127; a torque of 1e308 overflowed with a warning, now a reading is bounded by ``MAX_READING``);
``run_study``, ``report``, ``read_status``, ``leftovers`` and ``default_run_dir`` took
something other than a study, a run folder or a path (112); ``FamilyVectorEnv.reset`` passed
its seed to Gymnasium unchecked (14); a run's config of complex numbers reached ``json`` (5).
The 11 calls of the interval helpers, ``check_hand``, ``load_policy``, the sampled POMDP's
``build_task_pomdp`` and ``belief_update``, ``policy_costs`` and ``run_controller`` on the code
of bcaf586: 430 of 700 failed, as type, attribute and index errors from inside, scipy's
``DegenerateDataWarning`` for a confidence of 1e-320, and 3 calls still running at the time limit
(``check_hand`` with 10**100 worlds, ``build_task_pomdp`` with 10**100 samples or starts).

Usage: ``python benchmarks/api_fuzz.py [--seconds 5]``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import signal
import sys
import tempfile
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from scipy import sparse

import api_examples_io
import crmgrasp as c
import task_file_fuzz
from crmgrasp import sim
from crmgrasp.agents import (
    GreedyPolicy,
    encoder_for,
    episodes_to_within,
    evaluate,
    make_agent,
    run_episode,
    train_trials,
)
from crmgrasp.envs import ContinuousCRMEnv
from crmgrasp.envs.continuous import PairOffsetActions, flat_action
from crmgrasp.envs.vector import vector_env
from crmgrasp.hardware.runner import HandSteps, KinematicHand, PolicyRunner, log_columns
from crmgrasp.model.actions import CRMRange, full_ranges, grid_points
from crmgrasp.model.families import BoxFamily, RegularPolygonFamily
from crmgrasp.model.mesh import open_cup
from crmgrasp.model.quality3d import ferrari_canny, force_closure_3d, min_friction_3d
from crmgrasp.model.solid_families import BoxOnTable, CylinderOnTable
from crmgrasp.model.spatial import CRM3D, Config3D, Contact3D, Cylinder, Hand3D, box3d, execute_crm3d, observe3d
from crmgrasp.planners import pomdp
from crmgrasp.planners import references as refs
from crmgrasp.planners.korder import korder_search
from crmgrasp.planners.realizable import realizable_reference
from crmgrasp.plotting import friction_histogram, learning_curve_figure, scene_figure
from crmgrasp.tasks import UniformStarts
from crmgrasp.tasks.families import default_crms, family_task
from crmgrasp.tasks.files import TEMPLATE, load_task_file, resolve_task, task_to_dict
from crmgrasp.tasks.fingers import finger_crms, three_finger_task
from crmgrasp.tasks.offsets import offset_grid
from crmgrasp.tasks.spatial import SpatialTask, SurfaceStarts, spatial_crms, tripod_crms

HOSTILE: tuple[Any, ...] = (
    None,
    math.nan,
    math.inf,
    -math.inf,
    -1,
    0,
    1e308,
    1e-320,
    10**100,
    "x",
    "",
    True,
    [],
    (),
    [[1.0, 2.0]],
    {"a": 1},
    np.array([math.nan]),
    complex(1, 1),
    b"x",
    object(),
)
"""The values each argument is given in turn."""


class Call:
    """One working call: ``function(*args, **kwargs)``, named."""

    def __init__(self, label: str, function: Callable[..., Any], *args: Any, **kwargs: Any) -> None:
        self.name, self.function, self.args, self.kwargs = label, function, args, kwargs

    def working(self) -> Callable[[], Any]:
        """The call itself."""
        return _bound(self.function, self.args, self.kwargs)

    def variants(self) -> Iterator[tuple[str, Any, Callable[[], Any]]]:
        """Per argument and hostile value: the argument's name, the value and the call with it
        replaced."""
        for i in range(len(self.args)):
            for value in HOSTILE:
                args = (*self.args[:i], value, *self.args[i + 1 :])
                yield f"argument {i}", value, _bound(self.function, args, self.kwargs)
        for key in self.kwargs:
            for value in HOSTILE:
                yield key, value, _bound(self.function, self.args, {**self.kwargs, key: value})


def _bound(function: Callable[..., Any], args: tuple[Any, ...], kwargs: dict[str, Any]) -> Callable[[], Any]:
    return lambda: function(*args, **kwargs)


def _observe_contact(x: Any, y: Any, nx: Any, ny: Any) -> Any:
    """The observation of a configuration whose contact ``a`` is ``Contact(x, y, nx, ny)``."""
    return c.observe(c.Config(c.Contact(x, y, nx, ny), c.Contact(-0.10, -0.05, 0.0, 1.0)))


def _friction_contact(x: Any, y: Any, nx: Any, ny: Any) -> Any:
    """The least friction of the same configuration."""
    return c.min_friction(c.Config(c.Contact(x, y, nx, ny), c.Contact(-0.10, -0.05, 0.0, 1.0)))


def examples() -> list[Call]:
    """One working call of each public constructor and function."""
    box = c.paper_box()
    cup = c.make_task("cup-3d")
    cfg = box.hand.contact(box.obj, a=(-0.15, -0.02), b=(-0.10, -0.05))
    points, normals = [(-0.15, -0.02), (-0.10, -0.05)], [(1.0, 0.0), (0.0, 1.0)]
    task_kwargs = {
        "name": "t",
        "obj": box.obj,
        "hand": box.hand,
        "actions": box.actions,
        "discretizer": box.discretizer,
        "mu_goal": 0.05,
        "max_steps": 10,
        "noise": c.SensorNoise(),
        "reference_mean_steps": 1.66,
        "description": "",
        "grasp_reward": -1.0,
        "error_cost": 0.0,
    }
    hand_kwargs = {"backoff": 0.01, "r_max": 0.16, "palm_normal_tol": 1e-9, "min_separation": 0.0, "contacts": 2}
    bins = {"names": ("rho", "m_a", "m_b"), "abs_moments": True, "rho": (1.0,), "m_a": (0.1,), "m_b": (0.1,)}
    agent = train_trials(box, "sarsa", trials=1, episodes=3, seed=0, eval_episodes=0).agents[0]
    policy = GreedyPolicy.from_agent(box, 2, agent)
    policy.save("policy.json")  # in the scratch folder main works in: what load reads
    return [
        Call("Disc", c.Disc, 0.1, center=(0.0, 0.0)),
        Call("Polygon", c.Polygon, [(0.0, 0.0), (0.1, 0.0), (0.0, 0.1)]),
        Call("Rectangle", c.Rectangle, 0.3, 0.1, pose=(0.0, 0.0, 0.0)),
        Call("regular_polygon", c.regular_polygon, 5, 0.1, center=(0.0, 0.0), rotation=0.0),
        Call("CRM", c.CRM, "a", "b", 0.0),
        Call("Hand", c.Hand, 0.16, 0.12, **hand_kwargs),
        Call("force_closure", c.force_closure, points, normals, 0.1),
        Call("is_force_closure", c.is_force_closure, cfg, 0.1),
        Call("min_friction", c.min_friction, cfg),
        Call("observe", c.observe, cfg),
        Call("observe(Config(Contact(...)))", _observe_contact, -0.15, -0.02, 1.0, 0.0),
        Call("min_friction(Config(Contact(...)))", _friction_contact, -0.15, -0.02, 1.0, 0.0),
        Call("Discretizer", c.Discretizer, **bins),
        Call("SensorNoise", c.SensorNoise, 0.05, 0.002),
        Call("Task", c.Task, **task_kwargs),
        Call("make_task", c.make_task, "paper-box"),
        Call("CRMGraspEnv", c.CRMGraspEnv, task="paper-box", render_mode=None, backend="auto", exact_friction=True),
        Call("KOrderHistory", c.KOrderHistory, c.CRMGraspEnv(), k=2),
        Call("Hand.contact", box.hand.contact, box.obj, a=(-0.15, -0.02), b=(-0.10, -0.05)),
        Call("Hand.execute", box.hand.execute, box.obj, cfg, c.CRM("a", "b", 0.0)),
        Call("Task.place", box.place, (-0.15, -0.02), (-0.10, -0.05)),
        Call("Task.check_config", box.check_config, cfg),
        Call("Task.crm", box.crm, 1),
        Call("Task.place (cup-3d)", cup.instance(np.random.default_rng(0)).place, (0.1, 0.0, 0.05), (-0.1, 0.0, 0.05)),
        Call("Task.sample_start", box.sample_start, np.random.default_rng(0)),
        Call(
            "Hand.execute with noise",
            box.hand.execute,
            box.obj,
            cfg,
            box.actions[0],
            noise=c.SensorNoise(0.05, 0.002),
            rng=np.random.default_rng(0),
        ),
        Call("Hand.execute with a reading", box.hand.execute, box.obj, cfg, box.actions[0], sensed=cfg),
        Call("UniformStarts", UniformStarts, max_tries=100),
        Call("CRMRange", CRMRange, "a", "b", (-0.1,), (0.1,)),
        Call(
            "train_trials",
            train_trials,
            box,
            "sarsa",
            trials=1,
            episodes=3,
            seed=0,
            k=2,
            eval_episodes=2,
            params={"alpha": 0.3},
            checkpoints=(2,),
            checkpoint_episodes=2,
            backend="auto",
        ),
        Call("GreedyPolicy.from_agent", GreedyPolicy.from_agent, box, 2, agent),
        Call("GreedyPolicy.predict", policy.predict, [0], [], np.random.default_rng(0)),
        Call("GreedyPolicy.save", policy.save, "policy.json"),
        Call("GreedyPolicy.load", GreedyPolicy.load, "policy.json"),
        *planning_examples(box),
        *loop_examples(box),
        *spatial_examples(),
        *hardware_examples(box, cfg),
        *config_examples(),
        *kernel_examples(box, cfg),
        *mujoco_examples(box, cfg),
        *learner_examples(box),
        *(Call(label, f, *args, **kwargs) for label, f, args, kwargs in api_examples_io.io_examples(box)),
    ]


def planning_examples(box: c.Task) -> list[Call]:
    """The planners and references a user calls on a task and its sampled starts."""
    starts = refs.sample_starts(box, 4, 0)
    m = pomdp.POMDP(
        2, 1, 2, [sparse.identity(2, format="csr")], np.full((1, 2, 2), 0.5), np.full(2, 0.5), np.zeros(2, bool)
    )
    pomdp.write_cassandra(m, "m.pomdp")
    return [
        Call("sample_starts", refs.sample_starts, box, 4, 0),
        Call("clairvoyant_steps", refs.clairvoyant_steps, box, starts[0], horizon=5, backend="auto"),
        Call("clairvoyant_bound", refs.clairvoyant_bound, box, starts, horizon=5, backend="auto"),
        Call("graspable_starts", refs.graspable_starts, box, starts, horizon=5, backend="auto"),
        Call("ungraspable_fraction", refs.ungraspable_fraction, box, starts, horizon=5, backend="auto"),
        Call("belief_optimum", refs.belief_optimum, box, starts, horizon=5, backend="auto"),
        Call("block_optima", refs.block_optima, box, starts, 2, horizon=5, backend="auto"),
        Call("BeliefPolicy", refs.BeliefPolicy, box, starts, fallback="restart", backend="auto"),
        Call("BeliefPolicy.run", refs.BeliefPolicy(box, starts).run, starts[0], np.random.default_rng(0)),
        Call("realizable_reference", realizable_reference, box, starts, 4, 1, fallback="nearest", backend="auto"),
        Call("korder_search", korder_search, box, starts, k=1, max_passes=2, init="belief"),
        Call("collect_beliefs", pomdp.collect_beliefs, m, 3, 2, np.random.default_rng(0)),
        Call("solve_pbvi", pomdp.solve_pbvi, m, np.full((1, 2), 0.5), 2),
        Call("write_cassandra", pomdp.write_cassandra, m, "n.pomdp"),
        Call("read_cassandra", pomdp.read_cassandra, "m.pomdp"),
    ]


def loop_examples(box: c.Task) -> list[Call]:
    """The episode loop, the learners' helpers, the environments' steps and the families."""
    enc = encoder_for(box, 1)
    agent = make_agent("sarsa", len(box.actions))
    env, cont, vec = c.CRMGraspEnv(), ContinuousCRMEnv(), vector_env(2)
    env.reset(seed=0), cont.reset(seed=0), vec.reset(seed=0)
    family = RegularPolygonFamily(sides=(3, 5), radius=(0.04, 0.08))
    return [
        Call("make_agent", make_agent, "sarsa", 4, alpha=0.3),
        Call("encoder_for", encoder_for, box, 2),
        Call("agents.run_episode", run_episode, box, agent, enc, np.random.default_rng(0), np.random.default_rng(1)),
        Call("evaluate", evaluate, box, agent, enc, 3, np.random.default_rng(0), np.random.default_rng(1)),
        Call("episodes_to_within", episodes_to_within, np.full(20, 1.7), 1.66, factor=1.05, window=10),
        Call(
            "sim.run_episode",
            sim.run_episode,
            box,
            refs.BeliefPolicy(box, refs.sample_starts(box, 4, 0)),
            np.random.default_rng(0),
            start=None,
            trace=True,
        ),
        Call("CRMGraspEnv.reset", env.reset, seed=0, options=None),
        Call("CRMGraspEnv.step", env.step, 1),
        Call("ContinuousCRMEnv", ContinuousCRMEnv, "paper-box", backend="auto"),
        Call("ContinuousCRMEnv.step", cont.step, {"pair": 1, "r": np.array([0.0])}),
        Call("vector_env", vector_env, 2, "paper-box"),
        Call("CRMGraspVectorEnv.step", vec.step, np.array([0, 1])),
        Call("flat_action", flat_action, PairOffsetActions(box).ranges, np.array([0.1, 0.2])),
        Call("default_crms", default_crms, (0.04, 0.08)),
        Call("finger_crms", finger_crms, ("a", "b", "c"), (0.03,)),
        Call("RegularPolygonFamily", RegularPolygonFamily, sides=(3, 5), radius=(0.04, 0.08)),
        Call("BoxFamily", BoxFamily, length=(0.2, 0.4), width=(0.06, 0.14)),
        Call("family_task", family_task, "f", family, actions=default_crms(), symmetric=True, description=""),
        Call("three_finger_task", three_finger_task, "f3", family, "three fingers", mu_goal=0.15),
    ]


def _observe3d(x: Any, n: Any) -> Any:
    """The observation of a spatial configuration whose contact ``a`` is ``Contact3D(x, n)``."""
    return observe3d(Config3D(Contact3D(x, n), Contact3D((-0.1, 0.0, 0.05), (1.0, 0.0, 0.0))))


def spatial_examples() -> list[Call]:
    """The spatial model's objects, families, hand, CRMs, quality and task."""
    cup = c.make_task("cup-3d")
    world = cup.sample_world(np.random.default_rng(0))
    solid = box3d((-0.1, -0.05, 0.0), (0.1, 0.05, 0.1))
    points, normals = [(0.1, 0.0, 0.05), (-0.1, 0.0, 0.05)], [(-1.0, 0.0, 0.0), (1.0, 0.0, 0.0)]
    return [
        Call("Hand3D", Hand3D, 0.16, 0.12, backoff=0.01, h=(0.0, 0.0, 1.0), g=(1.0, 0.0, 0.0)),
        Call("CRM3D", CRM3D, "a", "b", (0.0, 0.0)),
        Call("observe3d(Config3D(Contact3D(...)))", _observe3d, (0.1, 0.0, 0.05), (-1.0, 0.0, 0.0)),
        Call("box3d", box3d, (-0.1, -0.05, 0.0), (0.1, 0.05, 0.1)),
        Call("Cylinder", Cylinder, (0.0, 0.0, 0.0), (0.0, 0.0, 1.0), 0.05, 0.1),
        Call("open_cup", open_cup, 0.05, 0.1, wall=0.005, segments=24),
        Call("BoxOnTable", BoxOnTable, length=(0.15, 0.3), width=(0.06, 0.12), height=(0.06, 0.2)),
        Call("CylinderOnTable", CylinderOnTable, radius=(0.03, 0.07), height=(0.06, 0.2), upright=0.5),
        Call("min_friction_3d", min_friction_3d, points, normals),
        Call("force_closure_3d", force_closure_3d, points, normals, 0.1, edges=8),
        Call("ferrari_canny", ferrari_canny, points, normals, 0.5, edges=8),
        Call("execute_crm3d", execute_crm3d, world.task.obj, cup.hand, world.config, CRM3D("a", "b"), table=0.0),
        Call("spatial_crms", spatial_crms, 0.05),
        Call("tripod_crms", tripod_crms, ("a", "b", "c"), 0.03),
        Call("SurfaceStarts", SurfaceStarts, max_tries=100, up=0.5),
        Call("SpatialTask", SpatialTask, name="s", obj=solid, hand=cup.hand, actions=spatial_crms(), mu_goal=0.05),
    ]


def _run_policy(path: Any, start: Any, log: Any) -> Any:
    """One run of the saved policy at ``path`` on a kinematic hand from ``start``, logged to ``log``."""
    policy = GreedyPolicy.load(path)
    hand = KinematicHand(policy.task, start, np.random.default_rng(0))
    return PolicyRunner(policy).run(hand, np.random.default_rng(1), log=log)


def _closed(figure: Callable[..., Any]) -> Callable[..., None]:
    """``figure``'s call, its figure closed (matplotlib warns past 20 open figures)."""

    def call(*args: Any, **kwargs: Any) -> None:
        import matplotlib.pyplot as plt

        plt.close(figure(*args, **kwargs))

    return call


def hardware_examples(box: c.Task, cfg: c.Config) -> list[Call]:
    """A saved policy on a hand, task files, CRM grids and figures."""
    Path("t.toml").write_text(TEMPLATE, encoding="utf-8")
    curves = {"sarsa": (np.full(5, 2.0), np.full(5, 0.1))}
    return [
        Call("PolicyRunner.run", _run_policy, "policy.json", cfg, "run.csv"),
        Call("KinematicHand", KinematicHand, box, cfg, np.random.default_rng(0), noise=None),
        Call("HandSteps", HandSteps, box, hand=None),
        Call("log_columns", log_columns, box),
        Call("offset_grid", offset_grid, box, 8),
        Call("full_ranges", full_ranges, ("a", "b"), 1, 0.16),
        Call("grid_points", grid_points, -0.1, 0.1, 5),
        Call("resolve_task", resolve_task, "paper-box"),
        Call("load_task_file", load_task_file, "t.toml"),
        Call("task_to_dict", task_to_dict, box),
        Call("scene_figure", _closed(scene_figure), box.obj, box.hand, cfg, None, title="t"),
        Call("learning_curve_figure", _closed(learning_curve_figure), curves, 1.66, "t", highlight="sarsa"),
        Call("friction_histogram", _closed(friction_histogram), [0.1, 0.2], 0, "t"),
    ]


def kernel_examples(box: c.Task, cfg: c.Config) -> list[Call]:
    """The seam's entry points: picking a kernel, its per-episode steps and the batch helper."""
    from crmgrasp.kernels import compiled_rules, execute_batch, kernel_for

    kernel = kernel_for(box, "auto")
    state = kernel.begin(cfg, np.random.default_rng(0)).state
    rows = np.array([[-0.15, -0.02, 1.0, 0.0, -0.10, -0.05, 0.0, 1.0]])
    return [
        Call("kernel_for", kernel_for, box, "auto", "exact"),
        Call("compiled_rules", compiled_rules, box),
        Call("execute_batch", execute_batch, box.obj, box.hand, rows, 0, 1, 0.0, sensed=None, backend="auto"),
        Call("Kernel.begin", kernel.begin, cfg, np.random.default_rng(0)),
        Call("Kernel.step_one", kernel.step_one, state, 1, np.random.default_rng(0)),
        Call("Kernel.sample_start", kernel.sample_start, np.random.default_rng(0)),
        Call("Kernel.sample_starts", kernel.sample_starts, np.random.default_rng(0), 4),
        Call("Kernel.successors", kernel.successors, cfg),
        Call("Kernel.execute", kernel.execute, rows, rows, np.array([1])),
        Call("Kernel.execute_crms", kernel.execute_crms, rows, rows, np.array([0]), np.array([1]), np.array([0.0])),
        Call("Kernel.observe", kernel.observe, rows, rows, np.array([0])),
        Call("Kernel.read_rows", kernel.read_rows, rows, np.random.default_rng(0)),
        Call("Kernel.step_row", kernel.step_row, state, kernel.crm_row(box.actions[1]), np.random.default_rng(0)),
    ]


def mujoco_examples(box: c.Task, cfg: c.Config) -> list[Call]:
    """The MuJoCo stand-in's hand, stepper and task (none without the extra ``crmgrasp[mujoco]``)."""
    from crmgrasp.hardware.mujoco import hardware_task, mujoco_available

    if not mujoco_available():
        return []
    from crmgrasp.hardware.mujoco.hand import MujocoHand
    from crmgrasp.hardware.mujoco.model import PhysicsParams
    from crmgrasp.hardware.mujoco.steps import MujocoSteps

    return [
        Call("MujocoHand", MujocoHand, box, cfg, np.random.default_rng(0), params=PhysicsParams()),
        Call("MujocoSteps", MujocoSteps, box, params=None, palm_tolerance_deg=10.0),
        Call("hardware_task", hardware_task, box, palm_tolerance_deg=10.0, mu_goal=None),
    ]


def learner_examples(box: c.Task) -> list[Call]:
    """The learners' helpers: presets, the peers written from their papers, the deep peer's
    settings and features (``check_deep`` only with the extra ``crmgrasp[deep]``)."""
    import dataclasses

    from crmgrasp.agents import deep, deep_trials, peers, presets

    config = deep.RecurrentPPOConfig()
    fields = {f.name: getattr(config, f.name) for f in dataclasses.fields(config)}
    out = [
        Call(
            "apply_preset", presets.apply_preset, "fastest", box, agent=None, k=None, symmetric=False, prior_task=None
        ),
        Call("PSRL", peers.PSRL, 4, alpha0=0.1),
        Call("UCBVI", peers.UCBVI, 4, scale=0.03),
        Call("RecurrentPPOConfig", deep.RecurrentPPOConfig, **fields),
        Call("deep_config", deep_trials.deep_config, "recurrent-ppo", {"gamma": 0.9}),
        Call("features", deep.features, [1.0, 0.02, 0.03], 0, deep.bounds_of(box)),
        Call("bounds_of", deep.bounds_of, box),
        Call("crm_of_action", deep.crm_of_action, box, 1),
    ]
    if deep.deep_available():
        out.append(Call("check_deep", deep_trials.check_deep, "recurrent-ppo", {"gamma": 0.9}))
    return out


CONFIG_MODULES = (
    "compare",
    "continuous_offsets",
    "cost_of_failure",
    "figure4",
    "figure7",
    "figure8",
    "figure9",
    "generalization",
    "mujoco",
    "mujoco_spatial",
    "non_convex",
    "physics_learning",
    "sensitivity",
    "spatial",
    "third_contact",
)
"""The modules of ``crmgrasp.experiments`` whose parameters are a ``...Config`` dataclass."""


def config_examples() -> list[Call]:
    """Every experiment's config, built with each of its fields given as its default."""
    import dataclasses
    import importlib

    out = []
    for name in CONFIG_MODULES:
        module = importlib.import_module(f"crmgrasp.experiments.{name}")
        for cls in vars(module).values():
            if isinstance(cls, type) and cls.__name__.endswith("Config") and cls.__module__ == module.__name__:
                default = cls()
                fields = {f.name: getattr(default, f.name) for f in dataclasses.fields(default)}
                out.append(Call(cls.__name__, cls, **fields))
    return out


class _LateError(Exception):
    """A call still running at the time limit."""


def _alarm(signum: int, frame: Any) -> None:
    raise _LateError


def attempt(call: Callable[[], Any], seconds: int) -> str | None:
    """``task_file_fuzz.attempt``'s rule, with a time limit (SIGALRM)."""
    signal.signal(signal.SIGALRM, _alarm)
    signal.alarm(seconds)
    try:
        return task_file_fuzz.attempt(call)
    except _LateError:
        return f"still running after {seconds} s"
    finally:
        signal.alarm(0)


def _fuzz(seconds: int) -> tuple[int, list[dict[str, str]]]:
    """Every call of [`examples`][] with each argument hostile in turn: the count and the failures."""
    count, failures = 0, []
    for call in examples():
        problem = attempt(call.working(), seconds)
        if problem is not None:  # the working call itself: the script is wrong
            raise SystemExit(f"{call.name} fails as written: {problem}")
        for argument, value, variant in call.variants():
            count += 1
            problem = attempt(variant, seconds)
            if problem is not None:
                failures.append(
                    {"call": call.name, "argument": argument, "value": repr(value)[:40], "problem": problem}
                )
    return count, failures


def main(argv: list[str] | None = None) -> dict[str, Any]:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=int, default=5)
    args = ap.parse_args(argv)
    t0, count, failures = time.perf_counter(), 0, []
    here = os.getcwd()
    with tempfile.TemporaryDirectory() as scratch:  # the calls that write files write there
        os.chdir(scratch)
        try:
            count, failures = _fuzz(args.seconds)
        finally:
            os.chdir(here)
    out = {
        "calls": count,
        "failed": len(failures),
        "seconds": round(time.perf_counter() - t0, 1),
        "failed_by_call": {
            name: sum(f["call"] == name for f in failures) for name in dict.fromkeys(f["call"] for f in failures)
        },
        "failures": failures[:80],
    }
    print(json.dumps(out, indent=1))
    return out


if __name__ == "__main__":
    sys.exit(1 if main()["failed"] else 0)

"""The kernel interface: one task's dynamics over many configurations at once.

A kernel evaluates the model's rules (CRM transition, observation, bins, min
friction, start acceptance) on rows of the task's contact model
(`crmgrasp.tasks.Task.model`: ``(N, 8)`` rows ``[ax, ay, anx, any, bx, by, bnx,
bny]`` in the plane, ``(N, 12)`` in space); the row width, the CRMs' parameters and the
observation's names and bounds all come from the model. The composite steps
([`Kernel.begin`][], [`Kernel.step_one`][], [`Kernel.step_batch`][]) are
written here once from those rules and [`crmgrasp.sim`][]; a compiled kernel may
override a composite with a fused version that the tests hold equal to this one
bit for bit.
"""

from __future__ import annotations

import functools
import math
from abc import ABC, abstractmethod
from typing import Any, ClassVar, NamedTuple

import numpy as np
from numpy.typing import NDArray

from crmgrasp._validation import CrmgraspError, float_array, shown
from crmgrasp.model.hand import CRM, Error
from crmgrasp.model.sensing import Discretizer
from crmgrasp.sim import OneStep, SimState, begin, checked_state, episode_end, step, step_reward
from crmgrasp.tasks import StartFilter, Task

__all__ = [
    "Kernel",
    "FusedSingleStep",
    "OneStep",
    "BatchStep",
    "Successor",
    "UNSET",
    "bin_thresholds",
    "stepwise_successors",
]

_ERRORS = tuple(Error)


def _per_row(value: Any, name: str, n: int, low: int, high: int) -> None:
    """A one-line error unless ``value`` is one integer in ``[low, high]`` or ``n`` of them."""
    a = float_array(value, name)
    if a.ndim > 1 or (a.ndim == 1 and len(a) not in (1, n)):
        raise CrmgraspError(f"{name} must be one integer or {n}, got shape {a.shape}")
    if not np.all((a >= low) & (a <= high) & (a == np.floor(a))):
        raise CrmgraspError(f"{name} must be integers in [{low}, {high}]")


_new = tuple.__new__  # builds the step's NamedTuples without their Python-level __new__ (the hot path)

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]


class BatchStep(NamedTuple):
    """A batch of environments after one step: true and sensed rows, the observation
    (each of the model's observation names as ``(N, 1)`` clipped into the observation
    space, ``error`` as ``(N,)``), bin indices and min friction of the true rows."""

    config: F64
    sensed: F64
    obs: dict[str, np.ndarray]
    obs_index: I64
    min_friction: F64


class Successor(NamedTuple):
    """Where one CRM leads from a configuration, noise-free ([`Kernel.successors`][]): the
    next configuration (the same one after an error), the bin index of its observation
    with the error, the error, and its least friction (from a kernel made with
    ``friction="decided"``, a friction that decides the grasp as it does)."""

    config: Any
    obs_index: int
    error: Error
    min_friction: float


def stepwise_successors(step: Any, config: Any, table: F64) -> list[Successor]:
    """[`Kernel.successors`][] from a kernel's fused single step ``step(state, action,
    table)`` (a `FusedSingleStep`'s ``_step``), one call per row of ``table``: for kernels
    whose batched rows run the readable rules."""
    state = _new(SimState, (config, config, 0))
    out = []
    for a in range(len(table)):
        s = step(state, a, table)
        out.append(_new(Successor, (s.state.config, s.obs_index, s.error, s.min_friction)))
    return out


def bin_thresholds(d: Discretizer) -> F64:
    """The thresholds of ``d`` as one array for compiled code: a row per quantity, in
    ``d.names``' order, padded with ``+inf`` (a value is never ``>= inf``, so the padding
    changes no bin)."""
    th = np.full((len(d.thresholds), max(1, *map(len, d.thresholds))), np.inf)
    for row, t in zip(th, d.thresholds, strict=True):
        row[: len(t)] = t
    return th


@functools.lru_cache(maxsize=64)
def _action_table(key: tuple[Any, ...], actions: Any, labels: tuple[str, ...]) -> F64:
    """The table of ``actions``, cached: per CRM the index of the moving contact, of the
    frame contact (in ``labels``' order) and the offset's coordinates; ``key`` (labels and
    the offsets' reprs) tells -0.0 from 0.0, which equality of the CRMs alone does not."""
    index = labels.index
    table = np.array([(index(a.c), index(a.f), *np.atleast_1d(a.r)) for a in actions], dtype=np.float64)
    table.flags.writeable = False
    return table


UNSET: Any = object()
"""What no configuration is: the mark of a kernel's buffer or check that holds none yet (``None``
may be given as a configuration, and must then be checked and refused)."""


class Kernel(ABC):
    """A task's rules over rows. Subclasses implement [`execute_crms`][] and
    [`observe`][], and may set `start_filter` (a compiled
    [`crmgrasp.tasks.StartFilter`][] that the task's sampler uses where it can); build
    one with [`crmgrasp.kernels.kernel_for`][]."""

    name: ClassVar[str] = "abstract"
    _checked: Any = UNSET  # the configuration [`trust`][] checked last

    def __init__(self, task: Task) -> None:
        self.task = task
        self.model = task.model
        self.acts = self.action_table(task)
        self.bounds = self.model.observation_bounds()  # the observation space: name -> (low, high)
        self.start_filter: StartFilter | None = None  # a compiled one, where the kernel has it

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.task.name!r})"

    def trust(self, config: Any) -> Any:
        """``config`` once it is a configuration of the task's model (its type, one contact per
        finger, finite numbers, unit normals: ``ContactModel.check_reading``), before compiled
        code reads it: that code indexes its arrays by what it reads, unchecked. The last
        configuration checked, or one the kernel produced itself (``trusted``), is not checked
        again, so that an episode checks its start once."""
        if config is not self._checked:
            self.model.check_reading(config, "configuration")
            self._checked = config
        return config

    def check_batch(self, cfg: Any, sen: Any, err: Any = UNSET, crms: tuple[Any, Any, Any] | None = None) -> int:
        """The number ``N`` of rows, once ``cfg`` and ``sen`` are arrays of the model's layout,
        ``(N, row_width)``; ``err`` (if given) error codes and ``crms`` (if given) the contact
        indices and finite offsets ``(c, f, r)``, each one value or one per row. Compiled code
        reads them by those sizes and values, unchecked (a one-line error otherwise)."""
        width = self.model.row_width
        for a, name in ((cfg, "rows"), (sen, "sensed rows")):
            if not isinstance(a, np.ndarray) or a.ndim != 2 or a.shape[1] != width:
                got = a.shape if isinstance(a, np.ndarray) else shown(a)
                raise CrmgraspError(f"{name} must be an array of shape (N, {width}), got {got}")
        n = len(cfg)
        if sen.shape != cfg.shape:
            raise CrmgraspError(f"sensed rows must have the rows' shape {cfg.shape}, got {sen.shape}")
        if err is not UNSET:
            _per_row(err, "error codes", n, 0, len(Error) - 1)
        if crms is not None:
            self._check_crms(n, *crms)
        return n

    def _check_crms(self, n: int, c: Any, f: Any, r: Any) -> None:
        """A one-line error unless ``c`` and ``f`` are contact indices and ``r`` finite offsets,
        one or ``n`` of each."""
        last = self.model.n_contacts - 1
        _per_row(c, "contact indices c", n, 0, last)
        _per_row(f, "contact indices f", n, 0, last)
        r, d = float_array(r, "offsets"), self.model.offset_dim
        try:
            np.broadcast_to(r, (n,) if d == 1 else (n, d))
        except ValueError:
            raise CrmgraspError(f"offsets must be one or {n} of {d} number(s), got shape {r.shape}") from None
        if not np.all(np.isfinite(r)):
            raise CrmgraspError("offsets must be finite")

    def check_row(self, state: Any, row: Any) -> None:
        """A one-line error unless ``state`` is a `SimState` and ``row`` one action-table row,
        an array of shape ``(1, 2 + offset_dim)``: the compiled single step reads that many
        numbers, the contact indices among them, unchecked."""
        checked_state(state)
        width = 2 + self.model.offset_dim
        if not isinstance(row, np.ndarray) or row.shape != (1, width) or row.dtype != np.float64:
            got = (row.shape, str(row.dtype)) if isinstance(row, np.ndarray) else shown(row)
            raise CrmgraspError(f"an action-table row must be a float64 array of shape (1, {width}), got {got}")
        c, f, *r = row[0].tolist()  # plain floats: a few tests in Python beat numpy's on one row
        last = self.model.n_contacts - 1
        if not (0 <= c <= last and 0 <= f <= last and c == int(c) and f == int(f) and all(map(math.isfinite, r))):
            raise CrmgraspError(f"an action-table row holds contact indices in [0, {last}] and finite offsets")

    def trusted(self, config: Any) -> Any:
        """``config``, produced by this kernel: the next [`trust`][] of it passes at once."""
        self._checked = config
        return config

    def rebind(self, instance: Task) -> Kernel:
        """This kernel's path for ``instance``, the task on another object of the same kind
        (one episode of a family): a new kernel of the same class. A compiled kernel may
        instead move itself onto the new object, in place, keeping what does not depend on
        the object (a family's kernel steps one object at a time: nothing else holds the
        kernel of the object before)."""
        return type(self)(instance)

    @staticmethod
    def action_table(task: Task) -> F64:
        """One row per action: ``(c, f, r)``, the moving and the frame contact's indices and
        the offset (``r_1, r_2`` for a spatial CRM; for two contacts the indices read as "is
        b", which the compiled kernels take); one array per CRM set, not to be written to.

        numba compiles a function once per argument types, and a read-only array is another
        type than a writable one; so every table or row a compiled step takes is read-only
        (this one, [`crm_row`][]'s, the continuous environments' rows and batches): one
        machine code serves the task's CRMs and the continuous action space."""
        key = tuple((a.c, a.f, repr(a.r)) for a in task.actions)
        return _action_table(key, task.actions, task.model.labels)

    @property
    def instance(self) -> Task:
        """The task on the current episode's object: the task itself (a family's kernel
        says which object it steps now)."""
        return self.task

    def use(self, instance: Task) -> None:
        """Step ``instance``, a task on one object drawn from this task's family: only a
        family task's kernel can (a one-line error here)."""
        raise CrmgraspError(f"task {self.task.name!r} has one object: a World start needs a family task")

    def config_of(self, row: Any) -> Any:
        """The configuration of one row (the model's ``config_of``)."""
        return self.model.config_of(row)

    def read_rows(self, rows: F64, rng: np.random.Generator) -> F64:
        """One sensed reading per row (the model's ``read_rows``)."""
        self.check_batch(rows, rows)
        return self.model.read_rows(rows, rng)

    # ------------------------------------------------------------ the rules
    @abstractmethod
    def execute_crms(self, cfg: F64, sen: F64, c: I64, f: I64, r: F64) -> tuple[F64, NDArray[np.int8]]:
        """The CRM ``(c, f, r)`` of each row (``c``, ``f``: contact indices in the model's
        label order; ``r``: offsets) from true rows ``cfg`` and sensed rows ``sen`` (the
        model's ``execute``): new rows and error codes."""

    @abstractmethod
    def observe(self, cfg: F64, sen: F64, err: np.ndarray) -> tuple[np.ndarray, ...]:
        """Each of the model's observation quantities (one ``(N,)`` array per name, in
        order), then the bin index of each sensed row (with the rows' error codes) and the
        min friction of each true row."""

    # ------------------------------------------------------------ composites
    def execute(self, cfg: F64, sen: F64, actions: I64) -> tuple[F64, NDArray[np.int8]]:
        """[`execute_crms`][] of the task's actions ``actions`` (indices)."""
        n = self.check_batch(cfg, sen)
        return self.execute_table(cfg, sen, self.acts[self.task.action_indices(actions, n)])

    def execute_table(self, cfg: F64, sen: F64, table: F64) -> tuple[F64, NDArray[np.int8]]:
        """[`execute_crms`][] of one CRM per row given as a row of an action table
        ([`action_table`][]: ``c``, ``f``, offsets; ``(N,)`` offsets for a scalar offset,
        ``(N, offset_dim)`` otherwise)."""
        r = np.ascontiguousarray(table[:, 2]) if self.model.offset_dim == 1 else table[:, 2:]
        return self.execute_crms(cfg, sen, table[:, 0].astype(np.int64), table[:, 1].astype(np.int64), r)

    def crm_row(self, crm: Any) -> F64:
        """The action-table row ``[[c, f, r...]]`` (shape ``(1, 2 + offset_dim)``) of a CRM of the
        task's model, checked against the hand (one-line errors)."""
        crm = self.task.crm(crm)
        index = self.model.labels.index
        row = np.array([[index(crm.c), index(crm.f), *np.atleast_1d(crm.r)]], dtype=np.float64)
        row.flags.writeable = False  # read-only as the task's table: the same compiled step (`action_table`)
        return row

    def successors(self, config: Any) -> list[Successor]:
        """Every action of the task from ``config``, in order, noise-free (the reading is the
        configuration): one [`Successor`][] each, from one batched call of the rules
        ([`execute`][], [`observe`][]); the reference values' search step."""
        self.trust(config)
        n = len(self.acts)
        rows = np.array([self.model.row_of(config)] * n, dtype=np.float64)
        new, err = self.execute(rows, rows, np.arange(n))
        *_, index, mu = self.observe(new, new, err)
        of = self.config_of
        return [
            _new(Successor, (of(row) if not code else config, i, _ERRORS[code], m))
            for row, i, code, m in zip(new.tolist(), index.tolist(), err.tolist(), mu.tolist(), strict=True)
        ]

    def sample_start(self, rng: np.random.Generator) -> Any:
        """One start (`crmgrasp.tasks.Task.sample_start`, with `start_filter`):
        the task's scalar stream; [`trusted`][]: the sampler places contacts on the object)."""
        return self.trusted(self.task.sample_start(rng, self.start_filter))

    def sample_starts(self, rng: np.random.Generator, n: int) -> F64:
        """``n`` starts as rows (`crmgrasp.tasks.Task.sample_starts`, with
        `start_filter`)."""
        return self.task.sample_starts(rng, n, self.start_filter)

    def begin(self, config: Any, rng: np.random.Generator) -> OneStep:
        """An episode starting at ``config`` ([`crmgrasp.sim.begin`][])."""
        return begin(self.task, config, rng)

    def step_one(self, state: SimState, action: int | CRM, rng: np.random.Generator) -> OneStep:
        """The CRM ``task.actions[action]`` (or the CRM ``action``) from ``state``
        ([`crmgrasp.sim.step`][])."""
        return step(self.task, state, action, rng)

    def step_row(self, state: SimState, row: F64, rng: np.random.Generator, checked: bool = False) -> OneStep:
        """The CRM of the action-table row ``row`` (shape ``(1, 2 + offset_dim)``: contact
        indices and offsets) from ``state``: the continuous action's step,
        [`crmgrasp.sim.step`][] of that CRM. The row is checked ([`check_row`][]) unless
        ``checked``: a caller that has checked it (the continuous environments, which check the
        pair and the offset against the pair's range) skips the second check."""
        if not checked:
            self.check_row(state, row)
        r = row[0, 2] if self.model.offset_dim == 1 else row[0, 2:]
        return step(self.task, state, self.model.crm(int(row[0, 0]), int(row[0, 1]), r), rng)

    def step_batch(
        self, cfg: F64, sen: F64, actions: I64, resets: NDArray[np.bool_], starts: F64, rng: np.random.Generator
    ) -> BatchStep:
        """One step of a batch of environments: the CRM ``actions[j]`` in each row, or
        the next of ``starts`` (in order) in the rows where ``resets`` is set; then one
        reading per row, its observation, bins and min friction."""
        return self.step_table(cfg, sen, self.acts[actions], resets, starts, rng)

    def step_table(
        self, cfg: F64, sen: F64, table: F64, resets: NDArray[np.bool_], starts: F64, rng: np.random.Generator
    ) -> BatchStep:
        """[`step_batch`][] with one CRM per row given as an action-table row (``table``:
        ``(N, 2 + offset_dim)``, within reach: the caller checks): the continuous actions'
        batched step."""
        new, err = self.execute_table(cfg, sen, table)
        rows = resets.nonzero()[0]
        if len(rows):
            new[rows] = starts
            err[rows] = 0
        sensed = self.read_rows(new, rng)
        *values, index, mu = self.observe(new, sensed, err)
        return BatchStep(new, sensed, self.clip(values, err), index, mu)

    def clip(self, values: Any, err: np.ndarray) -> dict[str, np.ndarray]:
        """The observation dict: each of the model's observations (``values``, in the
        model's order) clipped into its bounds as ``(N, 1)``, and the error codes."""
        out: dict[str, np.ndarray] = {}
        with np.errstate(invalid="ignore"):
            for name, v in zip(self.model.observation_names, values, strict=True):
                low, high = self.bounds[name]
                out[name] = np.minimum(np.maximum(v, low), high)[:, None]
        out["error"] = np.asarray(err, dtype=np.int64)
        return out


class FusedSingleStep(Kernel):
    """The single step of a kernel that runs a noise-free CRM, its observation, bin and
    least friction as one compiled call, keeping the configuration in a buffer from one
    step to the next. A subclass (listed before its kernel class) sets the buffers ``_v``
    and ``_out`` (a configuration's row, any shape) and ``_vals`` (the observation as a
    column) and implements `_begin_call` and `_step_call`; after an errored CRM
    (the row unchanged) the call may return the observation and least friction it already
    holds (``_known``, ``_mu``)."""

    _v: F64
    _out: F64
    _vals: F64

    def _forget(self) -> None:
        """No configuration in the buffer (at construction and on a new object)."""
        self._v_of: Any = UNSET
        # whether _vals and _mu hold the observation and least friction of _v's row
        self._known, self._mu = False, 0.0

    def _load(self, config: Any) -> None:
        if config is not self._v_of:
            self._v.reshape(-1)[:] = self.model.row_of(self.trust(config))
            self._v_of, self._known = config, False

    @abstractmethod
    def _begin_call(self) -> tuple[int, float]:
        """``(bin index, least friction)`` of ``_v``'s row, its observation into ``_vals``."""

    @abstractmethod
    def _step_call(self, action: int, table: F64) -> tuple[int, int, float]:
        """``(error code, bin index, least friction)`` of the CRM ``table[action]`` from
        ``_v``'s row: the new row into ``_out``, its observation into ``_vals``."""

    def begin(self, config: Any, rng: np.random.Generator) -> OneStep:
        self._load(config)
        index, mu = self._begin_call()
        self._known, self._mu = True, mu
        return OneStep(SimState(config, config, 0), tuple(self._vals[:, 0].tolist()), Error.NONE, index, mu)

    def step_one(self, state: SimState, action: Any, rng: np.random.Generator) -> OneStep:
        checked_state(state)
        if self.model.is_crm(action):  # a CRM of the hand's continuous action space
            return self._step(state, 0, self.crm_row(action))
        if type(action) is not int or not 0 <= action < len(self.acts):  # compiled code does not check indices
            action = self.task.action_index(action)
        return self._step(state, action, self.acts)

    def step_row(self, state: SimState, row: F64, rng: np.random.Generator, checked: bool = False) -> OneStep:
        if not checked:
            self.check_row(state, row)
        return self._step(state, 0, row)

    def _step(self, state: SimState, action: int, table: F64) -> OneStep:
        """The CRM ``table[action]`` from ``state``, one compiled call."""
        config = state.config
        self._load(config)
        code, index, mu = self._step_call(action, table)
        self._known, self._mu = True, mu
        if not code:
            config = self.model.config_of(self._out.reshape(-1).tolist())
            self._v, self._out = self._out, self._v  # the output is the next step's input
            self._v_of = config
        steps = state.steps + 1
        terminated, truncated = episode_end(self.task, mu, steps)
        reward = step_reward(self.task, terminated, code)
        obs = tuple(self._vals[:, 0].tolist())
        return _new(
            OneStep,
            (_new(SimState, (config, config, steps)), obs, _ERRORS[code], index, mu, reward, terminated, truncated),
        )

"""Named grasping tasks: object, hand, CRM set, observation bins, starts, goal.

A [`Task`][] bundles everything an environment or experiment needs. Tasks are
looked up by name with [`make_task`][] (``"paper-box"`` is [docs/model.md section 7][model-7]);
users build their own by constructing [`Task`][] directly and may register a
factory under a new name with [`register_task`][].
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, NamedTuple, overload

import numpy as np
from numpy.typing import NDArray

from crmgrasp._validation import (
    CrmgraspError,
    finite,
    generator,
    integer,
    is_finite_number,
    listed,
    non_negative,
    shown,
)
from crmgrasp.model.actions import CRMRange
from crmgrasp.model.contact_model import ContactModel
from crmgrasp.model.contacts import Config, Grip
from crmgrasp.model.families import ShapeFamily, check_family
from crmgrasp.model.geometry import Rectangle, Shape
from crmgrasp.model.hand import CRM, Error, Hand
from crmgrasp.model.planar_model import PlanarModel
from crmgrasp.model.sensing import Discretizer, SensorNoise
from crmgrasp.model.shape import check_shape
from crmgrasp.tasks.starts import CornerStarts, StartFilter, StartSampler, accept_corner_candidates
from crmgrasp.tasks.symmetry import Symmetry, check_symmetry, symmetry_of

__all__ = [
    "Task",
    "World",
    "Symmetry",
    "symmetry_of",
    "paper_box",
    "make_task",
    "register_task",
    "task_names",
    "checked_name",
]


NUMBER_WORDS = {2: "two", 3: "three", 4: "four"}


def _takes(sampler: Any, accept: Any) -> bool:
    """Whether ``sampler`` decides its starts through the filter ``accept`` (a uniform filter
    says ``kind = "uniform"``; a corner filter says nothing)."""
    if getattr(accept, "kind", None) == "uniform":
        return bool(getattr(sampler, "takes_uniform_filter", False))
    return bool(getattr(sampler, "takes_corner_filter", False))


MAX_SAMPLED = 10_000_000
"""The most starts [`Task.sample_starts`][] draws in one call."""

MAX_STEPS = 1000
"""The longest episode a task may ask for, in CRMs (the task files' bound too)."""


@dataclass(frozen=True)
class Task:
    """A grasping task.

    Parameters
    ----------
    name
        Registry name, e.g. ``"paper-box"``.
    obj
        The object ([`Polygon`][crmgrasp.model.geometry.Polygon], [`Disc`][crmgrasp.model.geometry.Disc], ...).
    hand
        The two-contact hand.
    actions
        The CRM set; action ``i`` of an agent is ``actions[i]``.
    discretizer
        Observation bins (with the error flag).
    starts
        Start sampler.
    mu_goal
        Success when ``min_friction(true config) <= mu_goal`` (unitless, >= 0).
    max_steps
        Episode truncation, in CRMs (1 to [`MAX_STEPS`][]).
    noise
        Sensing noise applied during the task (off by default).
    reference_mean_steps
        Best achievable mean CRMs per episode for a learner on this task (the
        belief-space optimum where known), used to report ``episodes_to_5pct``.
    symmetry
        A declared mirror symmetry ([`Symmetry`][crmgrasp.tasks.symmetry.Symmetry]), or None.
    grasp_reward
        Reward of the CRM that reaches a grasp (every other CRM: -1). The paper's "-1
        in all states" read literally gives -1 (the default); read as "in all non-goal
        states" it gives 0.
    error_cost
        Extra cost (>= 0, reward units) of a CRM that ends in an error: its reward is
        ``-1 - error_cost`` (0 in the paper). Makes failed attempts expensive, the
        Discussion's "infrequent failures [that] come with a high cost".
    family
        An object family ([`crmgrasp.model.families`][]), or None. With a family, each
        episode draws its object (`instance`) and ``obj`` is only the shape
        scenes show (the family's nominal one); the smallest object the family can
        draw must fit the hand's aperture.
    ranges
        The continuous action space ([`CRMRange`][crmgrasp.model.actions.CRMRange] per contact
        pair, each offset within the hand's reach); empty (the default): every ordered pair
        of the hand's contacts over ``[-r_max, r_max]`` ([`crm_ranges`][]).
    """

    name: str
    obj: Shape
    hand: Hand
    actions: tuple[CRM, ...]
    discretizer: Discretizer = field(default_factory=Discretizer)
    starts: StartSampler = field(default_factory=CornerStarts)
    mu_goal: float = 0.05
    max_steps: int = 10
    noise: SensorNoise = field(default_factory=SensorNoise)
    reference_mean_steps: float | None = None
    description: str = ""
    symmetry: Symmetry | None = None
    grasp_reward: float = -1.0
    family: ShapeFamily | None = None
    error_cost: float = 0.0
    ranges: tuple[CRMRange, ...] = ()
    model: ContactModel = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        check_shape(self.obj, "task object")
        if not isinstance(self.hand, Hand):
            raise CrmgraspError(f"task hand must be a Hand, got {self.hand!r}")
        self._set_model(PlanarModel(self.hand, self.noise))
        self._check_starts()
        self._check_common()
        if self.family is not None:
            check_family(self.family)
            self._check_family_width()

    def _check_family_width(self) -> None:
        w = self.family.min_width()  # type: ignore[union-attr]
        if w > self.hand.aperture:
            raise CrmgraspError(
                f"family {self.family.describe()['kind']!r}: its smallest object is {w:.4g} m wide, "  # type: ignore[union-attr]
                f"beyond the hand's aperture {self.hand.aperture:g} m; no object it draws can be grasped"
            )

    def _set_model(self, model: ContactModel) -> None:
        """Hold ``model``, the contact model every rule of this task goes through; bins left
        at their default become the default thresholds over the model's observation."""
        object.__setattr__(self, "model", model)
        if self.discretizer == Discretizer() and model.observation_names != self.discretizer.names:
            object.__setattr__(self, "discretizer", Discretizer(names=model.observation_names))

    def _check_starts(self) -> None:
        """Refuse a start sampler that places two contacts on a hand with more."""
        if self.hand.contacts != 2 and not getattr(self.starts, "any_contacts", False):
            kind = getattr(self.starts, "kind", type(self.starts).__name__)
            raise CrmgraspError(
                f"{kind!r} starts place two contacts, but the hand has {self.hand.contacts}; use 'uniform' starts"
            )

    def _check_common(self) -> None:
        """The checks every task takes, planar or spatial: actions (through the hand's
        ``check_crm``), goal, length, symmetry, rewards, reference."""
        checked_name(self.name, 2 * NAME_LENGTH)
        actions = listed(self.actions, "task actions", "a sequence of CRMs")
        if not actions:
            raise CrmgraspError("a task needs at least one CRM action")
        for a in actions:
            self.hand.check_crm(a)
        object.__setattr__(self, "actions", actions)
        if not isinstance(self.ranges, (tuple, list)):
            raise CrmgraspError(f"task ranges must be a sequence of CRMRange, got {self.ranges!r}")
        object.__setattr__(self, "ranges", tuple(self.model.check_range(r) for r in self.ranges))
        object.__setattr__(self, "mu_goal", non_negative(self.mu_goal, "mu_goal"))
        if not isinstance(self.discretizer, Discretizer):
            raise CrmgraspError(f"task discretizer must be a Discretizer, got {self.discretizer!r}")
        if self.discretizer.names != self.model.observation_names:
            raise CrmgraspError(
                f"the bins are over {', '.join(self.discretizer.names)}, but the {self.model.kind} model observes "
                f"{', '.join(self.model.observation_names)}"
            )
        if (
            isinstance(self.max_steps, bool)
            or not isinstance(self.max_steps, int)
            or not 1 <= self.max_steps <= MAX_STEPS
        ):
            raise CrmgraspError(f"max_steps must be an integer in [1, {MAX_STEPS}], got {self.max_steps!r}")
        if self.symmetry is not None:
            if not isinstance(self.symmetry, Symmetry):
                raise CrmgraspError(f"task symmetry must be a Symmetry, got {self.symmetry!r}")
            try:
                check_symmetry(self.symmetry, actions, self.discretizer, self.model)
            except CrmgraspError as exc:
                raise CrmgraspError(
                    f"{exc} (a task made from a symmetric one with other CRMs or bins needs symmetry=None)"
                ) from None
        object.__setattr__(self, "grasp_reward", finite(self.grasp_reward, "grasp_reward"))
        object.__setattr__(self, "error_cost", non_negative(self.error_cost, "error_cost"))
        if self.reference_mean_steps is not None and not (
            is_finite_number(self.reference_mean_steps) and self.reference_mean_steps > 0
        ):
            raise CrmgraspError(f"reference_mean_steps must be > 0, got {self.reference_mean_steps!r}")

    # -- the model's rules in this task's world: each written once in crmgrasp.model and
    # applied through the task's contact model (Task.model), planar or spatial alike
    def mirror_crm(self, crm: Any) -> Any:
        """The CRM a declared mirror symmetry maps ``crm`` to (the model's ``mirror_crm``)."""
        return self.model.mirror_crm(crm)

    @property
    def crm_ranges(self) -> tuple[CRMRange, ...]:
        """The continuous action space: ``ranges``, or by default the model's whole space
        (every ordered contact pair, offsets within the hand's reach)."""
        return self.ranges or self.model.full_ranges()

    def crm(self, action: Any) -> Any:
        """The CRM of action index ``action``, or ``action`` itself checked against the hand."""
        return self.model.check_crm(action) if self.model.is_crm(action) else self.actions[self.action_index(action)]

    def action_index(self, action: Any) -> int:
        """``action`` as an index of ``actions``: an integer (a Python or NumPy one, or a 0-d
        integer array; not a bool) in ``[0, len(actions))``; else a one-line error. Every step
        that takes an index (the readable step, the kernels, the environments) takes it through
        here.

        >>> paper_box().action_index(np.int64(3))
        3
        """
        n = len(self.actions)
        if type(action) is int and 0 <= action < n:
            return action
        value = action.item() if isinstance(action, np.ndarray) and action.ndim == 0 else action
        if isinstance(value, (int, np.integer)) and not isinstance(value, (bool, np.bool_)) and 0 <= value < n:
            return int(value)
        raise CrmgraspError(f"action must be an integer in [0, {n}), got {shown(action)}")

    def action_indices(self, actions: Any, rows: int) -> NDArray[np.int64]:
        """``actions`` as ``rows`` indices of ``actions`` at once (a batch's
        [`action_index`][]): an integer array of shape ``(rows,)`` with every entry in
        ``[0, len(actions))``, as int64; else a one-line error. The batched steps (the vector
        environments, [`crmgrasp.kernels.rows.KernelRows`][]) take their indices through here."""
        a, n = np.asarray(actions), len(self.actions)
        if a.shape != (rows,) or a.dtype.kind not in "iu":
            raise CrmgraspError(f"actions must be {rows} integers, got shape {a.shape} dtype {a.dtype}")
        if rows and (a.min() < 0 or a.max() >= n):
            raise CrmgraspError(f"actions must be in [0, {n})")
        return a.astype(np.int64, copy=False)

    def execute(self, config: Any, crm: Any, sensed: Any) -> Any:
        """The CRM transition (the model's ``execute``), goal line from ``sensed``."""
        return self.model.execute(self.obj, config, crm, sensed)

    def read(self, config: Any, rng: np.random.Generator) -> Any:
        """One sensed reading of ``config`` (the model's ``read``)."""
        return self.model.read(config, rng)

    def observe(self, sensed: Any) -> tuple[float, ...]:
        """The observation of a reading (the model's ``observe``)."""
        return self.model.observe(sensed)

    def quality(self, config: Any) -> float:
        """The min friction of a configuration (the model's ``quality``)."""
        return self.model.quality(config)

    def feasible(self, config: Any) -> Error:
        """``Error.NONE`` if ``config`` is feasible on the object (the model's ``feasible``)."""
        return self.model.feasible(self.obj, config)

    def check_config(self, config: object, name: str = "configuration") -> Any:
        """``config`` if it is a valid configuration on the object, else a one-line error."""
        return self.model.check_config(self.obj, config, name)

    def place(self, *points: Any) -> Any:
        """The configuration a user's points name on the object, one per contact (the
        model's ``place``: the nearest boundary points in the plane, the surface points
        toward them from the centre in space)."""
        return self.model.place(self.obj, points)

    def instance(self, rng: np.random.Generator) -> Task:
        """This task with an object drawn from its family (one episode's world; the
        family's draws from ``rng``); the task itself if it has no family."""
        return self if self.family is None else self.with_object(self.family.sample(rng))

    def with_model(self, model: ContactModel) -> Task:
        """This task with its rules applied through ``model``: the same model with a rule
        a kernel computes in compiled code, equal bit for bit (nothing is checked again)."""
        return self._copied(model=model)

    def with_object(self, obj: Shape) -> Task:
        """This task on the object ``obj``, without a family (the object is not checked
        again: families draw valid shapes)."""
        return self._copied(obj=obj, family=None)

    def _copied(self, **fields: Any) -> Task:
        """A copy with ``fields`` replaced, unchecked: copy.copy's result, without its
        generic machinery (a family builds one per episode)."""
        out = object.__new__(type(self))
        out.__dict__.update(self.__dict__, **fields)
        return out

    def _one_object(self) -> None:
        """Refuse, with the reason, to draw starts without an object on a family task."""
        if self.family is not None:
            raise CrmgraspError(
                f"task {self.name!r} draws an object per episode: use sample_world (the object and a start on it)"
            )

    def sample_world(self, rng: np.random.Generator, accept: StartFilter | None = None) -> World:
        """An episode's hidden world: `instance`, then a start on it."""
        inst = self.instance(generator(rng))
        return World(inst, inst.sample_start(rng, accept))

    def sample_start(self, rng: np.random.Generator, accept: Any = None) -> Config | Grip:
        """A start configuration drawn from ``rng``. ``accept``: a compiled start filter, used
        by the samplers that take its kind (the same start either way), ignored by others: a
        corner [`StartFilter`][crmgrasp.tasks.starts.StartFilter] by samplers built on corner
        candidates ([`CornerStarts`][] and the presets of `crmgrasp.tasks.presets`), a
        [`UniformFilter`][crmgrasp.tasks.starts.UniformFilter] by [`UniformStarts`][]."""
        self._one_object()
        generator(rng)
        if accept is not None and _takes(self.starts, accept):
            return self.starts(self.obj, self.hand, self.mu_goal, rng, accept)  # type: ignore[call-arg]
        return self.starts(self.obj, self.hand, self.mu_goal, rng)

    def sample_starts(self, rng: np.random.Generator, n: int, accept: StartFilter | None = None) -> np.ndarray:
        """``n`` starts as rows of the model's layout: [`CornerStarts.batch`][] (another stream than
        `sample_start`'s, the same distribution; ``accept`` as there), or ``n``
        scalar draws for other samplers (``n``: 0 to [`MAX_SAMPLED`][])."""
        self._one_object()
        rng, n = generator(rng), integer(n, "number of starts", 0, MAX_SAMPLED)
        if isinstance(self.starts, CornerStarts):
            return self.starts.batch(self.obj, self.hand, self.mu_goal, rng, n, accept or accept_corner_candidates)
        return self.model.rows_of([self.sample_start(rng, accept) for _ in range(n)])

    @overload
    def grasped(self, mu: float) -> bool: ...

    @overload
    def grasped(self, mu: NDArray[np.float64]) -> NDArray[np.bool_]: ...

    def grasped(self, mu: float | NDArray[np.float64]) -> bool | NDArray[np.bool_]:
        """The success rule ([docs/model.md section 5][model-5]) from a configuration's min friction:
        ``mu <= mu_goal`` (elementwise on an array)."""
        return mu <= self.mu_goal

    def headline(self) -> str:
        """The task's line in a listing: its description and its hand's number of fingers."""
        n = self.model.n_contacts
        return f"{self.description}; {NUMBER_WORDS.get(n, str(n))} fingers"

    def is_success(self, config: Any) -> bool:
        """[docs/model.md section 5][model-5]: `grasped` of [`quality`][]."""
        return self.grasped(self.quality(config))

    def action_names(self) -> tuple[str, ...]:
        """``('C1 (a,b,0)', ...)``: readable action names in index order."""
        return tuple(f"C{i + 1} {crm}" for i, crm in enumerate(self.actions))


class World(NamedTuple):
    """One episode's hidden world: the task on the object drawn for it, and the start."""

    task: Task
    config: Config | Grip


PAPER_HAND = Hand(aperture=0.16, palm_depth=0.12, backoff=0.01)
"""The paper's hand ([docs/model.md section 7][model-7]): aperture 0.16 m, palm depth 0.12 m."""

PAPER_CRMS = (CRM("a", "b", 0.0), CRM("b", "a", 0.0), CRM("a", "a", 0.08), CRM("b", "b", -0.08))
"""The paper's four CRMs: oppose a, oppose b, slide a, slide b (mirror pairs C1-C2, C3-C4)."""

PAPER_BINS = Discretizer(rho=(1.0,), m_a=(0.10,), m_b=(0.10,))
"""The paper's observation bins: rho at 1, moment magnitudes at 0.10 m (24 observations)."""


def paper_box() -> Task:
    """The paper's box task ([docs/model.md section 7][model-7]).

    Examples
    --------
    >>> t = paper_box()
    >>> t.actions
    (CRM('a', 'b', 0), CRM('b', 'a', 0), CRM('a', 'a', 0.08), CRM('b', 'b', -0.08))
    >>> t.discretizer.size, t.max_steps, t.mu_goal
    (24, 10, 0.05)
    """
    return Task(
        name="paper-box",
        obj=Rectangle(0.30, 0.10),
        hand=PAPER_HAND,
        actions=PAPER_CRMS,
        discretizer=PAPER_BINS,
        starts=CornerStarts(),
        mu_goal=0.05,
        max_steps=10,
        reference_mean_steps=1.66,
        description="0.30 x 0.10 m box, aperture 0.16 m, palm depth 0.12 m (Platt, Sec. III-C)",
        symmetry=Symmetry((1, 0, 3, 2)),  # reflection x -> -x: C1 <-> C2, C3 <-> C4
    )


_TASKS: dict[str, Callable[[], Task]] = {"paper-box": paper_box}


_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9._-]*")
"""A task's name (it names run folders and is typed after ``--task``)."""

NAME_LENGTH = 64
"""The longest name a user gives a task (a file, a registration, a study); a task made from
another (``<name>-grid<n>``, ``<name>-train<n>``) may add up to as many characters again."""


def checked_name(name: Any, longest: int = NAME_LENGTH) -> str:
    """``name`` if it is a valid task name: 1 to ``longest`` letters, digits, ``.``, ``_`` or
    ``-``, the first a letter or digit (one-line error otherwise).

    >>> checked_name("paper-box")
    'paper-box'
    """
    if not isinstance(name, str) or not _NAME.fullmatch(name) or len(name) > longest:
        raise CrmgraspError(
            f"name must be 1-{longest} letters, digits, '.', '_' or '-' (first a letter or digit), got {shown(name)}"
        )
    return name


def register_task(name: str, factory: Callable[[], Task], *, overwrite: bool = False) -> None:
    """Make ``make_task(name)`` return ``factory()`` (``name``: [`checked_name`][]; ``factory``
    callable with no arguments, returning a [`Task`][])."""
    checked_name(name)
    if not callable(factory):
        raise CrmgraspError(f"a task factory must be callable with no arguments, got {shown(factory)}")
    if name in _TASKS and not overwrite:
        raise CrmgraspError(f"task {name!r} is already registered")
    _TASKS[name] = factory


def task_names() -> tuple[str, ...]:
    """Registered task names, sorted."""
    return tuple(sorted(_TASKS))


def make_task(name: str) -> Task:
    """The task registered as ``name``."""
    try:
        factory = _TASKS[name]
    except (KeyError, TypeError):
        raise CrmgraspError(f"unknown task {name!r}; known tasks: {', '.join(task_names())}") from None
    task = factory()
    if not isinstance(task, Task):
        raise CrmgraspError(f"the factory registered as task {name!r} returned {shown(task)}, not a Task")
    return task


def checked_task(task: object, who: str) -> Task:
    """``task`` if it is a [`Task`][]; otherwise a one-line error saying that ``who`` needs one.

    >>> checked_task("paper-box", "belief_optimum")
    Traceback (most recent call last):
    ...
    crmgrasp._validation.CrmgraspError: belief_optimum needs a Task (crmgrasp.make_task(name)), got 'paper-box'
    """
    if not isinstance(task, Task):
        raise CrmgraspError(f"{who} needs a Task (crmgrasp.make_task(name)), got {shown(task)}")
    return task


def as_task(task: object, who: str) -> Task:
    """``task`` as a [`Task`][]: a registered name through [`make_task`][], a `Task` as it is
    (one-line error otherwise, naming ``who``)."""
    return make_task(task) if isinstance(task, str) else checked_task(task, who)

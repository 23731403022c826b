"""Named grasping tasks: object, hand, CRM set, observation bins, starts, goal.

A :class:`Task` bundles everything an environment or experiment needs. Tasks are
looked up by name with :func:`make_task` (``"paper-box"`` is docs/model.md section 7);
users build their own by constructing :class:`Task` directly and may register a
factory under a new name with :func:`register_task`.
"""

from __future__ import annotations

import copy
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, ClassVar, NamedTuple, Protocol, overload, runtime_checkable

import numpy as np
from numpy.typing import NDArray

from crmgrasp._validation import CrmgraspError, finite, non_negative, tries
from crmgrasp.model.contact_model import ContactModel
from crmgrasp.model.contacts import ROW_WIDTH, Config, Contact, config_from_row, configs_to_array
from crmgrasp.model.families import ShapeFamily
from crmgrasp.model.geometry import Polygon, Rectangle, Shape
from crmgrasp.model.hand import CRM, Error, Hand, feasible
from crmgrasp.model.planar_model import PlanarModel
from crmgrasp.model.quality import min_friction
from crmgrasp.model.sensing import Discretizer, Observation, SensorNoise

__all__ = [
    "StartSampler",
    "StartFilter",
    "CornerStarts",
    "UniformStarts",
    "Task",
    "World",
    "Symmetry",
    "paper_box",
    "make_task",
    "register_task",
    "task_names",
]


@runtime_checkable
class StartSampler(Protocol):
    """Draws a start configuration; every draw comes from ``rng``."""

    def __call__(self, obj: Shape, hand: Hand, mu_goal: float, rng: np.random.Generator) -> Config: ...


StartFilter = Callable[[Shape, Hand, float, np.ndarray], np.ndarray]
"""``(obj, hand, mu_goal, u) -> starts``: the accepted corner-start candidates of the
uniforms ``u`` (``(4, m)``, see :func:`corner_candidate`), in order, as rows of the
planar layout (:func:`~crmgrasp.model.contacts.configs_to_array`).
:func:`accept_corner_candidates` is the reference; :mod:`crmgrasp.kernels` supplies a
compiled one that makes the same decisions."""


def acceptable(obj: Shape, hand: Hand, mu_goal: float, config: Config) -> bool:
    """The start rule: feasible (docs/model.md section 2) and not already a grasp
    (``min_friction > mu_goal``)."""
    return feasible(obj, hand, config) is Error.NONE and min_friction(config) > mu_goal


def _edge_contact(obj: Polygon, edge: int, frac: float) -> Contact:
    ax, ay, ex, ey, _, nx, ny = obj.edges[edge]
    return Contact(ax + frac * ex, ay + frac * ey, nx, ny)


def corner_candidate(obj: Polygon, u_corner: float, u_in: float, u_out: float, u_coin: float) -> Config | None:
    """The corner-start candidate of four uniforms (``None`` on a vertex): corner
    ``k = floor(u_corner n)``, a contact at fraction ``u_in`` along the side that ends
    at vertex ``k``, one at ``u_out`` along the side that starts there; the first is
    ``a`` when ``u_coin < 0.5``."""
    if u_in == 0.0 or u_out == 0.0:  # a vertex: normal undefined
        return None
    n = len(obj.vertices)
    k = int(u_corner * n)
    first = _edge_contact(obj, (k - 1) % n, u_in)
    second = _edge_contact(obj, k, u_out)
    return Config(first, second) if u_coin < 0.5 else Config(second, first)


def accept_corner_candidates(obj: Shape, hand: Hand, mu_goal: float, u: np.ndarray) -> np.ndarray:
    """Reference :data:`StartFilter`: :func:`corner_candidate` and :func:`acceptable` per
    column of ``u``."""
    assert isinstance(obj, Polygon)
    rows = []
    for uc, ui, uo, coin in u.T.tolist():
        cfg = corner_candidate(obj, uc, ui, uo, coin)
        if cfg is not None and acceptable(obj, hand, mu_goal, cfg):
            rows.append(cfg)
    return configs_to_array(rows)


def corner_boxes(obj: Polygon, aperture: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per corner ``k`` (vertex ``k``), the largest fractions of the incoming and the
    outgoing side that a feasible pair can use, and the cumulative corner weights.

    Two points at distances ``d_1``, ``d_2`` from a corner whose sides meet at the
    angle ``theta`` (at most 180 degrees, convex or reflex corner) are
    ``d^2 = d_1^2 + d_2^2 - 2 d_1 d_2 cos(theta)`` apart, at least
    ``d_1^2`` when ``cos(theta) <= 0`` and at least ``d_1^2 sin^2(theta)`` otherwise;
    so ``d <= A`` needs ``d_i <= A / s`` with ``s = 1`` or ``sin(theta)``, i.e. a
    fraction ``c = min(1, A / (s L))`` of a side of length ``L`` (widened by 1e-9 for
    rounding). Corner ``k`` is proposed with probability proportional to its box
    area ``c_in c_out``, which keeps the accepted distribution that of the uniform
    proposal (each accepted candidate has the same density).
    """
    e = obj.edges
    nv = len(e)
    c_in, c_out = np.ones(nv), np.ones(nv)
    for k in range(nv):
        ki = (k - 1) % nv
        l_in, l_out = math.sqrt(e[ki][4]), math.sqrt(e[k][4])
        cos = -(e[ki][2] * e[k][2] + e[ki][3] * e[k][3]) / (l_in * l_out)
        s = 1.0 if cos <= 0.0 else abs(e[ki][2] * e[k][3] - e[ki][3] * e[k][2]) / (l_in * l_out)
        if s > 0.0:
            c_in[k] = min(1.0, aperture / (s * l_in) * (1.0 + 1e-9))
            c_out[k] = min(1.0, aperture / (s * l_out) * (1.0 + 1e-9))
    w = np.cumsum(c_in * c_out)
    return w / w[-1], c_in, c_out


def corner_proposal(w: np.ndarray, cum: np.ndarray, c_in: np.ndarray, c_out: np.ndarray) -> np.ndarray:
    """Uniforms ``w`` (``(4, m)``) to candidates in :func:`corner_candidate`'s
    parametrisation: corner ``k`` with probability ``cum[k] - cum[k - 1]``, a contact
    uniform within ``c_in[k]`` of the corner on the incoming side and within
    ``c_out[k]`` on the outgoing side (a draw of exactly 0, the corner itself, is
    marked rejected), the coin unchanged."""
    nv = len(cum)
    k = np.zeros(w.shape[1], dtype=np.intp)  # the number of cum[j] <= w, j < nv - 1
    for j in range(nv - 1):
        k += w[0] >= cum[j]
    u = np.empty_like(w)
    u[0] = (k + 0.5) / nv
    u[1] = np.where(w[1] == 0.0, 0.0, 1.0 - c_in.take(k) * w[1])
    u[2] = c_out.take(k) * w[2]
    u[3] = w[3]
    return u


@dataclass(frozen=True)
class CornerStarts:
    """docs/model.md section 7 starts: a random polygon corner, one contact uniform on each
    of the two sides meeting there, a fair coin for which contact is ``a``;
    resampled until feasible and not already a grasp (``min_friction > mu_goal``).

    Each attempt draws four uniforms in one call: corner (``floor(u n)``), fraction
    along the incoming side, fraction along the outgoing side, coin (a is the
    incoming-side contact when ``u < 0.5``). A fraction of exactly 0 (a vertex) is
    rejected. ``accept`` (a compiled :data:`StartFilter`, given by a kernel) decides
    each candidate as :func:`acceptable` does, so the stream is the same with or
    without it.
    """

    max_tries: int = 10_000
    takes_corner_filter = True  # class attribute: decides candidates through a start filter
    kind: ClassVar[str] = "corners"

    def __post_init__(self) -> None:
        object.__setattr__(self, "max_tries", tries(self.max_tries))

    def __call__(
        self, obj: Shape, hand: Hand, mu_goal: float, rng: np.random.Generator, accept: StartFilter | None = None
    ) -> Config:
        if not isinstance(obj, Polygon):
            raise CrmgraspError(f"corner starts need a polygon, got {type(obj).__name__}")
        for _ in range(self.max_tries):
            u = rng.random(4)
            if accept is not None:
                got = accept(obj, hand, mu_goal, u[:, None])
                if len(got):
                    return config_from_row(got[0].tolist())
                continue
            cfg = corner_candidate(obj, *u.tolist())
            if cfg is not None and acceptable(obj, hand, mu_goal, cfg):
                return cfg
        raise CrmgraspError(f"no feasible corner start found in {self.max_tries} tries")

    def batch(
        self,
        obj: Shape,
        hand: Hand,
        mu_goal: float,
        rng: np.random.Generator,
        n: int,
        accept: StartFilter = accept_corner_candidates,
    ) -> np.ndarray:
        """``n`` starts as rows of the planar layout (``(n, 8)``), drawn in rounds of candidates.

        Same distribution as :meth:`__call__`, not the same stream: candidates come
        from a tighter proposal (:func:`corner_proposal`) and pass :func:`acceptable`
        through ``accept`` (the reference filter, or a compiled one making the same
        decisions, so the stream does not depend on which).
        """
        if not isinstance(obj, Polygon):
            raise CrmgraspError(f"corner starts need a polygon, got {type(obj).__name__}")
        cum, c_in, c_out = corner_boxes(obj, hand.aperture)
        out = np.empty((n, ROW_WIDTH))
        filled, rounds, rate = 0, 0, 0.5
        while filled < n:
            rounds += 1
            if rounds > self.max_tries:
                raise CrmgraspError(f"no feasible corner start found in {self.max_tries} rounds")
            m = int((n - filled) / rate * 1.2) + 32
            u = corner_proposal(rng.random((4, m)), cum, c_in, c_out)
            got = accept(obj, hand, mu_goal, u)
            rate = max(0.02, 0.5 * rate + 0.5 * len(got) / m)
            take = min(len(got), n - filled)
            out[filled : filled + take] = got[:take]
            filled += take
        return out


@dataclass(frozen=True)
class UniformStarts:
    """Two contacts uniform in arclength on the whole boundary, resampled until
    feasible, not a grasp and (for polygons) off the vertices."""

    max_tries: int = 10_000
    kind: ClassVar[str] = "uniform"

    def __post_init__(self) -> None:
        object.__setattr__(self, "max_tries", tries(self.max_tries))

    def __call__(self, obj: Shape, hand: Hand, mu_goal: float, rng: np.random.Generator) -> Config:
        vertices = set(obj.vertex_arclengths()) if isinstance(obj, Polygon) else set()
        for _ in range(self.max_tries):
            s = rng.random(2) * obj.perimeter
            if vertices and (float(s[0]) in vertices or float(s[1]) in vertices):
                continue
            pa, pb = obj.boundary(float(s[0])), obj.boundary(float(s[1]))
            cfg = Config(Contact(*pa.point, *pa.normal), Contact(*pb.point, *pb.normal))
            if acceptable(obj, hand, mu_goal, cfg):
                return cfg
        raise CrmgraspError(f"no feasible uniform start found in {self.max_tries} tries")


@dataclass(frozen=True)
class Symmetry:
    """A mirror symmetry of a task, declared by its author.

    Claim: some reflection of the plane maps the object onto itself and the start
    distribution onto itself (with the labels ``a`` and ``b`` swapped, which puts
    the palm back on the right). Then CRM ``(c, f, r)`` corresponds to
    ``(c', f', -r)`` (primes: swapped labels), ``rho`` and the error flag are
    unchanged and ``(m_a, m_b)`` becomes ``(-m_b, -m_a)``. ``actions[i]`` is the index
    of the CRM that corresponds to CRM ``i``; :class:`Task` checks it against that
    rule and the observation bins (moments binned by magnitude, the same thresholds
    for both). Learners may use it to pool experience (``symmetric=True``).
    """

    actions: tuple[int, ...]


def _check_symmetry(sym: Symmetry, actions: tuple[Any, ...], disc: Discretizer, model: ContactModel) -> None:
    perm = tuple(sym.actions)
    n = len(actions)
    if sorted(perm) != list(range(n)) or any(perm[perm[i]] != i for i in range(n)):
        raise CrmgraspError(f"symmetry actions must be an involutive permutation of 0..{n - 1}, got {perm!r}")
    for i, crm in enumerate(actions):
        m, expected = actions[perm[i]], model.mirror_crm(crm)
        if m != expected:
            raise CrmgraspError(f"symmetry maps {crm} to {m}, but its mirror is {expected}")
    axes, th = model.mirror_axes, disc.thresholds
    swapped = [(disc.names[i], disc.names[j]) for i, j in enumerate(axes) if i < j]
    if not disc.abs_moments or any(th[i] != th[j] for i, j in enumerate(axes)):
        same = ", ".join(f"{a} and {b}" for a, b in swapped)
        raise CrmgraspError(f"a symmetric task needs moments binned by magnitude with the same {same} thresholds")


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
        The object (:class:`~crmgrasp.model.geometry.Polygon`, :class:`~crmgrasp.model.geometry.Disc`, ...).
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
        Episode truncation, in CRMs (1 to :data:`MAX_STEPS`).
    noise
        Sensing noise applied during the task (off by default).
    reference_mean_steps
        Best achievable mean CRMs per episode for a learner on this task (the
        belief-space optimum where known), used to report ``episodes_to_5pct``.
    symmetry
        A declared mirror symmetry (:class:`Symmetry`), or None.
    grasp_reward
        Reward of the CRM that reaches a grasp (every other CRM: -1). The paper's "-1
        in all states" read literally gives -1 (the default); read as "in all non-goal
        states" it gives 0.
    error_cost
        Extra cost (>= 0, reward units) of a CRM that ends in an error: its reward is
        ``-1 - error_cost`` (0 in the paper). Makes failed attempts expensive, the
        Discussion's "infrequent failures [that] come with a high cost".
    family
        An object family (:mod:`crmgrasp.model.families`), or None. With a family, each
        episode draws its object (:meth:`instance`) and ``obj`` is only the shape
        scenes show (the family's nominal one); the smallest object the family can
        draw must fit the hand's aperture.
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
    model: ContactModel = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if not isinstance(self.obj, Shape):
            raise CrmgraspError(f"task object must be a Shape (Polygon, Disc, ...), got {self.obj!r}")
        if not isinstance(self.hand, Hand):
            raise CrmgraspError(f"task hand must be a Hand, got {self.hand!r}")
        self._set_model(PlanarModel(self.hand, self.noise))
        self._check_common()
        if self.family is not None:
            if not isinstance(self.family, ShapeFamily):
                raise CrmgraspError(f"task family must be a ShapeFamily, got {self.family!r}")
            self._check_family_width()

    def _check_family_width(self) -> None:
        w = self.family.min_width()  # type: ignore[union-attr]
        if w > self.hand.aperture:
            raise CrmgraspError(
                f"family {self.family.describe()['kind']!r}: its smallest object is {w:.4g} m wide, "  # type: ignore[union-attr]
                f"beyond the hand's aperture {self.hand.aperture:g} m; no object it draws can be grasped"
            )

    def _set_model(self, model: ContactModel) -> None:
        """Hold ``model``, the contact model every rule of this task goes through."""
        object.__setattr__(self, "model", model)

    def _check_common(self) -> None:
        """The checks every task takes, planar or spatial: actions (through the hand's
        ``check_crm``), goal, length, symmetry, rewards, reference."""
        actions = tuple(self.actions)
        if not actions:
            raise CrmgraspError("a task needs at least one CRM action")
        for a in actions:
            self.hand.check_crm(a)
        object.__setattr__(self, "actions", actions)
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
                _check_symmetry(self.symmetry, actions, self.discretizer, self.model)
            except CrmgraspError as exc:
                raise CrmgraspError(
                    f"{exc} (a task made from a symmetric one with other CRMs or bins needs symmetry=None)"
                ) from None
        object.__setattr__(self, "grasp_reward", finite(self.grasp_reward, "grasp_reward"))
        object.__setattr__(self, "error_cost", non_negative(self.error_cost, "error_cost"))
        if self.reference_mean_steps is not None and not (
            math.isfinite(self.reference_mean_steps) and self.reference_mean_steps > 0
        ):
            raise CrmgraspError(f"reference_mean_steps must be > 0, got {self.reference_mean_steps!r}")

    # -- the model's rules in this task's world: each written once in crmgrasp.model and
    # applied through the task's contact model (Task.model), planar or spatial alike
    def mirror_crm(self, crm: Any) -> Any:
        """The CRM a declared mirror symmetry maps ``crm`` to (the model's ``mirror_crm``)."""
        return self.model.mirror_crm(crm)

    def crm(self, action: Any) -> Any:
        """The CRM of action index ``action``, or ``action`` itself checked against the hand."""
        return self.model.check_crm(action) if self.model.is_crm(action) else self.actions[action]

    def execute(self, config: Any, crm: Any, sensed: Any) -> Any:
        """The CRM transition (the model's ``execute``), goal line from ``sensed``."""
        return self.model.execute(self.obj, config, crm, sensed)

    def read(self, config: Any, rng: np.random.Generator) -> Any:
        """One sensed reading of ``config`` (the model's ``read``)."""
        return self.model.read(config, rng)

    def observe(self, sensed: Any) -> Observation:
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

    def with_object(self, obj: Shape) -> Task:
        """This task on the object ``obj``, without a family (the object is not checked
        again: families draw valid shapes)."""
        out = copy.copy(self)
        object.__setattr__(out, "obj", obj)
        object.__setattr__(out, "family", None)
        return out

    def _one_object(self) -> None:
        """Refuse, with the reason, to draw starts without an object on a family task."""
        if self.family is not None:
            raise CrmgraspError(
                f"task {self.name!r} draws an object per episode: use sample_world (the object and a start on it)"
            )

    def sample_world(self, rng: np.random.Generator, accept: StartFilter | None = None) -> World:
        """An episode's hidden world: :meth:`instance`, then a start on it."""
        inst = self.instance(rng)
        return World(inst, inst.sample_start(rng, accept))

    def sample_start(self, rng: np.random.Generator, accept: StartFilter | None = None) -> Config:
        """A start configuration drawn from ``rng``. ``accept``: a compiled start filter,
        used by samplers built on corner candidates (:class:`CornerStarts` and the presets
        of :mod:`crmgrasp.tasks.presets`; the same start either way), ignored by others."""
        self._one_object()
        if accept is not None and getattr(self.starts, "takes_corner_filter", False):
            return self.starts(self.obj, self.hand, self.mu_goal, rng, accept)  # type: ignore[call-arg]
        return self.starts(self.obj, self.hand, self.mu_goal, rng)

    def sample_starts(self, rng: np.random.Generator, n: int, accept: StartFilter | None = None) -> np.ndarray:
        """``n`` starts as rows of the model's layout: :meth:`CornerStarts.batch` (another stream than
        :meth:`sample_start`'s, the same distribution; ``accept`` as there), or ``n``
        scalar draws for other samplers."""
        self._one_object()
        if isinstance(self.starts, CornerStarts):
            return self.starts.batch(self.obj, self.hand, self.mu_goal, rng, n, accept or accept_corner_candidates)
        return self.model.rows_of([self.sample_start(rng) for _ in range(n)])

    @overload
    def grasped(self, mu: float) -> bool: ...

    @overload
    def grasped(self, mu: NDArray[np.float64]) -> NDArray[np.bool_]: ...

    def grasped(self, mu: float | NDArray[np.float64]) -> bool | NDArray[np.bool_]:
        """The success rule (docs/model.md section 5) from a configuration's min friction:
        ``mu <= mu_goal`` (elementwise on an array)."""
        return mu <= self.mu_goal

    def is_success(self, config: Any) -> bool:
        """docs/model.md section 5: :meth:`grasped` of :meth:`quality`."""
        return self.grasped(self.quality(config))

    def action_names(self) -> tuple[str, ...]:
        """``('C1 (a,b,0)', ...)``: readable action names in index order."""
        return tuple(f"C{i + 1} {crm}" for i, crm in enumerate(self.actions))


class World(NamedTuple):
    """One episode's hidden world: the task on the object drawn for it, and the start."""

    task: Task
    config: Config


PAPER_HAND = Hand(aperture=0.16, palm_depth=0.12, backoff=0.01)
"""The paper's hand (docs/model.md section 7): aperture 0.16 m, palm depth 0.12 m."""

PAPER_CRMS = (CRM("a", "b", 0.0), CRM("b", "a", 0.0), CRM("a", "a", 0.08), CRM("b", "b", -0.08))
"""The paper's four CRMs: oppose a, oppose b, slide a, slide b (mirror pairs C1-C2, C3-C4)."""

PAPER_BINS = Discretizer(rho=(1.0,), m_a=(0.10,), m_b=(0.10,))
"""The paper's observation bins: rho at 1, moment magnitudes at 0.10 m (24 observations)."""


def paper_box() -> Task:
    """The paper's box task (docs/model.md section 7).

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


def register_task(name: str, factory: Callable[[], Task], *, overwrite: bool = False) -> None:
    """Make ``make_task(name)`` return ``factory()``."""
    if not isinstance(name, str) or not name:
        raise CrmgraspError(f"task name must be a non-empty string, got {name!r}")
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
    return factory()

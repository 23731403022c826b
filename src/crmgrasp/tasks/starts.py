"""Start samplers: where an episode's contacts are placed before the first CRM.

A sampler draws a start configuration from the generator it is given and accepts it by
the start rule ([`acceptable`][]: feasible, [docs/model.md section 2][model-2], and not already a
grasp). [`CornerStarts`][] is the paper's ([docs/model.md section 7][model-7]): a random polygon
corner and one contact on each side meeting there; [`UniformStarts`][] places both
contacts anywhere on the boundary. Each sampler class states its task-file ``kind`` and
checks its own parameters ([`crmgrasp.tasks.files`][] reads and writes them from its
fields); more samplers live in `crmgrasp.tasks.presets`,
[`crmgrasp.tasks.families`][] and [`crmgrasp.tasks.spatial`][].
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import ClassVar, Protocol, runtime_checkable

import numpy as np

from crmgrasp._validation import CrmgraspError, tries
from crmgrasp.model.contacts import ROW_WIDTH, Config, Contact, Grip, config_from_row, configs_to_array, make_config
from crmgrasp.model.geometry import Polygon, Shape
from crmgrasp.model.hand import Error, Hand, feasible
from crmgrasp.model.quality import min_friction

__all__ = [
    "StartSampler",
    "StartFilter",
    "CornerStarts",
    "UniformStarts",
    "UniformFilter",
    "uniform_candidate",
    "acceptable",
    "corner_candidate",
    "accept_corner_candidates",
    "corner_boxes",
    "corner_proposal",
]


@runtime_checkable
class StartSampler(Protocol):
    """Draws a start configuration; every draw comes from ``rng``."""

    def __call__(self, obj: Shape, hand: Hand, mu_goal: float, rng: np.random.Generator) -> Config | Grip: ...


StartFilter = Callable[[Shape, Hand, float, np.ndarray], np.ndarray]
"""``(obj, hand, mu_goal, u) -> starts``: the accepted corner-start candidates of the
uniforms ``u`` (``(4, m)``, see [`corner_candidate`][]), in order, as rows of the
planar layout ([`configs_to_array`][crmgrasp.model.contacts.configs_to_array]).
[`accept_corner_candidates`][] is the reference; [`crmgrasp.kernels`][] supplies a
compiled one that makes the same decisions."""


def acceptable(obj: Shape, hand: Hand, mu_goal: float, config: Config | Grip) -> bool:
    """The start rule: feasible ([docs/model.md section 2][model-2]) and not already a grasp
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
    """Reference [`StartFilter`][]: [`corner_candidate`][] and [`acceptable`][] per
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
    """Uniforms ``w`` (``(4, m)``) to candidates in [`corner_candidate`][]'s
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
    """[docs/model.md section 7][model-7] starts: a random polygon corner, one contact uniform on each
    of the two sides meeting there, a fair coin for which contact is ``a``;
    resampled until feasible and not already a grasp (``min_friction > mu_goal``).

    Each attempt draws four uniforms in one call: corner (``floor(u n)``), fraction
    along the incoming side, fraction along the outgoing side, coin (a is the
    incoming-side contact when ``u < 0.5``). A fraction of exactly 0 (a vertex) is
    rejected. ``accept`` (a compiled [`StartFilter`][], given by a kernel) decides
    each candidate as [`acceptable`][] does, so the stream is the same with or
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

        Same distribution as `__call__`, not the same stream: candidates come
        from a tighter proposal ([`corner_proposal`][]) and pass [`acceptable`][]
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
    """The hand's contacts (two or more) uniform in arclength on the whole boundary,
    resampled until feasible, not a grasp and (for polygons) off the vertices."""

    max_tries: int = 10_000
    kind: ClassVar[str] = "uniform"
    any_contacts: ClassVar[bool] = True
    """Places any number of contacts (the other samplers place two)."""
    takes_uniform_filter: ClassVar[bool] = True
    """Decides each try through a [`UniformFilter`][] when a kernel supplies one."""

    def __post_init__(self) -> None:
        object.__setattr__(self, "max_tries", tries(self.max_tries))

    def __call__(
        self, obj: Shape, hand: Hand, mu_goal: float, rng: np.random.Generator, accept: UniformFilter | None = None
    ) -> Config | Grip:
        """Per try, ``hand.contacts`` arclengths ``u * perimeter`` (``u`` uniform), decided by
        ``accept`` (a compiled [`UniformFilter`][], the same decision) or [`uniform_candidate`][]."""
        decide = accept or uniform_candidate
        for _ in range(self.max_tries):
            cfg = decide(obj, hand, mu_goal, rng.random(hand.contacts) * obj.perimeter)
            if cfg is not None:
                return cfg
        raise CrmgraspError(f"no feasible uniform start found in {self.max_tries} tries")


class UniformFilter(Protocol):
    """``(obj, hand, mu_goal, s) -> start or None``: [`uniform_candidate`][]'s decision on the
    arclengths ``s`` (one per contact), compiled by a kernel; ``kind`` is ``"uniform"`` (a
    corner [`StartFilter`][] has none)."""

    kind: str

    def __call__(self, obj: Shape, hand: Hand, mu_goal: float, s: np.ndarray) -> Config | Grip | None: ...


def uniform_candidate(obj: Shape, hand: Hand, mu_goal: float, s: np.ndarray) -> Config | Grip | None:
    """The uniform start at arclengths ``s`` (one per contact, in label order) if it is
    [`acceptable`][] and (on a polygon) no contact sits on a vertex, else ``None``."""
    arcs = s.tolist()
    if isinstance(obj, Polygon) and not set(obj.vertex_arclengths()).isdisjoint(arcs):
        return None
    points = [obj.boundary(v) for v in arcs]
    cfg = make_config([Contact(*p.point, *p.normal) for p in points])
    return cfg if acceptable(obj, hand, mu_goal, cfg) else None

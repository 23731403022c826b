"""Start presets and task readings: the choices the paper leaves open, as options.

The paper's Figure 7 task is read here as "a random corner, one contact uniform on each
side" ([`CornerStarts`][crmgrasp.tasks.starts.CornerStarts]). Its figures suggest other start
distributions, and its reward sentence ("-1 in all states") has two readings. These
are first-class options, so that their effect can be measured
(``crmgrasp reproduce figure7-sensitivity``):

* [`NearCornerStarts`][]: both contacts within ``within`` (0.10 m) of the same
  corner, like the aliased starts of the paper's Figure 8(a);
* [`VertexStarts`][]: both contacts near one given vertex, the labels fixed (a
  hand of fixed handedness);
* [`LongSideStarts`][]: corner starts whose contact on the longer side is
  ``lo..hi`` from the corner, like the Robonaut trials of Figure 9;
* [`MixtureStarts`][]: a weighted mixture of samplers;
* ``grasp_reward`` ([`Task`][crmgrasp.tasks.core.Task]): -1 or 0 for the grasping CRM.

`with_reading` applies them to a task. Every sampler draws only from the ``rng``
it is given and accepts a start by the start rule
([`acceptable`][crmgrasp.tasks.starts.acceptable]: feasible and not already a grasp).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from crmgrasp._validation import CrmgraspError, positive, tries
from crmgrasp.model.contacts import Config, Grip, config_from_row
from crmgrasp.model.geometry import Polygon, Shape
from crmgrasp.model.hand import Hand
from crmgrasp.tasks.core import Task
from crmgrasp.tasks.starts import CornerStarts, StartFilter, StartSampler, acceptable, corner_candidate

__all__ = [
    "NearCornerStarts",
    "VertexStarts",
    "LongSideStarts",
    "MixtureStarts",
    "START_PRESETS",
    "with_reading",
]


def _polygon(obj: Shape, what: str) -> Polygon:
    if not isinstance(obj, Polygon):
        raise CrmgraspError(f"{what} starts need a polygon, got {type(obj).__name__}")
    return obj


def _decide(obj: Polygon, hand: Hand, mu_goal: float, u: list[float], accept: StartFilter | None) -> Config | None:
    """The corner candidate of the uniforms ``u`` if the start rule accepts it."""
    if accept is not None:
        got = accept(obj, hand, mu_goal, np.array(u)[:, None])
        return config_from_row(got[0].tolist()) if len(got) else None
    cfg = corner_candidate(obj, *u)
    return cfg if cfg is not None and acceptable(obj, hand, mu_goal, cfg) else None


@dataclass(frozen=True)
class NearCornerStarts:
    """Both contacts within ``within`` metres of one corner (Figure 8(a)-like starts).

    Each attempt draws four uniforms ``(u_c, u_1, u_2, u_coin)``: corner ``k =
    floor(u_c n)`` (every corner equally likely), the incoming-side contact at distance
    ``min(within, L_in) u_1`` from the corner, the outgoing-side one at ``min(within,
    L_out) u_2``, contact ``a`` the incoming one when ``u_coin < 0.5``; a draw of 0 (the
    corner itself) is rejected, the rest by the start rule.
    """

    within: float = 0.10
    max_tries: int = 10_000
    takes_corner_filter = True
    kind: ClassVar[str] = "near-corner"

    def __post_init__(self) -> None:
        object.__setattr__(self, "max_tries", tries(self.max_tries))
        positive(self.within, "within")

    def __call__(
        self, obj: Shape, hand: Hand, mu_goal: float, rng: np.random.Generator, accept: StartFilter | None = None
    ) -> Config:
        poly = _polygon(obj, "near-corner")
        n = len(poly.vertices)
        for _ in range(self.max_tries):
            uc, u1, u2, coin = rng.random(4).tolist()
            if u1 == 0.0 or u2 == 0.0:
                continue
            k = int(uc * n)
            l_in, l_out = poly.edge_length((k - 1) % n), poly.edge_length(k)
            u_in = 1.0 - min(self.within, l_in) / l_in * u1
            u_out = min(self.within, l_out) / l_out * u2
            cfg = _decide(poly, hand, mu_goal, [(k + 0.5) / n, u_in, u_out, coin], accept)
            if cfg is not None:
                return cfg
        raise CrmgraspError(f"no feasible near-corner start found in {self.max_tries} tries")


@dataclass(frozen=True)
class VertexStarts:
    """Both contacts near one given vertex (index ``vertex`` of the polygon's
    counter-clockwise vertices): one on the side that ends there (*incoming*) at a
    distance from the vertex uniform in ``incoming`` metres, one on the side that starts
    there (*outgoing*) at a distance uniform in ``outgoing``; contact ``a`` is on the
    side ``a_on`` (no coin: the hand's handedness is fixed). Each attempt draws two
    uniforms; the start rule rejects, at most ``max_tries`` times."""

    vertex: int = 0
    incoming: tuple[float, float] = (0.005, 0.05)
    outgoing: tuple[float, float] = (0.005, 0.05)
    a_on: str = "incoming"
    max_tries: int = 10_000
    kind: ClassVar[str] = "vertex"

    def __post_init__(self) -> None:
        object.__setattr__(self, "max_tries", tries(self.max_tries))
        if not isinstance(self.vertex, int) or isinstance(self.vertex, bool) or self.vertex < 0:
            raise CrmgraspError(f"vertex starts: vertex must be an index >= 0, got {self.vertex!r}")
        for name in ("incoming", "outgoing"):
            lo, hi = (float(v) for v in getattr(self, name))
            if not (0.0 < lo <= hi and math.isfinite(hi)):
                raise CrmgraspError(f"vertex starts: {name} must be [low, high] with 0 < low <= high, got {[lo, hi]}")
            object.__setattr__(self, name, (lo, hi))
        if self.a_on not in ("incoming", "outgoing"):
            raise CrmgraspError(f"vertex starts: a_on must be 'incoming' or 'outgoing', got {self.a_on!r}")

    def __call__(
        self, obj: Shape, hand: Hand, mu_goal: float, rng: np.random.Generator, accept: StartFilter | None = None
    ) -> Config:
        poly = _polygon(obj, "vertex")
        n = len(poly.vertices)
        if self.vertex >= n:
            raise CrmgraspError(f"vertex starts: vertex {self.vertex} does not exist on a polygon of {n} vertices")
        l_in, l_out = poly.edge_length((self.vertex - 1) % n), poly.edge_length(self.vertex)
        if self.incoming[1] >= l_in or self.outgoing[1] >= l_out:
            raise CrmgraspError(
                f"vertex starts: distances up to {self.incoming[1]:g} / {self.outgoing[1]:g} m reach past the sides "
                f"at vertex {self.vertex} ({l_in:g} / {l_out:g} m long)"
            )
        coin = 0.0 if self.a_on == "incoming" else 1.0
        for _ in range(self.max_tries):
            u1, u2 = rng.random(2).tolist()
            d_in = self.incoming[0] + (self.incoming[1] - self.incoming[0]) * u1
            d_out = self.outgoing[0] + (self.outgoing[1] - self.outgoing[0]) * u2
            cfg = _decide(poly, hand, mu_goal, [(self.vertex + 0.5) / n, 1.0 - d_in / l_in, d_out / l_out, coin], None)
            if cfg is not None:
                return cfg
        raise CrmgraspError(f"no feasible start near vertex {self.vertex} in {self.max_tries} tries")


@dataclass(frozen=True)
class LongSideStarts:
    """Corner starts whose contact on the longer of its two sides lies ``lo < d <= hi``
    metres from the corner (Figure 9-like starts: the thumb far along the long side)."""

    lo: float = 0.10
    hi: float = math.inf
    max_tries: int = 100_000
    takes_corner_filter = True
    kind: ClassVar[str] = "long-side"

    def __post_init__(self) -> None:
        object.__setattr__(self, "max_tries", tries(self.max_tries))
        if not (0.0 <= self.lo < self.hi):
            raise CrmgraspError(f"long-side starts need 0 <= lo < hi, got lo={self.lo!r}, hi={self.hi!r}")

    def __call__(
        self, obj: Shape, hand: Hand, mu_goal: float, rng: np.random.Generator, accept: StartFilter | None = None
    ) -> Config:
        poly = _polygon(obj, "long-side")
        corner = CornerStarts(max_tries=self.max_tries)
        for _ in range(self.max_tries):
            cfg = corner(poly, hand, mu_goal, rng, accept)
            (la, da), (lb, db) = ((poly.edge_length(poly.edge_index(c.point)), _to_corner(poly, c.point)) for c in cfg)
            if la != lb and self.lo < (da if la > lb else db) <= self.hi:
                return cfg
        raise CrmgraspError(f"no long-side start found in {self.max_tries} tries")


def _to_corner(poly: Polygon, point: tuple[float, float]) -> float:
    return min(math.dist(point, v) for v in poly.vertices)


@dataclass(frozen=True)
class MixtureStarts:
    """Component ``i`` with probability ``weights[i] / sum(weights)``: one uniform picks
    the component, which then draws its start."""

    components: tuple[StartSampler, ...]
    weights: tuple[float, ...]
    takes_corner_filter = True
    kind: ClassVar[str] = "mixture"

    def __post_init__(self) -> None:
        w = tuple(float(x) for x in self.weights)
        if len(w) != len(self.components) or not w or any(not math.isfinite(x) or x < 0 for x in w) or sum(w) <= 0:
            raise CrmgraspError(f"mixture weights must be non-negative, one per component, not all 0: {self.weights}")
        object.__setattr__(self, "weights", w)
        object.__setattr__(self, "components", tuple(self.components))

    def __call__(
        self, obj: Shape, hand: Hand, mu_goal: float, rng: np.random.Generator, accept: StartFilter | None = None
    ) -> Config | Grip:
        cum = np.cumsum(self.weights) / sum(self.weights)
        i = min(int(np.searchsorted(cum, rng.random(), side="right")), len(cum) - 1)
        part = self.components[i]
        if accept is not None and getattr(part, "takes_corner_filter", False):
            return part(obj, hand, mu_goal, rng, accept)  # type: ignore[call-arg]
        return part(obj, hand, mu_goal, rng)


START_PRESETS: dict[str, StartSampler] = {
    "corners": CornerStarts(),
    "near-corner": NearCornerStarts(0.10),
    "long-side": LongSideStarts(0.10),
    "mixture": MixtureStarts((NearCornerStarts(0.10), LongSideStarts(0.10)), (0.4, 0.6)),
}
"""Named start distributions: the SPEC corners, Figure 8(a)-like, Figure 9-like, and the
40/60 mixture of the last two."""

_SYMMETRIC = ("corners", "near-corner")  # presets that map onto themselves under the box's mirror


def with_reading(task: Task, *, starts: str | None = None, grasp_reward: float | None = None) -> Task:
    """``task`` with a start preset ([`START_PRESETS`][]) and/or a grasp reward. A
    declared symmetry is kept only for presets that are mirror-symmetric by construction."""
    changes: dict[str, object] = {}
    if starts is not None:
        if starts not in START_PRESETS:
            raise CrmgraspError(f"unknown start preset {starts!r}; choose one of {', '.join(START_PRESETS)}")
        changes["starts"] = START_PRESETS[starts]
        if starts not in _SYMMETRIC:
            changes["symmetry"] = None
        if starts != "corners":
            changes["reference_mean_steps"] = None  # the optimum belongs to the original starts
    if grasp_reward is not None:
        changes["grasp_reward"] = grasp_reward
    return dataclasses.replace(task, **changes) if changes else task  # type: ignore[arg-type]

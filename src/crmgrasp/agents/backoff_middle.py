"""The middle level of [`BackoffVI`][crmgrasp.agents.backoff.BackoffVI] (``middle`` = true).

A long history ``h`` (its last ``k`` CRMs and observations, ``k >= 3``) is met rarely; its
last two CRMs and observations, its k = 2 suffix ``h_2``, are met by every long history
that ends the same way. The middle level pools the long level's counts by that suffix and
blends them with the short (k = 1) level's estimate:

``p_2(r, o, t | h_2, b) = (n_2(h_2, b, r, o, t) + beta p_1(r, o, t | h_1, b)) / (N_2(h_2, b) + beta)``,

where ``n_2`` sums the counts of every long history with suffix ``h_2`` after CRM ``b``,
outcome reward ``r``, sensed observation ``o`` (in the long history's own frame) and
terminal flag ``t``, and ``N_2`` is their total. It stands in for ``p_1`` in the long
history's blend (the module docstring of [`crmgrasp.agents.backoff`][]).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

from crmgrasp._validation import CrmgraspError
from crmgrasp.agents.model_based import Outcome
from crmgrasp.agents.pooled import HistoryFrame
from crmgrasp.model.history import KOrderEncoder

__all__ = ["ShortOutcomes", "SuffixPool"]

Pooled = dict[tuple[float, int, bool], float]
"""Weights (or probabilities) of outcomes ``(r, observation, terminal)``."""

ShortOutcomes = Callable[[int, int], list[tuple[float, int, bool, float, int]]]
"""The short level's outcomes of CRM ``b`` after long history ``s``, read in ``s``'s frame:
``(r, observation, terminal, p, n)``, each of the ``n`` observations that can have led to
an outcome of probability ``p`` listed once."""


class SuffixPool:
    """The long level's counts pooled by k = 2 suffix, blended with the short level.

    The long histories' encoder is the frame's given to
    [`pool`][crmgrasp.agents.backoff_middle.SuffixPool.pool], which is called first.
    """

    def __init__(self) -> None:
        self._encoder: KOrderEncoder | None = None
        self._suffix_encoder: KOrderEncoder | None = None
        self._code: dict[int, int] = {}
        self._counts: dict[tuple[int, int], Pooled] = {}
        self._blend: dict[tuple[int, int], Pooled] = {}

    def code(self, s: int) -> int:
        """The code of history ``s``'s last two CRMs and observations (its k = 2 suffix), remembered."""
        v = self._code.get(s)
        if v is None:
            if self._encoder is None or self._suffix_encoder is None:
                raise CrmgraspError("the middle level reads a history code before any counts were pooled")
            v = self._code[s] = self._suffix_encoder.encode(self._encoder.decode(s)[:4])
        return v

    def pool(
        self, counts: Mapping[tuple[int, int], Mapping[Outcome, float]], scale: float, frame: HistoryFrame
    ) -> None:
        """Pool the long counts ``n(h, b, (r, h', t))`` (each times ``scale``) by k = 2 suffix into
        ``n_2(h_2, b, (r, o, t))``, an outcome's weight split evenly among the observations
        that can have led to ``h'``; forget the blends of the previous plan."""
        enc = frame.encoder
        if self._encoder is not enc:
            self._encoder, self._code = enc, {}
            self._suffix_encoder = KOrderEncoder(enc.n_obs, enc.n_actions, 2)
        pooled: dict[tuple[int, int], Pooled] = {}
        for (s, b), row in counts.items():
            out = pooled.setdefault((self.code(s), b), {})
            for (r, s2, t), c in row.items():
                seen = frame.outcome_observations(s, b, s2)
                for obs in seen:
                    key = (r, obs, t)
                    out[key] = out.get(key, 0.0) + c * scale / len(seen)
        self._counts, self._blend = pooled, {}

    def outcomes(self, s: int, b: int, beta: float, short: ShortOutcomes) -> Pooled | None:
        """``p_2(. | h_2, b)`` for history ``s``'s suffix ``h_2`` (``None`` where no history with
        that suffix tried ``b``), with ``beta`` pseudo-counts of ``short(s, b)``; remembered
        until the next [`pool`][crmgrasp.agents.backoff_middle.SuffixPool.pool]."""
        key = (self.code(s), b)
        out = self._blend.get(key)
        if out is not None or key not in self._counts:
            return out
        blend = dict(self._counts[key])
        for r, obs, t, p, n in short(s, b):
            o = (r, obs, t)
            blend[o] = blend.get(o, 0.0) + beta * p / n
        total = sum(blend.values())
        out = self._blend[key] = {o: c / total for o, c in blend.items()}
        return out

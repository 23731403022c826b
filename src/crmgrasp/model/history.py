"""k-order internal state (paper Eq. 5, [docs/model.md section 6][model-6]).

``s_t = (o_t, a_{t-1}, o_{t-1}, ..., o_{t-k+1}, a_{t-k})``: the current discretized
observation, the last ``k`` actions and the ``k - 1`` observations between them.
History missing at the episode start takes a distinct padding value
(``n_actions`` for actions, ``n_obs`` for observations).

The integer code is mixed-radix, current observation most significant:
``code = (((o_t * (nA+1) + a_{t-1}) * (nO+1) + o_{t-1}) * (nA+1) + a_{t-2}) ...``.
Of the ``size`` codes, ``n_obs * n_actions**k * n_obs**(k-1)`` have no padding.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

from crmgrasp._validation import CrmgraspError, integer

__all__ = ["KOrderEncoder", "MAX_K", "MAX_SYMBOLS"]

MAX_K = 10
"""Largest history order: beyond it the state space (at least ``n_obs * n_actions**k``)
is far past anything a table can learn, and encoding grows with ``k``."""

MAX_SYMBOLS = 1_000_000
"""The most discrete observations, or actions, a history encoder accepts."""

History = tuple[int, ...]


@dataclass(frozen=True)
class KOrderEncoder:
    """Encode k-order histories of discrete observations and actions as integers.

    Examples
    --------
    >>> enc = KOrderEncoder(n_obs=24, n_actions=4, k=2)
    >>> enc.size, enc.unpadded_size
    (15000, 9216)
    >>> h = enc.start(5)                     # (o_0, pad, pad, pad)
    >>> h
    (5, 4, 24, 4)
    >>> h = enc.push(h, 2, 17)               # took action 2, observed 17
    >>> h
    (17, 2, 5, 4)
    >>> enc.decode(enc.encode(h)) == h
    True
    """

    n_obs: int
    n_actions: int
    k: int

    def __post_init__(self) -> None:
        integer(self.n_obs, "n_obs", 1, MAX_SYMBOLS)
        integer(self.n_actions, "n_actions", 1, MAX_SYMBOLS)
        integer(self.k, "history order k", 0, MAX_K)

    @cached_property
    def radices(self) -> tuple[int, ...]:
        """Radix of each history slot, most significant first."""
        out = [self.n_obs]
        for i in range(self.k):
            out.append(self.n_actions + 1)
            if i < self.k - 1:
                out.append(self.n_obs + 1)
        return tuple(out)

    @cached_property
    def size(self) -> int:
        """Number of codes, padded histories included."""
        n = 1
        for r in self.radices:
            n *= r
        return n

    @property
    def unpadded_size(self) -> int:
        """Number of conceivable histories without padding."""
        return self.n_obs * self.n_actions**self.k * self.n_obs ** max(self.k - 1, 0)

    def start(self, obs: int) -> History:
        """History at the episode start: ``obs`` followed by padding."""
        self._check_obs(obs)
        pads = []
        for i in range(self.k):
            pads.append(self.n_actions)
            if i < self.k - 1:
                pads.append(self.n_obs)
        return (obs, *pads)

    def push(self, history: History, action: int, obs: int) -> History:
        """History after taking ``action`` and observing ``obs``."""
        if self.k == 0:
            return (obs,)
        return (obs, action, *history[: 2 * self.k - 2])

    def push_code(self, code: int, action: int, obs: int) -> int:
        """``encode(push(decode(code), action, obs))`` by arithmetic on the code: the new
        slots ``(obs, action)`` on top, the oldest two slots dropped,
        ``(obs (nA+1) + action) W + code // ((nO+1)(nA+1))`` with ``W`` the weight of the
        third slot (for ``k = 1`` the whole old code drops; for ``k = 0``, ``obs``)."""
        if self.k == 0:
            return obs
        top = obs * (self.n_actions + 1) + action
        if self.k == 1:
            return top
        return top * self._weight + self.kept(code)

    def kept(self, code: int) -> int:
        """What [`push_code`][] keeps of history ``code``: the code of its newest ``k - 1``
        CRMs and observations, ``code // ((nO+1)(nA+1))`` (0 for ``k <= 1``, whose next
        history keeps nothing). Histories with the same value have the same next history
        after every CRM and observation.

        >>> enc = KOrderEncoder(n_obs=3, n_actions=2, k=2)
        >>> h, g = enc.encode((1, 0, 2, 1)), enc.encode((1, 0, 0, 0))
        >>> enc.kept(h) == enc.kept(g), enc.push_code(h, 1, 2) == enc.push_code(g, 1, 2)
        (True, True)
        """
        if self.k <= 1:
            return 0
        return code // ((self.n_obs + 1) * (self.n_actions + 1))

    @cached_property
    def _weight(self) -> int:
        return self.size // (self.n_obs * (self.n_actions + 1))

    def encode(self, history: History) -> int:
        """Integer code of a history."""
        code = 0
        for value, radix in zip(history, self.radices, strict=True):
            code = code * radix + value
        return code

    def decode(self, code: int) -> History:
        """Inverse of [`encode`][]."""
        if not 0 <= code < self.size:
            raise CrmgraspError(f"history code {code} is outside [0, {self.size})")
        out = []
        for radix in reversed(self.radices):
            code, v = divmod(code, radix)
            out.append(v)
        return tuple(reversed(out))

    def is_padded(self, history: History) -> bool:
        """True if any slot holds the padding value."""
        return any(v == r - 1 for v, r in zip(history[1:], self.radices[1:]))

    def _check_obs(self, obs: int) -> None:
        if not 0 <= obs < self.n_obs:
            raise CrmgraspError(f"observation index {obs} is outside [0, {self.n_obs})")

"""Reference peers from the literature on tabular episodic RL, over the same k-order
states as every learner here: posterior sampling (`PSRL`) and optimism with count
bonuses (`UCBVI`).

Both see the k-order MDP as a finite-horizon problem: horizon ``H`` = the task's step
limit, states = every code of the k-order encoder, and per state-action pair a
categorical distribution over ``n_obs + 1`` outcomes (the next observation, which fixes
the next history, or success, which ends the episode). They keep the counts ``N(s, a,
o)`` and the sum of rewards, and plan once per episode by backward induction over the
whole state space (time-dependent values ``Q_h``, ``h = 0 .. H-1``; ``V_H = 0``; success
has value 0 after it):

``Q_h(s, a) = R(s, a) + sum_o P(o | s, a) V_{h+1}(next(s, a, o))``,
``V_h(s) = max_a Q_h(s, a)``.

* **PSRL** (Osband, Russo and Van Roy, "(More) efficient reinforcement learning via
  posterior sampling", NeurIPS 2013): at each episode's start it draws ``P(. | s, a) ~
  Dirichlet(N(s, a, .) + alpha0 / (n_obs + 1))`` (``alpha0`` pseudo-counts per pair,
  spread evenly) and ``R(s, a) ~ Normal(sum_r / (n + 1), 1 / (n + 1))`` (a unit-variance normal
  prior at 0), solves that MDP and follows its policy for the episode.
* **UCBVI** (Azar, Osband and Munos, "Minimax regret bounds for reinforcement
  learning", ICML 2017), with the Chernoff-Hoeffding bonus without its constants:
  ``b(s, a) = scale * v_max / sqrt(n(s, a))``, ``v_max`` the largest cost of an episode
  (``H`` times the largest cost of a CRM); ``Q_h = min(0, R_hat + P_hat V_{h+1} + b)``, and an untried pair is worth
  0 (the best any CRM can do). It plans on the empirical model plus bonus at each
  episode's start.

The greedy (evaluated) policy of both plans on the point estimate (PSRL: the posterior
mean; UCBVI: the empirical model without bonus), among the CRMs tried in a state (any
where none was). They take no mirror symmetry: the peers see the task as a generic MDP
would. They need the k-order encoder and the horizon (`EpisodicModel.bind`); state tables
are dense (``encoder.size x n_actions x (n_obs + 1)``), which suits k = 1 and 2.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable
from typing import Any

import numpy as np

from crmgrasp._validation import CrmgraspError, positive
from crmgrasp.agents.pooled import HistoryFrame

__all__ = ["PSRL", "UCBVI", "EpisodicModel"]

MAX_TABLE = 20_000_000
"""Largest ``states x actions x outcomes`` table a peer builds (about 160 MB of counts)."""


class EpisodicModel(ABC):
    """Counts, rewards and finite-horizon planning shared by the peers (see the module
    docstring); subclasses choose the model they plan on while acting."""

    name = "episodic"

    def __init__(self, n_actions: int) -> None:
        if isinstance(n_actions, bool) or not isinstance(n_actions, int) or n_actions < 1:
            raise CrmgraspError(f"n_actions must be an integer >= 1, got {n_actions!r}")
        self.n_actions = n_actions
        self.horizon = 0
        self._t = 0
        self._acting: np.ndarray | None = None
        self._greedy: np.ndarray | None = None

    def params(self) -> dict[str, Any]:
        """Hyperparameters, for saving with results."""
        return {}

    def bind(self, frame: HistoryFrame) -> None:
        """Size the tables for the task's k-order states and take its horizon."""
        enc = frame.encoder
        n_obs, n_states = enc.n_obs, enc.size
        cells = n_states * self.n_actions * (n_obs + 1)
        if cells > MAX_TABLE:
            raise CrmgraspError(
                f"{self.name} keeps a dense table of {cells:,} cells here (more than {MAX_TABLE:,}); use a smaller k"
            )
        self.horizon, self.n_obs = frame.horizon, n_obs
        self._obs_stride = n_states // n_obs  # the current observation is a code's top digit
        self.counts = np.zeros((n_states, self.n_actions, n_obs + 1))
        self.reward_sum = np.zeros((n_states, self.n_actions))
        self.visits = np.zeros((n_states, self.n_actions))
        codes = [enc.decode(s) for s in range(n_states)]
        self.next = np.array(
            [[[enc.encode(enc.push(h, a, o)) for o in range(n_obs)] for a in range(self.n_actions)] for h in codes],
            dtype=np.int64,
        ).reshape(n_states, self.n_actions, n_obs)
        self.v_max = float(frame.horizon * frame.max_cost)

    def begin_episode(self) -> None:
        """Plan anew at the episode's first act."""
        self._t = 0
        self._acting = None

    def act(self, state: int, rng: np.random.Generator) -> int:
        """The acting policy's CRM at this step of the episode."""
        if self._acting is None:
            self._acting = self._plan_acting(rng)
        return self._pick(self._acting, state, rng, tried_only=False)

    def greedy(self, state: int, rng: np.random.Generator) -> int:
        """The point estimate's best tried CRM at this step of the episode."""
        if self._greedy is None:
            self._greedy = self._plan(self._mean_model(), self._mean_reward(), self._point_estimate)
        return self._pick(self._greedy, state, rng, tried_only=True)

    def update(
        self, s: int, a: int, r: float, s2: int, a2: int | None, terminal: bool, rng: np.random.Generator
    ) -> None:
        """Count the outcome: the next observation, or success."""
        o = self.n_obs if terminal else self._observation(s2)
        self.counts[s, a, o] += 1.0
        self.reward_sum[s, a] += r
        self.visits[s, a] += 1.0
        self._greedy = None

    def _observation(self, s2: int) -> int:
        return int(s2 // self._obs_stride)

    def _pick(self, q: np.ndarray, state: int, rng: np.random.Generator, *, tried_only: bool) -> int:
        row = q[min(self._t, self.horizon - 1), state]
        self._t += 1
        acts = np.flatnonzero(self.visits[state] > 0) if tried_only else np.arange(self.n_actions)
        if len(acts) == 0:
            acts = np.arange(self.n_actions)
        best = acts[row[acts] == row[acts].max()]
        return int(best[0] if len(best) == 1 else best[rng.integers(len(best))])

    def _mean_model(self) -> np.ndarray:
        n = self.visits[..., None]
        return np.divide(self.counts, n, out=np.zeros_like(self.counts), where=n > 0)

    def _mean_reward(self) -> np.ndarray:
        return np.divide(self.reward_sum, self.visits, out=np.zeros_like(self.reward_sum), where=self.visits > 0)

    def _plan(
        self, p: np.ndarray, r: np.ndarray, adjust: Callable[[np.ndarray], np.ndarray] | None = None
    ) -> np.ndarray:
        """``Q_h`` for ``h = 0 .. H-1`` by backward induction (``(H, S, A)``), each stage's
        values passed through ``adjust`` (bonus, clip, untried pairs) before the next."""
        q = np.empty((self.horizon, *r.shape))
        v = np.zeros(r.shape[0])
        for h in range(self.horizon - 1, -1, -1):
            qh = r + np.einsum("sao,sao->sa", p[..., : self.n_obs], v[self.next])
            q[h] = qh if adjust is None else adjust(qh)
            v = q[h].max(axis=1)
        return q

    def _point_estimate(self, qh: np.ndarray) -> np.ndarray:
        """The greedy policy's stage values: an untried pair is worth ``-v_max``."""
        return np.where(self.visits > 0, qh, -self.v_max)

    @abstractmethod
    def _plan_acting(self, rng: np.random.Generator) -> np.ndarray:
        """``Q_h`` of the model the acting policy follows this episode."""


class PSRL(EpisodicModel):
    """Posterior sampling for reinforcement learning (see the module docstring).

    Parameters
    ----------
    n_actions
        Number of actions.
    alpha0
        Total Dirichlet pseudo-count per pair, spread evenly over its outcomes (0.1 by
        default: the best of 1, 0.1 and 0.01 on paper-box, seeds 0-9, 200 episodes).
    """

    name = "psrl"

    def __init__(self, n_actions: int, alpha0: float = 0.1) -> None:
        super().__init__(n_actions)
        self.alpha0 = positive(alpha0, "alpha0")

    def params(self) -> dict[str, Any]:
        return {"alpha0": self.alpha0}

    def _plan_acting(self, rng: np.random.Generator) -> np.ndarray:
        conc = self.counts + self.alpha0 / (self.n_obs + 1)
        g = rng.gamma(conc)
        total = g.sum(axis=2, keepdims=True)
        # a draw whose every gamma variate underflows to 0 (tiny concentrations) takes the mean
        p = np.where(total > 0, g / np.where(total > 0, total, 1.0), conc / conc.sum(axis=2, keepdims=True))
        r = rng.normal(self.reward_sum / (self.visits + 1.0), 1.0 / np.sqrt(self.visits + 1.0))
        return self._plan(p, r)

    def _mean_model(self) -> np.ndarray:
        conc = self.counts + self.alpha0 / (self.n_obs + 1)
        return conc / conc.sum(axis=2, keepdims=True)

    def _mean_reward(self) -> np.ndarray:
        return self.reward_sum / (self.visits + 1.0)


class UCBVI(EpisodicModel):
    """Upper-confidence value iteration with a Hoeffding bonus (see the module docstring).

    Parameters
    ----------
    n_actions
        Number of actions.
    scale
        Bonus factor: ``b = scale * v_max / sqrt(n)`` (0.03 by default: the best of 1, 0.3,
        0.1 and 0.03 on paper-box, seeds 0-9, 200 episodes; 1 is the paper's form without
        its constants and log factor).
    """

    name = "ucbvi"

    def __init__(self, n_actions: int, scale: float = 0.03) -> None:
        super().__init__(n_actions)
        self.scale = positive(scale, "scale")

    def params(self) -> dict[str, Any]:
        return {"scale": self.scale}

    def _plan_acting(self, rng: np.random.Generator) -> np.ndarray:
        bonus = self.scale * self.v_max / np.sqrt(np.maximum(self.visits, 1.0))
        tried = self.visits > 0

        def optimistic(qh: np.ndarray) -> np.ndarray:
            return np.where(tried, np.minimum(qh + bonus, 0.0), 0.0)

        return self._plan(self._mean_model(), self._mean_reward(), optimistic)

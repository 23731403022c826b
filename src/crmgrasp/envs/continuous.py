"""The paper's full action space as Gymnasium environments: a contact pair and a real offset.

[`ContinuousCRMEnv`][] is [`CRMGraspEnv`][crmgrasp.envs.single.CRMGraspEnv] with the action
``(pair, r)``: CRM range ``task.crm_ranges[pair]`` at offset ``r`` (metres; one number in
the plane, two in space). [`FlatCRMAction`][] maps one ``Box(-1, 1)`` vector onto that
action, so that agents of continuous control (Stable-Baselines3's SAC or PPO) run on it
unchanged. The registered ids end in ``Continuous-v0``
([`CONTINUOUS_ENVS`][crmgrasp.envs.single.CONTINUOUS_ENVS]).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from crmgrasp._validation import CrmgraspError, shown
from crmgrasp.envs.single import CONTINUOUS_ENVS, CRMGraspEnv
from crmgrasp.model.actions import CRMRange
from crmgrasp.tasks import Task

__all__ = ["ContinuousCRMEnv", "FlatCRMAction", "PairOffsetActions", "flat_action", "CONTINUOUS_ENVS"]


def _read_only_view(buffer: np.ndarray) -> np.ndarray:
    """A read-only view of ``buffer``: writes to the buffer show through it."""
    view = buffer.view()
    view.flags.writeable = False
    return view


class PairOffsetActions:
    """A task's continuous action space: the ``Dict`` space, and the one check (and clip) of
    an action, single and batched (see [`ContinuousCRMEnv`][] for the rule)."""

    def __init__(self, task: Task) -> None:
        self.ranges = task.crm_ranges
        self.model = task.model
        self.dim = task.model.offset_dim
        low = np.min([rg.low for rg in self.ranges], axis=0)
        high = np.max([rg.high for rg in self.ranges], axis=0)
        r_space = spaces.Box(low, high, shape=(self.dim,), dtype=np.float64)
        self.space = spaces.Dict({"pair": spaces.Discrete(len(self.ranges)), "r": r_space})
        self._low, self._high = low.tolist(), high.tolist()
        index = task.model.labels.index
        self._buffers = [np.array([[index(rg.c), index(rg.f), *rg.low]], dtype=np.float64) for rg in self.ranges]
        self.rows = [_read_only_view(b) for b in self._buffers]  # what the kernels take (`row`)
        self._table = np.concatenate(self.rows)  # per pair: c, f, low...
        self._range_low = np.array([rg.low for rg in self.ranges])
        self._range_high = np.array([rg.high for rg in self.ranges])
        self._shape = (self.dim,)
        self.uniform = all(rg.low == self.ranges[0].low and rg.high == self.ranges[0].high for rg in self.ranges)

    def one(self, action: Any) -> tuple[int, list[float]]:
        """``(pair, offsets)`` of one action, checked, the offsets clipped into the pair's range."""
        if (
            (type(action) is not dict and not isinstance(action, Mapping))
            or len(action) != 2
            or "pair" not in action
            or "r" not in action
        ):
            raise CrmgraspError(f"action must be a dict with keys 'pair' and 'r' only, got {action!r:.80}")
        pair, r = action["pair"], action["r"]
        if type(pair) is not int:
            if (
                not isinstance(pair, (np.integer, np.ndarray))
                or np.ndim(pair) != 0
                or np.asarray(pair).dtype.kind not in "iu"
            ):
                raise CrmgraspError(f"action['pair'] must be an integer in [0, {len(self.ranges)}), got {pair!r}")
            pair = int(pair)
        if not 0 <= pair < len(self.ranges):
            raise CrmgraspError(f"action['pair'] must be an integer in [0, {len(self.ranges)}), got {pair}")
        values = r.tolist() if type(r) is np.ndarray and r.shape == self._shape else self._offsets(r)
        if self.dim == 1:  # the planar offset, the common case: no loop
            if not self._low[0] <= values[0] <= self._high[0]:  # also NaN
                self._out_of_range(values)
        elif not all(lo <= v <= hi for v, lo, hi in zip(values, self._low, self._high)):
            self._out_of_range(values)
        if not self.uniform:
            values = list(self.ranges[pair].clip(values))
        return pair, values

    def _out_of_range(self, values: list[float]) -> None:
        """The one-line error for the first offset that is not finite or not in its range."""
        for v, lo, hi in zip(values, self._low, self._high):
            if not lo <= v <= hi:
                raise CrmgraspError(f"action['r'] = {v!r} must be finite and within [{lo:g}, {hi:g}] m")

    def _offsets(self, r: Any) -> list[float]:
        """``r`` as ``d`` numbers, else a one-line error."""
        try:
            values = [float(v) for v in np.asarray(r, dtype=np.float64).reshape(-1)]
        except (TypeError, ValueError):
            raise CrmgraspError(f"action['r'] must be {self.dim} number(s), got {r!r:.60}") from None
        if len(values) != self.dim or np.ndim(r) > 1:
            raise CrmgraspError(f"action['r'] must be {self.dim} number(s), got shape {np.shape(r)}")
        return values

    def row(self, pair: int, values: list[float]) -> np.ndarray:
        """The action-table row ``[[c, f, r...]]`` of a checked action, in a buffer of its pair
        that the next call overwrites."""
        buffer = self._buffers[pair]
        if self.dim == 1:
            buffer[0, 2] = values[0]
        else:
            buffer[0, 2:] = values
        return self.rows[pair]  # the buffer, read-only as the task's table (`Kernel.action_table`)

    def batch(self, actions: Any, n: int) -> np.ndarray:
        """The action table ``(n, 2 + d)`` of a batch ``{"pair": (n,), "r": (n, d)}``, checked
        and clipped as [`one`][] (one-line errors naming the problem)."""
        if not isinstance(actions, Mapping) or len(actions) != 2 or "pair" not in actions or "r" not in actions:
            keys = list(actions) if isinstance(actions, Mapping) else type(actions).__name__
            raise CrmgraspError(f"actions must be a dict with keys 'pair' and 'r' only, got {keys}")
        pair, r = np.asarray(actions["pair"]), np.asarray(actions["r"])
        if pair.shape != (n,) or pair.dtype.kind not in "iu":
            raise CrmgraspError(f"actions['pair'] must be {n} integers, got shape {pair.shape} dtype {pair.dtype}")
        if pair.min() < 0 or pair.max() >= len(self.ranges):
            raise CrmgraspError(f"actions['pair'] must be in [0, {len(self.ranges)})")
        if r.shape != (n, self.dim) or r.dtype.kind not in "iuf":
            raise CrmgraspError(f"actions['r'] must have shape ({n}, {self.dim}), got {r.shape}")
        if not np.all((r >= self._low) & (r <= self._high)):  # also NaN
            raise CrmgraspError(f"actions['r'] must be finite and within {self._low} to {self._high} m")
        table = self._table[pair]
        table[:, 2:] = r if self.uniform else np.clip(r, self._range_low[pair], self._range_high[pair])
        table.flags.writeable = False  # as the task's table (`Kernel.action_table`)
        return table

    def crm(self, pair: int, values: Any) -> Any:
        """The CRM of a checked action."""
        return self.model.range_crm(self.ranges[pair], values)


class ContinuousCRMEnv(CRMGraspEnv):
    """A hand grasping an unseen object by CRMs whose offset it chooses.

    ## Action Space
    ``Dict({"pair": Discrete(P), "r": Box(low, high, (d,), float64)})``: execute CRM range
    ``task.crm_ranges[pair]`` at offset ``r`` (metres, ``d = 1`` in the plane, 2 in space).
    By default the ranges are every ordered pair of the hand's contacts over the offsets
    within its reach (``P = 4``, ``r`` in ``[-0.16, 0.16]`` m for paper-box: the paper's
    ``A = C x C x [-r_max, r_max]``); a task may declare its own (``Task.ranges``). The
    ``r`` box is the smallest box holding every range; an ``r`` inside the box but outside
    the chosen pair's range is moved into that range coordinate by coordinate (the one
    clip, here), and an ``r`` outside the box or not finite is a one-line error.

    ## Observation Space, Rewards, Starting State, Episode End, Arguments
    As [`CRMGraspEnv`][crmgrasp.envs.single.CRMGraspEnv] (``task`` also as a registered name).

    ## Version History
    * v0: initial version.
    """

    def __init__(self, task: Task | str = "paper-box", **kwargs: Any) -> None:
        super().__init__(task, **kwargs)  # render_mode, backend, exact_friction: as CRMGraspEnv's
        self.actions = PairOffsetActions(self.task)
        self.ranges = self.actions.ranges
        self.action_space = self.actions.space  # type: ignore[assignment]

    def action_row(self, action: Any) -> np.ndarray:
        """The action-table row ``[[c, f, r...]]`` of ``action`` (checked; see the class), in a
        buffer of its pair that the next call overwrites."""
        return self.actions.row(*self.actions.one(action))

    def step(self, action: Any) -> tuple[dict[str, Any], float, bool, bool, dict[str, Any]]:
        """Execute CRM range ``action["pair"]`` at offset ``action["r"]``
        ([`crmgrasp.kernels.Kernel.step_row`][])."""
        if self._state is None:
            raise CrmgraspError("call reset() before step()")
        pair, values = self.actions.one(action)
        row = self.actions.row(pair, values)
        self._last = (self._state, (pair, values))
        res = self.kernel.step_row(self._state, row, self.np_random, checked=True)  # the pair and offset checked above
        obs, info = self._emit(res)
        return obs, res.reward, res.terminated, res.truncated, info

    def crm_of(self, action: Any) -> Any:
        """The CRM of a stepped action ``(pair, offsets)``."""
        return self.actions.crm(*action)


class FlatCRMAction(gym.ActionWrapper[dict[str, Any], np.ndarray, dict[str, Any]], gym.utils.RecordConstructorArgs):
    """[`ContinuousCRMEnv`][]'s action as one vector ``u`` in ``Box(-1, 1, (1 + d,), float32)``.

    ``u[0]`` chooses the pair: ``[-1, 1]`` cut into ``P`` equal parts, part ``i`` for
    pair ``i`` (``u[0] = 1`` in the last); ``u[1:]`` map affinely onto the chosen pair's
    range, ``-1`` to ``low`` and ``1`` to ``high``. A ``u`` of the wrong shape, not finite
    or outside ``[-1, 1]`` is a one-line error (Stable-Baselines3 clips its actions into the
    space before stepping).
    """

    def __init__(self, env: gym.Env) -> None:
        gym.utils.RecordConstructorArgs.__init__(self)
        gym.ActionWrapper.__init__(self, env)
        inner = env.unwrapped
        if not isinstance(inner, ContinuousCRMEnv):
            raise CrmgraspError(f"FlatCRMAction wraps a ContinuousCRMEnv, got {type(inner).__name__}")
        self._ranges = inner.ranges
        self.action_space = spaces.Box(-1.0, 1.0, shape=(1 + inner.actions.dim,), dtype=np.float32)  # type: ignore[assignment]

    def action(self, action: Any) -> dict[str, Any]:
        """The ``{"pair", "r"}`` action of ``u`` (see the class)."""
        pair, r = flat_action(self._ranges, action)
        return {"pair": pair, "r": r}


def flat_action(ranges: Sequence[CRMRange], u: np.ndarray) -> tuple[int, np.ndarray]:
    """The pair and offsets of a flat action ``u`` (``1 + d`` numbers in ``[-1, 1]``) over
    ``ranges`` ([`FlatCRMAction`][]): ``u[0]`` picks range ``min(floor((u[0] + 1) P / 2), P - 1)``,
    ``u[1:]`` map affinely onto its box; a ``u`` of another shape, outside ``[-1, 1]`` or not
    finite is a one-line error."""
    listed = isinstance(ranges, Sequence) and not isinstance(ranges, (str, bytes)) and len(ranges) > 0
    if not listed or not all(isinstance(rg, CRMRange) for rg in ranges):
        raise CrmgraspError(f"ranges must be a non-empty list of CRMRange, got {shown(ranges)}")
    dim = len(ranges[0].low)
    try:
        u = np.asarray(u, dtype=np.float64)
    except (TypeError, ValueError, OverflowError):
        raise CrmgraspError(f"the flat action must be {1 + dim} numbers, got {shown(u)}") from None
    if u.shape != (1 + dim,):
        raise CrmgraspError(f"the flat action must have shape ({1 + dim},), got {u.shape}")
    if not np.all((u >= -1.0) & (u <= 1.0)):  # also NaN
        raise CrmgraspError(f"the flat action must be finite and within [-1, 1], got {u.tolist()}")
    n = len(ranges)
    pair = min(int((u[0] + 1.0) * 0.5 * n), n - 1)
    rg = ranges[pair]
    low, high = np.asarray(rg.low), np.asarray(rg.high)
    return pair, np.minimum(low + (u[1:] + 1.0) * 0.5 * (high - low), high)

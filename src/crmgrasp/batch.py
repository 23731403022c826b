"""Vectorised CRM execution over many independent configurations.

Configurations use the ``(N, 8)`` layout ``[ax, ay, anx, any, bx, by, bnx, bny]``;
a CRM per row is given by integer arrays ``c`` and ``f`` (0 = a, 1 = b) and a float
array ``r``. Every function evaluates the same floating-point expressions in the
same order as the scalar path in :mod:`crmgrasp.hand`, so the results agree bit
for bit (the tests check this on random cases).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._validation import CrmgraspError
from .contacts import configs_to_array
from .geometry import Shape
from .hand import CRM, Hand
from .sensing import Error

__all__ = ["crm_arrays", "feasible_batch", "execute_batch"]

F64 = NDArray[np.float64]


def crm_arrays(crms: list[CRM] | tuple[CRM, ...]) -> tuple[NDArray[np.int64], NDArray[np.int64], F64]:
    """Split CRMs into ``(c, f, r)`` arrays for :func:`execute_batch`."""
    c = np.array([0 if m.c == "a" else 1 for m in crms], dtype=np.int64)
    f = np.array([0 if m.f == "a" else 1 for m in crms], dtype=np.int64)
    r = np.array([m.r for m in crms], dtype=np.float64)
    return c, f, r


def _check_configs(configs: ArrayLike, name: str) -> F64:
    arr = np.asarray(configs, dtype=np.float64)
    if isinstance(configs, (list, tuple)) and configs and hasattr(configs[0], "a"):
        arr = configs_to_array(list(configs))  # type: ignore[arg-type]
    if arr.ndim != 2 or arr.shape[1] != 8:
        raise CrmgraspError(f"{name} must have shape (N, 8), got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise CrmgraspError(f"{name} must be finite")
    return arr


def feasible_batch(obj: Shape, hand: Hand, configs: F64) -> NDArray[np.int8]:
    """Vectorised :func:`crmgrasp.hand.feasible`: an :class:`Error` code per row."""
    cf = configs
    dx, dy = cf[:, 4] - cf[:, 0], cf[:, 5] - cf[:, 1]
    dist = np.sqrt(dx * dx + dy * dy)
    with np.errstate(all="ignore"):
        ux, uy = dy / dist, -dx / dist
    tol = hand.palm_normal_tol
    facing = (cf[:, 2] * ux + cf[:, 3] * uy > tol) | (cf[:, 6] * ux + cf[:, 7] * uy > tol)
    palm = np.stack(
        [0.5 * (cf[:, 0] + cf[:, 4]) + hand.palm_depth * ux, 0.5 * (cf[:, 1] + cf[:, 5]) + hand.palm_depth * uy],
        axis=1,
    )
    out = np.zeros(len(cf), dtype=np.int8)
    check = dist > 0.0
    blocked = np.zeros(len(cf), dtype=bool)
    blocked[check] = obj.contains_batch(palm[check]) if np.any(check) else blocked[check]
    out[(dist == 0.0) | facing | blocked] = Error.PALM
    out[dist > hand.aperture] = Error.APERTURE
    return out


def execute_batch(
    obj: Shape,
    hand: Hand,
    configs: ArrayLike,
    c: ArrayLike,
    f: ArrayLike,
    r: ArrayLike,
    sensed: ArrayLike | None = None,
) -> tuple[F64, NDArray[np.int8]]:
    """Execute one CRM per row; returns new configurations ``(N, 8)`` and error codes ``(N,)``.

    Rows whose CRM fails keep their configuration (SPEC section 3, step 7).
    ``sensed`` (same layout) supplies the frame for the goal lines; it defaults
    to ``configs``.
    """
    cfg = _check_configs(configs, "configs")
    sen = cfg if sensed is None else _check_configs(sensed, "sensed configs")
    n = len(cfg)
    ci = np.broadcast_to(np.asarray(c, dtype=np.int64), (n,))
    fi = np.broadcast_to(np.asarray(f, dtype=np.int64), (n,))
    rr = np.broadcast_to(np.asarray(r, dtype=np.float64), (n,))
    if sen.shape != cfg.shape:
        raise CrmgraspError(f"sensed configs must have shape {cfg.shape}, got {sen.shape}")
    if np.any((ci < 0) | (ci > 1) | (fi < 0) | (fi > 1)):
        raise CrmgraspError("contact indices c and f must be 0 (a) or 1 (b)")
    if not np.all(np.isfinite(rr)) or np.any(np.abs(rr) > hand.r_max):  # type: ignore[operator]
        raise CrmgraspError(f"CRM offsets r must be finite and within r_max = {hand.r_max:g}")
    rows = np.arange(n)
    fcol, scol = 4 * fi, 4 * (1 - ci)
    fx, fy = sen[rows, fcol], sen[rows, fcol + 1]
    fnx, fny = sen[rows, fcol + 2], sen[rows, fcol + 3]
    sx, sy = cfg[rows, scol], cfg[rows, scol + 1]
    # 1-2. goal line and its chord within the aperture of the stationary contact
    bx, by = fx + rr * fny, fy - rr * fnx
    wx, wy = bx - sx, by - sy
    qa = fnx * fnx + fny * fny
    qb = wx * fnx + wy * fny
    qc = wx * wx + wy * wy - hand.aperture * hand.aperture
    disc = qb * qb - qa * qc
    reach = disc >= 0.0
    with np.errstate(all="ignore"):
        root = np.sqrt(disc)
    t_lo, t_hi = (-qb - root) / qa, (-qb + root) / qa
    # 3-4. start point, approach, first entry
    same = ci == fi
    t0, t1 = np.where(same, t_lo, t_hi), np.where(same, t_hi, t_lo)
    start = np.stack([bx + t0 * fnx, by + t0 * fny], axis=1)
    sign = np.where(same, 1.0, -1.0)
    direction = np.stack([sign * fnx, sign * fny], axis=1)
    ok = reach.copy()
    ok[reach] = ~obj.contains_batch(start[reach]) if np.any(reach) else ok[reach]
    u, pts, normals = obj.ray_entry_batch(start, direction, np.abs(t1 - t0))
    entered = ok & np.isfinite(u)
    # 5. new contact; 6. palm
    new = cfg.copy()
    mcol = 4 * ci[entered]
    erows = rows[entered]
    new[erows, mcol] = pts[entered, 0]
    new[erows, mcol + 1] = pts[entered, 1]
    new[erows, mcol + 2] = normals[entered, 0]
    new[erows, mcol + 3] = normals[entered, 1]
    errors = np.full(n, Error.APERTURE, dtype=np.int8)
    if np.any(entered):
        errors[entered] = feasible_batch(obj, hand, new[entered])
    # 7. any error leaves the configuration unchanged
    failed = errors != Error.NONE
    new[failed] = cfg[failed]
    return new, errors

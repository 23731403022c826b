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

from . import _numba
from ._columns import execute_convex
from ._validation import CrmgraspError
from .contacts import configs_to_array
from .geometry import Polygon, Shape
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
    c = configs
    with np.errstate(all="ignore"):
        return _feasible(obj, hand, c[:, 0], c[:, 1], c[:, 2], c[:, 3], c[:, 4], c[:, 5], c[:, 6], c[:, 7])


def _feasible(
    obj: Shape, hand: Hand, ax: F64, ay: F64, anx: F64, any_: F64, bx: F64, by: F64, bnx: F64, bny: F64
) -> NDArray[np.int8]:
    """Feasibility on columns (same expressions as the scalar path)."""
    dx, dy = bx - ax, by - ay
    dist = np.sqrt(dx * dx + dy * dy)
    ux, uy = dy / dist, -dx / dist
    tol = hand.palm_normal_tol
    facing = (anx * ux + any_ * uy > tol) | (bnx * ux + bny * uy > tol)
    h = hand.palm_depth
    blocked = obj.contains_xy(0.5 * (ax + bx) + h * ux, 0.5 * (ay + by) + h * uy)
    out = np.where((dist == 0.0) | facing | blocked, np.int8(Error.PALM), np.int8(Error.NONE))
    return np.where(dist > hand.aperture, np.int8(Error.APERTURE), out).astype(np.int8)


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
    cols = np.ascontiguousarray(cfg.T)
    scols = cols if sensed is None else np.ascontiguousarray(sen.T)
    with np.errstate(all="ignore"):
        new, errors = execute_columns(obj, hand, cols, scols, ci == 1, fi == 1, rr)
    return np.ascontiguousarray(new.T), errors


def execute_columns(
    obj: Shape, hand: Hand, cfg: F64, sen: F64, c_is_b: NDArray[np.bool_], f_is_b: NDArray[np.bool_], rr: F64
) -> tuple[F64, NDArray[np.int8]]:
    """The kernel of :func:`execute_batch` on column blocks of shape ``(8, N)`` (row
    ``k`` is column ``k`` of the ``(N, 8)`` layout), without input checks: for
    trusted callers such as the vector environment. Returns the new ``(8, N)``
    block and the error codes. Call inside ``np.errstate(all="ignore")``.

    Polygons use the compiled kernel when numba is installed, convex ones otherwise
    :func:`crmgrasp._columns.execute_convex` (same results)."""
    if _numba.AVAILABLE and isinstance(obj, Polygon):
        new = np.empty_like(cfg)
        errors = np.empty(cfg.shape[1], dtype=np.int8)
        _numba.execute_rows(
            np.ascontiguousarray(cfg),
            np.ascontiguousarray(sen),
            np.ascontiguousarray(c_is_b),
            np.ascontiguousarray(f_is_b),
            np.ascontiguousarray(rr, dtype=np.float64),
            obj._edge_arrays,
            obj.convex,
            hand.aperture,
            hand.palm_depth,
            hand.palm_normal_tol,
            new,
            errors,
        )
        return new, errors
    if isinstance(obj, Polygon) and obj.convex:
        return execute_convex(
            obj._columns, hand.aperture, hand.palm_depth, hand.palm_normal_tol, cfg, sen, c_is_b, f_is_b, rr
        )
    # 1-2. goal line in the sensed frame of f; chord within the aperture of the stationary contact
    fx = np.where(f_is_b, sen[4], sen[0])
    fy = np.where(f_is_b, sen[5], sen[1])
    fnx = np.where(f_is_b, sen[6], sen[2])
    fny = np.where(f_is_b, sen[7], sen[3])
    sx = np.where(c_is_b, cfg[0], cfg[4])
    sy = np.where(c_is_b, cfg[1], cfg[5])
    bx, by = fx + rr * fny, fy - rr * fnx
    wx, wy = bx - sx, by - sy
    qa = fnx * fnx + fny * fny
    qb = wx * fnx + wy * fny
    qc = wx * wx + wy * wy - hand.aperture * hand.aperture
    disc = qb * qb - qa * qc
    root = np.sqrt(disc)
    t_lo, t_hi = (-qb - root) / qa, (-qb + root) / qa
    # 3-4. start point (inside: aperture error), approach, first entry
    same = c_is_b == f_is_b
    t0, t1 = np.where(same, t_lo, t_hi), np.where(same, t_hi, t_lo)
    x0, y0 = bx + t0 * fnx, by + t0 * fny
    sign = np.where(same, 1.0, -1.0)
    ok = (disc >= 0.0) & ~obj.contains_xy(x0, y0)
    u, px, py, nx, ny = obj.ray_entry_xy(x0, y0, sign * fnx, sign * fny, np.abs(t1 - t0))
    entered = ok & (u != np.inf)
    # 5. the new contact replaces the mover's columns
    ma, mb = entered & ~c_is_b, entered & c_is_b
    cols = [
        np.where(ma, px, cfg[0]),
        np.where(ma, py, cfg[1]),
        np.where(ma, nx, cfg[2]),
        np.where(ma, ny, cfg[3]),
        np.where(mb, px, cfg[4]),
        np.where(mb, py, cfg[5]),
        np.where(mb, nx, cfg[6]),
        np.where(mb, ny, cfg[7]),
    ]
    # 6. palm; 7. any error leaves the configuration unchanged
    errors = np.where(entered, _feasible(obj, hand, *cols), np.int8(Error.APERTURE)).astype(np.int8)
    new = np.where(errors != Error.NONE, cfg, np.stack(cols))
    return new, errors

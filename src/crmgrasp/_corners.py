"""Corner starts (SPEC section 7) drawn in vectorised rounds: the tighter per-corner
proposal and the acceptance filter behind :meth:`crmgrasp.tasks.CornerStarts.batch`."""

from __future__ import annotations

import math

import numpy as np

from . import _numba
from ._columns import pair_checks
from .geometry import Polygon
from .hand import Hand
from .quality import min_friction_xy

__all__ = ["_corner_boxes", "_corner_proposal", "_corner_candidates"]


def _corner_boxes(obj: Polygon, aperture: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
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
    e = obj._edge_arrays
    nv = len(e)
    c_in, c_out = np.ones(nv), np.ones(nv)
    for k in range(nv):
        ki = (k - 1) % nv
        l_in, l_out = math.sqrt(e[ki, 4]), math.sqrt(e[k, 4])
        cos = -(e[ki, 2] * e[k, 2] + e[ki, 3] * e[k, 3]) / (l_in * l_out)
        s = 1.0 if cos <= 0.0 else abs(e[ki, 2] * e[k, 3] - e[ki, 3] * e[k, 2]) / (l_in * l_out)
        if s > 0.0:
            c_in[k] = min(1.0, aperture / (s * l_in) * (1.0 + 1e-9))
            c_out[k] = min(1.0, aperture / (s * l_out) * (1.0 + 1e-9))
    w = np.cumsum(c_in * c_out)
    return w / w[-1], c_in, c_out


def _corner_proposal(w: np.ndarray, cum: np.ndarray, c_in: np.ndarray, c_out: np.ndarray) -> np.ndarray:
    """Uniforms ``w`` (``(4, m)``) to candidates in :func:`_corner_candidates`'s
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


def _corner_candidates(obj: Polygon, hand: Hand, mu_goal: float, u: np.ndarray) -> np.ndarray:
    """The accepted corner-start candidates of the uniforms ``u`` (``(4, m)``: corner,
    fraction in, fraction out, coin), in order, as an ``(8, k)`` block.

    The compiled filter (numba) and this numpy one make the same decisions: the
    numpy one tests the unlabelled pair (incoming-side contact first) with
    :func:`~crmgrasp._columns.pair_checks` and the label-symmetric
    :func:`~crmgrasp.quality.min_friction_xy`, and applies the coin at the end."""
    e = obj._edge_arrays
    if _numba.AVAILABLE:
        got = np.empty((8, u.shape[1]))
        count = _numba.corner_candidates(
            u, e, obj.convex, hand.aperture, hand.palm_depth, hand.palm_normal_tol, mu_goal, got
        )
        return got[:, :count]
    nv = len(e)
    k = (u[0] * nv).astype(np.intp)
    e_in = e[(np.arange(nv) - 1) % nv].T.copy()  # per corner: its incoming side's row, then its outgoing side's
    e_out = e.T.copy()
    ins = (e_in[0].take(k) + u[1] * e_in[2].take(k), e_in[1].take(k) + u[1] * e_in[3].take(k))
    outs = (e_out[0].take(k) + u[2] * e_out[2].take(k), e_out[1].take(k) + u[2] * e_out[3].take(k))
    first = (*ins, e_in[5].take(k), e_in[6].take(k))
    second = (*outs, e_out[5].take(k), e_out[6].take(k))
    a_first = u[3] < 0.5
    with np.errstate(all="ignore"):
        q = np.where(a_first, 1.0, -1.0)  # b - a = q (second - first)
        dist, palm = pair_checks(obj.contains_xy, hand.palm_depth, hand.palm_normal_tol, first, second, q)
        mu = min_friction_xy(outs[0] - ins[0], outs[1] - ins[1], *first[2:], *second[2:])
    ok = (u[1] > 0.0) & (u[2] > 0.0) & (dist <= hand.aperture) & ~palm & (mu > mu_goal)
    keep = np.flatnonzero(ok)
    pair = np.empty((8, len(keep)))
    for row, col in zip(pair, first + second):
        col.take(keep, out=row)
    flip = ~a_first.take(keep)
    out = np.empty_like(pair)
    out[:4] = np.where(flip, pair[4:], pair[:4])
    out[4:] = np.where(flip, pair[:4], pair[4:])
    return out

"""Kernels: the one seam between the model's rules and their fast evaluation.

[`kernel_for`][] is the only place that chooses a path, from the backend asked
for, the shape of the task's object and its sensing noise:

===========================  ==========================  ===============================
backend                      object                      kernel
===========================  ==========================  ===============================
``"reference"``              a planar shape              ``ReferenceKernel``
``"auto"``                   a shape without a kernel    ``ReferenceKernel``
``"auto"``, ``"numba"``      polygon, sensing noise      ``PolygonKernel``
``"auto"``, ``"numba"``      polygon, noise-free         ``FusedPolygonKernel``
``"auto"``, ``"numba"``      polygon, three+, noise      ``FingersKernel``
``"auto"``, ``"numba"``      polygon, three+, noise-free ``FusedFingersKernel``
``"reference"``              a solid (spatial task)      ``SpatialKernel``
``"auto"``, ``"numba"``      a solid, noise-free         ``FusedSpatialKernel``
``"auto"``                   a solid, sensing noise      ``SpatialKernel``
``"reference"``              a solid, three+ contacts    ``SpatialKernel``
``"auto"``, ``"numba"``      a solid, three+, noise-free ``FusedFingersSpatialKernel``
``"auto"``                   a solid, three+, noise      ``FingersSpatialKernel``
any                          a family (one per episode)  ``FamilyKernel`` over the above
===========================  ==========================  ===============================

A solid is a convex polyhedron, a cylinder or a closed triangle mesh (the compiled
spatial kernels take all three). A family task (`crmgrasp.tasks.Task.family`) gets a
[`FamilyKernel`][crmgrasp.kernels.family.FamilyKernel], which builds the kernel of each
episode's object by this same rule (``"numba"`` with a disc family is an error on
the first disc).

Every kernel gives the reference kernel's results bit for bit (the tests check
each path). The compiled kernels ([`crmgrasp.kernels.polygon`][]) import numba
when first chosen, not when `crmgrasp` is imported.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from crmgrasp._validation import CrmgraspError, float_array, shown
from crmgrasp.kernels.base import BatchStep, Kernel
from crmgrasp.kernels.reference import ReferenceKernel
from crmgrasp.model.contact_model import ContactModel
from crmgrasp.model.contacts import Config, Grip
from crmgrasp.model.geometry import Polygon, Shape
from crmgrasp.model.hand import CRM, Hand
from crmgrasp.sim import OneStep
from crmgrasp.tasks import Task, checked_task

__all__ = [
    "BACKENDS",
    "Backend",
    "FRICTIONS",
    "PATHS",
    "kernel_for",
    "compiled_rules",
    "execute_batch",
    "Kernel",
    "OneStep",
    "BatchStep",
    "ReferenceKernel",
]

Backend = Literal["auto", "numba", "reference"]
BACKENDS: tuple[str, ...] = ("auto", "numba", "reference")
"""``"auto"``: the compiled kernel where one exists, else the reference;
``"numba"``: the compiled kernel (an error where none exists);
``"reference"``: the readable rules, row by row."""

FRICTIONS: tuple[str, ...] = ("exact", "decided")
"""What a kernel's ``min_friction`` is: the least friction, or one that decides the grasp
([`kernel_for`][])."""


def kernel_for(task: Task, backend: str = "auto", friction: str = "exact") -> Kernel:
    """The kernel that steps ``task`` on ``backend`` (see the module docstring): a family's
    kernel over per-object kernels, else the path [`PATHS`][] lists for the task's
    contact model (``task.model.kind``).

    ``friction`` (one of [`FRICTIONS`][]) says what each result's ``min_friction`` must be:
    ``"exact"``, the configuration's least friction; ``"decided"``, any friction that decides
    the grasp as the least friction does (at most ``mu_goal`` exactly when it is). Every
    observation, error, reward and episode end is the same either way; a kernel whose least
    friction is cheap returns the exact one in both. A tripod's compiled step then stops its
    least friction once the grasp is decided (`crmgrasp.kernels._closure_jit.decided_friction`)."""
    checked_task(task, "kernel_for")
    if backend not in BACKENDS:
        raise CrmgraspError(f"unknown backend {shown(backend)}; choose one of {', '.join(BACKENDS)}")
    if friction not in FRICTIONS:
        raise CrmgraspError(f"unknown friction {friction!r}; choose one of {', '.join(FRICTIONS)}")
    if task.family is not None:
        from crmgrasp.kernels.family import FamilyKernel

        return FamilyKernel(task, lambda instance: kernel_for(instance, backend, friction))
    try:
        choose = PATHS[task.model.kind]
    except KeyError:
        raise CrmgraspError(f"no kernel for the contact model {task.model.kind!r}") from None
    return choose(task, backend, friction)


def _planar(task: Task, backend: str, friction: str) -> Kernel:
    """Planar model on a polygon compiled (fused when noise-free; three or more contacts on
    the fingers kernels), else the reference rules; the least friction is exact on every
    path (a few microseconds)."""
    compiled = isinstance(task.obj, Polygon)
    if backend == "reference" or (backend == "auto" and not compiled):
        return ReferenceKernel(task)
    if not compiled:
        raise CrmgraspError(f"no compiled kernel for a {type(task.obj).__name__}; use backend 'auto' or 'reference'")
    if task.model.n_contacts > 2:
        from crmgrasp.kernels.fingers import FingersKernel, FusedFingersKernel

        return FingersKernel(task) if task.noise.active else FusedFingersKernel(task)
    from crmgrasp.kernels.polygon import FusedPolygonKernel, PolygonKernel

    return PolygonKernel(task) if task.noise.active else FusedPolygonKernel(task)


def _spatial(task: Task, backend: str, friction: str) -> Kernel:
    """Spatial model on a polyhedron, a cylinder or a mesh without noise: compiled and fused
    (two contacts, or three and more, which alone take ``friction`` = ``"decided"``: the
    least friction is exact elsewhere); with noise the reference rules, for three and more
    contacts with their least friction compiled."""
    from crmgrasp.kernels.spatial import FusedSpatialKernel, SpatialKernel

    if backend == "numba" and task.noise.active:
        raise CrmgraspError("the compiled spatial kernel is noise-free; use backend 'auto' or 'reference'")
    if backend == "reference":
        return SpatialKernel(task)
    slow = task.noise.active
    if task.model.n_contacts > 2:
        from crmgrasp.kernels.closure import FingersSpatialKernel
        from crmgrasp.kernels.fingers3d import FusedFingersSpatialKernel

        return FingersSpatialKernel(task) if slow else FusedFingersSpatialKernel(task, decided=friction == "decided")
    return SpatialKernel(task) if slow else FusedSpatialKernel(task)


def compiled_rules(task: Task) -> Task:
    """``task`` with each rule that the kernels compile for its model handed to that model:
    today the least friction of three or more contacts, spatial
    ([`crmgrasp.kernels.closure.with_compiled_least_friction`][]) and planar
    ([`crmgrasp.kernels.fingers.compiled_least_friction`][]); ``task`` itself otherwise.
    For code that applies the task's rules directly rather than through a kernel (the
    reference values and the k-order search); the results are the same bit for bit."""
    if checked_task(task, "compiled_rules").model.n_contacts <= 2:
        return task
    if task.model.kind == "spatial":
        from crmgrasp.kernels.closure import with_compiled_least_friction

        return with_compiled_least_friction(task)
    if task.model.kind == "planar":
        from crmgrasp.kernels.fingers import compiled_least_friction

        return task.with_model(dataclasses.replace(task.model, least_friction=compiled_least_friction()))  # type: ignore[type-var]
    return task


PATHS: dict[str, Callable[[Task, str, str], Kernel]] = {"planar": _planar, "spatial": _spatial}
"""Contact model kind -> the function that picks its kernel from the backend, the friction
asked for ([`kernel_for`][]), the object and the noise. A new contact model adds one row."""


def _rows(configs: ArrayLike, name: str, model: ContactModel) -> NDArray[np.float64]:
    if isinstance(configs, (list, tuple)) and configs and isinstance(configs[0], (Config, Grip)):
        try:
            arr = model.rows_of(list(configs))
        except (TypeError, ValueError):
            raise CrmgraspError(f"{name} must be configurations of the hand's contacts, got {shown(configs)}") from None
    else:
        arr = float_array(configs, name)
    width = model.row_width
    if arr.ndim != 2 or arr.shape[1] != width:
        raise CrmgraspError(f"{name} must have shape (N, {width}), got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise CrmgraspError(f"{name} must be finite")
    return arr


def _per_row(value: ArrayLike, name: str, n: int) -> NDArray[np.float64]:
    """``value`` as ``n`` numbers: one for every row, or one per row (one-line error otherwise)."""
    arr = float_array(value, name)
    try:
        return np.broadcast_to(arr, (n,))
    except ValueError:
        raise CrmgraspError(f"{name} must be one number or {n}, got shape {arr.shape}") from None


def execute_batch(
    obj: Shape,
    hand: Hand,
    configs: ArrayLike,
    c: ArrayLike,
    f: ArrayLike,
    r: ArrayLike,
    sensed: ArrayLike | None = None,
    *,
    backend: str = "auto",
) -> tuple[NDArray[np.float64], NDArray[np.int8]]:
    """Execute one CRM per row of a planar hand: new configurations ``(N, 4 n)`` (``n`` the
    hand's contacts) and error codes ``(N,)``.

    ``c`` and ``f`` are contact indices (0 = a, 1 = b, ...) and ``r`` offsets in metres,
    per row or broadcast; ``sensed`` (same layout as ``configs``) supplies the goal
    lines' frames and defaults to ``configs``. Rows whose CRM fails keep their
    configuration ([`crmgrasp.model.hand.execute_crm`][]).
    """
    task = Task(name="execute_batch", obj=obj, hand=hand, actions=(CRM("a", "b", 0.0),))
    cfg = _rows(configs, "configs", task.model)
    sen = cfg if sensed is None else _rows(sensed, "sensed configs", task.model)
    if sen.shape != cfg.shape:
        raise CrmgraspError(f"sensed configs must have shape {cfg.shape}, got {sen.shape}")
    n = len(cfg)
    ci, fi, rr = (_per_row(v, name, n) for v, name in ((c, "c"), (f, "f"), (r, "r")))
    last = hand.contacts - 1
    if not np.all((ci >= 0) & (ci <= last) & (fi >= 0) & (fi <= last) & (ci == np.floor(ci)) & (fi == np.floor(fi))):
        raise CrmgraspError(f"contact indices c and f must be integers in [0, {last}] (the hand's contacts)")
    if not np.all(np.isfinite(rr)) or np.any(np.abs(rr) > hand.r_max):  # type: ignore[operator]
        raise CrmgraspError(f"CRM offsets r must be finite and within r_max = {hand.r_max:g}")
    return kernel_for(task, backend).execute_crms(cfg, sen, ci.astype(np.int64), fi.astype(np.int64), rr)

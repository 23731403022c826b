"""Tasks from files, from code, and back to plain data.

A task file is TOML (`TEMPLATE` is a commented example; ``crmgrasp
task-template`` prints it). Every key is checked: an unknown key, a missing one, a
value of the wrong type or out of range gets a one-line error naming the file and the
key. [`task_to_dict`][] writes a task in the same schema (as plain data, which is
how a policy file carries its task), and [`task_from_dict`][] reads it back, so
``task_from_dict(task_to_dict(t))`` equals ``t`` for every task the schema can state.

[`resolve_task`][] is what ``--task`` accepts: a registered name, a ``.toml`` file,
or ``package.module:factory`` (a callable returning a [`Task`][], or a Task).
"""

from __future__ import annotations

import dataclasses
import importlib
import re
import tomllib
from pathlib import Path
from typing import Any

from crmgrasp._io import as_path, read_bounded
from crmgrasp._validation import CrmgraspError, shown
from crmgrasp.model import families as fam
from crmgrasp.model.geometry import Disc, Polygon
from crmgrasp.model.hand import Hand
from crmgrasp.model.sensing import Discretizer, SensorNoise
from crmgrasp.tasks.core import Task, checked_name, checked_task, make_task, task_names
from crmgrasp.tasks.families import BoundaryStarts
from crmgrasp.tasks.presets import LongSideStarts, MixtureStarts, NearCornerStarts, VertexStarts, with_reading
from crmgrasp.tasks.schema import (
    COMMON_SECTIONS,
    DEFAULT_GRID,
    SCALAR_KEYS,
    check_top_level,
    common_dict,
    common_keys,
    crm_tables,
    field_rows,
    init_keys,
    number,
    numbers,
    range_entries,
    read_fields,
    section,
    table_keys,
    write_fields,
)
from crmgrasp.tasks.starts import CornerStarts, UniformStarts

__all__ = [
    "TEMPLATE",
    "MAX_TASK_FILE_BYTES",
    "task_from_dict",
    "task_to_dict",
    "load_task_file",
    "resolve_task",
    "resolve_reading",
    "STARTS",
    "starts_dict",
    "key_reference",
]

MAX_TASK_FILE_BYTES = 1 << 20
"""Largest task file read (1 MiB)."""

_FACTORY = re.compile(r"[A-Za-z_][A-Za-z0-9_]*(\.[A-Za-z_][A-Za-z0-9_]*)*:[A-Za-z_][A-Za-z0-9_]*")

TEMPLATE = """\
# A crmgrasp task: use it with `crmgrasp learn --task my-u.toml` (any command taking --task).
# Lengths in metres, angles in radians. Keys marked "optional" may be left out.
name = "my-u"                      # letters, digits, '.', '_', '-'; names run folders and policies
description = "a U-shaped handle"  # optional
mu_goal = 0.05                     # optional: success when min friction <= mu_goal
max_steps = 10                     # optional: CRMs before an episode is cut off
grasp_reward = -1.0                # optional: reward of the grasping CRM (every other CRM: -1)
error_cost = 0.0                   # optional: extra cost of a CRM that ends in an error
# reference_mean_steps = 1.66      # optional: the best mean CRMs per episode, if known
# symmetry = [1, 0, 3, 2]          # optional: a declared mirror symmetry, the action each action
                                   # maps to (the object and the starts must have it too)

[object]   # exactly one of: polygon = [[x, y], ...] (simple, counter-clockwise or not);
           # disc = { radius = r, center = [x, y] }; rectangle = { length = l, width = w }
polygon = [[0, 0], [0.3, 0], [0.3, 0.2], [0.2, 0.2], [0.2, 0.05], [0.1, 0.05], [0.1, 0.2], [0, 0.2]]

[hand]
aperture = 0.16                    # largest distance between two contacts
palm_depth = 0.12                  # palm point behind the contacts' midpoint (centroid)
backoff = 0.01                     # optional: retreat along the normal before a CRM
# r_max = 0.2                      # optional: largest |r| of a CRM
# min_separation = 0.0             # optional: contacts closer than this collide
# contacts = 2                     # optional: fingers a, b, c, ... (2 to 4); CRMs may name
                                   # any of them and the bins take m_c, ... for more than two

[[crm]]    # one table per action: contact c moves onto the line through contact f's
c = "a"    # position offset by r along f's tangent, along f's normal
f = "b"
r = 0.0    # or a range, r = [-0.16, 0.16]: the continuous action space's pair (c, f),
           # and `grid = 5` (optional) evenly spaced CRMs of it among the actions

[[crm]]
c = "b"
f = "a"
r = 0.0

[[crm]]
c = "a"
f = "a"
r = 0.08

[[crm]]
c = "b"
f = "b"
r = -0.08

[bins]     # thresholds per quantity: a value v is in bin k = number of thresholds <= v
rho = [1.0]
m_a = [0.1]
m_b = [0.1]
abs_moments = true                 # optional: bin moments by magnitude

[starts]
kind = "uniform"                   # "uniform" on the whole boundary; for polygons also "corners" (one
                                   # contact on each side of a random corner), "near-corner" (within =
                                   # 0.10 m of it), "long-side" (corner starts whose contact on the
                                   # longer side is lo..hi from the corner), or "mixture" with
                                   # mix = [{ kind = "near-corner", weight = 0.4 }, ...];
                                   # "boundary": contacts anywhere on the boundary within
                                   # the aperture of each other (near_vertex = d: within d
                                   # of a vertex); the default of family tasks; "vertex":
                                   # vertex = i, incoming = [lo, hi], outgoing = [lo, hi]
                                   # (distances from vertex i), a_on = "incoming" (fixed labels)
# A family task draws its object anew each episode: replace [object] by, e.g.,
# [family]
# kind = "box"                     # box, disc, regular-polygon, convex-polygon, u-handle,
# length = [0.20, 0.40]            # l-shape, t-shape, star (ranges [low, high]), polygon
#                                  # (vertices = [[x, y], ...]: one fixed shape, posed), or
# width = [0.06, 0.14]             # mixed with members = [{ kind = ... }, ...], weights = [...]
# pose = { angle = [0.0, 6.2832], offset = [-0.05, 0.05] }

# [noise]                          # optional sensing noise
# sigma_n = 0.0                    # normal rotation, radians (<= 0.785)
# sigma_p = 0.0                    # position, metres (<= 0.1)

# A spatial task (3-D: boxes, cylinders, meshes on a table) sets model = "spatial" and states
# [solid] or a 3-D [family]: see docs/model-3d.md, section 6.
"""

_TOP = {*COMMON_SECTIONS, "object"}
"""The keys of a planar task file."""
STARTS: dict[str, type] = {
    cls.kind: cls  # type: ignore[attr-defined]
    for cls in (
        CornerStarts,
        UniformStarts,
        NearCornerStarts,
        LongSideStarts,
        MixtureStarts,
        BoundaryStarts,
        VertexStarts,
    )
}
"""The planar start samplers a task file names, by ``kind`` (each class states its kind,
keys, defaults and bounds)."""
_FAMILIES: dict[str, type] = {
    cls.kind: cls  # type: ignore[attr-defined]
    for cls in (
        fam.BoxFamily,
        fam.DiscFamily,
        fam.RegularPolygonFamily,
        fam.ConvexPolygonFamily,
        fam.UHandleFamily,
        fam.LShapeFamily,
        fam.TShapeFamily,
        fam.StarFamily,
        fam.FixedShape,
    )
}


def _object(table: Any) -> Polygon | Disc:
    t = table_keys(table, "[object]", {"polygon", "disc", "rectangle"})
    if len(t) != 1:
        raise CrmgraspError("[object] needs exactly one of polygon, disc, rectangle")
    ((kind, value),) = t.items()
    if kind == "polygon":
        if not isinstance(value, list) or not all(isinstance(p, list) and len(p) == 2 for p in value):
            raise CrmgraspError("object.polygon must be a list of [x, y] pairs")
        return Polygon([(number(x, "object.polygon x"), number(y, "object.polygon y")) for x, y in value])
    if kind == "disc":
        d = table_keys(value, "object.disc", {"radius", "center"}, {"radius"})
        center = numbers(d.get("center", [0.0, 0.0]), "object.disc.center")
        if len(center) != 2:
            raise CrmgraspError("object.disc.center must be [x, y]")
        return Disc(number(d["radius"], "object.disc.radius"), (center[0], center[1]))
    r = table_keys(value, "object.rectangle", {"length", "width"}, {"length", "width"})
    hx, hy = number(r["length"], "object.rectangle.length") / 2, number(r["width"], "object.rectangle.width") / 2
    if hx <= 0 or hy <= 0:
        raise CrmgraspError("object.rectangle length and width must be > 0")
    return Polygon([(-hx, -hy), (hx, -hy), (hx, hy), (-hx, hy)])


def _hand(table: Any) -> Hand:
    return Hand(**read_fields(Hand, table, "[hand]", "hand."))


def _starts(table: Any, where: str = "[starts]") -> Any:
    """A start sampler: ``kind`` and the keys of that kind's class (a mixture: ``mix``, a
    list of samplers each with a ``weight``)."""
    if not isinstance(table, dict):
        raise CrmgraspError(f"{where} must be a table, got {shown(table)}")
    kind = table.get("kind")
    if kind not in STARTS:
        raise CrmgraspError(f"{where} kind must be one of {', '.join(STARTS)}, got {shown(kind)}")
    cls = STARTS[kind]
    keys = {"mix"} if cls is MixtureStarts else init_keys(cls)[0]
    rest = {k: v for k, v in table.items() if k not in ("kind", "weight")}
    extra = set(rest) - keys
    if extra:
        takes = f"; it takes {', '.join(sorted(keys))}" if keys else ""
        raise CrmgraspError(f"{where}: kind {kind!r} takes no {', '.join(sorted(extra))}{takes}")
    if cls is not MixtureStarts:
        return cls(**read_fields(cls, rest, where, f"{where} "))
    mix = rest.get("mix")
    if not isinstance(mix, list) or not mix or not all(isinstance(m, dict) for m in mix):
        raise CrmgraspError(f"{where}: a mixture needs mix = [{{ kind = ..., weight = ... }}, ...]")
    parts = [_starts(m, f"{where} mix[{i}]") for i, m in enumerate(mix)]
    weights = [number(m.get("weight", 1.0), f"{where} mix[{i}] weight") for i, m in enumerate(mix)]
    return MixtureStarts(tuple(parts), tuple(weights))


def starts_dict(starts: Any) -> dict[str, Any]:
    """A start sampler in the task-file schema: its ``kind`` and its fields
    ([`write_fields`][crmgrasp.tasks.schema.write_fields]); ``{"kind": "custom"}`` for a sampler
    written in Python, which does not travel."""
    kind = getattr(type(starts), "kind", "")
    if STARTS.get(kind) is not type(starts):
        return {"kind": "custom"}
    if type(starts) is not MixtureStarts:
        return {"kind": kind, **write_fields(starts)}
    mix = [{**starts_dict(c), "weight": w} for c, w in zip(starts.components, starts.weights)]
    return {"kind": "custom"} if any(m["kind"] == "custom" for m in mix) else {"kind": kind, "mix": mix}


def _family(table: Any, where: str = "[family]") -> Any:
    """An object family: ``kind`` and its ranges as ``[low, high]``, an optional
    ``pose = { angle = [..], offset = [..] }``; ``kind = "mixed"`` takes
    ``members = [{ kind = ..., ... }, ...]`` and optional ``weights``."""
    kinds = [*_FAMILIES, "mixed"]
    t = table_keys(
        table, where, {"kind", "pose", "members", "weights"} | {f for c in _FAMILIES.values() for f in _fields(c)}
    )
    kind = t.get("kind")
    if kind not in kinds:
        raise CrmgraspError(f"{where} kind must be one of {', '.join(kinds)}, got {shown(kind)}")
    if kind == "mixed":
        extra = set(t) - {"kind", "members", "weights"}
        members = t.get("members")
        if extra or not isinstance(members, list) or not members:
            raise CrmgraspError(f"{where}: a mixed family takes members = [{{ kind = ... }}, ...] and weights only")
        parts = tuple(_family(m, f"{where} members[{i}]") for i, m in enumerate(members))
        weights = numbers(t["weights"], f"{where} weights") if "weights" in t else ()
        return fam.MixedFamily(parts, weights)
    cls = _FAMILIES[kind]
    extra = set(t) - {"kind", "pose", *_fields(cls)}
    if extra:
        raise CrmgraspError(
            f"{where}: kind {kind!r} takes no {', '.join(sorted(extra))}; it takes {', '.join(_fields(cls))}"
        )
    kw: dict[str, Any] = {k: tuple(v) if isinstance(v, list) else v for k, v in t.items() if k not in ("kind", "pose")}
    if "pose" in t:
        pose = table_keys(t["pose"], f"{where} pose", {"angle", "offset"})
        kw["pose"] = fam.Pose(**{k: tuple(v) if isinstance(v, list) else v for k, v in pose.items()})
    return cls(**kw)


def _fields(cls: type) -> tuple[str, ...]:
    return tuple(f.name for f in dataclasses.fields(cls) if f.name != "pose")


def task_from_dict(doc: Any) -> Task:
    """The [`Task`][] a task document (parsed TOML, or [`task_to_dict`][]) states;
    ``model = "spatial"`` states a spatial task (`crmgrasp.tasks.spatial_files`)."""
    check_top_level(doc)
    model = doc.get("model", "planar") if isinstance(doc, dict) else "planar"
    if model not in ("planar", "spatial"):
        raise CrmgraspError(f'model must be "planar" or "spatial", got {shown(model)}')
    if model == "spatial":
        from crmgrasp.tasks.spatial_files import spatial_from_dict

        return spatial_from_dict(doc)
    if isinstance(doc, dict):
        doc = {k: v for k, v in doc.items() if k != "model"}
    d = table_keys(doc, "the task file", _TOP, {"name", "hand", "crm"})
    name = checked_name(d["name"])
    hand = section("hand", _hand, d["hand"])
    actions, ranges = section("crm", lambda v: crm_tables(v, labels=hand.labels), d["crm"])
    kw: dict[str, Any] = {"hand": hand, "actions": actions, "ranges": ranges}
    if ("object" in d) == ("family" in d):
        raise CrmgraspError("the task file needs exactly one of [object] and [family]")
    if "family" in d:
        kw["family"] = section("family", _family, d["family"])
        kw["obj"] = kw["family"].nominal()
    else:
        kw["obj"] = section("object", _object, d["object"])
    kw["starts"] = section("starts", _starts, d.get("starts", {"kind": "boundary" if "family" in d else "uniform"}))
    if getattr(kw["starts"], "takes_corner_filter", False) and not isinstance(kw["obj"], Polygon):
        raise CrmgraspError('starts kinds "corners", "near-corner", "long-side" need a polygon object; use "uniform"')
    common_keys(d, kw)
    return section("task", lambda kw: Task(name=name, **kw), kw)


def _object_dict(obj: Any) -> dict[str, Any]:
    if isinstance(obj, Disc):
        return {"disc": {"radius": obj.radius, "center": list(obj.center)}}
    if isinstance(obj, Polygon):
        return {"polygon": [list(v) for v in obj.vertices]}
    raise CrmgraspError(f"a {type(obj).__name__} cannot be written as a task file object")


def task_to_dict(task: Task) -> dict[str, Any]:
    """The task as plain data in the task-file schema.

    A start sampler other than the built-in kinds is written as ``{"kind": "custom"}``
    (Python code does not travel); [`task_from_dict`][] refuses it."""
    from crmgrasp.tasks.spatial import SpatialTask

    checked_task(task, "task_to_dict")
    if isinstance(task, SpatialTask):
        from crmgrasp.tasks.spatial_files import spatial_to_dict

        return spatial_to_dict(task)
    doc = common_dict(task, task.hand)
    doc["crm"] = [{"c": a.c, "f": a.f, "r": a.r} for a in task.actions] + range_entries(task.ranges)
    doc["starts"] = starts_dict(task.starts)
    if task.family is None:
        doc["object"] = _object_dict(task.obj)
    else:
        doc["family"] = task.family.describe()  # a sampler family (Python code) is written, not read back
    return doc


def key_reference() -> str:
    """Every key a task file takes, as a Markdown table read from the classes that own
    them ([`Task`][crmgrasp.tasks.core.Task], the hands, the noise, the bins and each
    start sampler): key, type and default. ``crmgrasp task-template --keys`` prints it."""
    from crmgrasp.model.spatial import Hand3D
    from crmgrasp.tasks.spatial import SurfaceStarts

    rows = [("top level", "name", "string", "required"), ("top level", "symmetry", "list of action indices", "none")]
    rows += [("top level", *r) for r in field_rows(Task, {f.name for f in dataclasses.fields(Task)} - {*SCALAR_KEYS})]
    rows += [("[hand]", *r) for r in field_rows(Hand)]
    rows += [("[hand] (spatial)", *r) for r in field_rows(Hand3D)]
    rows += [("[[crm]]", "c", 'string: a contact label of the hand, "a", "b", ... (the moving contact)', "required")]
    rows += [("[[crm]]", "f", "string: a contact label of the hand (the frame contact)", "required")]
    rows += [("[[crm]]", "r", "number, or a range [low, high] (spatial: 2 numbers, or 2 ranges)", "0")]
    rows += [("[[crm]]", "grid", "integer >= 0: CRMs of an offset range among the actions", str(DEFAULT_GRID))]
    rows += [("[noise]", *r) for r in field_rows(SensorNoise)]
    d = Discretizer()
    rows += [("[bins]", n, "list of numbers", repr(list(t))) for n, t in zip(d.names, d.thresholds)]
    rows.append(("[bins]", "abs_moments", "true or false", "true"))
    for kind, cls in [*STARTS.items(), (SurfaceStarts.kind, SurfaceStarts)]:
        where = f'[starts] kind = "{kind}"'
        if cls is MixtureStarts:
            rows.append((where, "mix", "list of [starts] tables, each with a weight (number, 1.0)", "required"))
        rows += [(where, *r) for r in (() if cls is MixtureStarts else field_rows(cls))]
    lines = ["| table | key | type | default |", "| --- | --- | --- | --- |"]
    return "\n".join([*lines, *(f"| {t} | `{k}` | {ty} | {df} |" for t, k, ty, df in rows)]) + "\n"


def load_task_file(path: str | Path) -> Task:
    """The task a TOML file states (read with a 1 MiB bound; one-line errors naming
    the file and the key)."""
    p = as_path(path, "task file")
    data = read_bounded(p, MAX_TASK_FILE_BYTES, "task file")
    try:
        doc = tomllib.loads(data.decode("utf-8"))
    except UnicodeDecodeError:
        raise CrmgraspError(f"task file {str(p)!r} is not UTF-8 text") from None
    except tomllib.TOMLDecodeError as exc:
        raise CrmgraspError(f"task file {str(p)!r} is not valid TOML ({exc})") from None
    except RecursionError:
        raise CrmgraspError(f"task file {str(p)!r} is nested too deeply") from None
    try:
        return task_from_dict(doc)
    except CrmgraspError as exc:
        raise CrmgraspError(f"task file {str(p)!r}: {exc}") from None


def _from_factory(spec: str) -> Task:
    module, attr = spec.split(":")
    try:
        mod = importlib.import_module(module)
    except ImportError as exc:
        raise CrmgraspError(f"task {spec!r}: cannot import {module!r} ({exc})") from None
    try:
        made = getattr(mod, attr)
    except AttributeError:
        raise CrmgraspError(f"task {spec!r}: module {module!r} has no {attr!r}") from None
    if callable(made) and not isinstance(made, Task):
        try:
            made = made()
        except CrmgraspError as exc:
            raise CrmgraspError(f"task {spec!r}: {exc}") from None
        except Exception as exc:  # the user's code failed: one line, naming it
            raise CrmgraspError(f"task {spec!r}: the factory raised {type(exc).__name__}: {exc}") from None
        except SystemExit as exc:  # a factory must not end the program (exit 0 would say all went well)
            raise CrmgraspError(
                f"task {spec!r}: the factory called exit({exc.code!r}) instead of returning a task"
            ) from None
    if not isinstance(made, Task):
        raise CrmgraspError(f"task {spec!r} gave a {type(made).__name__}, not a crmgrasp Task")
    return made


def resolve_task(spec: str | Path | Task) -> Task:
    """The task ``spec`` names: a [`Task`][] itself, a registered name, a ``.toml``
    file, or ``package.module:factory``."""
    if isinstance(spec, Task):
        return spec
    text = str(spec)
    if text in task_names():
        return make_task(text)
    if _FACTORY.fullmatch(text) and not Path(text).exists():
        return _from_factory(text)
    if text.endswith(".toml") or Path(text).is_file():
        return load_task_file(text)
    raise CrmgraspError(
        f"unknown task {shown(text)}; known tasks: {', '.join(task_names())} "
        "(or a .toml task file, or package.module:factory)"
    )


def resolve_reading(
    spec: str | Task, *, starts: str | None = None, grasp_reward: float | None = None, offset_grid: int | None = None
) -> Task:
    """`with_reading` of the task ``spec`` names
    ([`resolve_task`][]), its CRMs replaced by a grid of ``offset_grid`` offsets per
    coordinate if given ([`crmgrasp.tasks.offsets.offset_grid`][]): what ``--task``,
    ``--start-preset``, ``--grasp-reward`` and ``--offset-grid`` (or a study cell) state."""
    task = with_reading(resolve_task(spec), starts=starts, grasp_reward=grasp_reward)
    if offset_grid is None:
        return task
    from crmgrasp.tasks.offsets import offset_grid as grid

    return grid(task, offset_grid)

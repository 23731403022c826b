"""Spatial tasks in task files: ``model = "spatial"`` (docs/model-3d.md section 6).

The schema follows the planar one ([`crmgrasp.tasks.files`][]) with spatial parts::

    name = "my-cup"
    model = "spatial"
    table = 0.0                      # the table's height, m (omit the key for no table)
    [hand]                           # aperture, palm_depth, backoff, r_max, min_separation,
    aperture = 0.16                  # palm_normal_tol, h = [0, 0, 1], g = [1, 0, 0],
                                     # contacts = 2 (2 to 4: a, b, c, d)
    palm_depth = 0.12
    [[crm]]                          # r = [r1, r2] in the reference contact's tangent frame
    c = "a"
    f = "b"
    r = [0.0, 0.0]
    [solid]                          # exactly one of [solid] and [family]:
    cylinder = { origin = [0, 0, 0], axis = [0, 0, 1], radius = 0.04, height = 0.1 }
    # box = { lo = [..], hi = [..] }, polyhedron = { planes = [[ax, ay, az, b], ..] },
    # mesh = { vertices = [[x, y, z], ..], faces = [[i, j, k], ..], pieces = [[i, j, k, l, ..], ..] },
    #   (pieces optional: convex pieces, corner indices, making up the solid, for MuJoCo)
    # open_cup = { radius = .., height = .., wall = .., segments = .. }
    # [family]  kind = "box3d" (length, width, height), "cylinder" (radius, height,
    #           upright) or "open_cup" (radius, height, wall, upright, segments),
    #           ranges [low, high], pose = { angle = [..], offset = [..] }
    [starts]
    kind = "surface"                 # up = 0.5, max_tries = 10000

``bins``, ``noise``, ``mu_goal``, ``max_steps``, ``grasp_reward``, ``error_cost``,
``description`` and ``reference_mean_steps`` are as in planar files.
"""

from __future__ import annotations

import dataclasses
from typing import Any

from crmgrasp._validation import CrmgraspError, shown
from crmgrasp.model.families import Pose
from crmgrasp.model.mesh import TriangleMesh, open_cup
from crmgrasp.model.solid_families import BoxOnTable, CylinderOnTable, OpenCupOnTable
from crmgrasp.model.solids import ConvexPolyhedron, Cylinder, box3d
from crmgrasp.model.spatial import CRM3D, Hand3D
from crmgrasp.tasks.core import checked_name
from crmgrasp.tasks.schema import (
    COMMON_SECTIONS,
    common_dict,
    common_keys,
    crm_tables,
    init_keys,
    number,
    numbers,
    range_entries,
    read_fields,
    section,
    table_keys,
    write_fields,
)
from crmgrasp.tasks.spatial import SpatialTask, SurfaceStarts

__all__ = ["spatial_from_dict", "spatial_to_dict", "SPATIAL_KEYS"]

SPATIAL_KEYS = {*COMMON_SECTIONS, "model", "solid", "table"}
"""The keys of a spatial task file."""
_FAMILIES3D: dict[str, type] = {"box3d": BoxOnTable, "cylinder": CylinderOnTable, "open_cup": OpenCupOnTable}


def _vector(value: Any, key: str, n: int) -> tuple[float, ...]:
    out = numbers(value, key)
    if len(out) != n:
        raise CrmgraspError(f"{key} must have {n} numbers, got {len(out)}")
    return out


def _hand(table: Any) -> Hand3D:
    return Hand3D(**read_fields(Hand3D, table, "[hand]", "hand."))


def _crm(c: str, f: str, r: Any, where: str) -> CRM3D:
    r1, r2 = _vector([0.0, 0.0] if r is None else r, f"{where} r", 2)
    return CRM3D(c, f, (r1, r2))


def _solid(table: Any) -> Any:
    kinds = {"box", "polyhedron", "cylinder", "mesh", "open_cup"}
    t = table_keys(table, "[solid]", kinds)
    if len(t) != 1:
        raise CrmgraspError(f"[solid] needs exactly one of {', '.join(sorted(kinds))}")
    ((kind, value),) = t.items()
    where = f"solid.{kind}"
    if kind == "box":
        v = table_keys(value, where, {"lo", "hi"}, {"lo", "hi"})
        return box3d(_vector(v["lo"], f"{where}.lo", 3), _vector(v["hi"], f"{where}.hi", 3))
    if kind == "polyhedron":
        v = table_keys(value, where, {"planes"}, {"planes"})
        if not isinstance(v["planes"], list):
            raise CrmgraspError(f"{where}.planes must be a list of [ax, ay, az, b]")
        return ConvexPolyhedron(tuple(_vector(p, f"{where}.planes[{i}]", 4) for i, p in enumerate(v["planes"])))  # type: ignore[arg-type,misc]
    if kind == "cylinder":
        v = table_keys(value, where, {"origin", "axis", "radius", "height"}, {"radius", "height"})
        origin = _vector(v.get("origin", [0.0, 0.0, 0.0]), f"{where}.origin", 3)
        axis = _vector(v.get("axis", [0.0, 0.0, 1.0]), f"{where}.axis", 3)
        return Cylinder(origin, axis, number(v["radius"], f"{where}.radius"), number(v["height"], f"{where}.height"))  # type: ignore[arg-type]
    if kind == "mesh":
        v = table_keys(value, where, {"vertices", "faces", "pieces"}, {"vertices", "faces"})
        if not isinstance(v["vertices"], list) or not isinstance(v["faces"], list):
            raise CrmgraspError(f"{where} needs vertices = [[x, y, z], ..] and faces = [[i, j, k], ..]")
        verts = tuple(_vector(p, f"{where}.vertices[{i}]", 3) for i, p in enumerate(v["vertices"]))
        for i, tri in enumerate(v["faces"]):
            if (
                not isinstance(tri, list)
                or len(tri) != 3
                or not all(isinstance(k, int) and not isinstance(k, bool) for k in tri)
            ):
                raise CrmgraspError(f"{where}.faces[{i}] must be three corner indices, got {shown(tri)}")
        pieces = v.get("pieces", [])
        if not isinstance(pieces, list) or not all(isinstance(p, list) for p in pieces):
            raise CrmgraspError(f"{where}.pieces must be a list of corner-index lists, got {shown(pieces)}")
        return TriangleMesh(verts, tuple(tuple(tri) for tri in v["faces"]), tuple(map(tuple, pieces)))  # type: ignore[arg-type]
    v = table_keys(value, where, {"radius", "height", "wall", "segments"}, {"radius", "height"})
    kw: dict[str, Any] = {k: number(x, f"{where}.{k}") for k, x in v.items() if k != "segments"}
    if "segments" in v:
        kw["segments"] = v["segments"]
    return open_cup(**kw)


def _family(table: Any) -> Any:
    fields = {fl.name for cls in _FAMILIES3D.values() for fl in dataclasses.fields(cls)}
    t = table_keys(table, "[family]", {"kind"} | fields)
    kind = t.get("kind")
    if kind not in _FAMILIES3D:
        raise CrmgraspError(
            f"[family] kind must be one of {', '.join(_FAMILIES3D)} in a spatial task, got {shown(kind)}"
        )
    cls = _FAMILIES3D[kind]
    own = {fl.name for fl in dataclasses.fields(cls)}
    extra = set(t) - {"kind"} - own
    if extra:
        raise CrmgraspError(
            f"[family]: kind {kind!r} takes no {', '.join(sorted(extra))}; it takes {', '.join(sorted(own))}"
        )
    kw: dict[str, Any] = {k: tuple(v) if isinstance(v, list) else v for k, v in t.items() if k not in ("kind", "pose")}
    if "pose" in t:
        pose = table_keys(t["pose"], "[family] pose", {"angle", "offset"})
        kw["pose"] = Pose(**{k: tuple(v) if isinstance(v, list) else v for k, v in pose.items()})
    return cls(**kw)


def _starts(table: Any) -> SurfaceStarts:
    t = table_keys(table, "[starts]", {"kind", *init_keys(SurfaceStarts)[0]}, {"kind"})
    if t["kind"] != SurfaceStarts.kind:
        raise CrmgraspError(f'a spatial task\'s starts kind is "{SurfaceStarts.kind}", got {shown(t["kind"])}')
    rest = {k: v for k, v in t.items() if k != "kind"}
    return SurfaceStarts(**read_fields(SurfaceStarts, rest, "[starts]", "starts."))


def spatial_from_dict(doc: Any) -> SpatialTask:
    """The [`SpatialTask`][] of a task document with ``model = "spatial"``."""
    d = table_keys(doc, "the task file", SPATIAL_KEYS, {"name", "hand", "crm"})
    name = checked_name(d["name"])
    if ("solid" in d) == ("family" in d):
        raise CrmgraspError("a spatial task file needs exactly one of [solid] and [family]")
    hand = section("hand", _hand, d["hand"])
    actions, ranges = section("crm", lambda v: crm_tables(v, _crm, labels=hand.labels, dim=2), d["crm"])
    kw: dict[str, Any] = {"hand": hand, "actions": actions, "ranges": ranges}
    if "family" in d:
        kw["family"] = section("family", _family, d["family"])
        kw["obj"] = kw["family"].nominal()
    else:
        kw["obj"] = section("solid", _solid, d["solid"])
    kw["starts"] = section("starts", _starts, d.get("starts", {"kind": "surface"}))
    kw["table"] = None if "table" not in d or d["table"] is None else number(d["table"], "table")
    common_keys(d, kw)
    return section("task", lambda kw: SpatialTask(name=name, **kw), kw)  # type: ignore[no-any-return]


def _solid_dict(obj: Any) -> dict[str, Any]:
    if isinstance(obj, Cylinder):
        return {
            "cylinder": {"origin": list(obj.origin), "axis": list(obj.axis), "radius": obj.radius, "height": obj.height}
        }
    if isinstance(obj, TriangleMesh):
        mesh = obj.describe()
        del mesh["kind"]
        return {"mesh": mesh}
    return {"polyhedron": {"planes": [list(p) for p in obj.planes]}}


def spatial_to_dict(task: SpatialTask) -> dict[str, Any]:
    """A spatial task as plain data in the schema above."""
    starts = task.starts
    doc = common_dict(task, task.hand3d)
    doc["model"] = "spatial"
    fixed = [{"c": a.c, "f": a.f, "r": [*a.r]} for a in task.actions]  # type: ignore[misc]
    doc["crm"] = fixed + range_entries(task.ranges)
    doc["starts"] = (
        {"kind": starts.kind, **write_fields(starts)} if type(starts) is SurfaceStarts else {"kind": "custom"}
    )
    if task.table is not None:
        doc["table"] = task.table
    if task.family is None:
        doc["solid"] = _solid_dict(task.obj)
    else:
        doc["family"] = task.family.describe()
    return doc

"""The MuJoCo stand-in in space: a solid free on a frictional table, one spherical
fingertip with force/torque sensors per contact (two, or three for a tripod), 3-D CRMs as
real motions.

[`MujocoHand3D`][] implements [`HandInterface`][crmgrasp.hardware.runner.HandInterface] for
spatial tasks ([`SpatialTask`][crmgrasp.tasks.spatial.SpatialTask]): ``sense()`` returns a
[`Config3D`][crmgrasp.model.spatial.Config3D] (a [`Grip3D`][crmgrasp.model.spatial.Grip3D] for
three or more) from the fingertip wrenches alone (intrinsic
contact sensing on a [`Sphere`][crmgrasp.hardware.contact_sensing.Sphere]), ``execute``
runs a [`CRM3D`][crmgrasp.model.spatial.CRM3D]. It shares the planar hand's servos,
sensor model (bias, drift, white noise, tare, averaging) and contact detector
([`MujocoHand`][crmgrasp.hardware.mujoco.hand.MujocoHand]); what differs is the geometry.

Scene ([`spatial_mjcf`][], world frame = the task's: z up, the table plane z =
``task.table``): the solid (a convex polyhedron as a MuJoCo mesh, a cylinder as a
cylinder) on a free joint resting on the table (friction ``floor_friction``, mass
``object_mass``; between them alone MuJoCo's rolling friction, ``rolling_friction``, so
that a lying cylinder pressed by one fingertip does not roll away: a cup on a cloth);
each fingertip a sphere of ``tip_radius`` on a jointless child of a
carriage with x, y, z slide joints under position servos; the palm a mocap sphere kept
at the palm point ``P`` of the fingertip centres (docs/model-3d.md section 2), colliding
with the object and the table while it is switched on. The fingertips do not collide
with the table (a fingertip stands for a point contact that can reach the object down to
the table, as in the kinematic model) nor with each other.

A CRM ``(c, f, r)`` runs as (docs/model-3d.md section 3 made physical):

1. the chord of the goal line from the *sensed* configuration, within the aperture of every
   fingertip that stays ([`goal_chord3d`][crmgrasp.model.spatial.goal_chord3d]; none: aperture
   error, no motion), its
   start moved up to the table plane by [`table_lift`][crmgrasp.model.spatial.table_lift]
   (never above the table before the chord ends: palm error, no motion);
2. the moving fingertip backs off by ``hand.backoff`` along its sensed outward normal
   and tares its sensor (the others keep pressing);
3. *transit* to the chord's start with the fingertip's collisions off: a real arm would
   plan a path around the object; the stand-in does not simulate that path. Collisions
   back on: a fingertip overlapping the object there means the start is inside it
   (aperture error; palm error for a start moved up to the table);
4. the palm's collisions on (already overlapping the object or the table: palm error),
   approach along the chord at ``approach_speed`` until the high-pass filtered force
   rises by ``contact_on`` (contact), the palm collides (palm error) or the chord ends
   (aperture error);
5. press with ``hold_force``, settle, sense; a sensed surface facing the palm side
   ([`faces_palm3d`][crmgrasp.model.spatial.faces_palm3d], the hand's tolerance) is a palm error;
6. on any error the fingertip goes back to its back-off point (collisions off) and
   re-approaches along its old normal.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from crmgrasp._validation import CrmgraspError
from crmgrasp.hardware.contact_sensing import NoContact, Sphere, contact_from_wrench
from crmgrasp.hardware.mujoco.hand import MujocoHand
from crmgrasp.hardware.mujoco.model import PhysicsParams, hand_mjcf, preamble
from crmgrasp.model.hand import Error
from crmgrasp.model.mesh import TriangleMesh
from crmgrasp.model.solids import ConvexPolyhedron, Cylinder
from crmgrasp.model.spatial import (
    Config3D,
    Contact3D,
    Contacts3D,
    Grip3D,
    Hand3D,
    config3d,
    faces_palm3d,
    goal_chord3d,
    palm_point3d,
    table_lift,
)
from crmgrasp.tasks import Task
from crmgrasp.tasks.spatial import SpatialTask

__all__ = ["MujocoHand3D", "spatial_mjcf", "mujoco_hand"]

_UP = (0.0, 0.0, 1.0)


def _vec(v: Any) -> str:
    return " ".join(repr(float(x)) for x in v)


def _geom(name: str, mass: float, p: PhysicsParams, shape: str) -> str:
    """One geom of the object: ``shape`` (its type and size attributes) with the object's
    friction and collision classes and its share ``mass`` of the object's mass."""
    return (
        f'<geom name="{name}" mass="{mass!r}" friction="{p.floor_friction!r} 0.005 0.0001" '
        f'contype="1" conaffinity="3" rgba=".2 .35 .7 1" {shape}/>'
    )


def _solid_geoms(task: SpatialTask, p: PhysicsParams) -> tuple[str, dict[str, str]]:
    """(asset XML, geom name -> geom XML) of the task's solid, in world coordinates: a
    cylinder, a convex polyhedron as a MuJoCo mesh, or a triangle mesh as its convex pieces
    (one MuJoCo mesh each, the object's mass shared by their volumes). MuJoCo collides a mesh
    as its convex hull, so a non-convex solid needs its pieces
    ([`TriangleMesh.pieces`][crmgrasp.model.mesh.TriangleMesh.pieces])."""
    obj, mass = task.obj, p.object_mass
    if isinstance(obj, Cylinder):
        size = f"{obj.radius!r} {obj.height / 2!r}"
        shape = f'type="cylinder" size="{size}" pos="{_vec(obj.centre)}" zaxis="{_vec(obj.axis)}"'
        return "", {"object": _geom("object", mass, p, shape)}
    if isinstance(obj, ConvexPolyhedron):
        verts = " ".join(_vec(v) for v in obj.vertices)
        geom = _geom("object", mass, p, 'type="mesh" mesh="object"')
        return f'<mesh name="object" vertex="{verts}"/>', {"object": geom}
    if isinstance(obj, TriangleMesh) and obj.pieces:
        from scipy.spatial import ConvexHull

        hulls = [obj.corner_array[list(piece)] for piece in obj.pieces]
        volumes = np.array([ConvexHull(h).volume for h in hulls])
        if volumes.sum() < obj.volume * (1.0 - 1e-9):  # pieces may overlap, never fall short
            held = f"{volumes.sum():.4g} m^3 of its {obj.volume:.4g} m^3"
            raise CrmgraspError(f"the mesh's convex pieces hold {held}: they miss part of it")
        names = [f"object_{i}" for i in range(len(hulls))]
        assets = "".join(f'<mesh name="{n}" vertex="{" ".join(map(_vec, h))}"/>' for n, h in zip(names, hulls))
        shares = (mass * volumes / volumes.sum()).tolist()
        return assets, {n: _geom(n, m, p, f'type="mesh" mesh="{n}"') for n, m in zip(names, shares)}
    what = type(obj).__name__ + (" without convex pieces" if isinstance(obj, TriangleMesh) else "")
    raise CrmgraspError(
        f"the spatial MuJoCo stand-in takes convex polyhedra, cylinders and meshes with convex pieces, not a {what}"
    )


def spatial_mjcf(task: SpatialTask, params: PhysicsParams | None = None) -> str:
    """MJCF text of the spatial stand-in scene: ``task``'s solid on the table and a hand
    with one fingertip per contact label of the task's model (``params.height`` and
    ``params.lift`` are the planar scene's and unused here)."""
    if task.model.kind != "spatial":
        raise CrmgraspError(f"the spatial MuJoCo stand-in needs a spatial task, got {task.name!r}")
    p = PhysicsParams() if params is None else params
    asset, geoms = _solid_geoms(task, p)
    friction = f"{p.floor_friction!r} {p.floor_friction!r} 0.005 {p.rolling_friction!r} {p.rolling_friction!r}"
    pairs = "\n    ".join(f'<pair geom1="{n}" geom2="floor" condim="6" friction="{friction}"/>' for n in geoms)
    geom = "\n      ".join(geoms.values())
    table = 0.0 if task.table is None else float(task.table)
    fingers, drives = hand_mjcf(p, 0.0, tuple(task.model.labels))
    return f"""{preamble(f"crmgrasp-{task.name}-3d", p, asset)}
    <camera name="view" pos="0.33 -0.33 0.30" xyaxes="0.7071 0.7071 0 -0.38 0.38 0.843"/>
    <geom name="floor" type="plane" size="2 2 0.1" pos="0 0 {table!r}" material="grid"
      contype="0" conaffinity="2"/>
    <body name="object">
      <freejoint name="object"/>
      {geom}
    </body>{fingers}
    <body name="palm" mocap="true" pos="0 -1 {table + 0.5!r}">
      <geom name="palm" type="sphere" size="{p.palm_radius!r}" contype="0" conaffinity="0" rgba=".9 .5 .2 1"/>
    </body>
  </worldbody>
  <contact>
    {pairs}
  </contact>
  {drives}
</mujoco>
"""


def mujoco_hand(task: Task, start: Any, rng: np.random.Generator, params: PhysicsParams | None = None) -> MujocoHand:
    """The MuJoCo stand-in for ``task`` by its contact model ([`HANDS`][]):
    [`MujocoHand3D`][] on a spatial task (a family task on its nominal solid), the
    planar [`MujocoHand`][crmgrasp.hardware.mujoco.hand.MujocoHand] on a planar one."""
    try:
        hand = HANDS[task.model.kind]
    except KeyError:
        raise CrmgraspError(f"no MuJoCo stand-in for the contact model {task.model.kind!r}") from None
    if hand is MujocoHand3D and task.family is not None:
        task = task.with_object(task.obj)
    return hand(task, start, rng, params)


class MujocoHand3D(MujocoHand):
    """The spatial MuJoCo stand-in holding ``task.obj`` from ``start`` (world = task frame).

    Parameters
    ----------
    task
        A spatial task on one solid (``task.sample_world(rng).task``); its hand's
        ``palm_normal_tol`` applies to the sensed surfaces
        ([`hardware_task`][crmgrasp.hardware.mujoco.hardware_task]).
    start
        The true starting contacts; each fingertip is placed just outside its contact
        and approaches along the inward normal until contact is felt.
    rng
        Source of all sensor noise and drift.
    params
        Physical and controller parameters ([`PhysicsParams`][crmgrasp.hardware.mujoco.model.PhysicsParams]).
    """

    camera = "view"

    def __init__(
        self, task: SpatialTask, start: Contacts3D, rng: np.random.Generator, params: PhysicsParams | None = None
    ) -> None:
        if task.model.kind != "spatial" or task.family is not None:
            raise CrmgraspError(
                "the spatial MuJoCo hand needs a spatial task on one solid (task.sample_world(rng).task)"
            )
        super().__init__(task, task.check_config(start, "start"), rng, params)  # type: ignore[arg-type]

    # -- hooks of the shared machinery ---------------------------------------------
    def _scene(self) -> str:
        return spatial_mjcf(self.task, self.params)  # type: ignore[arg-type]

    def _origin(self) -> np.ndarray:
        return np.zeros(3)

    def _palm_obstacles(self) -> list[int]:
        floor = self.mj.mj_name2id(self.model, self.mj.mjtObj.mjOBJ_GEOM, "floor")
        return [*self._objects, floor]

    def _palm_target(self) -> np.ndarray | None:
        tips = [Contact3D(tuple(self._centre(i)), _UP) for i in range(len(self.labels))]  # type: ignore[arg-type]
        return palm_point3d(config3d(tips), self.hand)

    @property
    def hand(self) -> Hand3D:
        """The task's hand (typed)."""
        return self.task.hand  # type: ignore[return-value]

    def _tip_collisions(self, i: int, on: bool) -> bool:
        """Switch fingertip ``i``'s collisions; on, False if it then overlaps the object."""
        m = self.model
        g = self._tip_geom[i]
        m.geom_contype[g], m.geom_conaffinity[g] = (4, 1) if on else (0, 0)
        return not on or all(self.mj.mj_geomDistance(m, self.data, g, o, 0.01, None) > 0.0 for o in self._objects)

    def _transit(self, i: int, centre: np.ndarray) -> bool:
        """Move fingertip ``i``'s centre to ``centre`` with its collisions off; True if it
        is clear of the object there."""
        self._set_palm(False)
        self._tip_collisions(i, False)
        self._move(i, centre, self.params.travel_speed)
        return self._tip_collisions(i, True)

    # -- placement, sensing, truth -----------------------------------------------
    def _place(self, start: Any) -> None:
        p, d = self.params, self.data
        gap = p.tip_radius + 0.005
        for i, c in enumerate(start):
            self._cmd[i] = np.array(c.x) - gap * np.array(c.n)
            d.qpos[7 + 3 * i : 10 + 3 * i] = self._cmd[i]
        self.mj.mj_forward(self.model, d)
        for _ in range(20):  # the object settles on the table
            self._tick()
        for i in range(len(self.labels)):
            self._tare_tip(i)
        for i, c in enumerate(start):
            n = np.array(c.n)
            if self._approach(i, np.array(c.x) - 0.005 * n, n, 0.015) == "contact":
                self._hold(i, n)
        self._set_palm(True)

    def sense(self) -> Contacts3D | NoContact:  # type: ignore[override]
        """Every contact from the tared, averaged fingertip wrenches (world frame)."""
        wrench = self._read_wrench()
        contacts = []
        for i, x in enumerate(self.labels):
            got = contact_from_wrench(self._sphere, wrench[i, :3], wrench[i, 3:], self.params.contact_threshold)
            if isinstance(got, NoContact):
                self._sensed = None
                return NoContact(f"fingertip {x}: {got.reason}")
            point = self._centre(i) + np.array(got.point)
            contacts.append(Contact3D(tuple(point.tolist()), got.normal))  # type: ignore[arg-type]
        self._wrench = wrench
        self._sensed = config3d(contacts)  # type: ignore[assignment]
        return self._sensed  # type: ignore[return-value]

    @property
    def _sphere(self) -> Sphere:
        return Sphere(self.params.tip_radius)

    def raw_reading(self) -> dict[str, Any]:
        """The tared wrench behind the last reading: force (N) and torque (N m) per fingertip."""
        return {x: [round(float(v), 6) for v in self._wrench[i]] for i, x in enumerate(self.labels)}

    def true_config(self) -> Contacts3D | None:  # type: ignore[override]
        """The true contacts from MuJoCo's contact list (the deepest per fingertip), None if a tip is free."""
        d = self.data
        found: list[tuple[float, Contact3D] | None] = [None] * len(self.labels)
        for k in range(d.ncon):
            con = d.contact[k]
            pair = (int(con.geom1), int(con.geom2))
            for i, g in enumerate(self._tip_geom):
                if g in pair and (pair[0] in self._objects or pair[1] in self._objects):
                    n = np.array(con.frame[:3]) * (1.0 if pair[0] == g else -1.0)
                    c = Contact3D(tuple(float(v) for v in con.pos), tuple((n / np.linalg.norm(n)).tolist()))  # type: ignore[arg-type]
                    if found[i] is None or con.dist < found[i][0]:  # type: ignore[index]
                        found[i] = (float(con.dist), c)
        if any(f is None for f in found):
            return None
        return config3d([f[1] for f in found])  # type: ignore[index]

    def object_pose(self) -> tuple[float, ...]:  # type: ignore[override]
        """The object's position (m) and orientation quaternion ``(w, x, y, z)``."""
        return tuple(float(v) for v in self.data.qpos[:7])

    # -- CRMs ------------------------------------------------------------------
    def _approach(self, i: int, point: np.ndarray, direction: np.ndarray, length: float) -> str:
        """Approach from contact-point ``point`` along unit ``direction`` for ``length`` m."""
        d = np.asarray(direction)
        c0 = np.asarray(point) - self.params.tip_radius * d
        return self._move(i, c0 + length * d, self.params.approach_speed, detect=True, watch_palm=True)

    def _execute(self, crm: Any) -> Error:
        got = self._sensed if self._sensed is not None else self.sense()
        if isinstance(got, NoContact):
            raise CrmgraspError(f"cannot execute a CRM without contact ({got.reason})")
        s: Contacts3D = got  # type: ignore[assignment]
        i = self.labels.index(crm.c)
        mover, stills = s[i], [c for j, c in enumerate(s) if j != i]
        chord = goal_chord3d(self.hand, crm, s[self.labels.index(crm.f)], stills)
        if chord is None:
            return Error.APERTURE
        up = table_lift(chord, self.task.table)  # type: ignore[attr-defined]
        if up >= chord.length:
            return Error.PALM
        start, length = chord.start + up * chord.ahead, chord.length - up
        n = np.array(mover.n)
        home = self._centre(i) - self.hand.backoff * n
        self._set_palm(False)
        self._move(i, home, self.params.travel_speed)
        self._tare_tip(i)
        self._sensed = None
        if not self._transit(i, start - self.params.tip_radius * chord.ahead):
            return self._recover(i, mover, home, Error.PALM if up > 0.0 else Error.APERTURE)
        if not self._set_palm(True):
            return self._recover(i, mover, home, Error.PALM)
        outcome = self._approach(i, start, chord.ahead, length)
        if outcome != "contact":
            return self._recover(i, mover, home, Error.APERTURE if outcome == "end" else Error.PALM)
        self._hold(i, chord.ahead)
        new = self.sense()
        if self._palm_hit or (isinstance(new, (Config3D, Grip3D)) and faces_palm3d(new, self.hand)):
            return self._recover(i, mover, home, Error.PALM)
        return Error.NONE

    def _recover(self, i: int, original: Any, home: np.ndarray, error: Error) -> Error:
        """Back to the back-off point (collisions off) and re-touch along the old normal."""
        self._transit(i, home)
        n = np.array(original.n)
        self._set_palm(True)
        point = home + self.params.tip_radius * n
        if self._approach(i, point, n, 3 * self.hand.backoff + 0.01) == "contact":
            self._hold(i, n)
        self._sensed = None
        return error


HANDS: dict[str, type[MujocoHand]] = {"planar": MujocoHand, "spatial": MujocoHand3D}
"""Contact model kind -> the MuJoCo stand-in that holds it."""

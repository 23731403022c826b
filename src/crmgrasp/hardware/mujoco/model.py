"""The MuJoCo scene of the stand-in hand: parameters and the MJCF text.

World frame: the task's object frame at the start of a run (x-y in the table
plane, z up). The object is extruded to ``height`` and rests on a frictional
floor on a free joint, so it slides and turns when pushed hard enough. Each
fingertip is a sphere on a jointless child body (``tip_a``, ``tip_b``) of a
carriage with three slide joints driven by position servos; the child carries a
site with a ``force`` and a ``torque`` sensor, which measure what the fingertip
transmits to its carriage. The fingertips pass through each other (a real
hand's fingers do not share a plane); they collide with the object and floor.
The palm is a mocap body with a small sphere geom that the controller places at
the palm point ``P`` of [docs/model.md section 2][model-2] each tick.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

from crmgrasp._validation import CrmgraspError, non_negative, positive, shown
from crmgrasp.model.disc import Disc
from crmgrasp.model.geometry import Polygon
from crmgrasp.tasks import Task

__all__ = ["PhysicsParams", "mjcf"]


@dataclass(frozen=True)
class PhysicsParams:
    """Physical and controller parameters of the MuJoCo stand-in (SI units)."""

    height: float = 0.05
    """Object height, m (extrusion of the planar shape)."""
    object_mass: float = 1.0
    """kg; with ``floor_friction`` it sets the push (about 4.9 N) that slides the object."""
    floor_friction: float = 0.5
    rolling_friction: float = 0.01
    """Rolling friction between object and table, m (a torque of this times the normal
    force resists rolling; the spatial scene's lying cylinders: a cup on a cloth). The
    planar scene's contacts have no rolling friction (MuJoCo's condim 3)."""
    tip_radius: float = 0.01
    """Spherical fingertip radius, m."""
    tip_friction: float = 1.0
    palm_radius: float = 0.005
    """Radius of the palm's collision sphere at ``P``, m."""
    kp: float = 1000.0
    """Servo stiffness of each fingertip slide joint, N/m."""
    timestep: float = 0.002
    """Physics step, s."""
    control_steps: int = 5
    """Physics steps per control tick (the sensors are read once a tick)."""
    approach_speed: float = 0.05
    """Fingertip speed along a goal line while approaching, m/s."""
    travel_speed: float = 0.25
    """Fingertip speed in free space (back off, lift, travel, lower), m/s."""
    lift: float = 0.01
    """Clearance above the object's top while travelling, m."""
    hold_force: float = 2.0
    """Force a fingertip keeps pressing with once in contact, N."""
    contact_on: float = 0.3
    """Contact onset: rise of the high-pass filtered force along the push, N."""
    contact_off: float = 0.1
    """Detector re-arms when the filtered force magnitude is below this, N."""
    filter_tau: float = 0.5
    """High-pass filter time constant, s."""
    contact_threshold: float = 0.2
    """Smallest tared force that [`MujocoHand.sense`][crmgrasp.hardware.mujoco.hand.MujocoHand.sense]
    accepts as contact, N."""
    force_noise: float = 0.01
    """Standard deviation of each force channel's white noise, N."""
    torque_noise: float = 2e-5
    """Standard deviation of each torque channel's white noise, N m."""
    force_bias: float = 0.5
    """Standard deviation of each force channel's zero offset (strain gauges), N."""
    torque_bias: float = 0.005
    """Standard deviation of each torque channel's zero offset, N m."""
    force_drift: float = 0.002
    """Standard deviation of each force channel's drift rate (temperature), N/s."""
    torque_drift: float = 1e-5
    """Standard deviation of each torque channel's drift rate, N m/s."""
    sense_ticks: int = 5
    """Control ticks averaged by one [`MujocoHand.sense`][crmgrasp.hardware.mujoco.hand.MujocoHand.sense]."""
    settle_ticks: int = 20
    """Ticks a fingertip holds after contact before the CRM ends."""
    max_penetration: float = 0.005
    """Deepest interpenetration of two geoms after a CRM before it counts as a physics fault, m
    (MuJoCo's soft contacts sink about 0.7 mm under the 2 N holds)."""
    max_displacement: float = 0.3
    """Farthest the object's centre may move from where it was placed before the CRM counts
    as a physics fault (the object thrown off the table), m."""

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            if f.name in ("control_steps", "sense_ticks", "settle_ticks"):
                if not isinstance(value, int) or value < 1:
                    raise CrmgraspError(f"physics {f.name} must be an integer >= 1, got {value!r}")
            elif f.name.split("_")[-1] in ("noise", "bias", "drift") or f.name == "lift":
                non_negative(value, f"physics {f.name}")
            else:
                positive(value, f"physics {f.name}")
        if self.contact_off > self.contact_on:
            raise CrmgraspError("physics contact_off must be <= contact_on")

    @property
    def tick(self) -> float:
        """Control period, s."""
        return self.timestep * self.control_steps


def checked_params(params: object) -> PhysicsParams:
    """``params`` if it is a [`PhysicsParams`][] (the defaults for ``None``); one-line error otherwise."""
    if params is None:
        return PhysicsParams()
    if not isinstance(params, PhysicsParams):
        raise CrmgraspError(f"physics parameters must be a PhysicsParams, got {shown(params)}")
    return params


def _object_geom(task: Task, p: PhysicsParams) -> tuple[str, str]:
    """(asset XML, geom XML) of the task's object, extruded to ``p.height``."""
    obj, h = task.obj, p.height / 2
    common = (
        f'name="object" mass="{p.object_mass!r}" friction="{p.floor_friction!r} 0.005 0.0001" '
        'group="1" contype="3" conaffinity="3"'
    )
    if isinstance(obj, Disc):
        cx, cy = obj.center
        return "", f'<geom {common} type="cylinder" size="{obj.radius!r} {h!r}" pos="{cx!r} {cy!r} 0"/>'
    if isinstance(obj, Polygon):
        if not obj.convex:
            raise CrmgraspError("the MuJoCo stand-in needs a convex object (MuJoCo collides convex hulls)")
        verts = " ".join(f"{x!r} {y!r} {z!r}" for x, y in obj.vertices for z in (-h, h))
        return f'<mesh name="object" vertex="{verts}"/>', f'<geom {common} type="mesh" mesh="object"/>'
    raise CrmgraspError(f"the MuJoCo stand-in supports polygons and discs, not {type(obj).__name__}")


_TIP_COLOURS = {"a": ".85 .15 .15 1", "b": ".15 .65 .2 1", "c": ".15 .3 .85 1", "d": ".8 .6 .1 1"}
"""Fingertip colours by label (a red, b green, c blue, d amber)."""


def _finger(label: str, p: PhysicsParams, z: float) -> str:
    """A fingertip carriage at height ``z`` (its servo origin) with x, y, z slides."""
    r = p.tip_radius
    joints = "".join(
        f'<joint name="{label}{ax}" type="slide" axis="{v}" damping="0"/>'
        for ax, v in (("x", "1 0 0"), ("y", "0 1 0"), ("z", "0 0 1"))
    )
    return f"""
    <body name="carriage_{label}" pos="0 0 {z!r}" gravcomp="1">
      {joints}
      <inertial pos="0 0 0" mass="0.05" diaginertia="1e-5 1e-5 1e-5"/>
      <body name="tip_{label}" gravcomp="1">
        <geom name="tip_{label}" type="sphere" size="{r!r}" mass="0.01" friction="{p.tip_friction!r} 0.005 0.0001"
          contype="4" conaffinity="1"          rgba="{_TIP_COLOURS.get(label, ".5 .5 .5 1")}"/>
        <site name="tip_{label}"/>
      </body>
    </body>"""


def preamble(name: str, p: PhysicsParams, asset: str) -> str:
    """The opening of a stand-in scene's MJCF: options, lighting, assets, the world's light."""
    return f"""<mujoco model="{name}">
  <option timestep="{p.timestep!r}" integrator="implicitfast" cone="elliptic" noslip_iterations="3"/>
  <visual>
    <global offwidth="800" offheight="800"/>
    <headlight ambient=".25 .25 .25" diffuse=".3 .3 .3" specular="0 0 0"/>
  </visual>
  <asset>{asset}
    <texture name="grid" type="2d" builtin="checker" rgb1=".55 .55 .55" rgb2=".5 .5 .5" width="64" height="64"/>
    <material name="grid" texture="grid" texrepeat="20 20"/>
  </asset>
  <worldbody>
    <light pos="0 0 2" dir="0 0 -1" directional="true" diffuse=".5 .5 .5"/>"""


def hand_mjcf(p: PhysicsParams, z: float, labels: tuple[str, ...] = ("a", "b")) -> tuple[str, str]:
    """(bodies, actuators and sensors) of a hand with one fingertip per label (two by
    default), carriages at height ``z``: position servos (critically damped for the 60 g
    finger) and each tip's force and torque sensors."""
    kv = 2.0 * math.sqrt(p.kp * 0.06)
    servos = "".join(
        f'<position name="{lab}{ax}" joint="{lab}{ax}" kp="{p.kp!r}" kv="{kv!r}"/>' for lab in labels for ax in "xyz"
    )
    sensors = "".join(
        f'<force name="force_{lab}" site="tip_{lab}"/><torque name="torque_{lab}" site="tip_{lab}"/>' for lab in labels
    )
    bodies = "".join(_finger(lab, p, z) for lab in labels)
    return bodies, f"<actuator>{servos}</actuator>\n  <sensor>{sensors}</sensor>"


def mjcf(task: Task, params: PhysicsParams = PhysicsParams(), labels: tuple[str, ...] = ("a", "b")) -> str:
    """MJCF text of the stand-in scene for ``task``'s object and a hand with one fingertip
    per label (two by default)."""
    p = params
    asset, geom = _object_geom(task, p)
    fingers, drives = hand_mjcf(p, p.height / 2, labels)
    return f"""{preamble(f"crmgrasp-{task.name}", p, asset)}
    <camera name="top" pos="0 0 0.6" xyaxes="1 0 0 0 1 0"/>
    <geom name="floor" type="plane" size="2 2 0.1" material="grid" friction="{p.floor_friction!r} 0.005 0.0001"/>
    <body name="object" pos="0 0 {p.height / 2!r}">
      <freejoint name="object"/>
      {geom.replace("/>", ' rgba=".2 .35 .7 1"/>')}
    </body>{fingers}
    <body name="palm" mocap="true" pos="0 -1 {p.height / 2!r}">
      <geom name="palm" type="sphere" size="{p.palm_radius!r}" contype="0" conaffinity="0" rgba=".9 .5 .2 1"/>
    </body>
  </worldbody>
  {drives}
</mujoco>
"""

"""A MuJoCo-simulated two-fingertip hand that executes CRMs as real motions.

[`MujocoHand`][] implements [`HandInterface`][crmgrasp.hardware.runner.HandInterface]. It knows
its own kinematics (fingertip sensor poses) but not the object: ``sense()`` reads
the two fingertip force/torque sensors (with white noise and a slow linear drift
per channel), subtracts each sensor's tare (taken whenever that fingertip is
free), averages ``sense_ticks`` control ticks, and turns each wrench into a
contact by intrinsic contact sensing ([`contact_from_wrench`][crmgrasp.hardware.contact_sensing.contact_from_wrench]
on a [`Circle`][crmgrasp.hardware.contact_sensing.Circle] of the tip radius). MuJoCo's
contact list is used only by [`MujocoHand.true_config`][], for evaluation.

A CRM ``(c, f, r)`` runs as ([docs/model.md section 3][model-3] made physical):

1. the goal line and its reach chord from the *sensed* configuration (the
   stationary contact's sensed position); no chord: aperture error, no motion;
2. back off by ``hand.backoff`` along the moving contact's sensed outward
   normal, tare its sensor, lift above the object, travel to above the chord's
   start, lower to the contact plane. Contact felt while lowering means the start
   is over (inside) the object: aperture error;
3. switch the palm's collision geometry on (if it already overlaps the object:
   palm error) and approach along the line at ``approach_speed`` until the
   high-pass filtered force rises by ``contact_on`` (contact), the palm collides
   (palm error), or the chord ends (aperture error);
4. press with ``hold_force``, settle, sense; a sensed contact surface facing the
   palm side by more than ``hand.palm_normal_tol`` (the fingertip cannot push
   toward its own palm) is a palm error;
5. on any error the fingertip goes back over the air to its original back-off
   point and re-approaches along its original normal.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from crmgrasp._validation import CrmgraspError, generator
from crmgrasp.hardware.contact_sensing import Circle, ContactDetector, NoContact, contact_from_wrench
from crmgrasp.hardware.mujoco import require_mujoco
from crmgrasp.hardware.mujoco.model import PhysicsParams, checked_params, mjcf
from crmgrasp.model.contacts import Config, Contact, Grip
from crmgrasp.model.hand import CRM, Error, goal_line
from crmgrasp.model.palm import faces_palm, palm_point
from crmgrasp.tasks import Task, checked_task

__all__ = ["MujocoHand", "PhysicsError", "FAULTS"]

FAULTS = ("unstable", "penetration", "off the table")
"""The kinds of [`PhysicsError`][]."""


class PhysicsError(CrmgraspError):
    """A CRM (or the placement) after which MuJoCo's state cannot be trusted: ``kind`` is one
    of [`FAULTS`][]: ``"unstable"`` (a state that is not finite, or MuJoCo's own bad
    acceleration warning, after which it resets the state), ``"penetration"`` (two geoms
    interpenetrate by more than ``PhysicsParams.max_penetration``) or ``"off the table"``
    (the object's centre moved more than ``PhysicsParams.max_displacement``)."""

    def __init__(self, kind: str, detail: str) -> None:
        super().__init__(f"physics fault ({kind}): {detail}")
        self.kind = kind


class MujocoHand:
    """The MuJoCo stand-in hand holding ``task.obj`` from ``start`` (object frame = world).

    Parameters
    ----------
    task
        The task (object, hand limits, CRM set). Its hand's ``palm_normal_tol``
        applies to the fingertips' pushing direction (use a noisy-execution task).
    start
        The true starting contacts; the fingertips are placed just outside them
        and approach along the inward normals until contact is felt.
    rng
        Source of all sensor noise and drift.
    params
        Physical and controller parameters.
    """

    camera = "top"
    """The scene camera that renderings use."""

    def __init__(
        self, task: Task, start: Config, rng: np.random.Generator, params: PhysicsParams | None = None
    ) -> None:
        self.mj = require_mujoco()
        task = checked_task(task, "MujocoHand")
        start, params = task.check_config(start, "start"), checked_params(params)
        self.task, self.params, self.rng = task, params, generator(rng)
        self.labels = tuple(task.model.labels)
        """The fingertips, in the contact model's order (``a, b``; ``a, b, c`` for three fingers)."""
        n = len(self.labels)
        self.model = self.mj.MjModel.from_xml_string(self._scene())
        self.data = self.mj.MjData(self.model)
        m = self.model
        self._tip_geom = [self.mj.mj_name2id(m, self.mj.mjtObj.mjOBJ_GEOM, f"tip_{x}") for x in self.labels]
        self._site = [self.mj.mj_name2id(m, self.mj.mjtObj.mjOBJ_SITE, f"tip_{x}") for x in self.labels]
        body = self.mj.mj_name2id(m, self.mj.mjtObj.mjOBJ_BODY, "object")
        self._objects = [g for g in range(m.ngeom) if int(m.geom_bodyid[g]) == body]
        """The object's geoms (one, or a mesh's convex pieces)."""
        self._palm = self.mj.mj_name2id(m, self.mj.mjtObj.mjOBJ_GEOM, "palm")
        sd = np.array([params.force_noise] * 3 + [params.torque_noise] * 3)
        bias = np.array([params.force_bias] * 3 + [params.torque_bias] * 3)
        drift = np.array([params.force_drift] * 3 + [params.torque_drift] * 3)
        self._noise_sd = sd
        self._bias = rng.normal(0.0, 1.0, size=(n, 6)) * bias
        self._rates = rng.normal(0.0, 1.0, size=(n, 6)) * drift
        self._tare = np.zeros((n, 6))
        self._raw = np.zeros((n, 6))
        self._wrench = np.zeros((n, 6))
        sensor = m.sensor
        # per fingertip, the sensordata indices of its force (3) and torque (3) readings
        first = np.array([[sensor(f"{kind}_{x}").adr[0] for kind in ("force", "torque")] for x in self.labels])
        self._sensors = (first[:, :, None] + np.arange(3)).reshape(n, 6)
        self._cmd = np.zeros((n, 3))
        self._sensed: Config | Grip | None = None
        self._palm_hit = False
        self.tip = Circle(params.tip_radius)
        self.crm_seconds: list[float] = []
        """Wall time of each executed CRM, s."""
        self.on_tick: Callable[[MujocoHand], None] | None = None
        """Called after every control tick (e.g. to record animation frames)."""
        self._place(start)
        self._home = np.array(self.data.qpos[:3])
        self.check_physics()

    # -- the scene's geometry (overridden by the spatial hand) ----------------------
    def _scene(self) -> str:
        """The MJCF text of the scene."""
        return mjcf(self.task, self.params, tuple(self.task.model.labels))

    def _origin(self) -> np.ndarray:
        """World position of the carriages' origin (a servo target of 0)."""
        return np.array([0.0, 0.0, self.params.height / 2])

    def _palm_obstacles(self) -> list[int]:
        """Geoms the palm must not overlap when it is switched on."""
        return list(self._objects)

    def _config(self, contacts: list[Contact]) -> Config | Grip:
        """The configuration of one contact per fingertip, in label order."""
        return Config(*contacts) if len(contacts) == 2 else Grip(*contacts)

    def _palm_target(self) -> np.ndarray | None:
        """The palm point ``P`` of the fingertip centres (None if the outer two coincide)."""
        centres = [self._centre(i).tolist() for i in range(len(self.labels))]
        px, py = palm_point(self._config([Contact(x, y, 0.0, 0.0) for x, y, _ in centres]), self.task.hand.palm_depth)
        return np.array([px, py, self.params.height / 2]) if math.isfinite(px) else None

    # -- low level -------------------------------------------------------------
    def _tick(self) -> None:
        """Place the palm at ``P`` of the fingertip centres, step, read the sensors."""
        d, p = self.data, self.params
        palm = self._palm_target()
        if palm is not None:  # the 1 cm tips never coincide; if they did, the palm stays put
            d.mocap_pos[0] = palm
        d.ctrl[:] = self._cmd.ravel()
        self.mj.mj_step(self.model, d, nstep=p.control_steps)
        # the sensors report what the tip transmits to its carriage: the object's push on the
        # fingertip is the negative (one draw of 6 normals per fingertip, in label order)
        wrench = d.sensordata[self._sensors]
        noise = self.rng.normal(0.0, 1.0, self._raw.shape)
        self._raw[:] = -wrench + self._bias + self._rates * d.time + noise * self._noise_sd
        if self.model.geom_contype[self._palm] and d.ncon:
            geoms = d.contact.geom
            self._palm_hit |= bool(np.any(geoms == self._palm))
        if self.on_tick is not None:
            self.on_tick(self)

    def _centre(self, i: int) -> np.ndarray:
        """Fingertip centre, world frame (the robot's forward kinematics)."""
        return np.array(self.data.site_xpos[self._site[i]])

    def _to_cmd(self, world: np.ndarray) -> np.ndarray:
        return np.asarray(world, dtype=float) - self._origin()

    def _move(self, i: int, target: np.ndarray, speed: float, detect: bool = False, watch_palm: bool = False) -> str:
        """Drive fingertip ``i``'s servo target in a straight line to ``target`` (world).

        Returns ``"contact"`` at a detected onset, ``"palm"`` on a palm collision,
        ``"end"`` when the target is reached (after the servo settles).
        """
        p = self.params
        detector = ContactDetector(p.filter_tau, p.tick, p.contact_on, p.contact_off) if detect else None
        if detector is not None:
            detector(self._raw[i, :3])
        start = self._cmd[i].copy()
        goal = self._to_cmd(target)
        n = max(1, math.ceil(float(np.linalg.norm(goal - start)) / (speed * p.tick)))
        for k in range(1, n + 1 + p.settle_ticks // 2):
            self._cmd[i] = start + (goal - start) * min(1.0, k / n)
            self._tick()
            if watch_palm and self._palm_hit:
                return "palm"
            if detector is not None and detector(self._raw[i, :3]):
                return "contact"
        return "end"

    def _hold(self, i: int, direction: np.ndarray) -> None:
        """Press fingertip ``i`` along ``direction`` (2-D: in the plane) with about ``hold_force``."""
        push = self.params.hold_force / self.params.kp
        d = np.zeros(3)
        d[: len(direction)] = direction
        self._cmd[i] = self._to_cmd(self._centre(i)) + push * d
        for _ in range(self.params.settle_ticks):
            self._tick()

    def _set_palm(self, on: bool) -> bool:
        """Switch the palm's collision geometry; False if it would start inside the object."""
        m = self.model
        self._palm_hit = False
        if not on:
            m.geom_contype[self._palm] = m.geom_conaffinity[self._palm] = 0
            return True
        for g in self._palm_obstacles():
            if self.mj.mj_geomDistance(m, self.data, self._palm, g, 0.01, None) <= 0.0:
                return False
        m.geom_contype[self._palm] = m.geom_conaffinity[self._palm] = 2
        return True

    def _tare_tip(self, i: int) -> None:
        acc = np.zeros(6)
        for _ in range(self.params.sense_ticks):
            self._tick()
            acc += self._raw[i]
        self._tare[i] = acc / self.params.sense_ticks

    def _approach(self, i: int, point: np.ndarray, direction: np.ndarray, length: float) -> str:
        """Approach from contact-point ``point`` along unit ``direction`` for ``length`` m."""
        r = self.params.tip_radius
        z = self.params.height / 2
        c0 = np.array([point[0] - r * direction[0], point[1] - r * direction[1], z])
        c1 = c0 + length * np.array([direction[0], direction[1], 0.0])
        return self._move(i, c1, self.params.approach_speed, detect=True, watch_palm=True)

    def _air(self, i: int, centre_xy: np.ndarray) -> str:
        """Lift fingertip ``i``, travel over the object to ``centre_xy``, lower to the
        contact plane; ``"contact"`` if the object is felt while lowering."""
        p = self.params
        self._set_palm(False)
        up = p.height + p.tip_radius + p.lift
        here = self._centre(i)
        self._move(i, np.array([here[0], here[1], up]), p.travel_speed)
        self._move(i, np.array([centre_xy[0], centre_xy[1], up]), p.travel_speed)
        down = np.array([centre_xy[0], centre_xy[1], p.height / 2])
        return self._move(i, down, p.approach_speed, detect=True)

    # -- placement, sensing, truth -----------------------------------------------
    def _place(self, start: Config) -> None:
        p, d = self.params, self.data
        gap = p.tip_radius + 0.005
        for i, c in enumerate(start):
            self._cmd[i] = (c.x - gap * c.nx, c.y - gap * c.ny, 0.0)
            d.qpos[7 + 3 * i : 10 + 3 * i] = self._cmd[i]
        self.mj.mj_forward(self.model, d)
        for _ in range(10):
            self._tick()
        for i in range(len(self.labels)):
            self._tare_tip(i)
        for i, c in enumerate(start):
            n = np.array(c.normal)
            if self._approach(i, np.array(c.point) - 0.005 * n, n, 0.015) == "contact":
                self._hold(i, n)
        self._set_palm(True)

    def _read_wrench(self) -> np.ndarray:
        """Every fingertip's wrench ``(f, m)``, averaged over ``sense_ticks`` and tared, ``(N, 6)``."""
        p = self.params
        acc = np.zeros((len(self.labels), 6))
        for _ in range(p.sense_ticks):
            self._tick()
            acc += self._raw
        return acc / p.sense_ticks - self._tare

    def sense(self) -> Config | Grip | NoContact:
        """Every contact from the tared, averaged fingertip wrenches (world frame)."""
        p = self.params
        wrench = self._read_wrench()
        contacts = []
        for i, x in enumerate(self.labels):
            got = contact_from_wrench(self.tip, wrench[i, :2], float(wrench[i, 5]), p.contact_threshold)
            if isinstance(got, NoContact):
                self._sensed = None
                return NoContact(f"fingertip {x}: {got.reason}")
            centre = self._centre(i)
            contacts.append(Contact(centre[0] + got.point[0], centre[1] + got.point[1], *got.normal))
        self._wrench = wrench
        self._sensed = self._config(contacts)
        return self._sensed

    def raw_reading(self) -> dict[str, Any]:
        """The tared wrench behind the last reading: ``f_x, f_y, m_z`` per fingertip (N, N m)."""
        w = self._wrench
        return {x: [round(float(v), 6) for v in (w[i, 0], w[i, 1], w[i, 5])] for i, x in enumerate(self.labels)}

    def true_config(self) -> Config | Grip | None:
        """The true contacts from MuJoCo's contact list (world frame), None if a tip is free."""
        d = self.data
        found: list[Contact | None] = [None] * len(self.labels)
        for k in range(d.ncon):
            con = d.contact[k]
            pair = (int(con.geom1), int(con.geom2))
            for i, g in enumerate(self._tip_geom):
                if g in pair and (pair[0] in self._objects or pair[1] in self._objects):
                    n = np.array(con.frame[:2]) * (1.0 if pair[0] == g else -1.0)
                    n /= np.linalg.norm(n)
                    found[i] = Contact(float(con.pos[0]), float(con.pos[1]), float(n[0]), float(n[1]))
        if any(c is None for c in found):
            return None
        return self._config(found)  # type: ignore[arg-type]

    @property
    def time(self) -> float:
        """The simulated time, s (the clock of the hand's records)."""
        return float(self.data.time)

    def object_pose(self) -> tuple[float, float, float]:
        """Object position ``(x, y)`` (m) and yaw (rad) in the world."""
        q = self.data.qpos
        return float(q[0]), float(q[1]), 2.0 * math.atan2(float(q[6]), float(q[3]))

    def check_physics(self) -> None:
        """Raise [`PhysicsError`][] if MuJoCo's state cannot be trusted (see there)."""
        d, p, mj = self.data, self.params, self.mj
        warned = (mj.mjtWarning.mjWARN_BADQACC, mj.mjtWarning.mjWARN_BADQPOS, mj.mjtWarning.mjWARN_BADQVEL)
        if not (np.isfinite(d.qpos).all() and np.isfinite(d.qvel).all()) or any(d.warning[w].number for w in warned):
            raise PhysicsError("unstable", "the simulation state diverged")
        if d.ncon and float(d.contact.dist.min()) < -p.max_penetration:
            depth = -float(d.contact.dist.min())
            raise PhysicsError("penetration", f"geoms interpenetrate by {depth * 1e3:.1f} mm")
        shift = float(np.linalg.norm(d.qpos[:3] - self._home))
        if shift > p.max_displacement:
            raise PhysicsError("off the table", f"the object moved {shift:.2f} m")

    # -- CRMs ------------------------------------------------------------------
    def execute(self, crm: Any) -> Error:
        """Execute ``crm`` as a real motion; return its error flag, or raise
        [`PhysicsError`][] if the physics went wrong on the way."""
        t0 = time.perf_counter()
        try:
            error = self._execute(self.task.hand.check_crm(crm))
        finally:
            self.crm_seconds.append(time.perf_counter() - t0)
        self.check_physics()
        return error

    def _execute(self, crm: CRM) -> Error:
        s = self._sensed if self._sensed is not None else self.sense()
        if isinstance(s, NoContact):
            raise CrmgraspError(f"cannot execute a CRM without contact ({s.reason})")
        i = crm.ci
        mover, stills = s[i], tuple(c for j, c in enumerate(s) if j != i)
        line = goal_line(crm, s, stills, self.task.hand.aperture)
        if line is None:
            return Error.APERTURE
        same = crm.c == crm.f
        t0, t1 = (line.t_lo, line.t_hi) if same else (line.t_hi, line.t_lo)
        sign = 1.0 if same else -1.0
        direction = np.array(line.direction) * sign
        start = np.array(line.at(t0))
        home = self._centre(i) - self.task.hand.backoff * np.array([mover.nx, mover.ny, 0.0])
        self._set_palm(False)
        self._move(i, home, self.params.travel_speed)
        self._tare_tip(i)
        self._sensed = None
        centre = start - self.params.tip_radius * direction
        if self._air(i, centre) == "contact":
            return self._recover(i, mover, home, Error.APERTURE)
        if not self._set_palm(True):
            return self._recover(i, mover, home, Error.PALM)
        outcome = self._approach(i, start, direction, abs(t1 - t0))
        if outcome != "contact":
            return self._recover(i, mover, home, Error.APERTURE if outcome == "end" else Error.PALM)
        self._hold(i, direction)
        new = self.sense()
        if self._palm_hit or (isinstance(new, Config) and faces_palm(new, self.task.hand.palm_normal_tol)):
            return self._recover(i, mover, home, Error.PALM)
        return Error.NONE

    def _recover(self, i: int, original: Contact, home: np.ndarray, error: Error) -> Error:
        """Go back over the air to the back-off point and re-establish the contact."""
        self._set_palm(False)
        self._air(i, home[:2])
        n = np.array(original.normal)
        self._set_palm(True)
        if self._approach(i, home[:2] + self.params.tip_radius * n, n, 3 * self.task.hand.backoff + 0.01) == "contact":
            self._hold(i, n)
        self._sensed = None
        return error

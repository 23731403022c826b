"""A grasp-controller baseline: a fixed feedback rule on the frictionless residuals.

In the spirit of the grasp controllers the paper cites (Coelho and Grupen), it
does not learn; it displaces contacts to drive the frictionless residuals to
zero. The moment about contact ``i``, ``m_i = (x_j - x_i) x n_j``, vanishes
exactly when ``i`` lies on contact ``j``'s normal line, so the rule is:

1. Oppose with the contact that has the larger ``|m|``: CRM ``(i, j, 0)``, which
   puts ``i`` on ``j``'s normal line and zeroes ``m_i`` (and ``rho`` on parallel
   faces).
2. If that CRM reports an error, slide the frame contact ``j`` along its own
   tangent so that its normal line moves toward ``i``: CRM ``(j, j, r)``. Since
   ``tau_j x n_j = 1``, this changes ``m_i`` by exactly ``r`` (on a flat face), so
   ``r = clip(-m_i, -r_step, r_step)``, at most ``r_step`` (default: the largest
   ``|r|`` among the task's own-frame CRMs, 0.08 m for paper-box). Then go back
   to 1. (Sliding ``i`` itself changes ``m_i`` by ``r n_i . n_j``: nothing at a
   right-angle corner.)
3. If the slide fails too, or would be shorter than 1 mm, oppose with the other
   contact instead.

It reads sensed contact frames (what a CRM's goal line is built from anyway) and
the error flag; it may issue any ``(c, f, r)`` with ``|r| <= r_max``, not only the
task's four CRMs. It is a [`Policy`][crmgrasp.sim.Policy]: episodes run through
[`crmgrasp.sim.run_episode`][].
"""

from __future__ import annotations

import numpy as np

from crmgrasp._validation import CrmgraspError, generator, integer
from crmgrasp.agents.training import MAX_EPISODE_RECORDS
from crmgrasp.model.contacts import Config, Grip
from crmgrasp.model.hand import CRM, Error
from crmgrasp.sim import Percept, run_episode
from crmgrasp.tasks import Task, checked_task

__all__ = ["GraspController", "run_controller"]


class GraspController:
    """The fixed rule above, for one task."""

    name = "grasp-controller"

    def __init__(self, task: Task, r_step: float | None = None) -> None:
        if task.model.kind != "planar" or task.model.n_contacts != 2:
            kind = f"{task.model.kind} with {task.model.n_contacts} contacts"
            raise CrmgraspError(f"the grasp controller drives two contacts in the plane; {task.name!r} is {kind}")
        self.task = task
        own = [abs(a.r) for a in task.actions if a.c == a.f]
        self.r_step = r_step if r_step is not None else (max(own) if own else 0.5 * task.hand.aperture)
        self._last: CRM | None = None
        self._last_error = Error.NONE
        self._sensed: Config | Grip | None = None
        self._pending = CRM("a", "b", 0.0)

    def begin(self, first: Percept) -> None:
        """Forget the previous episode; read the first percept."""
        self._last, self._last_error, self._sensed = None, Error.NONE, first.sensed

    def act(self) -> CRM:
        """The next CRM ([`choose`][] on the last sensed configuration)."""
        assert self._sensed is not None, "begin() first"
        self._pending = self.choose(self._sensed)
        return self._pending

    def tell(self, percept: Percept) -> None:
        """Record the outcome of the CRM just executed and the new reading."""
        self.observe(self._pending, percept.error)
        self._sensed = percept.sensed

    def choose(self, sensed: Config | Grip) -> CRM:
        """The next CRM, given the sensed configuration and the last CRM's outcome."""
        _, *moments = self.task.observe(sensed)
        m = dict(zip(self.task.model.labels, moments, strict=True))  # the moment about each contact
        last = self._last
        if last is None or self._last_error is Error.NONE:
            c = "a" if abs(m["a"]) >= abs(m["b"]) else "b"
            return CRM(c, "b" if c == "a" else "a", 0.0)
        if last.opposition:
            moment = m[last.c]
            r = float(np.clip(-moment, -self.r_step, self.r_step))
            if abs(r) >= 1e-3:
                return CRM(last.f, last.f, r)
        # the slide failed, or would be too short to matter: oppose with the other contact
        return CRM("b" if last.c == "a" else "a", last.c, 0.0)

    def observe(self, crm: CRM, error: Error) -> None:
        """Record the outcome of the CRM just executed."""
        self._last, self._last_error = crm, error


def run_controller(task: Task, episodes: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """CRMs per episode and success flags of the controller over fresh starts (noise
    from ``task.noise``; starts and readings drawn from ``rng``)."""
    task, rng = checked_task(task, "run_controller"), generator(rng)
    episodes = integer(episodes, "episodes", 1, MAX_EPISODE_RECORDS)
    ctl = GraspController(task)
    steps = np.empty(episodes, dtype=np.int64)
    success = np.empty(episodes, dtype=bool)
    for e in range(episodes):
        steps[e], success[e], _ = run_episode(task, ctl, rng)
    return steps, success

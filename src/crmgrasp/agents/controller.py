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
task's four CRMs.
"""

from __future__ import annotations

import numpy as np

from ..contacts import Config
from ..hand import CRM, Error, execute_crm
from ..quality import min_friction
from ..tasks import Task

__all__ = ["GraspController", "run_controller"]


class GraspController:
    """The fixed rule above, for one task."""

    name = "grasp-controller"

    def __init__(self, task: Task, r_step: float | None = None) -> None:
        self.task = task
        own = [abs(a.r) for a in task.actions if a.c == a.f]
        self.r_step = r_step if r_step is not None else (max(own) if own else 0.5 * task.hand.aperture)
        self._last: CRM | None = None
        self._last_error = Error.NONE

    def begin_episode(self) -> None:
        """Forget the previous episode."""
        self._last, self._last_error = None, Error.NONE

    def choose(self, sensed: Config) -> CRM:
        """The next CRM, given the sensed configuration and the last CRM's outcome."""
        a, b = sensed
        m_a = (b.x - a.x) * b.ny - (b.y - a.y) * b.nx
        m_b = -(b.x - a.x) * a.ny + (b.y - a.y) * a.nx
        last = self._last
        if last is None or self._last_error is Error.NONE:
            c = "a" if abs(m_a) >= abs(m_b) else "b"
            return CRM(c, "b" if c == "a" else "a", 0.0)
        if last.opposition:
            m = m_a if last.c == "a" else m_b
            r = float(np.clip(-m, -self.r_step, self.r_step))
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
    ctl = GraspController(task)
    steps = np.empty(episodes, dtype=np.int64)
    success = np.empty(episodes, dtype=bool)
    for e in range(episodes):
        config = task.sample_start(rng)
        sensed = task.noise.sense(config, rng)
        ctl.begin_episode()
        n, ok = 0, False
        while n < task.max_steps and not ok:
            crm = task.hand.check_crm(ctl.choose(sensed))
            out = execute_crm(task.obj, task.hand, config, crm, sensed)
            config, n = out.config, n + 1
            sensed = task.noise.sense(config, rng)
            ctl.observe(crm, out.error)
            ok = min_friction(config) <= task.mu_goal
        steps[e], success[e] = n, ok
    return steps, success

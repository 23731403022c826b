"""The model: what a two-contact hand touching an unseen planar object is and senses.

One module per concept, each rule written once in readable Python:

* [`shape`][crmgrasp.model.shape]: tolerances, the [`Shape`][] protocol;
  `polygon`, [`disc`][crmgrasp.model.disc] and
  [`geometry`][crmgrasp.model.geometry]: objects, their boundary, inside test and first entry;
* [`contacts`][crmgrasp.model.contacts]: contacts and configurations;
* [`hand`][crmgrasp.model.hand]: the hand, feasibility (aperture and palm), the CRM
  transition and its error flags; [`palm`][crmgrasp.model.palm]: the palm's side and point;
* [`sensing`][crmgrasp.model.sensing]: observations, sensing noise, observation bins;
* [`quality`][crmgrasp.model.quality]: min friction and force closure;
* [`history`][crmgrasp.model.history]: the k-order history state.

The model imports no kernel, numba or matplotlib (a test keeps it so); fast
evaluations of these rules live in [`crmgrasp.kernels`][].
"""

from crmgrasp.model.contacts import Config, Contact
from crmgrasp.model.geometry import Disc, Polygon, Rectangle, regular_polygon
from crmgrasp.model.hand import CRM, Error, Hand, Outcome, execute_crm, feasible
from crmgrasp.model.history import KOrderEncoder
from crmgrasp.model.quality import force_closure, is_force_closure, min_friction
from crmgrasp.model.sensing import Discretizer, Observation, SensorNoise, observe
from crmgrasp.model.shape import EPS, LINE_TOL, S_TOL, Shape

__all__ = [
    "Config",
    "Contact",
    "Disc",
    "Polygon",
    "Rectangle",
    "regular_polygon",
    "CRM",
    "Error",
    "Hand",
    "Outcome",
    "execute_crm",
    "feasible",
    "KOrderEncoder",
    "force_closure",
    "is_force_closure",
    "min_friction",
    "Discretizer",
    "Observation",
    "SensorNoise",
    "observe",
    "EPS",
    "LINE_TOL",
    "S_TOL",
    "Shape",
]

"""crmgrasp: learning grasp strategies composed of contact relative motions (Platt)."""

from crmgrasp._validation import CrmgraspError
from crmgrasp.envs.single import CRMGraspEnv, KOrderHistory  # registers crmgrasp/PaperBox-v0
from crmgrasp.model.contacts import Config, Contact
from crmgrasp.model.geometry import Disc, Polygon, Rectangle, regular_polygon
from crmgrasp.model.hand import CRM, Error, Hand, Outcome
from crmgrasp.model.quality import force_closure, is_force_closure, min_friction
from crmgrasp.model.sensing import Discretizer, Observation, SensorNoise, observe
from crmgrasp.tasks import Task, make_task, paper_box, register_task

__version__ = "0.1.0"

__all__ = [
    "CrmgraspError",
    "Config",
    "Contact",
    "Disc",
    "Polygon",
    "Rectangle",
    "regular_polygon",
    "CRM",
    "Hand",
    "Outcome",
    "force_closure",
    "is_force_closure",
    "min_friction",
    "Discretizer",
    "Error",
    "Observation",
    "SensorNoise",
    "observe",
    "Task",
    "make_task",
    "paper_box",
    "register_task",
    "CRMGraspEnv",
    "KOrderHistory",
    "__version__",
]

"""crmgrasp: learning grasp strategies composed of contact relative motions (Platt)."""

from ._validation import CrmgraspError
from .contacts import Config, Contact
from .env import CRMGraspEnv, KOrderHistory  # registers crmgrasp/PaperBox-v0
from .geometry import Disc, Polygon, Rectangle, regular_polygon
from .hand import CRM, Error, Hand, Outcome
from .quality import force_closure, is_force_closure, min_friction
from .sensing import Discretizer, Observation, SensorNoise, observe
from .tasks import Task, make_task, paper_box, register_task

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

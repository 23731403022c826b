"""Grasping tasks: object, hand, CRM set, observation bins, starts, goal.

[`crmgrasp.tasks.core`][] defines [`Task`][], the start samplers and the registry
(``"paper-box"`` is the paper's box task); [`crmgrasp.tasks.files`][] reads tasks
from TOML files and ``package.module:factory`` strings ([`resolve_task`][], what
``--task`` accepts) and writes them back as plain data.
"""

from crmgrasp.tasks.core import (
    Symmetry,
    Task,
    World,
    as_task,
    checked_task,
    make_task,
    paper_box,
    register_task,
    task_names,
)
from crmgrasp.tasks.families import FAMILY_TASKS, BoundaryStarts, default_crms, family_task, mirror_symmetry
from crmgrasp.tasks.files import TEMPLATE, load_task_file, resolve_task, task_from_dict, task_to_dict
from crmgrasp.tasks.fingers import FINGER_TASKS, finger_crms, three_finger_task
from crmgrasp.tasks.spatial import SPATIAL_TASKS, SpatialTask, SurfaceStarts, spatial_crms
from crmgrasp.tasks.starts import (
    CornerStarts,
    StartFilter,
    StartSampler,
    UniformStarts,
    accept_corner_candidates,
    acceptable,
    corner_boxes,
    corner_candidate,
    corner_proposal,
)

__all__ = [
    "StartSampler",
    "StartFilter",
    "CornerStarts",
    "UniformStarts",
    "Task",
    "World",
    "BoundaryStarts",
    "default_crms",
    "family_task",
    "mirror_symmetry",
    "FAMILY_TASKS",
    "FINGER_TASKS",
    "finger_crms",
    "three_finger_task",
    "SPATIAL_TASKS",
    "SpatialTask",
    "SurfaceStarts",
    "spatial_crms",
    "Symmetry",
    "paper_box",
    "make_task",
    "as_task",
    "checked_task",
    "register_task",
    "task_names",
    "acceptable",
    "accept_corner_candidates",
    "corner_boxes",
    "corner_candidate",
    "corner_proposal",
    "TEMPLATE",
    "load_task_file",
    "resolve_task",
    "task_from_dict",
    "task_to_dict",
]

"""Loading a saved policy of any kind: the one entry point that knows every policy file.

[`load_policy`][] looks at the file and hands it to the loader of its kind: a tabular
[`GreedyPolicy`][crmgrasp.agents.policy.GreedyPolicy] (JSON) or a deep
[`RecurrentPolicy`][crmgrasp.agents.deep.RecurrentPolicy] (zip). It lives apart from both so that
neither policy module imports the other.
"""

from __future__ import annotations

import os
import stat
from typing import Any

from crmgrasp._io import as_path
from crmgrasp.agents.policy import GreedyPolicy
from crmgrasp.tasks import Task, checked_task

__all__ = ["load_policy"]


def _is_zip(path: str | os.PathLike[str]) -> bool:
    """Whether ``path`` is a regular file starting with a zip signature (two bytes read;
    anything else is left to the loaders, which report it)."""
    try:
        if not stat.S_ISREG(os.stat(path).st_mode):
            return False
        with open(path, "rb") as fh:
            return fh.read(2) == b"PK"
    except OSError:
        return False


def load_policy(path: str | os.PathLike[str], task: Task | None = None) -> Any:
    """A saved policy of any kind: a tabular [`GreedyPolicy`][] (JSON) or a deep
    [`RecurrentPolicy`][crmgrasp.agents.deep.RecurrentPolicy] (zip; needs the extra ``deep``)."""
    path = as_path(path, "policy file")
    if task is not None:
        task = checked_task(task, "load_policy")
    if _is_zip(path):
        from crmgrasp.agents.deep import RecurrentPolicy

        return RecurrentPolicy.load(path, task)
    return GreedyPolicy.load(path, task)

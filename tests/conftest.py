"""Shared fixtures; hypothesis profiles."""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")  # headless; MuJoCo reads it at its first import

import pytest
from hypothesis import HealthCheck, settings

from crmgrasp.tasks import paper_box

settings.register_profile(
    "default",
    max_examples=150,
    deadline=None,
    suppress_health_check=[HealthCheck.filter_too_much, HealthCheck.too_slow],
)
settings.register_profile("ci", parent=settings.get_profile("default"), derandomize=True)
settings.register_profile("stress", parent=settings.get_profile("default"), max_examples=3000)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE") or ("ci" if os.environ.get("CI") else "default"))


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Tests marked ``slow`` run first, the rest in their order: pytest-xdist hands tests out
    from the front, so with ``-n 2`` the longest ones start at once and not near the end, where
    one worker would run on alone."""
    items.sort(key=lambda item: item.get_closest_marker("slow") is None)


@pytest.fixture
def task():
    return paper_box()


@pytest.fixture
def hide_module(monkeypatch):
    """``hide_module(name)``: ``importlib.import_module(name)`` raises ImportError, as without
    the optional extra that provides it (for the one-line install hints)."""
    import importlib

    real = importlib.import_module

    def hide(name: str) -> None:
        def importer(wanted: str, *args: object) -> object:
            if wanted == name:
                raise ImportError(f"No module named {name!r}")
            return real(wanted, *args)

        monkeypatch.setattr(importlib, "import_module", importer)

    return hide


@pytest.fixture
def refused_policy(tmp_path):
    """``refused_policy(doc, edit, match)``: the policy document ``doc`` edited by ``edit`` (its
    checksum made to match again) is refused on load with a message matching ``match``."""
    import json

    from crmgrasp._validation import CrmgraspError
    from crmgrasp.agents.policy import GreedyPolicy, policy_digest

    def refused(doc: dict, edit, match: str) -> None:
        bad = json.loads(json.dumps(doc))
        edit(bad)
        bad["sha256"] = policy_digest(bad)
        path = tmp_path / "edited-policy.json"
        path.write_text(json.dumps(bad))
        with pytest.raises(CrmgraspError, match=match):
            GreedyPolicy.load(path)

    return refused

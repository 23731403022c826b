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


def pytest_configure(config: pytest.Config) -> None:
    """Before a parallel run (``-n 2``, in pytest-xdist's controller, before its workers start),
    compile the kernels into numba's on-disk cache in two processes at once, each its own half
    (tests/numba_warmup.py): on a cold cache (a fresh clone) each worker would otherwise compile
    nearly all of them for itself. Measured on the 2-core machine: the halves take 18 and 32 s
    cold, about 1.3 s warm. A half that fails says so in one line; the workers then compile what
    it missed, as without it."""
    if hasattr(config, "workerinput") or not getattr(config.option, "numprocesses", None):
        return
    if config.option.collectonly:
        return
    import subprocess
    import sys
    from pathlib import Path

    script = str(Path(__file__).with_name("numba_warmup.py"))
    halves = [
        subprocess.Popen([sys.executable, script, str(h)], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        for h in (0, 1)
    ]
    for h, proc in enumerate(halves):
        _, err = proc.communicate()
        if proc.returncode:
            last = err.decode(errors="replace").strip().splitlines()[-1:] or ["no output"]
            why = f"numba warm-up half {h} exited {proc.returncode} ({last[0]})"
            print(f"{why}; the workers compile what it missed", file=sys.stderr)


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Tests marked ``slow`` run first, the rest in their order: pytest-xdist hands tests out
    from the front, so with ``-n 2`` the longest ones start at once and not near the end, where
    one worker would run on alone."""
    items.sort(key=lambda item: item.get_closest_marker("slow") is None)


@pytest.fixture(autouse=True)
def _no_compile_notice(monkeypatch):
    """What a command prints on standard error must not depend on whether numba's cache was
    warm: the notice while numba compiles (crmgrasp.kernels.compiling) is off, except where a
    test turns it on (tests/test_compile_notice.py). Commands run in a subprocess keep it."""
    import math

    import crmgrasp.kernels.compiling

    monkeypatch.setattr(crmgrasp.kernels.compiling, "AFTER", math.inf)


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

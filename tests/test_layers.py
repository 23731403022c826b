"""The architecture, kept by tests: layers import only downward, the model stays free
of kernels, numba and matplotlib, and ``import crmgrasp`` stays light."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

PKG = Path(__file__).resolve().parents[1] / "src" / "crmgrasp"

LAYERS = [
    ("infrastructure", ("crmgrasp._validation", "crmgrasp._io", "crmgrasp._progress", "crmgrasp._collector")),
    ("model", ("crmgrasp.model",)),
    ("tasks", ("crmgrasp.tasks", "crmgrasp.sim")),
    ("kernels", ("crmgrasp.kernels",)),
    ("viz", ("crmgrasp.plotting",)),
    ("envs", ("crmgrasp.envs",)),
    ("agents and planners", ("crmgrasp.agents", "crmgrasp.planners")),
    ("hardware", ("crmgrasp.hardware",)),
    ("experiments", ("crmgrasp.experiments",)),
    ("cli", ("crmgrasp.cli", "crmgrasp.__main__")),
]
"""Bottom up; a module may import (at the top or inside a function) its own layer and
the layers below, never one above. The package root only re-exports."""


def _layer(name: str) -> int | None:
    for i, (_, prefixes) in enumerate(LAYERS):
        if any(name == p or name.startswith(p + ".") for p in prefixes):
            return i
    return None


def _modules() -> dict[str, Path]:
    out = {}
    for f in PKG.rglob("*.py"):
        parts = f.relative_to(PKG.parent).with_suffix("").parts
        out[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = f
    return out


def _imports(path: Path) -> set[str]:
    """Every absolute module name imported anywhere in the file (relative imports are not used)."""
    names: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            names |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom):
            assert node.level == 0, f"{path}: relative import"
            names.add(node.module or "")
            names |= {f"{node.module}.{a.name}" for a in node.names}  # 'from pkg import module'
    return names


MODULES = _modules()


def test_every_module_has_a_layer():
    assert [m for m in MODULES if m != "crmgrasp" and _layer(m) is None] == []


@pytest.mark.parametrize("module", sorted(m for m in MODULES if m != "crmgrasp"))
def test_nothing_imports_upward(module):
    mine = _layer(module)
    assert mine is not None
    up = [
        name
        for name in _imports(MODULES[module])
        if name.split(".")[0] == "crmgrasp" and name in MODULES and (_layer(name) or 0) > mine
    ]
    assert up == [], f"{module} ({LAYERS[mine][0]}) imports from above: {up}"
    if mine < len(LAYERS) - 1:
        assert "crmgrasp" not in _imports(MODULES[module]), f"{module} imports the package root"


def test_model_and_tasks_import_no_kernel_numba_or_matplotlib():
    for module, path in MODULES.items():
        layer = _layer(module)
        if layer is None or layer > 2:
            continue
        bad = {n for n in _imports(path) if n.split(".")[0] in {"numba", "matplotlib"} or "kernels" in n}
        assert not bad, f"{module} imports {bad}"


def test_numba_only_in_the_kernels():
    for module, path in MODULES.items():
        if not module.startswith("crmgrasp.kernels"):
            assert not {n for n in _imports(path) if n.split(".")[0] == "numba"}, module


def test_import_crmgrasp_is_light():
    """No plotting, optimisation, compilation, deep learning or physics at import time."""
    code = "import sys, crmgrasp; print(sorted({m.split('.')[0] for m in sys.modules}))"
    loaded = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    heavy = {"matplotlib", "scipy", "numba", "llvmlite", "torch", "mujoco", "stable_baselines3", "pandas"}
    assert heavy.isdisjoint(eval(loaded)), loaded


def test_root_holds_only_the_core():
    """Layers live in folders; the package root keeps the entry points, the task layer
    and the small shared helpers."""
    root = sorted(p.name for p in PKG.glob("*.py"))
    assert root == ["__init__.py", "__main__.py", "_collector.py", "_io.py", "_progress.py", "_validation.py", "sim.py"]


def _edges() -> dict[str, set[str]]:
    """Module -> the package's modules it imports anywhere (top level, in a function, or
    under ``TYPE_CHECKING``): ``from pkg import name`` counts as importing ``pkg`` and,
    where ``pkg.name`` is a module, that module too; a package's ``__init__`` is a module."""
    out: dict[str, set[str]] = {}
    for module, path in MODULES.items():
        hits = set()
        for name in _imports(path):
            while name and name not in MODULES:
                name = name.rpartition(".")[0]
            if name and name not in (module, "crmgrasp"):
                hits.add(name)
        out[module] = hits
    return out


def _cycles(edges: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan, iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    found: list[list[str]] = []
    for root in sorted(edges):
        if root in index:
            continue
        work = [(root, iter(sorted(edges[root])))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on.add(root)
        while work:
            v, it = work[-1]
            w = next(it, None)
            if w is not None:
                if w not in index:
                    index[w] = low[w] = len(index)
                    stack.append(w)
                    on.add(w)
                    work.append((w, iter(sorted(edges[w]))))
                elif w in on:
                    low[v] = min(low[v], index[w])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[v])
            if low[v] == index[v]:
                comp = []
                while True:
                    w = stack.pop()
                    on.discard(w)
                    comp.append(w)
                    if w == v:
                        break
                if len(comp) > 1:
                    found.append(sorted(comp))
    return found


def test_cycle_finder_finds_a_cycle():
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert _cycles({"a": {"b"}, "b": set()}) == []


def test_no_import_cycles():
    """No two modules import each other, directly or through others, inside a layer or
    across one (a package's ``__init__`` and its own submodules included)."""
    assert _cycles(_edges()) == []

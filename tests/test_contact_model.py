"""The contact model a task holds: both two-contact models state the protocol, their
layout round-trips, the kernel seam is a table keyed by the model, and nothing outside
the task layer tests a task's class."""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
import pytest

from crmgrasp import kernels
from crmgrasp._validation import CrmgraspError
from crmgrasp.kernels import PATHS, ReferenceKernel, kernel_for
from crmgrasp.model.contact_model import ContactModel, contact_columns, observation_names, row_width
from crmgrasp.model.contacts import ALL_LABELS
from crmgrasp.model.planar_model import PlanarModel
from crmgrasp.model.spatial_model import SpatialModel
from crmgrasp.tasks import make_task, task_names

PKG = Path(__file__).resolve().parents[1] / "src" / "crmgrasp"

MEMBERS = sorted(
    name
    for name in {*vars(ContactModel), *getattr(ContactModel, "__annotations__", {})}
    if not name.startswith("_") and name not in {"mro"}
)


@pytest.mark.parametrize("cls", [PlanarModel, SpatialModel])
def test_models_state_every_member_of_the_protocol(cls):
    missing = [m for m in MEMBERS if not hasattr(cls, m) and m not in {f for f in cls.__dataclass_fields__}]
    assert missing == []


@pytest.mark.parametrize("name", ["paper-box", "u-handle", "box-3d", "cup-3d"])
def test_rows_round_trip_and_name_their_columns(name):
    task = make_task(name)
    rng = np.random.default_rng(3)
    model = task.model
    configs = [task.sample_world(rng).config for _ in range(20)]
    rows = model.rows_of(configs)
    assert rows.shape == (20, model.row_width) == (20, row_width(model.n_contacts, model.dim))
    assert len(model.columns) == model.row_width
    assert [model.config_of(r) for r in rows.tolist()] == configs
    assert [model.row_of(c) for c in configs] == rows.tolist() == [model.numbers(c) for c in configs]
    assert model.observation_names == tuple(model.observation_bounds())


def test_the_two_models_differ_only_in_what_they_state():
    planar, spatial = make_task("paper-box").model, make_task("cup-3d").model
    assert (planar.kind, planar.dim, planar.offset_dim, planar.row_width) == ("planar", 2, 1, 8)
    assert (spatial.kind, spatial.dim, spatial.offset_dim, spatial.row_width) == ("spatial", 3, 2, 12)
    assert contact_columns(planar.labels, "xy") == planar.columns
    assert spatial.columns[:6] == ("ax", "ay", "az", "anx", "any", "anz")


@pytest.mark.parametrize("name", task_names())
def test_every_registered_task_holds_a_model_the_seam_knows(name):
    task = make_task(name)
    assert task.model.kind in PATHS
    inst = task.instance(np.random.default_rng(0))
    assert kernel_for(inst, "reference").model == inst.model


def test_a_new_model_kind_is_one_row_of_the_seam(monkeypatch):
    """A task whose model names a kind the table lacks is refused in one line; adding the
    row is all it takes for kernel_for (and so every environment and loop) to step it."""
    task = make_task("paper-box")

    class Toy(PlanarModel):
        kind = "toy"

    object.__setattr__(task, "model", Toy(task.hand))
    with pytest.raises(CrmgraspError, match="no kernel for the contact model 'toy'"):
        kernel_for(task)
    monkeypatch.setitem(kernels.PATHS, "toy", lambda t, backend, friction: ReferenceKernel(t))
    assert type(kernel_for(task)) is ReferenceKernel


def test_place_refuses_the_wrong_number_of_points():
    with pytest.raises(CrmgraspError, match="takes 2 points"):
        make_task("paper-box").place((-0.15, -0.02))
    with pytest.raises(CrmgraspError, match="finite X,Y,Z"):
        make_task("box-3d").with_object(make_task("box-3d").obj).place((0.0, 0.0), (1.0, 0.0, 0.0))


def _task_isinstance(path: Path) -> list[int]:
    """Lines of ``isinstance(x, <a task subclass: a name ending in Task>)`` (or a tuple
    holding one); ``isinstance(x, Task)``, a check of the input's type, is not one."""
    hits = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Call) and getattr(node.func, "id", None) == "isinstance" and len(node.args) == 2:
            kinds = node.args[1].elts if isinstance(node.args[1], ast.Tuple) else [node.args[1]]
            names = [getattr(k, "id", getattr(k, "attr", "")) for k in kinds]
            if any(n.endswith("Task") and n != "Task" for n in names):
                hits.append(node.lineno)
    return hits


def test_no_isinstance_on_tasks_outside_the_task_layer():
    """Code above the task layer asks the task's model, never the task's class."""
    found = {
        str(p.relative_to(PKG)): lines
        for p in PKG.rglob("*.py")
        if p.relative_to(PKG).parts[0] != "tasks" and (lines := _task_isinstance(p))
    }
    assert found == {}


def test_the_isinstance_finder_finds_one(tmp_path):
    f = tmp_path / "m.py"
    f.write_text("def g(t):\n    return isinstance(t, (int, SpatialTask))\n")
    assert _task_isinstance(f) == [2]


OBSERVATION_NAMES = set(observation_names(ALL_LABELS))


def _named_observations(path: Path) -> list[int]:
    """Lines where code (not a docstring) writes an observation quantity's name: a string,
    an attribute, a variable or a keyword ``m_a``; the keywords of a ``Discretizer(...)``
    call are a task's own bins and allowed in the task layer."""
    tree = ast.parse(path.read_text())
    docs = {
        id(node.body[0].value)
        for node in ast.walk(tree)
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef))
        and node.body
        and isinstance(node.body[0], ast.Expr)
        and isinstance(node.body[0].value, ast.Constant)
    }
    bins = {
        id(kw)
        for node in ast.walk(tree)
        if isinstance(node, ast.Call) and getattr(node.func, "id", None) == "Discretizer"
        for kw in node.keywords
    }
    task_layer = path.relative_to(PKG).parts[0] == "tasks" if path.is_relative_to(PKG) else False
    lines = []
    for node in ast.walk(tree):
        name = (
            node.value
            if isinstance(node, ast.Constant) and isinstance(node.value, str) and id(node) not in docs
            else getattr(node, "attr", None) or getattr(node, "id", None)
        )
        if isinstance(node, ast.keyword) and not (task_layer and id(node) in bins):
            name = node.arg
        if name in OBSERVATION_NAMES:
            lines.append(node.lineno if hasattr(node, "lineno") else node.value.lineno)
    return sorted(lines)


def test_no_observation_name_outside_the_model_and_its_kernels():
    """Code above the model reads the observation's names from the task's model."""
    found = {
        str(p.relative_to(PKG)): lines
        for p in PKG.rglob("*.py")
        if p.relative_to(PKG).parts[0] not in ("model", "kernels") and (lines := _named_observations(p))
    }
    assert found == {}


def test_the_observation_name_finder_finds_each_form(tmp_path):
    f = tmp_path / "m.py"
    f.write_text('"""m_a in a docstring is fine."""\ndef g(o):\n    x = o.m_a\n    return {"m_b": x}, f(rho=1)\n')
    assert _named_observations(f) == [3, 4, 4]


def test_bins_over_any_observation_names():
    from crmgrasp.model.sensing import Discretizer, Error

    d = Discretizer(names=("rho", "m_a", "m_b", "m_c"), m_c=(0.05, 0.2))
    assert d.sizes == (2, 2, 2, 3) and d.size == 2 * 2 * 2 * 3 * 3
    seen = set()
    for i in range(d.size):
        bins, err = d.decode(i)
        assert d.compose(bins, err) == i
        seen.add(i)
    assert seen == set(range(d.size))
    assert d.index((2.0, 0.0, -0.3, -0.1), Error.PALM) == d.compose((1, 0, 1, 1), 2)
    rng = np.random.default_rng(0)
    for values in [*rng.normal(0.0, 0.3, (200, 4)).tolist(), [float("nan"), 0.1, -0.1, 0.2]]:
        for flag in Error:
            assert d.index(values, flag) == d.compose(d.bins(values), flag)  # the hot loop is the rule
    assert d.to_dict() == {"rho": [1.0], "m_a": [0.1], "m_b": [0.1], "m_c": [0.05, 0.2], "abs_moments": True}
    assert Discretizer(names=d.names, **{k: v for k, v in d.to_dict().items()}) == d
    assert repr(Discretizer()) == "Discretizer(rho=(1.0,), m_a=(0.1,), m_b=(0.1,), abs_moments=True)"


def test_a_task_refuses_bins_over_other_quantities():
    import dataclasses

    from crmgrasp.model.sensing import Discretizer

    with pytest.raises(CrmgraspError, match="bins are over rho, m_a, m_b, m_c, but the planar model observes"):
        dataclasses.replace(make_task("paper-box"), discretizer=Discretizer(names=("rho", "m_a", "m_b", "m_c")))


def test_the_model_says_where_each_moment_is_and_what_a_mirror_swaps():
    for name in ("paper-box", "cup-3d"):
        model = make_task(name).model
        assert [model.observation_names[model.moment_index(lab)] for lab in model.labels] == ["m_a", "m_b"]
        assert [model.observation_names[i] for i in model.mirror_axes] == ["rho", "m_b", "m_a"]

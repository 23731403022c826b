"""Task files (TOML), ``package.module:factory`` tasks, and tasks carried by policies."""

from __future__ import annotations

import json
import sys

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from crmgrasp._validation import CrmgraspError
from crmgrasp.agents import GreedyPolicy
from crmgrasp.cli import main
from crmgrasp.model.geometry import Disc, Polygon
from crmgrasp.tasks import (
    TEMPLATE,
    load_task_file,
    make_task,
    paper_box,
    resolve_task,
    task_from_dict,
    task_names,
    task_to_dict,
)


def _write(tmp_path, text, name="t.toml"):
    p = tmp_path / name
    p.write_text(text)
    return p


def test_template_loads_and_round_trips(tmp_path):
    task = load_task_file(_write(tmp_path, TEMPLATE))
    assert task.name == "my-u" and isinstance(task.obj, Polygon) and len(task.actions) == 4
    assert task_from_dict(task_to_dict(task)) == task
    assert task_from_dict(task_to_dict(paper_box())) == paper_box()


def test_disc_and_rectangle_objects(tmp_path):
    disc = TEMPLATE.replace("polygon = [[0, 0]", "disc = { radius = 0.05 }\n# polygon = [[0, 0]")
    task = load_task_file(_write(tmp_path, disc))
    assert isinstance(task.obj, Disc) and task.obj.radius == 0.05
    rect = TEMPLATE.replace("polygon = [[0, 0]", "rectangle = { length = 0.3, width = 0.1 }\n# polygon = [[0, 0]")
    assert load_task_file(_write(tmp_path, rect)).obj == paper_box().obj
    corners = disc.replace('kind = "uniform"', 'kind = "corners"')
    with pytest.raises(CrmgraspError, match=r"need a polygon object"):
        load_task_file(_write(tmp_path, corners))


@pytest.mark.parametrize(
    ("old", "new", "message"),
    [
        ("aperture = 0.16", "aperture = -1", "aperture"),
        ("aperture = 0.16", 'aperture = "wide"', "hand.aperture must be a finite number"),
        ("aperture = 0.16", "apertur = 0.16", "unknown key 'apertur' in [hand]"),
        ('c = "a"    # position', 'c = "x"    # position', '[[crm]] number 1: c and f must be "a" or "b"'),
        ("rho = [1.0]", "rho = [2.0, 1.0]", "rho"),
        ('kind = "uniform"', 'kind = "everywhere"', "[starts] kind must be one of corners, uniform"),
        ('name = "my-u"', 'name = "../evil"', "name must be"),
        ("max_steps = 10", "max_steps = 0", "max_steps must be an integer"),
        ("[0.1, 0.2], [0, 0.2]]", "[0.1, 0.2], [0.3, 0.2]]", "polygon"),
        ("mu_goal = 0.05", "mu_goal = nan", "mu_goal must be a finite number"),
        ("grasp_reward = -1.0", 'grasp_reward = "zero"', "grasp_reward must be a finite number"),
        ('kind = "uniform"', 'kind = "near-corner"\nlo = 1', "takes no lo"),
        ("# symmetry = [1, 0, 3, 2]", "symmetry = [0, 1, 2, 3]", "symmetry"),
        ("name = ", "nom = ", "unknown key 'nom'"),
        ("[hand]", "[hand]\n[hand.extra]", "unknown key 'extra' in [hand]"),
        ("abs_moments = true", "abs_moments = 1", "bins.abs_moments must be true or false"),
        ("abs_moments = true", "abs_moments = true\nmu_goal = 0.1", "'mu_goal' sits in [bins] but is a top-level key"),
        ('[[crm]]\nc = "b"', '[[crm]]\nsymmetry = [1, 0, 3, 2]\nc = "b"', "'symmetry' sits in [crm] but is a top"),
    ],
)
def test_bad_task_file_names_the_key(tmp_path, old, new, message):
    assert old in TEMPLATE
    path = _write(tmp_path, TEMPLATE.replace(old, new, 1))
    with pytest.raises(CrmgraspError) as err:
        load_task_file(path)
    text = str(err.value)
    assert message in text and "\n" not in text and str(path) in text


def test_the_templates_symmetry_line_declares_the_mirror(tmp_path):
    """Uncommented as it stands, the template's symmetry line is a top-level key (it once sat
    after the [starts] header, where TOML made it a key of [starts])."""
    task = load_task_file(_write(tmp_path, TEMPLATE.replace("# symmetry = [1, 0, 3, 2]", "symmetry = [1, 0, 3, 2]")))
    assert task.symmetry is not None and task.symmetry.actions == (1, 0, 3, 2)


def test_unreadable_task_files(tmp_path):
    for data, message in ((b"\xff\xfe", "not UTF-8"), (b"a = [", "not valid TOML"), (b"", "needs the key")):
        p = tmp_path / "x.toml"
        p.write_bytes(data)
        with pytest.raises(CrmgraspError, match=message):
            load_task_file(p)
    with pytest.raises(CrmgraspError, match="does not exist"):
        resolve_task(str(tmp_path / "missing.toml"))
    with pytest.raises(CrmgraspError, match="larger than"):
        load_task_file(_write(tmp_path, "#" * (2 << 20)))
    with pytest.raises(CrmgraspError, match="is not a regular file"):
        load_task_file(tmp_path)


@settings(max_examples=300, deadline=None)
@given(st.binary(max_size=400) | st.text(max_size=400).map(str.encode))
def test_fuzz_task_reader_fails_in_one_line(tmp_path_factory, data):
    p = tmp_path_factory.mktemp("fuzz") / "t.toml"
    p.write_bytes(data)
    try:
        load_task_file(p)
    except CrmgraspError as exc:
        assert "\n" not in str(exc)


@settings(max_examples=200, deadline=None)
@given(
    st.dictionaries(
        st.sampled_from(["name", "object", "hand", "crm", "bins", "starts", "noise", "mu_goal", "symmetry"]),
        st.recursive(
            st.none() | st.booleans() | st.integers() | st.floats() | st.text(max_size=5),
            lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=8), inner, max_size=4),
            max_leaves=12,
        ),
    )
)
def test_fuzz_task_documents_fail_in_one_line(doc):
    base = task_to_dict(paper_box())
    try:
        task_from_dict({**base, **doc})
    except CrmgraspError as exc:
        assert "\n" not in str(exc)


def test_factory_tasks(tmp_path, monkeypatch):
    (tmp_path / "mytasks.py").write_text(
        "from crmgrasp.tasks import paper_box\nimport dataclasses\n"
        "def small():\n    return dataclasses.replace(paper_box(), name='small', symmetry=None)\n"
        "def broken():\n    raise ZeroDivisionError('oops')\n"
        "def quits():\n    raise SystemExit(0)\n"
        "not_a_task = 3\n"
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    assert resolve_task("mytasks:small").name == "small"
    for spec, message in (
        ("mytasks:broken", "the factory raised ZeroDivisionError: oops"),
        ("mytasks:quits", r"the factory called exit\(0\) instead of returning a task"),
        ("mytasks:not_a_task", "gave a int, not a crmgrasp Task"),
        ("mytasks:absent", "has no 'absent'"),
        ("nosuchmodule_xyz:f", "cannot import 'nosuchmodule_xyz'"),
        ("no-such-task", "unknown task"),
    ):
        with pytest.raises(CrmgraspError, match=message):
            resolve_task(spec)
    sys.modules.pop("mytasks", None)


def test_cli_with_a_task_file_and_the_policy_carrying_it(tmp_path, capsys):
    task_file = _write(tmp_path, TEMPLATE)
    assert main(["task-template"]) == 0 and capsys.readouterr().out == TEMPLATE
    out = tmp_path / "run"
    argv = ["learn", "--task", str(task_file), "--trials", "2", "--episodes", "30", "--eval-episodes", "5"]
    assert main([*argv, "--quiet", "--out", str(out)]) == 0
    capsys.readouterr()
    policy = GreedyPolicy.load(out / "policy.json")  # no task given: the file carries it
    assert policy.task == load_task_file(task_file)
    assert main(["evaluate", "--policy", str(out / "policy.json"), "--episodes", "5", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["task"] == "my-u"
    other = _write(tmp_path, TEMPLATE.replace("palm_depth = 0.12", "palm_depth = 0.13"), "other.toml")
    assert main(["evaluate", "--policy", str(out / "policy.json"), "--task", str(other)]) == 2
    assert "differs in hand.palm_depth" in capsys.readouterr().err
    assert main(["references", "--task", str(task_file), "--starts", "50", "--json"]) == 0
    frac = json.loads(capsys.readouterr().out)["ungraspable_fraction"]
    assert 0.0 < frac < 1.0
    assert main(["references", "--starts", "200", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["ungraspable_fraction"] == 0.0
    assert main(["tasks"]) == 0 and "paper-box" in capsys.readouterr().out


def test_cli_bad_task_files_are_one_line_exit_2_and_write_nothing(tmp_path, capsys):
    bad = _write(tmp_path, TEMPLATE.replace("aperture = 0.16", "aperture = 0.16\naperture = 0.2"))
    out = tmp_path / "run"
    for argv in (
        ["learn", "--task", str(bad), "--out", str(out)],
        ["references", "--task", str(bad)],
        ["compare", "--task", str(tmp_path / "missing.toml"), "--out", str(out)],
        ["crm", "--task", "os:getcwd", "--a", "0,0", "--b", "0,0", "--crm", "C1"],
    ):
        assert main(argv) == 2, argv
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "error:" in err, err
    assert not out.exists()


@pytest.mark.parametrize("name", task_names())
def test_every_registered_task_round_trips(name):
    """``task_from_dict(task_to_dict(t)) == t`` for every registered task, planar and
    spatial (solids compare by value, as polygons do)."""
    task = make_task(name)
    again = task_from_dict(task_to_dict(task))
    assert again == task and again.model == task.model


@pytest.mark.parametrize(
    ("starts", "message"),
    [
        ({"kind": "long-side", "hi": "0.2"}, "[starts] hi must be a finite number"),
        ({"kind": "long-side", "hi": True}, "[starts] hi must be a finite number"),
        ({"kind": "vertex", "vertex": 1.5}, "[starts] vertex must be an integer"),
        ({"kind": "corners", "max_tries": 0}, "max_tries must be an integer in [1, 1000000]"),
        ({"kind": "boundary", "near_vertex": "x"}, "[starts] near_vertex must be a finite number"),
        ({"kind": "vertex", "a_on": 3}, "[starts] a_on must be a string"),
        ({"kind": "near-corner", "lo": 0.1}, "kind 'near-corner' takes no lo; it takes max_tries, within"),
    ],
)
def test_start_keys_are_typed_by_their_class(starts, message):
    doc = {**task_to_dict(paper_box()), "starts": starts, "symmetry": None}
    with pytest.raises(CrmgraspError) as err:
        task_from_dict(doc)
    assert message in str(err.value) and "\n" not in str(err.value)


@pytest.mark.parametrize(
    "starts",
    [
        {"kind": "corners", "max_tries": 7},
        {"kind": "uniform"},
        {"kind": "near-corner", "within": 0.05},
        {"kind": "long-side", "lo": 0.02, "hi": 0.2},
        {"kind": "long-side"},
        {"kind": "boundary", "near_vertex": 0.03, "max_tries": 50},
        {"kind": "vertex", "vertex": 2, "incoming": [0.01, 0.02], "a_on": "outgoing"},
        {"kind": "mixture", "mix": [{"kind": "near-corner", "weight": 2.0}, {"kind": "uniform", "weight": 1.0}]},
    ],
)
def test_every_start_kind_round_trips_with_its_keys(starts):
    task = task_from_dict({**task_to_dict(paper_box()), "starts": starts, "symmetry": None})
    assert task_from_dict(task_to_dict(task)) == task
    written = task_to_dict(task)["starts"]
    assert written["kind"] == starts["kind"] and all(written[k] == v for k, v in starts.items() if k != "mix")


def test_spatial_starts_up_is_a_cosine():
    from crmgrasp.tasks import make_task

    doc = task_to_dict(make_task("cup-3d"))
    assert doc["starts"] == {"kind": "surface", "max_tries": 10_000, "up": 0.5}
    for up, message in ((2, r"starts.up is a cosine and must be in \[-1, 1\], got 2"), ("1", "starts.up must be a")):
        with pytest.raises(CrmgraspError, match=message):
            task_from_dict({**doc, "starts": {"kind": "surface", "up": up}})

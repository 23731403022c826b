"""The documentation: every command it shows parses, the tutorial's commands and every
Python example run, and the site builds with ``mkdocs build --strict``."""

from __future__ import annotations

import contextlib
import io
import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

from crmgrasp.cli import main
from crmgrasp.cli.parser import build_parser

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


def _blocks(path: Path, lang: str) -> list[str]:
    return re.findall(rf"```{lang}\n(.*?)```", path.read_text(encoding="utf-8"), flags=re.S)


def _commands(path: Path) -> list[str]:
    """``crmgrasp ...`` lines of the bash blocks, comments removed."""
    out = []
    for block in _blocks(path, "bash"):
        for line in block.splitlines():
            line = line.split(" #", 1)[0].strip()
            if line.startswith("crmgrasp "):
                out.append(line)
    return out


COMMANDS = [(p.name, c) for p in PAGES for c in _commands(p)]


@pytest.mark.parametrize(("page", "command"), COMMANDS, ids=[f"{p}:{c[:60]}" for p, c in COMMANDS])
def test_documented_commands_parse(page, command):
    argv = shlex.split(command.split(">", 1)[0])[1:]
    build_parser().parse_args(argv)  # an unknown option or bad value exits (fails the test)


def test_tutorial_runs_as_written(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    commands = _commands(ROOT / "docs" / "tutorial.md")
    assert len(commands) >= 6
    for command in commands:
        argv, _, target = command.partition(">")
        buf = io.StringIO()
        with contextlib.redirect_stdout(buf):
            status = main([*shlex.split(argv)[1:], *(["--quiet"] if " learn " in f" {argv} " else [])])
        assert status == 0, (command, capsys.readouterr().err)
        if target:
            Path(target.strip()).write_text(buf.getvalue())
    assert (tmp_path / "runs" / "my-u" / "run.json").exists() and (tmp_path / "my-u.png").exists()


PYTHON = [(p.name, i, b) for p in PAGES for i, b in enumerate(_blocks(p, "python"))]


@pytest.mark.parametrize(("page", "index", "code"), PYTHON, ids=[f"{p}:{i}" for p, i, _ in PYTHON])
def test_python_examples_run(page, index, code, tmp_path, monkeypatch):
    from crmgrasp.tasks import core

    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(core, "_TASKS", dict(core._TASKS))  # examples may register tasks
    with contextlib.redirect_stdout(io.StringIO()):
        exec(compile(code, f"{page} block {index}", "exec"), {"__name__": "__docs__"})


def test_site_builds_strictly(tmp_path):
    pytest.importorskip("mkdocs", reason="needs the extra: pip install 'crmgrasp[docs]'")
    pytest.importorskip("mkdocstrings", reason="needs the extra: pip install 'crmgrasp[docs]'")
    res = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(tmp_path / "site")],
        cwd=ROOT,
        env={**os.environ, "NO_MKDOCS_2_WARNING": "1"},
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert res.returncode == 0, res.stdout[-3000:] + res.stderr[-6000:]
    assert (tmp_path / "site" / "index.html").exists() and (tmp_path / "site" / "api" / "model" / "index.html").exists()
    # a role or an unresolved reference, as typed or as Markdown renders its backticks (<code>)
    leftover = re.compile(r":(class|func|meth|mod|data|attr|exc|obj):(`|<code>)|\[(`|<code>)[^\]]+\]\[")
    found = {
        str(p.relative_to(tmp_path / "site")): m.group(0)
        for p in (tmp_path / "site").rglob("*.html")
        if (m := leftover.search(p.read_text(encoding="utf-8")))
    }
    assert found == {}, f"Sphinx roles or unrendered cross-references in the built pages: {found}"
    tutorial = (tmp_path / "site" / "tutorial" / "index.html").read_text(encoding="utf-8")
    assert "stylesheets/extra.css" in tutorial  # long commands wrap (docs/stylesheets/extra.css)
    assert "pre-wrap" in (tmp_path / "site" / "stylesheets" / "extra.css").read_text()
    api = (tmp_path / "site" / "api" / "tasks" / "index.html").read_text(encoding="utf-8")
    assert api.count("autorefs-internal") > 20  # docstrings link to what they name


def test_the_task_file_key_table_is_the_one_the_code_states(capsys):
    """docs/usage.md's key table is `crmgrasp task-template --keys`, generated from the classes."""
    from crmgrasp.tasks.files import key_reference

    text = (ROOT / "docs" / "usage.md").read_text(encoding="utf-8")
    block = text.split("<!-- task-keys:start -->\n", 1)[1].split("<!-- task-keys:end -->", 1)[0]
    assert block == key_reference()
    assert main(["task-template", "--keys"]) == 0 and capsys.readouterr().out == block
    assert '| [starts] kind = "vertex" | `incoming` | 2 numbers | [0.005, 0.05] |' in block


def test_docstrings_name_model_sections_as_links():
    """A docstring that points at a section of docs/model.md links it (``[docs/model.md
    section 2][model-2]``, the heading's id), so that the API pages open the section."""
    import re

    plain = re.compile(r"(?<!\[)docs/model\.md sections? \d")
    link = re.compile(r"\[docs/model\.md sections? (\d)[^\]]*\]\[model-(\d)\]")
    found, linked = [], 0
    for path in (ROOT / "src").rglob("*.py"):
        text = path.read_text(encoding="utf-8")
        found += [f"{path.name}:{text[: m.start()].count(chr(10)) + 1}" for m in plain.finditer(text)]
        for m in link.finditer(text):
            assert m.group(1) == m.group(2), m.group(0)
            linked += 1
    assert found == [] and linked > 20
    model = (ROOT / "docs" / "model.md").read_text(encoding="utf-8")
    assert all(f"{{#model-{n}}}" in model for n in range(1, 9))

"""The notice while numba compiles (crmgrasp.kernels.compiling) and its place in the CLI."""

from __future__ import annotations

import importlib
import io
import multiprocessing
import threading

import pytest
from numba import njit

import crmgrasp.kernels.compiling
from crmgrasp._progress import Progress
from crmgrasp.cli import main
from crmgrasp.kernels.compiling import NOTICE, compile_notice


def _fresh():  # type: ignore[no-untyped-def]
    """A function numba has not compiled yet, which calls another (a nested compilation);
    not cached, so every call of ``_fresh`` gives one that compiles."""

    @njit(cache=False)
    def inner(x):  # type: ignore[no-untyped-def]
        return x * 2.0 + 1.0

    @njit(cache=False)
    def outer(x):  # type: ignore[no-untyped-def]
        return inner(x) - 3.0

    return outer


def test_a_compilation_past_the_threshold_is_told_once_then_timed():
    notes: list[str] = []
    with compile_notice(notes.append, after=0.0):
        assert _fresh()(1.0) == 0.0  # outer compiles inner inside itself: one outermost compilation
        assert _fresh()(2.0) == 2.0  # a second one: already told
    assert notes[0] == NOTICE and len(notes) == 2
    assert notes[1].startswith("compiling took ") and notes[1].endswith(" s of this run")


def test_short_compilations_loaded_functions_and_other_threads_say_nothing():
    notes: list[str] = []
    f = _fresh()
    with compile_notice(notes.append, after=1e9):
        f(1.0)  # compiles, but for less than the threshold
    assert notes == []
    with compile_notice(notes.append, after=0.0):
        f(1.0)  # compiled already: no compile event
        other = threading.Thread(target=_fresh(), args=(1.0,))
        other.start()  # compiles in another thread: not this command's wait
        other.join()
    assert notes == []


@pytest.mark.skipif("fork" not in multiprocessing.get_all_start_methods(), reason="needs fork")
def test_forked_workers_show_the_notice_once_for_them_all(tmp_path):
    """Two workers forked inside the context compile for themselves: one notice in all (they
    share the flag), and no total, which only the command's own process adds."""
    log = tmp_path / "notes"

    def note(text: str) -> None:
        with open(log, "a") as fh:
            fh.write(text + "\n")

    fork = multiprocessing.get_context("fork")
    with compile_notice(note, after=0.0):
        workers = [fork.Process(target=lambda: _fresh()(1.0)) for _ in range(2)]
        for w in workers:
            w.start()
        for w in workers:
            w.join()
    assert [w.exitcode for w in workers] == [0, 0]
    assert log.read_text().splitlines() == [NOTICE]


def test_interject_erases_a_live_line_first():
    live, plain = io.StringIO(), io.StringIO()
    Progress(live, live=True).interject("note")
    Progress(plain, live=False).interject("note")
    assert live.getvalue() == "\r\x1b[2Knote\n" and plain.getvalue() == "note\n"


@pytest.mark.parametrize("quiet", [False, True])
def test_the_cli_tells_while_a_command_compiles(monkeypatch, capsys, quiet):
    def references(args):  # type: ignore[no-untyped-def]
        _fresh()(1.0)
        return 0

    monkeypatch.setattr(importlib.import_module("crmgrasp.cli.main"), "_cmd_references", references)
    monkeypatch.setattr(crmgrasp.kernels.compiling, "AFTER", 0.0)
    assert main(["references", *(["--quiet"] if quiet else [])]) == 0
    err = capsys.readouterr().err
    if quiet:
        assert err == ""
    else:
        assert err.startswith(NOTICE + "\n") and "compiling took " in err

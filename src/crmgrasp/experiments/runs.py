"""Run folders: where a command's results go, and a record that cannot lie.

A run folder holds a command's files and ``run.json``::

    {"format": "crmgrasp-run", "command": "learn", "task": "paper-box",
     "status": "complete",            # running | complete | interrupted | failed
     "config": {...},                  # what the results depend on (checked by --resume)
     "completed": {...},               # units of work done (trials, experiments)
     "argv": [...], "seed": 0, "started": "...Z", "ended": "...Z", "error": null,
     "version": "0.1.0", "git_commit": "...", "source_sha256": "...",
     "python": "3.11.7", "platform": "...",
     "dependencies": {"numpy": "...", ...}, "host": "...", "pid": 1234}

Rules: the default folder is ``runs/<command>-<task>-<UTC time>``; an existing
non-empty folder is refused unless ``overwrite`` (it must then be a run folder, which
is emptied) or ``resume`` (it must be a run folder of the same command and config,
not complete and not still running). ``status`` is ``running`` while the work goes
on, so a run killed with SIGKILL still says ``running``; its ``pid`` and ``host`` tell
[`read_status`][] that nobody runs it (reported as ``killed``), and ``--resume``
takes it up. Ctrl-C ends a run with ``interrupted``; an error with ``failed`` and the
error's text.

A run holds an exclusive lock on its folder (``flock`` on the folder itself, POSIX) from
the moment it claims it until it finishes, and the claim checks the folder only once it
holds the lock: of two runs started into one folder at once, the second is refused in one
line, and a killed run's lock goes with its process. ``--resume`` says so when the run is complete
already (it then reruns nothing) and deletes the temporary files of writes a kill cut short
(`temporaries`), which [`leftovers`][] lists for ``crmgrasp status``.
"""

from __future__ import annotations

import datetime as _dt
import json
import os
import platform
import re
import shutil
import socket
import subprocess
import sys
from importlib import metadata
from pathlib import Path
from types import TracebackType
from typing import Any

from crmgrasp._io import as_path, check_folder, dumps_json, read_bounded, temporaries, write_json
from crmgrasp._validation import CrmgraspError, shown

__all__ = ["RunFolder", "read_status", "leftovers", "default_run_dir", "source_digest", "STATUSES", "JOURNAL"]

FORMAT = "crmgrasp-run"
STATUSES = ("running", "complete", "interrupted", "failed")
_DEPENDENCIES = ("numpy", "scipy", "matplotlib", "gymnasium", "numba", "mujoco", "torch", "stable-baselines3")


def _now() -> str:
    return _dt.datetime.now(_dt.UTC).strftime("%Y-%m-%dT%H:%M:%SZ")


def default_run_dir(command: str, task: str, root: str | Path = "runs") -> Path:
    """``runs/<command>-<task>-<UTC YYYYMMDDTHHMMSSZ>``, with ``-2``, ``-3``, ... if taken."""
    _names(command, task)
    stamp = _dt.datetime.now(_dt.UTC).strftime("%Y%m%dT%H%M%SZ")
    base = as_path(root, "runs folder") / f"{command}-{task}-{stamp}"
    path, n = base, 1
    while path.exists():
        n += 1
        path = base.with_name(f"{base.name}-{n}")
    return path


def _names(command: object, task: object) -> None:
    """A one-line error unless a run's ``command`` and ``task`` names are text."""
    for what, name in (("command", command), ("task", task)):
        if not isinstance(name, str):
            raise CrmgraspError(f"a run's {what} name must be text, got {shown(name)}")


def _git_commit() -> str | None:
    here = Path(__file__).resolve().parents[3]
    if not (here / ".git").exists():
        return None
    try:
        out = subprocess.run(
            ["git", "-C", str(here), "rev-parse", "HEAD"], capture_output=True, text=True, timeout=5, check=False
        )
    except (OSError, subprocess.SubprocessError):
        return None
    return out.stdout.strip() or None if out.returncode == 0 else None


def source_digest() -> str:
    """SHA-256 of the package's own source as installed (every ``.py`` file of
    ``crmgrasp``, by relative path and content, in sorted order): which code a run ran,
    also where there is no git checkout (``pip install .``)."""
    import hashlib

    root = Path(__file__).resolve().parents[1]
    h = hashlib.sha256()
    for path in sorted(root.rglob("*.py")):
        h.update(path.relative_to(root).as_posix().encode() + b"\0" + path.read_bytes() + b"\0")
    return h.hexdigest()


def _versions() -> dict[str, str]:
    out = {}
    for name in _DEPENDENCIES:
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            continue
    return out


def _alive(pid: object, host: object) -> bool:
    """Whether process ``pid`` on ``host`` may still be running (unknown hosts: yes)."""
    if host != socket.gethostname():
        return True
    if not isinstance(pid, int) or pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    proc = Path(f"/proc/{pid}")
    try:  # Linux: a zombie is dead, and a reused pid runs something else
        if proc.joinpath("stat").read_text().rsplit(")", 1)[1].split()[0] == "Z":
            return False
        return b"crmgrasp" in proc.joinpath("cmdline").read_bytes() or pid == os.getpid()
    except (OSError, IndexError):
        return True


JOURNAL = "journal.jsonl"
"""The units a running run has completed since ``run.json`` was last written: one JSON line
``{"unit": ..., "info": ...}`` each, appended (a run of many units does not rewrite its record
after each; ``run.json`` is written whole when the run starts and ends, and the journal is
folded into it then)."""


def _read(folder: Path) -> dict[str, Any]:
    path = folder / "run.json"
    try:
        doc = json.loads(read_bounded(path, 16 * 2**20, "run record").decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError, RecursionError):
        raise CrmgraspError(f"run record {str(path)!r} is damaged (not valid JSON)") from None
    if not isinstance(doc, dict) or doc.get("format") != FORMAT or doc.get("status") not in STATUSES:
        raise CrmgraspError(f"{str(path)!r} is not a crmgrasp run record")
    if not isinstance(doc.get("completed", {}), dict) or not isinstance(doc.get("config", {}), dict):
        raise CrmgraspError(f"run record {str(path)!r} is damaged (bad completed or config)")
    doc.setdefault("completed", {}).update(_journal(folder))
    return doc


def _journal(folder: Path) -> dict[str, Any]:
    """The units the journal records; a last line cut short by a kill is ignored (its unit
    was not recorded done, so it runs again), any other damage is a one-line error."""
    path = folder / JOURNAL
    if not path.is_file():
        return {}
    lines = read_bounded(path, 256 * 2**20, "run journal").decode("utf-8", "replace").split("\n")
    out: dict[str, Any] = {}
    for i, line in enumerate(lines):
        if not line:
            continue
        try:
            entry = json.loads(line)
            out[entry["unit"]] = entry["info"]
        except (json.JSONDecodeError, KeyError, TypeError):
            if i == len(lines) - 1:  # no newline after it: the append a kill cut short
                break
            raise CrmgraspError(f"run journal {str(path)!r} is damaged (line {i + 1})") from None
    return out


def read_status(folder: str | Path) -> str:
    """The status of a run folder: one of `STATUSES`, or ``killed`` for a run
    that says ``running`` but whose process is gone."""
    doc = _read(as_path(folder, "run folder"))
    if doc["status"] == "running" and not _alive(doc.get("pid"), doc.get("host")):
        return "killed"
    return str(doc["status"])


def leftovers(folder: str | Path) -> list[str]:
    """The temporary files that writes cut short left in a run folder (paths relative to
    it): ``--resume`` and ``--overwrite`` delete them."""
    folder = as_path(folder, "run folder")
    return [str(p.relative_to(folder)) for p in temporaries(folder)]


def _lock(folder: Path) -> int | None:
    """An exclusive lock on ``folder`` (``flock`` on the folder's descriptor), or a one-line
    error if another process holds it; ``None`` where the platform has no ``flock``."""
    try:
        import fcntl
    except ImportError:  # pragma: no cover - not POSIX
        return None
    fd = os.open(folder, os.O_RDONLY)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        os.close(fd)
        raise CrmgraspError(f"{str(folder)!r} is in use by another crmgrasp run") from None
    return fd


class RunFolder:
    """The folder and ``run.json`` of one run (a context manager that sets the final
    status).

    Parameters
    ----------
    path
        The folder; ``None`` for [`default_run_dir`][].
    command, task
        Names of the command and its task.
    config
        What the results depend on (JSON data); ``--resume`` requires it equal.
    argv, seed
        Recorded as given.
    overwrite, resume
        What to do with an existing non-empty folder (see the module).
    """

    def __init__(
        self,
        path: str | Path | None,
        command: str,
        task: str,
        config: dict[str, Any],
        *,
        argv: list[str] | None = None,
        seed: int | None = None,
        overwrite: bool = False,
        resume: bool = False,
    ) -> None:
        if overwrite and resume:
            raise CrmgraspError("--overwrite and --resume exclude each other")
        _names(command, task)
        try:
            self.config = json.loads(dumps_json(config))  # plain JSON data, as it will be read back
        except (TypeError, ValueError, RecursionError) as exc:
            raise CrmgraspError(f"a run's config must be JSON data ({shown(str(exc), 80)})") from None
        self.path = default_run_dir(command, task) if path is None else check_folder(path, "--out")
        self.resumed = self._was_complete = False
        made = not self.path.exists()
        self.path.mkdir(parents=True, exist_ok=True)
        self._lock_fd = _lock(self.path)
        try:
            previous = self._claim(command, overwrite, resume)
        except BaseException:
            self._unlock()
            if made:
                shutil.rmtree(self.path, ignore_errors=True)
            raise
        self.record: dict[str, Any] = {
            "format": FORMAT,
            "command": command,
            "task": task,
            "status": "running",
            "config": self.config,
            "completed": previous.get("completed", {}) if previous else {},
            "argv": list(sys.argv[1:] if argv is None else argv),
            "seed": seed,
            "started": _now(),
            "ended": None,
            "error": None,
            "version": _version(),
            "git_commit": _git_commit(),
            "source_sha256": source_digest(),
            "python": platform.python_version(),
            "platform": platform.platform(),
            "dependencies": _versions(),
            "host": socket.gethostname(),
            "pid": os.getpid(),
        }
        if previous:
            self.record["resumed_from"] = {k: previous.get(k) for k in ("started", "ended", "status")}
        self._save()

    def _unlock(self) -> None:
        if self._lock_fd is not None:
            os.close(self._lock_fd)  # closing the descriptor releases the flock
            self._lock_fd = None

    def _claim(self, command: str, overwrite: bool, resume: bool) -> dict[str, Any] | None:
        """Check what is in the folder already; empty it for ``overwrite``; return the
        previous record for ``resume``."""
        p = self.path
        busy = p.is_dir() and any(p.iterdir())
        if not busy:
            if resume:
                raise CrmgraspError(f"--resume: {str(p)!r} holds no run to resume")
            return None
        if not (p / "run.json").is_file():
            what = "delete" if overwrite else "resume"
            if overwrite or resume:
                raise CrmgraspError(f"{str(p)!r} is not a crmgrasp run folder (no run.json); refusing to {what} it")
            raise CrmgraspError(f"--out {str(p)!r} exists and is not empty; choose another folder")
        doc = _read(p)
        if doc["status"] == "running" and _alive(doc.get("pid"), doc.get("host")):
            raise CrmgraspError(f"{str(p)!r} is in use by a running crmgrasp (pid {doc.get('pid')})")
        if overwrite:
            for child in p.iterdir():
                shutil.rmtree(child) if child.is_dir() and not child.is_symlink() else child.unlink()
            return None
        if not resume:
            raise CrmgraspError(
                f"--out {str(p)!r} already holds a {doc['status']} {doc.get('command')} run; "
                "use --resume to continue it, --overwrite to replace it, or another --out"
            )
        if doc.get("command") != command:
            raise CrmgraspError(f"--resume: {str(p)!r} holds a {shown(doc.get('command'))} run, not {command}")
        old = doc.get("config", {})
        for key in sorted(set(old) | set(self.config)):
            if old.get(key) != self.config.get(key):
                raise CrmgraspError(
                    f"--resume: the run in {str(p)!r} has {key} = {shown(old.get(key))}, "
                    f"this command {shown(self.config.get(key))}; resume with the same settings"
                )
        self._was_complete = doc["status"] == "complete"  # said when the resumed run ends well
        for tmp in temporaries(p):  # writes a kill cut short: their files were never renamed into place
            tmp.unlink()
        self.resumed = True
        return doc

    # --- units of work -------------------------------------------------------------------
    def done(self, unit: str) -> Any:
        """What [`complete`][] recorded for ``unit`` (``None`` if not done)."""
        return self.record["completed"].get(unit)

    def complete(self, unit: str, info: Any = True) -> None:
        """Record ``unit`` as done (``info``: JSON data kept for a resumed run): one line
        appended to the journal ([`JOURNAL`][crmgrasp.experiments.runs.JOURNAL]), whatever the number of units done."""
        self.record["completed"][unit] = info
        line = dumps_json({"unit": unit, "info": info}, indent=None) + "\n"  # standard JSON, one line
        with open(self.path / JOURNAL, "a", encoding="utf-8") as fh:  # one write: a line is whole or cut
            fh.write(line)

    def sub(self, name: str) -> RunFolder:
        """A view of this run for one part of it (``name``): its units are recorded here
        prefixed with ``name``, its files go to a subfolder named after it."""
        return _Part(self, name)  # type: ignore[return-value]

    # --- final status ----------------------------------------------------------------------
    def finish(self, status: str, error: str | None = None) -> None:
        """Set the final status (and error text) and the end time."""
        if status not in STATUSES:
            raise ValueError(status)
        self.record.update(status=status, error=error, ended=_now())
        self._save()
        self._unlock()

    def __enter__(self) -> RunFolder:
        return self

    def __exit__(self, kind: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None) -> None:
        if kind is None:
            self.finish("complete")
            if self._was_complete:  # after the run, so that a record found damaged later says only that
                print(
                    f"crmgrasp: the run in {str(self.path)!r} was already complete; --resume reran nothing",
                    file=sys.stderr,
                )
        elif issubclass(kind, KeyboardInterrupt):
            self.finish("interrupted")
        else:
            self.finish("failed", f"{kind.__name__}: {exc}" if not isinstance(exc, CrmgraspError) else str(exc))

    def _save(self) -> None:
        """``run.json`` with every unit done, then the journal it now holds removed (a kill
        between the two leaves entries that are in both: reading merges them alike)."""
        write_json(self.path / "run.json", self.record)
        (self.path / JOURNAL).unlink(missing_ok=True)


def _version() -> str:
    try:
        return metadata.version("crmgrasp")
    except metadata.PackageNotFoundError:  # run from a source tree without installing
        return "unknown"


class _Part:
    """A named part of a run (see [`RunFolder.sub`][])."""

    def __init__(self, run: RunFolder, name: str) -> None:
        self.run, self.name = run, name
        slug = re.sub(r"[^A-Za-z0-9._-]+", "-", name).strip("-") or "part"
        self.path = run.path / "parts" / slug

    def done(self, unit: str) -> Any:
        return self.run.done(f"{self.name}: {unit}")

    def complete(self, unit: str, info: Any = True) -> None:
        self.run.complete(f"{self.name}: {unit}", info)

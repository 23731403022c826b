"""Safe file input and output.

Output is atomic (a reader never sees a half-written file, and a failed write leaves
the previous file intact), goes only to regular files (a device node, a FIFO, a
folder or a symlink to one of them is refused, never replaced), respects the umask,
and names the user's path in every error. JSON is standard (no NaN or Infinity: a
non-finite number is written as ``null``). Input of a file the user names is bounded
([`read_bounded`][]).
"""

from __future__ import annotations

import contextlib
import csv
import io
import json
import math
import os
import stat
import tempfile
from collections.abc import Iterable, Iterator, Sequence
from pathlib import Path
from typing import Any

from crmgrasp._validation import CrmgraspError, shown

__all__ = [
    "as_path",
    "check_output",
    "check_new_output",
    "check_folder",
    "read_bounded",
    "atomic_path",
    "atomic_write_bytes",
    "atomic_write_text",
    "json_safe",
    "dumps_json",
    "write_json",
    "write_csv",
    "save_figure",
    "temporaries",
]

_TMP_PREFIX, _TMP_SUFFIX = ".crmgrasp-", ".tmp"  # short: a 255-byte file name still gets one


def temporaries(folder: str | os.PathLike[str]) -> list[Path]:
    """The temporary files of unfinished atomic writes under ``folder`` (a write killed
    before its rename leaves one; nothing else is named ``.crmgrasp-*``), sorted."""
    return sorted(p for p in Path(folder).rglob(f"{_TMP_PREFIX}*") if p.is_file() and not p.is_symlink())


def as_path(path: object, what: str = "file") -> Path:
    """``path`` (text or an ``os.PathLike``) as a [`Path`][], or a one-line error naming ``what``."""
    if not isinstance(path, (str, os.PathLike)):
        raise CrmgraspError(f"{what} path must be text or a path, got {shown(path)}")
    return Path(path)


def check_output(path: str | os.PathLike[str], what: str = "output file") -> Path:
    """``path`` as a [`Path`][] if a file can be written there: not empty, not an
    existing non-regular file (device node, FIFO, socket, folder) or a symlink to one,
    and its folder exists (or can be made) and is writable. Call it before any long
    work, so that a bad path fails at once."""
    target = as_path(path, what)
    if str(path) == "":
        raise CrmgraspError(f"{what} path is empty")
    if target.exists() or target.is_symlink():
        try:
            mode = os.stat(target).st_mode  # follows a symlink
        except OSError as exc:
            raise CrmgraspError(f"{what} {str(target)!r} cannot be used: {exc.strerror}") from None
        if not stat.S_ISREG(mode):
            kind = "a folder" if stat.S_ISDIR(mode) else "not a regular file"
            raise CrmgraspError(f"{what} {str(target)!r} is {kind}; refusing to replace it")
    parent = target.resolve().parent
    probe = parent
    while not probe.exists():
        probe = probe.parent
    if not probe.is_dir() or not os.access(probe, os.W_OK | os.X_OK):
        raise CrmgraspError(f"{what} {str(target)!r} cannot be written: folder {str(probe)!r} is not writable")
    return target


def check_new_output(path: str | os.PathLike[str], what: str, overwrite: bool, earlier: str = "") -> Path:
    """``path`` as [`check_output`][] gives it, and refused if a file is already there
    unless ``overwrite``: a command never replaces a user's file silently. ``earlier``
    says what an existing file is (e.g. ``" (the log of an earlier run)"``)."""
    target = check_output(path, what)
    if target.exists() and not overwrite:
        raise CrmgraspError(f"{what} {str(target)!r} exists{earlier}; --overwrite replaces it")
    return target


def check_folder(path: str | os.PathLike[str], what: str = "output folder") -> Path:
    """``path`` as a [`Path`][] if it is, or can be made, a writable folder (checked
    before any long work)."""
    target = as_path(path, what)
    if str(path) == "":
        raise CrmgraspError(f"{what} path is empty")
    if target.exists() and not target.is_dir():
        raise CrmgraspError(f"{what} {str(target)!r} exists and is not a folder")
    probe = target.resolve()
    while not probe.exists():
        probe = probe.parent
    if not probe.is_dir() or not os.access(probe, os.W_OK | os.X_OK):
        raise CrmgraspError(f"{what} {str(target)!r} cannot be written: {str(probe)!r} is not a writable folder")
    return target


def read_bounded(path: str | os.PathLike[str], max_bytes: int, what: str = "file") -> bytes:
    """The bytes of a regular file of at most ``max_bytes``; a one-line error for a
    missing file, a FIFO, device or folder (never opened, so never blocking or endless)
    or a larger file."""
    p = as_path(path, what)
    try:
        mode = os.stat(p).st_mode
    except FileNotFoundError:
        raise CrmgraspError(f"{what} {str(p)!r} does not exist") from None
    except OSError as exc:
        raise CrmgraspError(f"{what} {str(p)!r} cannot be read: {exc.strerror}") from None
    if not stat.S_ISREG(mode):
        raise CrmgraspError(f"{what} {str(p)!r} is not a regular file")
    try:
        with open(p, "rb") as fh:
            data = fh.read(max_bytes + 1)
    except OSError as exc:
        raise CrmgraspError(f"{what} {str(p)!r} cannot be read: {exc.strerror}") from None
    if len(data) > max_bytes:
        raise CrmgraspError(f"{what} {str(p)!r} is larger than {max_bytes:,} bytes")
    return data


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def _destination(path: str | os.PathLike[str]) -> Path:
    """The file to replace: ``path``, or the regular file a symlink at ``path`` names."""
    target = check_output(path)
    return target.resolve() if target.is_symlink() else target


def atomic_write_bytes(path: str | os.PathLike[str], data: bytes) -> Path:
    """Write ``data`` to ``path`` via a temporary file in the same folder and ``os.replace``."""
    target = _destination(path)
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=target.parent, prefix=_TMP_PREFIX, suffix=_TMP_SUFFIX)
    except OSError as exc:
        raise CrmgraspError(f"cannot write {str(path)!r}: {exc.strerror}") from None
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
        os.chmod(tmp, 0o666 & ~_umask())
        os.replace(tmp, target)
    except OSError as exc:
        Path(tmp).unlink(missing_ok=True)
        raise CrmgraspError(f"cannot write {str(path)!r}: {exc.strerror}") from None
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return Path(path)


def atomic_write_text(path: str | os.PathLike[str], text: str) -> Path:
    """Atomically write UTF-8 text."""
    return atomic_write_bytes(path, text.encode("utf-8"))


def json_safe(obj: Any) -> Any:
    """``obj`` with every non-finite float replaced by ``None`` (JSON ``null``) and numpy
    scalars and tuples turned into plain values and lists."""
    if isinstance(obj, dict):
        return {str(k): json_safe(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [json_safe(v) for v in obj]
    if hasattr(obj, "item") and not isinstance(obj, (str, bytes)):
        obj = obj.item()
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


def dumps_json(obj: Any, indent: int | None = 2) -> str:
    """Standard JSON text of ``obj`` (`json_safe`; never NaN or Infinity)."""
    return json.dumps(json_safe(obj), indent=indent, allow_nan=False)


def write_json(path: str | os.PathLike[str], obj: Any) -> Path:
    """Atomically write ``obj`` as indented standard JSON."""
    return atomic_write_text(path, dumps_json(obj) + "\n")


def write_csv(path: str | os.PathLike[str], header: Sequence[str], rows: Iterable[Sequence[Any]]) -> Path:
    """Atomically write a CSV file with a header row (floats with ``repr`` precision)."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(header)
    for row in rows:
        w.writerow([_cell(v) for v in row])
    return atomic_write_text(path, buf.getvalue())


def _cell(v: Any) -> Any:
    """CSV cell: floats at full precision, numpy scalars as Python values."""
    if hasattr(v, "item") and not isinstance(v, (str, bytes)):
        v = v.item()
    return repr(v) if isinstance(v, float) else v


def save_figure(fig: Any, path: str | os.PathLike[str], **kwargs: Any) -> Path:
    """Atomically save a matplotlib figure (format from the suffix)."""
    target = Path(path)
    buf = io.BytesIO()
    fig.savefig(buf, format=target.suffix.lstrip(".") or "png", **kwargs)
    return atomic_write_bytes(target, buf.getvalue())


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str]) -> Iterator[Path]:
    """Yield a temporary path beside ``path`` (with its suffix, for writers that choose
    the format by it); on success it replaces ``path``."""
    target = _destination(path)
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=target.parent, prefix=_TMP_PREFIX, suffix=target.suffix or _TMP_SUFFIX)
    except OSError as exc:
        raise CrmgraspError(f"cannot write {str(path)!r}: {exc.strerror}") from None
    os.close(fd)
    try:
        yield Path(tmp)
        os.chmod(tmp, 0o666 & ~_umask())
        os.replace(tmp, target)
    except OSError as exc:
        Path(tmp).unlink(missing_ok=True)
        raise CrmgraspError(f"cannot write {str(path)!r}: {exc.strerror}") from None
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise

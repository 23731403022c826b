"""One stamp of every compiled source in each compiled module, so numba's disk cache follows them.

numba caches a compiled function on disk under a hash of the file that defines it, and
the cached machine code includes every compiled function it calls, from any module. A
change to a callee in another file (``_closure_jit.least_friction``, called by
``_fingers3d_jit.step_one``) leaves the caller's file, and so its cache entry, as it was:
the cached caller keeps running the old callee (numba's documented limitation, numba
issue 1833). That happens to a developer who edits one kernel module, to a clone after
``git pull`` and to an upgrade over a cache that outlived the install.

So each compiled module (``kernels/_*_jit.py``) ends with the line ``# compiled sources:
<digest>``, the SHA-256 of every compiled module and of ``_compile.py`` (how they are
compiled), each read without its stamp line and the blank lines before it. Any edit to any of them changes the
digest; the stamp lines then differ from it until they are rewritten, and rewriting them
changes every compiled module's file, so numba recompiles all of them once.
``tests/test_kernels.py`` fails while a stamp is out of date; ``python -m
crmgrasp.kernels._stamp`` rewrites them (atomically, file by file).
"""

from __future__ import annotations

import hashlib
import os
import tempfile
from pathlib import Path

__all__ = ["PREFIX", "compiled_modules", "digest", "stale", "write"]

PREFIX = "# compiled sources: "
"""The start of the stamp line, the last line of each compiled module."""

HERE = Path(__file__).resolve().parent


def compiled_modules(directory: Path = HERE) -> list[Path]:
    """The compiled modules (``_*_jit.py``) of ``directory``, sorted by name."""
    return sorted(directory.glob("_*_jit.py"))


def _body(path: Path) -> str:
    """``path``'s text without its stamp line and the blank lines at its end."""
    lines = path.read_text().splitlines(keepends=True)
    return "".join(line for line in lines if not line.startswith(PREFIX)).rstrip() + "\n"


def digest(directory: Path = HERE) -> str:
    """SHA-256 (hex) over the name and the stamp-free text of each compiled module and of
    ``_compile.py``, in name order."""
    h = hashlib.sha256()
    for path in [*compiled_modules(directory), directory / "_compile.py"]:
        h.update(path.name.encode() + b"\0" + _body(path).encode() + b"\0")
    return h.hexdigest()


def stale(directory: Path = HERE) -> list[str]:
    """The compiled modules whose last line is not the stamp of the current digest."""
    line = PREFIX + digest(directory)
    return [p.name for p in compiled_modules(directory) if p.read_text().splitlines()[-1:] != [line]]


def write(directory: Path = HERE) -> list[str]:
    """Rewrite the stamp line of each stale compiled module (one atomic replace per file);
    returns their names."""
    line = PREFIX + digest(directory) + "\n"
    names = stale(directory)
    for name in names:
        path = directory / name
        fd, tmp = tempfile.mkstemp(dir=directory, prefix=f".{name}.", suffix=".tmp")
        with os.fdopen(fd, "w") as out:
            out.write(_body(path) + "\n\n" + line)  # two blank lines, as the formatter wants
        os.chmod(tmp, path.stat().st_mode)
        os.replace(tmp, path)
    return names


if __name__ == "__main__":  # pragma: no cover - the developer's command
    changed = write()
    print(f"stamped {len(changed)} compiled module(s): {', '.join(changed) or 'all current'}")

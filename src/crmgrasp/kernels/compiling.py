"""Telling the user that numba is compiling: the one wait a first run has that no progress
line covers.

The compiled kernels are compiled on their first call after an install (or an upgrade
of crmgrasp or numba) and cached on disk; later runs load them in well under a second.
The first compilation takes seconds to tens of seconds (the tripods' kernels about 30 s on
the 2-core development machine), inside the first CRM a command steps, before its
progress line has anything to show. [`compile_notice`][] listens to numba's compile
events (its event API, ``numba.core.event``, kind ``"numba:compile"``: sent only when a
function is compiled, never when it is loaded from the cache) and, once compilation has
taken ``after`` seconds in all, says so in one line; when the context ends it says how
long compiling took. Compiling for less than ``after`` seconds shows nothing. The
command line wraps every command that steps a kernel in it (`crmgrasp.cli.main`).

Worker processes forked from the command (``--jobs``, where the start method is fork, as on
Linux before torch is loaded) inherit the listener and compile for themselves: the first
process to compile for ``after`` seconds shows the notice, once for them all (a flag in
shared memory), and only the command's own process, if it showed it, adds the total.
Workers started by spawn compile silently.
"""

from __future__ import annotations

import math
import multiprocessing
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

__all__ = ["AFTER", "NOTICE", "compile_notice"]

AFTER = 2.0
"""Seconds of compiling after which [`compile_notice`][] speaks, unless told otherwise
(``math.inf``: never)."""

NOTICE = (
    "compiling crmgrasp's kernels with numba (the first run after installing or upgrading; "
    "cached on disk for later runs) ..."
)
"""The line shown once compilation has taken ``after`` seconds."""


class _Clock:
    """Seconds spent compiling (outermost compilations only: a function compiles the
    functions it calls inside its own compilation), and a timer that fires ``notify`` once
    their sum reaches ``after``."""

    def __init__(self, notify: Callable[[str], None], after: float) -> None:
        self.notify, self.after = notify, after
        self.depth, self.seconds, self.told, self.shown = 0, 0.0, False, False
        self._t0 = 0.0
        self._timer: threading.Timer | None = None
        self._lock = threading.Lock()
        self._anyone = multiprocessing.Value("b", 0)  # shown by this process or a forked worker

    def start(self) -> None:
        self.depth += 1
        if self.depth > 1:
            return
        self._t0 = time.monotonic()
        if self.told:
            return
        left = self.after - self.seconds
        if left <= 0.0:
            self._tell()
        elif math.isfinite(left):  # after = inf: never
            self._timer = threading.Timer(left, self._tell)
            self._timer.daemon = True
            self._timer.start()

    def end(self) -> None:
        self.depth -= 1
        if self.depth > 0:
            return
        self.seconds += time.monotonic() - self._t0
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None

    def _tell(self) -> None:
        with self._lock:
            if self.told:
                return
            self.told = True
        with self._anyone.get_lock():
            self.shown, self._anyone.value = not self._anyone.value, 1
        if self.shown:
            self.notify(NOTICE)

    def stop(self) -> None:
        """Cancel a pending notice; if this process showed one, say how long compiling took."""
        if self._timer is not None:
            self._timer.cancel()
        with self._lock:
            self.told = True  # a timer firing now shows nothing
        if self.shown:
            self.notify(f"compiling took {self.seconds:.0f} s of this run")


@contextmanager
def compile_notice(notify: Callable[[str], None], after: float | None = None) -> Iterator[None]:
    """Within the context, call ``notify`` with [`NOTICE`][] once numba has compiled for
    ``after`` seconds ([`AFTER`][] by default) in all, counting the compilations of the thread
    that entered the context (not those of other threads), and on exit, if it did, with the
    seconds compiling took (see the module docstring). ``notify`` may be called from a timer
    thread while the compiling thread waits in numba."""
    from numba.core import event

    clock, here = _Clock(notify, AFTER if after is None else after), threading.get_ident()

    class _Listener(event.Listener):  # type: ignore[misc]
        def on_start(self, ev: Any) -> None:
            if threading.get_ident() == here:
                clock.start()

        def on_end(self, ev: Any) -> None:
            if threading.get_ident() == here:
                clock.end()

    try:
        with event.install_listener("numba:compile", _Listener()):
            yield
    finally:
        clock.stop()

"""Progress of long work, shown to the user on standard error.

On a terminal a live line is redrawn in place at most ``refresh`` times a second::

    learn sarsa k=2  [##########----------]  52%  10,400/20,000 episodes  0:41 < 0:38

Elsewhere (a CI log, a file) one plain line is printed every ``interval`` seconds and
once at the end, so a log shows the run is alive without flooding. [`Quiet`][]
shows nothing (``--quiet``). Long functions take a ``progress`` argument (never a
global) and call [`Progress.stage`][] once per unit of work, then
[`Progress.advance`][] as work is done; a stage nested in another one replaces its
line while it runs.

Progress steps are also where a lost Ctrl-C stops the work. Python raises
`KeyboardInterrupt` wherever the main thread is when SIGINT arrives; inside a finaliser
(``__del__``), a weakref or garbage-collector callback, or a callback called from C, it
prints the traceback ("Exception ignored in ...") and carries on. The command line's
handler [`on_sigint`][] raises as Python does and also records the interrupt, and
[`check`][] (called by every stage and step) raises it again.
"""

from __future__ import annotations

import sys
import time
from typing import Any, TextIO

__all__ = ["Progress", "Quiet", "make_progress", "on_sigint", "check", "clear"]

_pending = False


def on_sigint(signum: int, frame: Any) -> None:
    """The SIGINT handler of the command line: record the interrupt, then raise it."""
    global _pending
    _pending = True
    raise KeyboardInterrupt


def check() -> None:
    """Raise `KeyboardInterrupt` if an interrupt is pending (one raised where Python
    swallowed it)."""
    if _pending:
        raise KeyboardInterrupt


def clear() -> None:
    """Forget the interrupt: the command stopped on it (or a new command starts)."""
    global _pending
    _pending = False


def _clock(seconds: float) -> str:
    """``m:ss`` or ``h:mm:ss``."""
    s = int(max(seconds, 0.0))
    h, rest = divmod(s, 3600)
    return f"{h}:{rest // 60:02d}:{rest % 60:02d}" if h else f"{rest // 60}:{rest % 60:02d}"


class Progress:
    """A progress display for one command.

    Parameters
    ----------
    stream : text stream written to (standard error by default).
    live : redraw one line in place (a terminal) instead of printing periodic lines;
        ``None`` asks ``stream.isatty()``.
    interval : seconds between plain lines when not live.
    """

    def __init__(self, stream: TextIO | None = None, live: bool | None = None, interval: float = 10.0) -> None:
        self.stream = sys.stderr if stream is None else stream
        self.live = bool(getattr(self.stream, "isatty", lambda: False)()) if live is None else live
        self.interval = interval
        self._stack: list[list] = []  # [label, total, done, unit, t0]
        self._last = 0.0
        self._width = 0

    def stage(self, label: str, total: int, unit: str = "") -> Progress:
        """Begin a unit of work of ``total`` steps (a context manager: it ends on exit)."""
        check()
        self._stack.append([label, max(int(total), 0), 0, unit, time.monotonic()])
        self._show(force=True)
        return self

    def __enter__(self) -> Progress:
        return self

    def __exit__(self, *exc: object) -> None:
        self.end()

    def advance(self, n: int = 1) -> None:
        """``n`` more steps of the innermost stage are done (and a Ctrl-C that Python
        swallowed stops the work here: [`check`][])."""
        check()
        if self._stack:
            self._stack[-1][2] += n
            self._show()

    def relabel(self, label: str) -> None:
        """Rename the innermost stage (e.g. to show failures so far)."""
        if self._stack:
            self._stack[-1][0] = label

    def end(self) -> None:
        """End the innermost stage (a final line when not live)."""
        if not self._stack:
            return
        label, total, done, unit, t0 = self._stack[-1]
        if not self.live:
            count = f"{done:,}/{total:,} {unit} " if total else (f"{done:,} {unit} " if done else "")
            self._write(f"{label}: done {count}in {_clock(time.monotonic() - t0)}\n")
        self._stack.pop()
        if self.live:
            self._clear()
            if self._stack:
                self._show(force=True)

    def note(self, text: str) -> None:
        """Print one line above the live line (or plainly)."""
        if self.live:
            self._clear()
        self._write(text + "\n")
        if self.live and self._stack:
            self._show(force=True)

    def interject(self, text: str) -> None:
        """Print one line from outside this display (another thread, another display of the
        same command): on a terminal it first erases the line a live display may be drawing
        there (ANSI "erase line"), which that display redraws on its next step."""
        self._write(("\r\x1b[2K" if self.live else "") + text + "\n")

    def line(self) -> str:
        """The current text of the innermost stage."""
        if not self._stack:
            return ""
        label, total, done, unit, t0 = self._stack[-1]
        elapsed = time.monotonic() - t0
        if total <= 0:
            return f"{label}  {done:,} {unit}  {_clock(elapsed)}".rstrip()
        frac = min(done / total, 1.0)
        bar = "#" * int(20 * frac) + "-" * (20 - int(20 * frac))
        eta = f" < {_clock(elapsed * (1 - frac) / frac)}" if 0 < frac < 1 else ""
        return f"{label}  [{bar}] {frac:4.0%}  {done:,}/{total:,} {unit}  {_clock(elapsed)}{eta}"

    def _show(self, force: bool = False) -> None:
        now = time.monotonic()
        if self.live:
            if force or now - self._last >= 0.1:
                text = self.line()
                self._write("\r" + text + " " * max(self._width - len(text), 0))
                self._width = len(text)
                self._last = now
        elif not force and now - self._last >= self.interval:
            self._write(self.line() + "\n")
            self._last = now
        elif force and not self._last:
            self._last = now

    def _clear(self) -> None:
        if self._width:
            self._write("\r" + " " * self._width + "\r")
            self._width = 0

    def _write(self, text: str) -> None:
        try:
            self.stream.write(text)
            self.stream.flush()
        except (OSError, ValueError):  # a closed or broken stream never stops the work
            pass


class Quiet(Progress):
    """Shows nothing (``--quiet``)."""

    def __init__(self) -> None:
        super().__init__(stream=sys.stderr, live=False)

    def _write(self, text: str) -> None:
        return None


def make_progress(quiet: bool = False) -> Progress:
    """[`Quiet`][] or a [`Progress`][] on standard error."""
    return Quiet() if quiet else Progress()

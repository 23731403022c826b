"""A child process that can be interrupted, whatever launched the test run."""

from __future__ import annotations

import signal


def default_sigint() -> None:
    """``preexec_fn`` of a child a test sends SIGINT to: SIGINT back to its default, so the
    child's Python installs its Ctrl-C handler. A shell's background job (``cmd &``) starts
    with SIGINT ignored, and Python keeps an inherited ignore: its child would not stop."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)

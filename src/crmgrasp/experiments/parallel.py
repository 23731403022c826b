"""Worker processes for independent runs (groups of trials, study cells).

Every caller's results depend only on what each call is given (its seeds included), never
on which process runs it or in which order calls finish, so ``jobs`` changes the time
and not the results. Workers are forked from the calling process where the platform
allows (compiled kernels are inherited), else spawned, and spawned too once the calling
process has loaded a library whose thread pool a forked child inherits broken
([`FORK_UNSAFE`][]: torch; a forked worker then hangs in its first parallel operation);
they ignore Ctrl-C, which the
calling process turns into stopping them all (``crmgrasp`` turns SIGTERM into the same).
"""

from __future__ import annotations

import multiprocessing
import os
import signal
import sys
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from typing import Any, TypeVar

from crmgrasp._validation import CrmgraspError

__all__ = ["usable_jobs", "run_parallel"]

K = TypeVar("K")
T = TypeVar("T")


def usable_jobs(jobs: int) -> int:
    """Worker processes for ``jobs``: itself if >= 1, every usable core if 0."""
    if isinstance(jobs, bool) or not isinstance(jobs, int) or jobs < 0:
        raise CrmgraspError(f"jobs must be an integer >= 0 (0: every usable core), got {jobs!r}")
    if jobs:
        return jobs
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


EXECUTORS = ("local", "ray")
"""Where [`run_parallel`][] runs calls: worker processes on this machine, or Ray."""


FORK_UNSAFE = ("torch",)
"""Libraries whose thread pools do not survive a fork: loaded in the calling process, they make
[`run_parallel`][] spawn its workers (seen: ``reproduce(..., jobs=2)`` after a torch matrix
product hung in the forked worker that ran the deep peer)."""


def start_method() -> str:
    """``"fork"`` where the platform has it and no [`FORK_UNSAFE`][] library is loaded, else
    ``"spawn"``."""
    forkable = "fork" in multiprocessing.get_all_start_methods()
    return "fork" if forkable and not any(name in sys.modules for name in FORK_UNSAFE) else "spawn"


def run_parallel(
    calls: Sequence[tuple[K, Callable[[], T]]], jobs: int, executor: str = "local", address: str | None = None
) -> Iterator[tuple[K, T]]:
    """``(key, call())`` for every call, in completion order: in this process when
    ``jobs`` is 1 (or there is one call), else in ``jobs`` worker processes (0: every
    usable core); with ``executor="ray"``, as Ray tasks (one per call) on the cluster at
    ``address`` (``"auto"``, ``"HOST:PORT"``) or, without one, on a local Ray instance of
    ``jobs`` CPUs. The calls must be picklable (module-level functions, frozen
    dataclasses, `functools.partial`)."""
    if executor not in EXECUTORS:
        raise CrmgraspError(f"unknown executor {executor!r}; choose one of {', '.join(EXECUTORS)}")
    if executor == "ray":
        yield from _run_ray(calls, jobs, address)
        return
    workers = min(usable_jobs(jobs), len(calls))  # more workers than calls would only idle
    if workers <= 1:
        for key, call in calls:
            yield key, call()
        return
    context = multiprocessing.get_context(start_method())
    pool = ProcessPoolExecutor(max_workers=workers, mp_context=context, initializer=_ignore_sigint)
    try:
        futures = {pool.submit(call): key for key, call in calls}
        for future in as_completed(futures):
            yield futures[future], future.result()
    except BaseException:  # Ctrl-C, an error, or the caller stopped early: stop the workers now
        procs = getattr(pool, "_processes", None)
        for proc in list(procs.values()) if isinstance(procs, dict) else []:
            if hasattr(proc, "terminate"):
                proc.terminate()
        # wait for the executor's manager thread (quick: the workers are stopped), so that no
        # wake-up of it is left for interpreter exit, where Python 3.11 may write it to a pipe
        # the thread already closed and print a traceback after the one-line message
        pool.shutdown(wait=True, cancel_futures=True)
        raise
    pool.shutdown()


def _call(call: Callable[[], T]) -> T:
    return call()


def _run_ray(calls: Sequence[tuple[K, Callable[[], T]]], jobs: int, address: str | None) -> Iterator[tuple[K, T]]:
    """[`run_parallel`][] on Ray (extra ``crmgrasp[ray]``)."""
    try:
        import ray
    except ImportError:
        raise CrmgraspError("the Ray executor needs the optional extra: pip install 'crmgrasp[ray]'") from None
    import logging

    started = not ray.is_initialized()
    if started:
        options: dict[str, Any] = {
            "include_dashboard": False,
            "log_to_driver": False,
            "logging_level": logging.ERROR,
        }
        if address:
            options["address"] = address
        else:
            options["num_cpus"] = usable_jobs(jobs)
        if address and address != "auto":
            _reachable(address)
        try:
            ray.init(**options)
        except (Exception, SystemExit) as exc:  # Ray's own errors (it may also exit), in one line
            raise CrmgraspError(f"cannot start or reach Ray ({type(exc).__name__}: {exc})") from None
    remote: Any = ray.remote(_call)
    pending = {remote.remote(call): key for key, call in calls}
    try:
        while pending:
            done, _ = ray.wait(list(pending), num_returns=1)
            for ref in done:
                yield pending.pop(ref), ray.get(ref)
    except BaseException:
        for ref in pending:
            ray.cancel(ref, force=True)
        raise
    finally:
        if started:
            ray.shutdown()


RAY_TIMEOUT = 10.0
"""Seconds a Ray address (``HOST:PORT``) has to answer as a Ray head does before the command
gives up in one line: an address that accepts connections but speaks no Ray would hang
``ray.init`` for minutes."""

_HTTP2_PREFACE = b"PRI * HTTP/2.0\r\n\r\nSM\r\n\r\n" + bytes([0, 0, 0, 4, 0, 0, 0, 0, 0])
"""The HTTP/2 client preface and an empty SETTINGS frame: a gRPC server (Ray's head, its GCS)
answers it with a frame of its own at once."""


def _reachable(address: str) -> None:
    """A one-line error within `RAY_TIMEOUT` seconds for a ``HOST:PORT`` that accepts no
    connection, or accepts one but does not answer as a Ray head does (Ray itself retries
    for minutes): the HTTP/2 preface must bring an answer."""
    import socket

    host, _, port = address.rpartition(":")
    if not host or not port.isdigit():
        raise CrmgraspError(f"Ray address must be auto or HOST:PORT, got {address!r}")
    try:
        with socket.create_connection((host, int(port)), timeout=RAY_TIMEOUT) as conn:
            conn.sendall(_HTTP2_PREFACE)
            answered = bool(conn.recv(1))
    except TimeoutError:
        answered = False
    except OSError as exc:
        raise CrmgraspError(f"Ray address {address} is unreachable ({exc.strerror or exc})") from None
    if not answered:
        raise CrmgraspError(
            f"Ray at {address} did not answer within {RAY_TIMEOUT:g} s (is it a Ray cluster's address?)"
        )


def _ignore_sigint() -> None:
    """Workers leave Ctrl-C to the calling process, and end at once on SIGTERM (the calling
    process stops them with it, whatever handler they inherited)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)

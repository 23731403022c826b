"""Worker processes for independent runs (groups of trials, study cells).

Every caller's results depend only on what each call is given (its seeds included), never
on which process runs it or in which order calls finish, so ``jobs`` changes the time
and not the results. Workers are forked from the calling process where the platform
allows (compiled kernels are inherited), else spawned; they ignore Ctrl-C, which the
calling process turns into stopping them all.
"""

from __future__ import annotations

import multiprocessing
import os
import signal
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from typing import TypeVar

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


def run_parallel(calls: Sequence[tuple[K, Callable[[], T]]], jobs: int) -> Iterator[tuple[K, T]]:
    """``(key, call())`` for every call, in completion order: in this process when
    ``jobs`` is 1 (or there is one call), else in ``jobs`` worker processes (0: every
    usable core). The calls must be picklable (module-level functions, frozen
    dataclasses, :func:`functools.partial`)."""
    workers = usable_jobs(jobs)
    if workers <= 1 or len(calls) <= 1:
        for key, call in calls:
            yield key, call()
        return
    methods = multiprocessing.get_all_start_methods()
    context = multiprocessing.get_context("fork" if "fork" in methods else "spawn")
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
        pool.shutdown(wait=False, cancel_futures=True)
        raise
    pool.shutdown()


def _ignore_sigint() -> None:
    """Workers leave Ctrl-C to the calling process."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)

"""Python's cyclic garbage collector held off while a large acyclic structure is built.

Two places build many small, long-lived objects that are in no reference cycle:

* ``backoff-vi`` and ``pooled-vi`` rebuild their planning model from all data after new
  data, a tuple and a dict per outcome, alive until the next rebuild;
* the belief-space optimum (`crmgrasp.planners.references.belief_optimum`) memoises the
  value of every belief it meets, a tuple of states per belief.

With the collector on, those allocations set off its full passes, and each walks every object
the process holds, so the time they take grows with what was built already. Reference counting
still frees whatever such a build drops; only cycles would wait, and the builds make none.

When the collector resumes, everything the build made is still in its youngest generation, and
the next allocation would set off a pass over all of it (then another when it moves on to the
middle generation). So the block's end first moves every tracked object into the oldest
generation, unwalked: ``gc.freeze()`` moves them all into the permanent generation and
``gc.unfreeze()`` moves that into the oldest one, two splices of the collector's lists. The
oldest generation is walked only by full passes, which still collect any cycle in it. Where
the process had frozen objects of its own (``gc.get_freeze_count() > 0``, e.g. a server before
it forks), nothing is moved, so that they stay frozen.
"""

from __future__ import annotations

import gc
from collections.abc import Iterator
from contextlib import contextmanager

__all__ = ["collector_paused"]


@contextmanager
def collector_paused(to_oldest: bool = True) -> Iterator[None]:
    """Hold off the cyclic collector for the block; it resumes, if it was on, when the block
    ends, also on an error, with the tracked objects first moved to its oldest generation
    (module docstring) unless ``to_oldest`` is false. What is computed is the same.

    Measured (``python benchmarks/bench_planning.py``, docs/performance.md): a ``--preset
    families`` run of 1,000 episodes on ``triangles-3f`` takes 16.2 s with the collector left
    alone, 4.7-5.2 s of it in full collections, and 11.3-12.3 s held off; the belief-space
    optimum over 4,000 starts of ``u-handle`` 5.2 s and 4.4 s. The move to the oldest
    generation (module docstring) then took off another 4-8% (0.92-0.96 of the time with the
    build's objects left young, 2026-12-07)."""
    was = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was:
            if to_oldest and gc.get_freeze_count() == 0:  # the build's objects to the oldest generation
                gc.freeze()
                gc.unfreeze()
            gc.enable()

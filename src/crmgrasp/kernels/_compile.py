"""How the compiled kernels are compiled: numba's ``njit``, cached on disk, in two forms.

* [`compiled`][]: a function that allocates nothing (it writes into arrays its caller
  made), compiled without numba's reference counting (``_nrt=False``). With counting,
  each call that hands an array to a callee increments and decrements the array's
  count atomically, several times per row; a function that owns no array gains
  nothing from them. numba refuses to compile an allocation (``np.empty``) in such a
  function, so the few functions that allocate keep plain ``njit(cache=True)``.
* [`inlined`][]: the same, and always inlined by LLVM into its callers
  (``forceinline``): the polygon kernel's per-rule helpers, which LLVM otherwise leaves
  as calls inside the per-row loops.

Neither changes a floating-point expression: no ``fastmath``, so LLVM neither
reassociates nor contracts, and each result equals the readable rules bit for bit (the
tests check every kernel). Measured on the 2-core development machine (``python
benchmarks/bench_env.py``; ``python benchmarks/step_breakdown.py``): the 1,024-env
vector env of ``paper-box`` from 7.8 M to 9.6-10.6 M env-steps per second (its compiled
pass over the 1,024 rows from 90 to 56 us); the first compilation of the polygon kernels took 4.1 s
against 4.2 s before (``python benchmarks/bench_compile.py``). numba's IR-level inlining
(``inline="always"``) was tried: the same speed, a slower first compilation.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, TypeVar

from numba import njit

__all__ = ["compiled", "inlined"]

F = TypeVar("F", bound=Callable[..., Any])
_UNCOUNTED: dict[str, Any] = {"cache": True, "_nrt": False}  # numba's flag for "no reference counting"


def compiled(fn: F) -> F:
    """``fn`` compiled as a loop that allocates nothing (see the module docstring)."""
    return njit(**_UNCOUNTED)(fn)  # type: ignore[no-any-return]


def inlined(fn: F) -> F:
    """``fn`` compiled as a helper LLVM inlines into its callers (see the module docstring)."""
    return njit(forceinline=True, **_UNCOUNTED)(fn)  # type: ignore[no-any-return]

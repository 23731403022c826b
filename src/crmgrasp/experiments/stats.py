"""Honest numbers: intervals over independent trials, and values written for reading.

A learner's score varies with its training seed; the variation that matters is
between trials, not between the episodes of one trial. So every interval of a
learned result is a bootstrap interval of the mean over per-trial values
([`bootstrap_ci`][], percentile method, 10,000 resamples, seeded), and the
interquartile mean ([`iqm`][], the mean of the middle 50%) is given beside the
mean. Text shows rounded numbers and ``never`` for a threshold not reached; CSV
and JSON files keep full precision and ``null``.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from crmgrasp._validation import CrmgraspError, finite, float_array, integer, seed_value, shown

__all__ = ["bootstrap_ci", "normal_ci", "iqm", "fmt", "never", "budget", "ci_text", "summary_lines", "MIN_TRIALS"]

MIN_TRIALS = 5
"""The fewest independent trials an interval over trials is given for: below it a bootstrap
of the mean has too few distinct resamples to mean anything, and no interval is reported."""


MAX_RESAMPLES = 10_000_000
"""The most bootstrap resamples an interval may ask for."""


def _values(values: Any) -> np.ndarray:
    """``values`` as a flat float array (one value per trial or episode), or a one-line error."""
    return float_array(values, "values").ravel()


def bootstrap_ci(values: Any, seed: int = 0, confidence: float = 0.95, resamples: int = 10_000) -> tuple[float, float]:
    """Percentile bootstrap interval of the mean of ``values`` (one value per trial);
    ``(nan, nan)``, no interval, for fewer than [`MIN_TRIALS`][] values; ``(v, v)``
    when all are equal.

    Examples
    --------
    >>> lo, hi = bootstrap_ci([1.0, 2.0, 3.0, 4.0, 5.0], seed=0)
    >>> 1.0 <= lo < 3.0 < hi <= 5.0
    True
    >>> bootstrap_ci([1.0, 2.0])
    (nan, nan)
    """
    x = _values(values)
    seed = seed_value(seed)
    confidence = finite(confidence, "confidence")
    if not 0.5 <= confidence < 1.0:
        raise CrmgraspError(f"confidence must be in [0.5, 1), got {confidence}")
    resamples = integer(resamples, "resamples", 100, MAX_RESAMPLES)
    if x.size < MIN_TRIALS or not np.all(np.isfinite(x)):
        return (math.nan, math.nan)
    if np.all(x == x[0]):
        return (float(x[0]), float(x[0]))
    from scipy.stats import bootstrap

    res = bootstrap(
        (x,),
        np.mean,
        confidence_level=confidence,
        n_resamples=resamples,
        method="percentile",
        random_state=np.random.default_rng(seed),
    )
    return float(res.confidence_interval.low), float(res.confidence_interval.high)


def normal_ci(values: Any) -> tuple[float, float, float]:
    """Mean and normal 95% interval ``mean +- 1.96 sd / sqrt(n)`` of ``values``: for a
    fixed policy, whose only variation is between its episodes (0 width for one value).

    Examples
    --------
    >>> normal_ci([1.0, 2.0, 3.0])[0]
    2.0
    """
    x = _values(values)
    if x.size == 0:
        raise CrmgraspError("a normal interval needs at least one value, got none")
    m = float(x.mean())
    half = 1.96 * float(x.std(ddof=1)) / math.sqrt(x.size) if x.size > 1 else 0.0
    return m, m - half, m + half


def ci_text(lo: float, hi: float, over: str = "trials") -> str:
    """An interval for reading: ``95% CI over trials 1.623-1.711``, or why none is given.

    >>> ci_text(1.6234, 1.7111), ci_text(float("nan"), float("nan"))
    ('95% CI over trials 1.623-1.711', 'no interval: fewer than 5 trials')
    """
    ends = float_array((lo, hi), "an interval's ends")
    if ends.shape != (2,):
        raise CrmgraspError(f"an interval's ends must be two numbers, got {shown((lo, hi))}")
    lo, hi = float(ends[0]), float(ends[1])
    if not (math.isfinite(lo) and math.isfinite(hi)):
        return f"no interval: fewer than {MIN_TRIALS} {over}"
    return f"95% CI over {over} {fmt(lo)}-{fmt(hi)}"


def summary_lines(summary: dict[str, Any], indent: int = 2, skip: tuple[str, ...] = ("seconds",)) -> list[str]:
    """A result's summary for the console: ``key: value`` per line, numbers rounded
    ([`fmt`][]; ``None`` is ``none``), nested tables indented under their key, lists of
    numbers inline (the first 8); files keep full precision.

    >>> summary_lines({"mean": 1.23456, "tasks": {"cup": {"ok": 4}}, "seconds": 2.0, "xs": [0.5, None]})
    ['  mean: 1.235', '  tasks:', '    cup:', '      ok: 4', '  xs: [0.500, none]']
    """

    def text(v: Any) -> str:
        return "none" if v is None else fmt(v)

    pad, out = " " * indent, []
    for key, value in summary.items():
        if key in skip:
            continue
        if isinstance(value, dict):
            out += [f"{pad}{key}:", *summary_lines(value, indent + 2, ())]
        elif isinstance(value, (list, tuple)) and any(isinstance(v, dict) for v in value):
            out.append(f"{pad}{key}:")
            for i, item in enumerate(value):
                out += summary_lines(item if isinstance(item, dict) else {str(i): item}, indent + 2, ())
        elif isinstance(value, (list, tuple)) and all(isinstance(v, str) for v in value):
            out.append(f"{pad}{key}: {', '.join(value)}")
        elif isinstance(value, (list, tuple)) and all(isinstance(v, (int, float)) or v is None for v in value):
            more = f", ... ({len(value)} in all)" if len(value) > 8 else ""
            out.append(f"{pad}{key}: [{', '.join(text(v) for v in value[:8])}{more}]")
        else:
            out.append(f"{pad}{key}: {text(value)}")
    return out


def iqm(values: Any) -> float:
    """Interquartile mean: the mean of the middle 50% of ``values``.

    Examples
    --------
    >>> iqm([0.0, 1.0, 2.0, 3.0, 100.0, -100.0, 1.5, 2.5])
    1.75
    """
    from scipy.stats import trim_mean

    x = _values(values)
    return float(trim_mean(x, 0.25)) if x.size else math.nan


def never(value: Any) -> str:
    """``"never"`` for a threshold not reached (``None``), else the value as text."""
    return "never" if value is None else fmt(value)


def fmt(value: Any, digits: int = 3) -> str:
    """A number for reading: ``digits`` decimals with trailing zeros kept (floats),
    thousands separators (integers), ``never`` for ``None``, ``n/a`` for NaN.

    Examples
    --------
    >>> fmt(2.3636363636363638), fmt(1049), fmt(None), fmt(float("nan")), fmt("text")
    ('2.364', '1,049', 'never', 'n/a', 'text')
    """
    if value is None:
        return "never"
    if isinstance(value, bool):
        return str(value)
    if isinstance(value, (int, np.integer)):
        return f"{int(value):,}"
    if isinstance(value, (float, np.floating)):
        return "n/a" if not math.isfinite(value) else f"{float(value):.{digits}f}"
    return str(value)


def budget(trials: int, episodes: int, seed: int | None = None) -> str:
    """``"20 trials x 2,000 episodes, seed 0"`` (singular for one trial)."""
    text = f"{trials:,} trial{'s' if trials != 1 else ''} x {episodes:,} episodes"
    return text if seed is None else f"{text}, seed {seed}"

"""Descriptive statistics with 95 % intervals, all from :mod:`scipy.stats`.

One function, :func:`describe`, aggregates a sample the way every summary of the
project does (the bench summary, :func:`rrtdrive.evaluation.summarise` and the
experiments): ``n``, mean, sample standard deviation, minimum, median, maximum and
a 95 % confidence interval of the mean. The interval depends on what the values
are (:class:`Interval`):

* rates (booleans as 0/1): Wilson's score interval
  (``scipy.stats.binomtest(k, n).proportion_ci(method="wilson")``);
* signed numbers: Student's t (``scipy.stats.t.interval``);
* non-negative quantities (times, lengths, node counts, errors): a percentile
  bootstrap of the mean (``scipy.stats.bootstrap``, 1999 resamples, fixed seed),
  which lies within the sample's range and so never goes below zero.

It lives outside :mod:`rrtdrive.bench` so the evaluators can use it without
importing the bench (which registers the OMPL planners on import).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from enum import Enum
from types import ModuleType

import numpy as np

from rrtdrive.types import InputError

__all__ = ["Interval", "Stat", "describe", "wilson_interval", "BOOTSTRAP_SEED"]

#: Seed and resample count of the bootstrap: the same sample always gets the same interval.
#: 1999 resamples (not scipy's default 9999): a bench summary bootstraps every metric of
#: every group, and the Monte-Carlo error at 1999 is small next to that of 5-30 seeds.
BOOTSTRAP_SEED = 0
BOOTSTRAP_RESAMPLES = 1999
CONFIDENCE = 0.95


def _scipy_stats() -> ModuleType:
    # Imported on first use: scipy.stats takes 0.5 s to import, and every CLI command,
    # bench worker and script imports this module through the evaluation package.
    import scipy.stats

    return scipy.stats


class Interval(str, Enum):  # noqa: UP042 (a StrEnum would change str() of a member)
    """Which 95 % interval of the mean :func:`describe` computes."""

    T = "t"
    WILSON = "wilson"
    BOOTSTRAP = "bootstrap"


@dataclass(frozen=True)
class Stat:
    """Summary of one metric over a group.

    Attributes
    ----------
    n : int
        Number of values (``None`` skipped).
    mean, std : float
        Mean and sample standard deviation (NaN for ``n < 2``).
    ci_low, ci_high : float
        95 % confidence interval of the mean (see ``interval``); NaN for ``n < 2``
        unless a rate.
    rate : bool
        The metric is boolean (mean = rate).
    min, median, max : float
        Order statistics of the sample (NaN when empty).
    interval : Interval
        How ``ci_low`` and ``ci_high`` were computed.
    """

    n: int
    mean: float
    std: float
    ci_low: float
    ci_high: float
    rate: bool
    min: float = math.nan
    median: float = math.nan
    max: float = math.nan
    interval: Interval = Interval.T


def wilson_interval(successes: float, n: int) -> tuple[float, float]:
    """95 % Wilson score interval of a rate (``scipy.stats.binomtest``).

    Parameters
    ----------
    successes : float
        Number of successes (a whole number).
    n : int
        Number of trials.

    Returns
    -------
    (float, float)
        Lower and upper bound; NaN for ``n == 0``.

    Examples
    --------
    >>> lo, hi = wilson_interval(10, 10)
    >>> round(lo, 3), hi
    (0.722, 1.0)
    """
    if n == 0:
        return (math.nan, math.nan)
    k = round(successes)
    if abs(k - successes) > 1e-9 or not 0 <= k <= n:
        raise InputError(f"successes: must be a whole number in [0, {n}], got {successes!r}")
    ci = _scipy_stats().binomtest(int(k), int(n)).proportion_ci(
        confidence_level=CONFIDENCE, method="wilson"
    )
    return (float(ci.low), float(ci.high))


def _t_interval(x: np.ndarray, mean: float, std: float) -> tuple[float, float]:
    if std == 0.0:
        return (mean, mean)  # scipy would compute 0 * inf
    lo, hi = _scipy_stats().t.interval(
        CONFIDENCE, len(x) - 1, loc=mean, scale=std / math.sqrt(len(x))
    )
    return (float(lo), float(hi))


def _bootstrap_interval(x: np.ndarray) -> tuple[float, float]:
    if np.all(x == x[0]):
        # Every resample has the same mean: the interval is that point.
        return (float(x[0]), float(x[0]))
    kwargs = {
        "n_resamples": BOOTSTRAP_RESAMPLES,
        "confidence_level": CONFIDENCE,
        "method": "percentile",
        "vectorized": True,
    }
    rng = np.random.default_rng(BOOTSTRAP_SEED)
    try:
        res = _scipy_stats().bootstrap((x,), np.mean, rng=rng, **kwargs)
    except TypeError:  # scipy < 1.15 calls the generator random_state
        res = _scipy_stats().bootstrap((x,), np.mean, random_state=rng, **kwargs)
    ci = res.confidence_interval
    return (float(ci.low), float(ci.high))


def describe(values: Sequence[float], rate: bool = False, nonnegative: bool = False) -> Stat:
    """Mean, std, order statistics and 95 % CI of ``values``.

    Parameters
    ----------
    values : sequence of float
        The sample (``None`` is not allowed: drop it first).
    rate : bool
        The values are 0/1: the Wilson interval of the rate.
    nonnegative : bool
        The quantity cannot be negative (a time, a length, a count): a percentile
        bootstrap interval, which stays within ``[min, max]`` of the sample.
        Otherwise Student's t.

    Returns
    -------
    Stat

    Examples
    --------
    >>> s = describe([1.0, 2.0, 3.0])
    >>> s.mean, s.std, round(s.ci_low, 3), round(s.ci_high, 3)
    (2.0, 1.0, -0.484, 4.484)
    >>> b = describe([1.0, 2.0, 3.0], nonnegative=True)
    >>> b.interval.value, b.ci_low >= 1.0
    ('bootstrap', True)
    """
    x = np.asarray(values, dtype=float).reshape(-1)
    n = len(x)
    method = Interval.WILSON if rate else Interval.BOOTSTRAP if nonnegative else Interval.T
    if n == 0:
        return Stat(0, math.nan, math.nan, math.nan, math.nan, rate, interval=method)
    mean = float(x.mean())
    std = float(x.std(ddof=1)) if n > 1 else math.nan
    if rate:
        lo, hi = wilson_interval(float(x.sum()), n)
    elif n < 2:
        lo = hi = math.nan
    elif nonnegative:
        lo, hi = _bootstrap_interval(x)
    else:
        lo, hi = _t_interval(x, mean, std)
    return Stat(
        n, mean, std, lo, hi, rate,
        min=float(np.min(x)), median=float(np.median(x)), max=float(np.max(x)),
        interval=method,
    )

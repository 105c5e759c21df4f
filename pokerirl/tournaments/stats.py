"""Estimates and tests for tournament results: mean, standard error, 95% CI, t-test, and the
Bonferroni and Holm corrections for many tests at once.

A sample is a 1-D array of independent units in milli-big-blinds per hand (mbb/h): duplicate
pairs' means within a seed, single hands without duplicate, or per-seed means for the pooled
test.

>>> e = estimate(np.array([100.0, 300.0, 200.0, 400.0]))
>>> e.mbb_per_hand, round(e.std_error, 3), e.n
(250.0, 64.55, 4)
>>> holm([0.01, 0.04, 0.03]).round(3).tolist(), bonferroni([0.01, 0.5]).tolist()
([0.03, 0.06, 0.06], [0.02, 1.0])
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from pokerirl.errors import ConfigError

CONFIDENCE = 0.95


@dataclass(frozen=True, kw_only=True)
class Estimate:
    """Mean mbb/h of ``n`` independent units, its standard error, 95% CI and the two-sided
    one-sample t-test of "mean = 0" (``n - 1`` degrees of freedom)."""

    mbb_per_hand: float
    std_error: float
    ci95: tuple[float, float]
    p_value: float
    n: int


def estimate(units_mbb: np.ndarray) -> Estimate:
    """The estimate of a sample of independent units in mbb/h (at least two).

    The CI and p-value come from ``scipy.stats.ttest_1samp``. When every unit is equal the
    t statistic is 0/0 or x/0, where scipy gives NaN or 0: here a sample of zeros has p = 1
    (nothing to tell it from no difference; a deterministic agent against itself in duplicate
    mode) and a constant non-zero sample has p = 0, both with a zero-width CI.

    >>> e = estimate(np.zeros(10))
    >>> e.mbb_per_hand, e.std_error, e.ci95, e.p_value
    (0.0, 0.0, (0.0, 0.0), 1.0)
    """
    units = np.asarray(units_mbb, dtype=np.float64)
    if units.ndim != 1 or units.size < 2:
        raise ConfigError(f"need at least two independent units, got {units.size}")
    mean = float(units.mean())
    if np.all(units == units[0]):
        p_value = 1.0 if mean == 0.0 else 0.0
        return Estimate(
            mbb_per_hand=mean, std_error=0.0, ci95=(mean, mean), p_value=p_value, n=units.size
        )
    from scipy import stats  # a second to import: ``pokerirl report`` reads estimates only

    std_error = float(units.std(ddof=1)) / math.sqrt(units.size)
    test = stats.ttest_1samp(units, 0.0)
    ci = test.confidence_interval(confidence_level=CONFIDENCE)
    return Estimate(
        mbb_per_hand=mean,
        std_error=std_error,
        ci95=(float(ci.low), float(ci.high)),
        p_value=float(test.pvalue),
        n=units.size,
    )


def bonferroni(p_values: Sequence[float] | np.ndarray) -> np.ndarray:
    """Bonferroni-adjusted p-values: ``min(1, m p)`` for a family of ``m`` tests."""
    p = np.asarray(p_values, dtype=np.float64)
    return np.minimum(1.0, p * p.size)


def holm(p_values: Sequence[float] | np.ndarray) -> np.ndarray:
    """Holm's step-down adjusted p-values, in the input order.

    The i-th smallest p (from 1) is multiplied by ``m - i + 1``, then a running maximum keeps
    the adjusted values in the order of the raw ones, capped at 1.

    >>> holm([0.04, 0.01]).tolist()
    [0.04, 0.02]
    """
    p = np.asarray(p_values, dtype=np.float64)
    order = np.argsort(p, kind="stable")
    scaled = p[order] * (p.size - np.arange(p.size))
    adjusted = np.empty_like(p)
    adjusted[order] = np.minimum(1.0, np.maximum.accumulate(scaled))
    return adjusted

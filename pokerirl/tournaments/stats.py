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


def t_estimate(mean: float, std_error: float, *, df: float, n: int) -> Estimate:
    """The two-sided t-test of "mean = 0" and the 95% CI for a mean whose standard error and
    degrees of freedom were estimated elsewhere (:func:`across_agents`). A zero standard error
    follows :func:`estimate`: p = 1 at a zero mean, else 0, with a zero-width CI."""
    if std_error == 0.0:
        return Estimate(mbb_per_hand=mean, std_error=0.0, ci95=(mean, mean),
                        p_value=1.0 if mean == 0.0 else 0.0, n=n)  # fmt: skip
    from scipy import stats

    half = float(stats.t.ppf(0.5 + CONFIDENCE / 2, df)) * std_error
    p_value = float(2.0 * stats.t.sf(abs(mean) / std_error, df))
    return Estimate(mbb_per_hand=mean, std_error=std_error, ci95=(mean - half, mean + half),
                    p_value=p_value, n=n)  # fmt: skip


@dataclass(frozen=True, kw_only=True)
class AcrossAgents:
    """The test across training seeds of a table of agent pairs (:func:`across_agents`).

    ``estimate``: the mean over the pairs, its standard error (never below ``deal_std_error``),
    CI and t-test with ``df`` degrees of freedom; ``n`` is the number of pairs.
    ``between_std_error``: the standard error estimated from the spread between the pairs'
    means alone; ``deal_std_error``: the one the deals' noise alone gives (each pair's own
    standard errors, as if the agents were the only ones that could have been trained).
    ``crossed``: the pairs fill an A x B table (every A agent met every B agent), tested with
    the two-way random-effects model; else they were taken as independent pairs.
    """

    estimate: Estimate
    df: float
    between_std_error: float
    deal_std_error: float
    crossed: bool


def across_agents(means: np.ndarray, deal_variances: np.ndarray) -> AcrossAgents:
    """The mean of a table of agent pairs and its test across training seeds.

    ``means[i, j]``: A's mbb/h when A's agent i met B's agent j (NaN: they did not meet);
    ``deal_variances[i, j]``: the squared standard error of that mean from its deals alone.

    * Independent pairs (one side has a single agent, or every agent is in one pair only,
      as when an agent set's seed k meets the other set's seed k): the one-sample t-test over
      the pairs' means, ``df = pairs - 1``.
    * A full table (``a x b`` agents, both at least 2, every pair played): pairs sharing an
      agent are not independent, so the variance of the grand mean is the two-way
      random-effects (method of moments) one, ``(MS_A + MS_B - MS_AB) / (a b)``, which carries
      each side's spread between its training seeds; ``df`` by Satterthwaite.
    * Any other table (agents met some but not all of the other side's) is taken as
      independent pairs.

    The variance is never taken below the deals' own (``sum(deal_variances) / pairs^2``): the
    spread between training seeds adds to the deals' noise, so an estimate under it is
    sampling error (a variance component truncated at 0). When that floor is what is used,
    ``df`` is the smaller side's agents (or the pairs) less one, the conservative choice.

    >>> table = np.array([[10.0, 30.0], [50.0, 70.0]])
    >>> found = across_agents(table, np.full((2, 2), 1.0))
    >>> found.estimate.mbb_per_hand, found.crossed, round(found.between_std_error, 3)
    (40.0, True, 22.361)
    >>> paired = across_agents(np.array([[1.0, np.nan], [np.nan, 3.0]]), np.full((2, 2), 4.0))
    >>> paired.estimate.std_error, paired.df, paired.crossed  # the deals' floor: sqrt(8)/2 > 1
    (1.4142135623730951, 1.0, False)
    """
    means = np.asarray(means, dtype=np.float64)
    deal_variances = np.asarray(deal_variances, dtype=np.float64)
    played = ~np.isnan(means)
    pairs = int(played.sum())
    if means.ndim != 2 or pairs < 2:
        raise ConfigError(f"need at least two agent pairs, got {pairs}")
    rows, cols = means.shape
    values = means[played]
    mean = float(values.mean())
    deal_variance = float(deal_variances[played].sum()) / pairs**2
    crossed = bool(played.all()) and rows >= 2 and cols >= 2
    if crossed:
        row_means, col_means = means.mean(axis=1), means.mean(axis=0)
        ms_a = cols * float(((row_means - mean) ** 2).sum()) / (rows - 1)
        ms_b = rows * float(((col_means - mean) ** 2).sum()) / (cols - 1)
        residual = means - row_means[:, None] - col_means[None, :] + mean
        ms_ab = float((residual**2).sum()) / ((rows - 1) * (cols - 1))
        between = (ms_a + ms_b - ms_ab) / pairs
        spread = ms_a**2 / (rows - 1) + ms_b**2 / (cols - 1) + ms_ab**2 / ((rows - 1) * (cols - 1))
        satterthwaite = (between * pairs) ** 2 / spread if spread > 0 else float(rows - 1)
        floor_df = float(min(rows, cols) - 1)
    else:
        between = float(values.var(ddof=1)) / pairs
        satterthwaite = floor_df = float(pairs - 1)
    between = max(between, 0.0)
    floored = between < deal_variance
    variance = deal_variance if floored else between
    df = floor_df if floored else max(satterthwaite, 1.0)
    return AcrossAgents(
        estimate=t_estimate(mean, math.sqrt(variance), df=df, n=pairs),
        df=df,
        between_std_error=math.sqrt(between),
        deal_std_error=math.sqrt(deal_variance),
        crossed=crossed,
    )

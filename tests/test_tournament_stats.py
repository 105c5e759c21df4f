"""Tournament statistics against scipy and closed forms; Bonferroni and Holm on known lists."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from scipy import stats

from pokerirl.tournaments import bonferroni, estimate, format_seeds, holm, parse_seeds

p_lists = st.lists(st.floats(min_value=0.0, max_value=1.0), min_size=1, max_size=30)


def test_estimate_matches_closed_form_for_two_degrees_of_freedom() -> None:
    # [2, 4, 6]: mean 4, sd 2, SE 2/sqrt(3), t = 2 sqrt(3). With df = 2 the t CDF is
    # 1/2 + t / (2 sqrt(2 + t^2)), so p = 1 - t / sqrt(2 + t^2) and the 97.5% quantile is
    # (2q - 1) / sqrt(2q(1 - q)) at q = 0.975.
    e = estimate(np.array([2.0, 4.0, 6.0]))
    t = 2 * math.sqrt(3)
    q = (2 * 0.975 - 1) / math.sqrt(2 * 0.975 * 0.025)
    assert e.n == 3
    assert e.mbb_per_hand == pytest.approx(4.0, abs=1e-12)
    assert e.std_error == pytest.approx(2 / math.sqrt(3), rel=1e-12)
    assert e.p_value == pytest.approx(1 - t / math.sqrt(2 + t * t), rel=1e-9)
    assert e.ci95 == pytest.approx((4 - q * 2 / math.sqrt(3), 4 + q * 2 / math.sqrt(3)), rel=1e-9)


@pytest.mark.parametrize("n", [2, 5, 40, 5_000])
def test_estimate_matches_scipy_and_the_t_distribution(n: int) -> None:
    units = np.random.default_rng(n).normal(loc=30.0, scale=400.0, size=n)
    e = estimate(units)
    reference = stats.ttest_1samp(units, 0.0)
    se = units.std(ddof=1) / math.sqrt(n)
    t = units.mean() / se
    assert e.mbb_per_hand == pytest.approx(units.mean(), rel=1e-12)
    assert e.std_error == pytest.approx(se, rel=1e-12)
    assert e.p_value == pytest.approx(reference.pvalue, rel=1e-9)
    assert e.p_value == pytest.approx(2 * stats.t.sf(abs(t), n - 1), rel=1e-9)
    half = stats.t.ppf(0.975, n - 1) * se
    assert e.ci95 == pytest.approx((units.mean() - half, units.mean() + half), rel=1e-9)


def test_equal_units_have_zero_error_and_a_defined_p_value() -> None:
    zeros, sevens = estimate(np.zeros(100)), estimate(np.full(10, 7.0))
    assert (zeros.std_error, zeros.ci95, zeros.p_value) == (0.0, (0.0, 0.0), 1.0)
    assert (sevens.mbb_per_hand, sevens.ci95, sevens.p_value) == (7.0, (7.0, 7.0), 0.0)


def test_fewer_than_two_units_are_refused() -> None:
    with pytest.raises(ValueError, match="two independent units"):
        estimate(np.array([1.0]))


def test_bonferroni_and_holm_on_known_lists() -> None:
    p = [0.01, 0.04, 0.03, 0.005]
    assert bonferroni(p).tolist() == pytest.approx([0.04, 0.16, 0.12, 0.02])
    # sorted: 0.005 x 4 = 0.02, 0.01 x 3 = 0.03, 0.03 x 2 = 0.06, 0.04 x 1 = 0.04 -> max 0.06
    assert holm(p).tolist() == pytest.approx([0.03, 0.06, 0.06, 0.02])
    assert holm([0.01, 0.02, 0.03, 0.04, 0.05]).tolist() == pytest.approx(
        [0.05, 0.08, 0.09, 0.09, 0.09]
    )
    assert bonferroni([0.3, 0.5]).tolist() == [0.6, 1.0]  # capped at 1
    assert holm([0.3, 0.6, 0.9]).tolist() == pytest.approx([0.9, 1.0, 1.0])


def _holm_rejections(p: list[float], alpha: float) -> set[int]:
    """Holm's step-down procedure as written in textbooks: reject the smallest p-values
    while p_(k) <= alpha / (m - k + 1), stop at the first that fails."""
    rejected: set[int] = set()
    for k, i in enumerate(sorted(range(len(p)), key=lambda i: p[i])):
        if p[i] > alpha / (len(p) - k):
            break
        rejected.add(i)
    return rejected


@given(p_lists, st.sampled_from([0.01, 0.05, 0.1]))
def test_holm_adjusted_values_reproduce_the_step_down_procedure(
    p: list[float], alpha: float
) -> None:
    adjusted = holm(p)
    assert {i for i, q in enumerate(adjusted) if q <= alpha} == _holm_rejections(p, alpha)
    assert (adjusted >= np.array(p)).all() and (adjusted <= bonferroni(p)).all()


@given(p_lists, st.randoms(use_true_random=False))
def test_holm_does_not_depend_on_the_order(p: list[float], random: object) -> None:
    order = list(range(len(p)))
    random.shuffle(order)  # type: ignore[attr-defined]
    np.testing.assert_array_equal(holm([p[i] for i in order]), holm(p)[order])


def test_seed_ranges() -> None:
    assert parse_seeds("0-19") == tuple(range(20))
    assert parse_seeds("4, 1-2 ,2") == (1, 2, 4)
    for bad in ("5-3", "", "-1", "a-b", "1-"):
        with pytest.raises(ValueError):
            parse_seeds(bad)


@given(st.sets(st.integers(min_value=0, max_value=200), min_size=1))
def test_format_seeds_inverts_parse_seeds(seeds: set[int]) -> None:
    assert parse_seeds(format_seeds(sorted(seeds))) == tuple(sorted(seeds))

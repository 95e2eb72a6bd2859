"""Restarts of a bounded fit and intervals that cover optima the noise cannot tell apart
(``identification.optima``), on small least-squares problems with known optima."""

from __future__ import annotations

import numpy as np
import pytest

import reference as ref
from pneumact.identification.estimates import covariance_from_jacobian
from pneumact.identification.optima import (
    CHI2_95_1DOF,
    restarted_least_squares,
    spread_starts,
    widen_for_optima,
)


def _two_roots(theta: np.ndarray) -> np.ndarray:
    """(θ + 1)·(θ − 2): optima at −1 (beyond the lower bound 0, where a start below ½
    ends) and at 2 (inside)."""
    return np.array([(theta[0] + 1.0) * (theta[0] - 2.0)])


def test_spread_starts_are_the_prior_and_each_parameter_moved_both_ways():
    starts = spread_starts(np.array([2.0, 10.0]), spread=0.5)
    assert [s.tolist() for s in starts] == [[2.0, 10.0], [1.5, 10.0], [2.5, 10.0],
                                            [2.0, 7.5], [2.0, 12.5]]


def test_a_fit_that_ends_at_a_bound_starts_again_from_the_prior():
    start = np.array([ref.OPTIMA_BOUND_START])
    out = restarted_least_squares(_two_roots, start, np.array([0.0]), np.array([5.0]),
                                  np.array([ref.OPTIMA_PRIOR]), ["theta"])
    assert out.solutions[0].active_mask[0] == -1  # the first ended at the lower bound
    assert len(out.solutions) == 1 + 3  # then the prior and two spread starts
    assert out.ok and out.reason == ""
    assert out.best.x[0] == pytest.approx(ref.OPTIMA_INSIDE, abs=ref.OPTIMA_ATOL)


def test_a_fit_stuck_at_its_bound_from_every_start_says_so():
    out = restarted_least_squares(lambda q: q, np.array([3.0]), np.array([1.0]),
                                  np.array([5.0]), np.array([3.0]), ["theta"])
    assert not out.ok
    assert out.reason == "theta stuck at its bound 1 after 4 starts"


def _plus_minus_one():
    """r_i = (θ²·x_i − y_i)/σ, y = x + noise: θ = +1 and −1 fit equally well."""
    rng = np.random.default_rng(0)
    x = np.linspace(0.5, 1.5, ref.OPTIMA_SAMPLES)
    y = x + rng.normal(0.0, ref.OPTIMA_NOISE, x.size)

    def residuals(theta):
        return (theta[0] ** 2 * x - y) / ref.OPTIMA_NOISE

    return residuals


def test_two_optima_within_the_noise_widen_the_interval_to_cover_both():
    residuals = _plus_minus_one()
    lower, upper = np.array([-3.0]), np.array([3.0])
    plus = restarted_least_squares(residuals, np.array([0.5]), lower, upper,
                                   np.array([0.5]), ["theta"])
    minus = restarted_least_squares(residuals, np.array([-0.5]), lower, upper,
                                    np.array([-0.5]), ["theta"])
    assert plus.best.x[0] == pytest.approx(1.0, abs=0.01)
    assert minus.best.x[0] == pytest.approx(-1.0, abs=0.01)
    cov, _ = covariance_from_jacobian(plus.best.jac, plus.best.fun, 1, correlated=False)
    half = 1.96 * np.sqrt(np.diag(cov))
    assert half[0] < 0.01  # alone, a tight interval about +1 that misses −1
    widened, which = widen_for_optima(plus.best.x, half, plus.best.cost,
                                      [(minus.best.x, minus.best.cost)])
    assert which.tolist() == [True]
    distance = plus.best.x[0] - minus.best.x[0]
    assert widened[0] == pytest.approx(distance + half[0])  # both optima and their noise


@pytest.mark.parametrize("delta_chi2, widens", [(0.99 * CHI2_95_1DOF, True),
                                                (1.01 * CHI2_95_1DOF, False)])
def test_only_an_optimum_within_the_noise_widens(delta_chi2, widens):
    """A second optimum 1.0 away from the best, its scaled cost just below or above the
    95 % χ² threshold; a third inside the interval never widens it."""
    half = np.array([0.1, 0.1])
    others = [(np.array([1.0, 0.0]), 0.5 * delta_chi2), (np.array([0.05, 0.0]), 0.0)]
    widened, which = widen_for_optima(np.zeros(2), half, 0.0, others)
    assert which.tolist() == [widens, False]
    assert widened[0] == pytest.approx(1.1 if widens else 0.1)
    assert widened[1] == pytest.approx(0.1)

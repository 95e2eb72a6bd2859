"""The test that says two laws "cannot be told apart" (validation.compare): equally good
predictions are called different about as often as the 5 % level says, even when the
errors are correlated in time as a dense record's are; a better one is found."""

from __future__ import annotations

import numpy as np
from scipy.signal import lfilter

import reference as ref
from pneumact.validation.compare import NOISE_Z, loss_differential_z


def _errors(rng, phi: float, n: int = 2000) -> np.ndarray:
    return lfilter([1.0], [1.0, -phi], rng.normal(size=n))


def _alarm_rate(phi: float) -> tuple[float, float]:
    """(share of seeds where the HAC test, and a test that takes the samples as
    independent, calls one of two equally good predictions better)."""
    hac = naive = 0
    for seed in range(ref.COMPARE_ALARM_SEEDS):
        rng = np.random.default_rng(seed)
        a, b = _errors(rng, phi), _errors(rng, phi)
        hac += abs(loss_differential_z([a], [b])) > NOISE_Z
        d = a**2 - b**2
        naive += abs(d.mean() / (d.std() / np.sqrt(d.size))) > NOISE_Z
    return hac / ref.COMPARE_ALARM_SEEDS, naive / ref.COMPARE_ALARM_SEEDS


def test_equal_predictions_with_white_errors_are_rarely_told_apart():
    hac, _ = _alarm_rate(0.0)
    assert hac <= ref.COMPARE_FALSE_ALARM_WHITE


def test_correlated_errors_do_not_make_a_winner_as_independent_samples_would():
    hac, naive = _alarm_rate(ref.COMPARE_AR_PHI)
    assert hac <= ref.COMPARE_FALSE_ALARM_AR
    assert naive > 2 * ref.COMPARE_FALSE_ALARM_AR  # why the long-run variance is needed


def test_a_better_prediction_is_found_and_the_sign_says_which():
    rng = np.random.default_rng(1)
    errors = [_errors(rng, 0.5) for _ in range(2)]
    worse = [1.2 * e for e in errors]
    assert loss_differential_z(errors, worse) < -NOISE_Z
    assert loss_differential_z(worse, errors) > NOISE_Z
    assert loss_differential_z(errors, errors) == 0.0

"""Two rounds of identification combined per parameter (issue 38,
``identification.combine``), on constructed identifications (no simulation): rounds that
agree give the inverse-variance weighted mean, rounds that disagree refuse the parameter
with the reason, a value from one round is carried with its interval and its round, and
the combined covariance keeps each round's correlations."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import reference as ref
from pneumact.errors import DataError, ParameterError
from pneumact.identification import PaperIdentification, combine_rounds
from pneumact.identification.combine import CONSISTENCY_Z, read_round
from pneumact.identification.diagnostics import IDENTIFIED, NOT_IDENTIFIABLE, POORLY, Verdict
from pneumact.identification.estimates import Estimates
from pneumact.io import Record

NAMES = ("F0", "k", "Fc")
UNITS = ("N", "N/m", "N")


def identification(values, stderr, verdicts, correlation=0.0, shown=NAMES, record="a"):
    """A constructed round: ``values`` and ``stderr`` of F0, k, Fc (F0 and k correlated by
    ``correlation``), its ``verdicts`` (one word per parameter) and the parameters whose
    interval it reports (``shown``)."""
    from conftest import load_quietly

    stderr = np.asarray(stderr, float)
    cov = np.diag(stderr**2)
    if correlation:
        cov[0, 1] = cov[1, 0] = correlation * stderr[0] * stderr[1]
    estimates = Estimates(NAMES, np.asarray(values, float), stderr, cov, 1000, UNITS)
    judged = [Verdict(n, v, f"{v} in this round", "" if v == IDENTIFIED else "a test")
              for n, v in zip(NAMES, verdicts, strict=True)]
    prior = load_quietly("vgt-paper")
    t = np.linspace(0.0, 1.0, 11)
    records = [Record.from_arrays(t, {"pressure": 1e5 + 0 * t, "position": 0 * t},
                                  source=f"ramp_{record}.csv")]
    return PaperIdentification({}, None, estimates, judged, [], pd.DataFrame(),
                               prior.replace(dict(zip(NAMES, values, strict=True))), prior,
                               records,
                               extra={"no_interval": [n for n in NAMES if n not in shown]})


def test_agreeing_rounds_give_the_inverse_variance_weighted_mean():
    first = identification([30.0, 12000.0, 2.50], [0.03, 60.0, 0.02], [IDENTIFIED] * 3)
    second = identification([30.02, 12050.0, 2.52], [0.01, 20.0, 0.04], [IDENTIFIED] * 3,
                            record="b")
    combined = combine_rounds(first, second)
    table = combined.to_pandas()
    w = 0.01**2 / (0.01**2 + 0.03**2)  # round 1's weight on F0
    assert table.loc["F0", "value"] == pytest.approx(w * 30.0 + (1 - w) * 30.02,
                                                     rel=ref.FRICTION_RTOL)
    assert table.loc["F0", "stderr"] == pytest.approx(
        1 / np.sqrt(1 / 0.03**2 + 1 / 0.01**2), rel=ref.FRICTION_RTOL)
    assert (table["round"] == "1+2").all() and (table["verdict"] == IDENTIFIED).all()
    assert combined.ok and "rounds 1 and 2 (weighted mean)" in combined.summary()
    assert "rounds 1 and 2: weighted mean" in combined.parameters.info["k"].source


def test_disagreeing_rounds_are_refused_with_the_reason():
    apart = (CONSISTENCY_Z + 0.5) * np.hypot(0.02, 0.02)  # beyond the consistency test
    first = identification([30.0, 12000.0, 2.50], [0.03, 60.0, 0.02], [IDENTIFIED] * 3)
    second = identification([30.0, 12000.0, 2.50 + apart], [0.03, 60.0, 0.02],
                            [IDENTIFIED] * 3, record="b")
    combined = combine_rounds(first, second)
    table = combined.to_pandas()
    assert table.loc["Fc", "verdict"] == POORLY
    assert "the rounds disagree" in table.loc["Fc", "reason"]
    # not a tight interval about a mean: one that covers both rounds' intervals
    assert table.loc["Fc", "ci95_low"] == pytest.approx(2.50 - 1.96 * 0.02, rel=1e-3)
    assert table.loc["Fc", "ci95_high"] == pytest.approx(2.50 + apart + 1.96 * 0.02,
                                                         rel=1e-3)
    assert "rounds 1 and 2 (disagree): Fc" in combined.summary()
    assert table.loc["F0", "verdict"] == IDENTIFIED  # the others still combine
    assert not combined.ok
    with pytest.raises(ParameterError, match="not checked"):
        _ = combined.parameters
    assert "prior" in combined.parameter_set(partial=True).info["Fc"].source


def test_a_value_from_one_round_is_carried_with_its_interval_and_round():
    first = identification([30.0, 12000.0, 2.50], [0.03, 60.0, 0.02], [IDENTIFIED] * 3)
    second = identification([31.0, 12500.0, 2.9], [np.inf, np.inf, 0.5],
                            [NOT_IDENTIFIABLE, NOT_IDENTIFIABLE, POORLY], shown=("Fc",),
                            record="b")
    table = combine_rounds(first, second).to_pandas()
    assert table.loc["F0", "round"] == "1" and table.loc["k", "round"] == "1"
    assert table.loc["F0", "value"] == 30.0 and table.loc["F0", "verdict"] == IDENTIFIED
    assert table.loc["F0", "ci95_high"] == pytest.approx(30.0 + 1.96 * 0.03, rel=1e-3)
    assert table.loc["F0", "reason"].startswith("round 1:")
    # Fc: poorly identified in round 2 (±39 %), identified in round 1: both combine
    assert table.loc["Fc", "round"] == "1+2" and table.loc["Fc", "verdict"] == IDENTIFIED


def test_refused_in_both_keeps_the_better_verdict_and_its_remedy():
    first = identification([30.0, 12000.0, 2.5], [0.03, 60.0, 0.02],
                           [POORLY, NOT_IDENTIFIABLE, IDENTIFIED], shown=("Fc",))
    second = identification([30.0, 12000.0, 2.5], [0.03, 60.0, 0.02],
                            [NOT_IDENTIFIABLE, POORLY, IDENTIFIED], shown=("Fc",),
                            record="b")
    combined = combine_rounds(first, second)
    table = combined.to_pandas()
    assert table.loc["F0", ["verdict", "round"]].tolist() == [POORLY, "1"]
    assert table.loc["k", ["verdict", "round"]].tolist() == [POORLY, "2"]
    assert combined.verdicts_table().loc["k", "remedy"] == "a test"


def test_the_combined_covariance_keeps_each_rounds_correlation():
    """cov(F0, k) = w_F0·w_k·C1 + (1 − w_F0)(1 − w_k)·C2: the rounds are independent."""
    first = identification([30.0, 12000.0, 2.5], [0.03, 60.0, 0.02], [IDENTIFIED] * 3,
                           correlation=-0.9)
    second = identification([30.0, 12000.0, 2.5], [0.01, 20.0, 0.02], [IDENTIFIED] * 3,
                            correlation=0.5, record="b")
    combined = combine_rounds(first, second)
    w0, wk = 0.01**2 / (0.01**2 + 0.03**2), 20.0**2 / (20.0**2 + 60.0**2)
    expected = w0 * wk * (-0.9 * 0.03 * 60.0) + (1 - w0) * (1 - wk) * (0.5 * 0.01 * 20.0)
    assert combined.estimates.covariance[0, 1] == pytest.approx(expected,
                                                                rel=ref.FRICTION_RTOL)


def test_a_folder_round_trip_and_shared_records_are_refused(tmp_path):
    first = identification([30.0, 12000.0, 2.5], [0.03, 60.0, 0.02], [IDENTIFIED] * 3,
                           correlation=-0.9)
    second = identification([30.01, 12010.0, 2.51], [0.01, 20.0, 0.02], [IDENTIFIED] * 3,
                            record="b")
    first.write(tmp_path / "round1")
    from_folder = combine_rounds(read_round(tmp_path / "round1"), second)
    in_memory = combine_rounds(first, second)
    np.testing.assert_allclose(from_folder.estimates.covariance,
                               in_memory.estimates.covariance, rtol=1e-12)
    with pytest.raises(DataError, match=r"estimates\.csv"):
        read_round(tmp_path / "nowhere")
    with pytest.raises(ParameterError, match="independent records"):
        combine_rounds(first, first)


def test_the_table_alone_combines_as_the_result_does():
    """``combined_table`` (two rounds' tables, no identification result) and
    ``combine_rounds`` give one combination."""
    from pneumact.identification.combine import combined_table, round_estimates

    first = identification([30.0, 12000.0, 2.5], [0.03, 60.0, 0.02], [IDENTIFIED] * 3,
                           correlation=-0.9)
    second = identification([30.01, 12010.0, 2.6], [0.01, 20.0, 0.02], [IDENTIFIED] * 3,
                            record="b")
    alone = combined_table(round_estimates(first, 1), round_estimates(second, 2))
    result = combine_rounds(first, second).to_pandas()
    for column in ("value", "ci95_low", "ci95_high"):
        np.testing.assert_allclose(alone[column], result.loc[alone.index, column],
                                   rtol=1e-6)
    assert (alone["verdict"] == result.loc[alone.index, "verdict"]).all()

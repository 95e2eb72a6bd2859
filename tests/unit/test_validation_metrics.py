"""Validation metrics and loop measures against hand-computed answers."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import reference as ref
from pneumact.errors import DataError
from pneumact.validation import autocorrelation, error_metrics, loop_measures, reversals


def test_metrics_of_a_small_prediction_by_hand():
    m = error_metrics([1.0, 2.0, 3.0, 4.0], [1.0, 2.0, 3.0, 5.0])
    assert m["rms"] == pytest.approx(0.5)  # √(1/4)
    assert m["max"] == pytest.approx(1.0)
    assert m["nrmse"] == pytest.approx(1 / np.sqrt(5.0))  # ‖e‖ = 1, ‖y − ȳ‖ = √5
    assert m["fit_percent"] == pytest.approx(100 * (1 - 1 / np.sqrt(5.0)))
    assert m["r2"] == pytest.approx(0.8)
    assert m["n"] == 4


def test_fit_of_a_perfect_and_of_a_mean_only_prediction():
    y = np.array([0.3, -1.0, 2.5, 0.7, 1.1])
    perfect = error_metrics(y, y)
    assert (perfect["fit_percent"], perfect["r2"], perfect["rms"]) == (100.0, 1.0, 0.0)
    mean_only = error_metrics(y, np.full_like(y, y.mean()))
    assert mean_only["fit_percent"] == pytest.approx(0.0, abs=1e-12)
    assert mean_only["r2"] == pytest.approx(0.0, abs=1e-12)


def test_metrics_refuse_mismatched_or_broken_signals():
    with pytest.raises(DataError, match="3 measured samples but 2 predicted"):
        error_metrics([1, 2, 3], [1, 2], "position")
    with pytest.raises(DataError, match="predicted value nan at sample 1"):
        error_metrics([1, 2, 3], [1, np.nan, 3])


def test_autocorrelation_by_hand():
    acf, band = autocorrelation([1.0, -1.0, 1.0, -1.0], max_lag=2)
    assert acf == pytest.approx([1.0, -0.75, 0.5])  # Σ e_t e_{t+k} / Σ e_t²
    assert band == pytest.approx(1.96 / 2)


def _parallelogram(n=8001):
    """Pressure 100 → 20 → 100 kPa; position of a spring with Coulomb friction."""
    p0, w, c = ref.PARALLELOGRAM_CENTRE, ref.PARALLELOGRAM_WIDTH, ref.PARALLELOGRAM_SLOPE
    down = np.linspace(100e3, 20e3, n)
    up = np.linspace(20e3, 100e3, n)[1:]
    x_down = np.maximum(0.0, c * (p0 - w / 2 - down))
    x_up = np.minimum(x_down[-1], np.maximum(0.0, c * (p0 + w / 2 - up)))
    pressure = np.concatenate([down, up])
    position = np.concatenate([x_down, x_up])
    return np.linspace(0.0, 20.0, pressure.size), pressure, position


def test_loop_measures_of_an_analytic_parallelogram():
    w, c = ref.PARALLELOGRAM_WIDTH, ref.PARALLELOGRAM_SLOPE
    t, p, x = _parallelogram()
    stroke = c * (ref.PARALLELOGRAM_CENTRE - w / 2 - 20e3)
    m = loop_measures(t, p, x)
    assert m["stroke"] == pytest.approx(stroke, rel=ref.LOOP_RTOL)
    assert m["loop_width_pressure"] == pytest.approx(w, rel=ref.LOOP_RTOL)
    assert m["loop_width_position"] == pytest.approx(c * w, rel=ref.LOOP_RTOL)
    assert m["loop_area"] == pytest.approx(w * stroke, rel=ref.LOOP_RTOL)
    # the falling branch's sliding line leaves x = 0 at p0 − w/2
    assert m["breakaway_pressure"] == pytest.approx(ref.PARALLELOGRAM_CENTRE - w / 2,
                                                    rel=ref.LOOP_RTOL)
    turns = reversals(t, p, x)
    assert turns["turn"].tolist() == ["minimum"]
    assert turns["pressure"].iloc[0] == pytest.approx(20e3)
    assert turns["position"].iloc[0] == pytest.approx(stroke)


def test_read_only_signals_reach_the_compiled_features_writeable(monkeypatch):
    """A Record's signals are read-only; numba compiles the features once more for each
    mix of read-only and writeable arguments (~3 s each): the loop measures and the
    reversals hand them writeable arrays, and measure the same loop."""
    from pneumact.validation import loops

    t, p, x = _parallelogram()
    frozen = [a.copy() for a in (t, p, x)]
    for a in frozen:
        a.setflags(write=False)
    seen = []

    def spy(wrapped):
        def call(*signals):
            seen.extend(a.flags.writeable for a in signals)
            return wrapped(*signals)
        return call

    monkeypatch.setattr(loops, "hysteresis_summary", spy(loops.hysteresis_summary))
    monkeypatch.setattr(loops, "turning_points", spy(loops.turning_points))
    assert loop_measures(*frozen) == loop_measures(t, p, x)
    pd.testing.assert_frame_equal(reversals(*frozen), reversals(t, p, x))
    assert len(seen) == 12 and all(seen)

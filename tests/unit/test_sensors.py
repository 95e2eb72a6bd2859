"""The bench's sensors (models/sensors.py): a first-order lag exact against its analytic
answer, its derivative against differences, offsets and quantisation, the catalogue
entries, and a fit that frees a lag."""

from __future__ import annotations

import numpy as np
import pytest

import reference as ref
from pneumact.errors import ParameterError
from pneumact.models.sensors import SENSOR_PARAMETERS, Sensors, first_order_lag, lag_derivative
from pneumact.parameters import catalogue

pytestmark = pytest.mark.unit


def _ramp_seen_through_a_lag(time, speed, tau):
    """A ramp v·t read by a first-order sensor settled at t = 0: v·(t − τ(1 − e^(−t/τ)))."""
    return speed * (time - tau * (1.0 - np.exp(-time / tau)))


@pytest.mark.parametrize("uniform", [True, False])
def test_a_lagged_ramp_is_the_analytic_answer(uniform):
    time = np.linspace(0.0, 0.1, 401)
    if not uniform:
        time = np.sort(np.concatenate([time, time[:-1] + 1e-4]))
    lagged = first_order_lag(time, 0.02 * time, ref.SENSOR_TEST_LAG)
    exact = _ramp_seen_through_a_lag(time, 0.02, ref.SENSOR_TEST_LAG)
    np.testing.assert_allclose(lagged, exact, rtol=0, atol=ref.SENSOR_LAG_ATOL)


def test_no_lag_is_the_signal_and_columns_lag_alone():
    time = np.linspace(0.0, 1.0, 501)
    signal = np.column_stack([np.sin(7 * time), 3 * np.sin(7 * time) + (time > 0.5)])
    np.testing.assert_array_equal(first_order_lag(time, signal, 0.0), signal)
    both = first_order_lag(time, signal, ref.SENSOR_TEST_LAG)
    one = first_order_lag(time, signal[:, 1], ref.SENSOR_TEST_LAG)
    np.testing.assert_allclose(both[:, 1], one, rtol=1e-12, atol=1e-15)
    assert both[0, 1] == signal[0, 1]  # settled at the first sample


def test_the_lag_derivative_is_the_difference_quotient():
    time = np.linspace(0.0, 0.5, 1001)
    signal = np.sin(40 * time) + (time > 0.2)
    tau = ref.SENSOR_TEST_LAG
    step = 1e-3 * tau
    difference = (first_order_lag(time, signal, tau + step)
                  - first_order_lag(time, signal, tau - step)) / (2 * step)
    np.testing.assert_allclose(lag_derivative(time, signal, tau), difference,
                               rtol=ref.SENSOR_DERIVATIVE_RTOL, atol=1e-9)
    # at τ = 0 the lag delays by τ: ∂/∂τ = −dy/dt (the slope of the last sample step,
    # along which the signal is linear)
    smooth = np.sin(40 * time)
    slope = np.diff(smooth) / np.diff(time)
    at_zero = lag_derivative(time, smooth, 0.0)
    np.testing.assert_allclose(at_zero[1:], -slope, rtol=1e-3, atol=1e-3)


def test_sensors_read_offsets_lags_and_resolution_from_a_parameter_set():
    sensors = Sensors.from_params({"position_offset": 1e-4, "position_lag": 2e-3,
                                   "position_resolution": 1e-5, "pressure_offset": 500.0,
                                   "k": 1e4})
    assert not sensors.ideal and sensors.lag("position") == 2e-3
    assert Sensors.from_params({}).ideal
    time = np.linspace(0.0, 0.1, 201)
    read = sensors.measure(time, "position", 0.01 * time)
    np.testing.assert_allclose(read / 1e-5, np.round(read / 1e-5), atol=1e-9)
    exact = _ramp_seen_through_a_lag(time, 0.01, 2e-3) + 1e-4
    assert np.max(np.abs(read - exact)) <= 0.5e-5 + 1e-12
    np.testing.assert_allclose(sensors.measure(time, "pressure", np.full(201, 1e5)),
                               1e5 + 500.0)


def test_impossible_sensors_are_refused_by_name():
    with pytest.raises(ParameterError, match=r"position_lag = -0\.001"):
        Sensors(position_lag=-1e-3)
    with pytest.raises(ParameterError, match="sample_rate"):
        Sensors(sample_rate=0.0)


def test_each_sensor_parameter_has_its_catalogue_entry():
    units = {"position_offset": "m", "pressure_offset": "Pa", "position_lag": "s",
             "pressure_lag": "s", "position_resolution": "m", "sample_rate": "Hz"}
    assert set(SENSOR_PARAMETERS) == set(units)
    for name, unit in units.items():
        spec = catalogue()[name]
        assert spec.unit == unit and spec.group == "sensors" and spec.default is None


class _HeldStill:
    """A fit of one level to a position held still on a quantised sensor (what
    ``faults.quantisation_covariance`` reads of a ``FitResult``)."""

    signals = ("position",)

    def __init__(self, level: float, samples: int):
        self.level, self.samples = level, samples
        self.jacobian = np.ones((samples, 1))

    def masks(self):
        return [np.ones(self.samples, bool)]

    def fitted(self, i, signal):
        return np.full(self.samples, self.level)

    def weight(self, i, signal):
        return 1.0


def test_a_held_position_rounds_by_one_error_not_by_white_noise():
    """Held still, every sample rounds by the same error, uniform over a step: the level
    moves by it, variance q²/12, where white noise of that size would average to
    q²/(12·n) over the n samples (the known answer of the quantisation covariance)."""
    from pneumact.identification.faults import quantisation_covariance

    step = ref.BENCH_RESOLUTION
    covariance = quantisation_covariance(_HeldStill(3.3e-3, 500), {0: step},
                                         draws=ref.QUANTISATION_TEST_DRAWS)
    assert covariance.item() == pytest.approx(step**2 / 12, rel=ref.QUANTISATION_TEST_RTOL)

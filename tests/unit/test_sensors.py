"""The bench's sensors (models/sensors.py): a first-order lag exact against its analytic
answer, its derivative against differences, offsets and quantisation, the catalogue
entries, and a fit that frees a lag."""

from __future__ import annotations

import numpy as np
import pytest

import pneumact as pa
import reference as ref
from conftest import load_quietly
from pneumact.errors import ParameterError
from pneumact.models.cylinder import CYLINDER_SENSORS
from pneumact.models.sensors import (
    DEFAULT_SENSORS,
    SENSOR_PARAMETERS,
    Sensors,
    first_order_lag,
    lag_derivative,
    sensor_names,
)
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


#: an instance parameter of the cylinder's sensors, and the default sensor's entry it takes
#: its unit and ranges from
INSTANCE_ENTRIES = {"sensor_position.offset": "position_offset",
                    "sensor_position.lag": "position_lag",
                    "sensor_position.resolution": "position_resolution",
                    "sensor_pressure_a.offset": "pressure_offset",
                    "sensor_pressure_a.lag": "pressure_lag",
                    "sensor_pressure_b.offset": "pressure_offset",
                    "sensor_pressure_b.lag": "pressure_lag"}


def test_a_sensor_instance_s_parameter_has_its_kind_s_catalogue_entry():
    """The cylinder's sensors, one per measured signal: sensor_<signal>.offset, .lag (and
    the position's .resolution), each with the unit and ranges of the default sensor of
    its signal's quantity, the instance named in its description."""
    specs = catalogue()
    assert {n for names in CYLINDER_SENSORS.values() for n in names if n} == set(
        INSTANCE_ENTRIES)
    for name, default in INSTANCE_ENTRIES.items():
        spec, kind = specs[name], specs[default]
        assert (spec.unit, spec.minimum, spec.strict_minimum, spec.maximum, spec.plausible,
                spec.group) == (kind.unit, kind.minimum, kind.strict_minimum, kind.maximum,
                                kind.plausible, kind.group), name
        assert spec.description.startswith(kind.description)
        assert name.split(".")[0].removeprefix("sensor_") in spec.description
    assert "sensor_pressure_a.resolution" not in specs  # a pressure sensor has none
    # the single-chamber actuator keeps its names: its default instances
    assert sensor_names(pa.Actuator(load_quietly("vgt-paper"))) is DEFAULT_SENSORS
    assert sensor_names(pa.Cylinder(load_quietly("iso15552-32"))) is CYLINDER_SENSORS


def test_a_model_s_sensor_instances_read_their_own_parameters():
    """Each pressure sensor of the cylinder lags and offsets its own signal; the default
    names are not its sensors'."""
    sensors = Sensors.from_params({"sensor_pressure_a.lag": 2e-3,
                                   "sensor_pressure_b.offset": 300.0,
                                   "sensor_position.resolution": 1e-5, "sample_rate": 1e3,
                                   "chamber_a.V_dead": 1e-5}, CYLINDER_SENSORS)
    assert not sensors.ideal and sensors.sample_rate == 1e3
    assert (sensors.lag("pressure_a"), sensors.lag("pressure_b")) == (2e-3, 0.0)
    time = np.linspace(0.0, 0.1, 201)
    ramp = 2e5 + 1e6 * time
    np.testing.assert_allclose(sensors.measure(time, "pressure_a", ramp),
                               _ramp_seen_through_a_lag(time, 1e6, 2e-3) + 2e5,
                               rtol=1e-12)
    np.testing.assert_allclose(sensors.measure(time, "pressure_b", ramp), ramp + 300.0)
    read = sensors.measure(time, "position", 0.01 * time)
    np.testing.assert_allclose(read / 1e-5, np.round(read / 1e-5), atol=1e-9)
    assert Sensors.from_params({}, CYLINDER_SENSORS).ideal


@pytest.mark.parametrize(("params", "names", "refused"), [
    ({"sensor_pressure_c.lag": 1e-3}, CYLINDER_SENSORS, "'sensor_pressure_c.lag' is"),
    ({"position_lag": 1e-3}, CYLINDER_SENSORS, "'position_lag' is"),
    ({"sensor_pressure_a.lag": 1e-3}, None, "'sensor_pressure_a.lag' is"),
])
def test_a_sensor_parameter_of_no_sensor_of_the_model_is_refused_naming_the_allowed(
        params, names, refused):
    allowed = ", ".join(n for sensor in (names or DEFAULT_SENSORS).values()
                        for n in sensor if n)
    with pytest.raises(ParameterError) as error:
        Sensors.from_params(params, names)
    assert f"{refused} no sensor parameter of this model; its sensors' parameters: " \
           f"{allowed}, sample_rate" in str(error.value)


def test_an_impossible_instance_lag_is_refused_by_its_name():
    with pytest.raises(ParameterError, match=r"sensor_pressure_b\.lag = -0\.001"):
        Sensors.from_params({"sensor_pressure_b.lag": -1e-3}, CYLINDER_SENSORS)


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

"""The cylinder's sensors as instances of the sensor component (issue 41, item 1): a
record of the default 5/3 cylinder seen through a lagging sensor on chamber A's pressure
(``sensor_pressure_a.lag``) and a stated lag on chamber B's is fitted back to A's lag,
B's held as stated; a lag of no sensor of the cylinder is refused naming the allowed ones.
The experiment is test_cylinder_instances.py's (one compiled kernel for both)."""

from __future__ import annotations

import numpy as np
import pytest

import pneumact as pa
import reference as ref
from conftest import load_quietly
from pneumact.experiments import Experiment, PiecewiseLinear
from pneumact.models.sensors import Sensors

pytestmark = pytest.mark.integration

#: held retracted, the spool opened to 0.3 over 50 ms: chamber A fills, the piston extends
EXPERIMENT = Experiment(PiecewiseLinear([0.0, 0.05, 0.1, 0.3], [-1.0, -1.0, 0.3, 0.3]),
                        "spool", 0.3, n_points=301)
HELD = {"sensor_pressure_b.lag": ref.CYLINDER_SENSOR_HELD_LAG}


@pytest.fixture(scope="module")
def bench():
    """The cylinder (B's sensor lag stated in its set) and its record: the run's signals
    seen through the true sensors (A's lag too)."""
    cylinder = pa.Cylinder(load_quietly("iso15552-32").with_values(HELD))
    run = pa.simulate(cylinder, EXPERIMENT)
    truth = Sensors.from_params({**HELD, "sensor_pressure_a.lag": ref.CYLINDER_SENSOR_LAG},
                                cylinder.sensor_names)
    signals = {s: truth.measure(run.time, s, run[s])
               for s in ("position", "pressure_a", "pressure_b")}
    record = pa.Record.from_arrays(run.time, {**signals, "spool": run["spool"]},
                                   {"position": "m", "pressure_a": "Pa", "pressure_b": "Pa",
                                    "spool": "1"}, "lagged pressure A")
    return cylinder, run, record


def test_a_fit_finds_a_pressure_sensor_s_lag_and_holds_the_stated_one(bench):
    cylinder, run, record = bench
    # the record is what the sensors made of the run: A's and B's pressures lag it
    assert np.max(np.abs(record["pressure_a"] - run["pressure_a"])) > 1e3
    assert np.max(np.abs(record["pressure_b"] - run["pressure_b"])) > 1e3
    result = pa.fit(cylinder, record, ["sensor_pressure_a.lag"],
                    start={"sensor_pressure_a.lag": ref.CYLINDER_SENSOR_LAG / 3},
                    signals=["pressure_a", "pressure_b"], smooth_input=False)
    assert result.values["sensor_pressure_a.lag"] == pytest.approx(
        ref.CYLINDER_SENSOR_LAG, rel=ref.CYLINDER_SENSOR_LAG_RTOL)
    assert result.estimates.units == ("s",)
    assert result.sensor_lags[0]["pressure_b"] == ref.CYLINDER_SENSOR_HELD_LAG
    # the held lag is applied: B's fitted signal is the record's (to the solvers' error)
    np.testing.assert_allclose(result.fitted(0, "pressure_b"), record["pressure_b"],
                               rtol=ref.CYLINDER_SENSOR_SIGNAL_RTOL)


@pytest.mark.parametrize("name", ["sensor_pressure_c.lag", "position_lag"])
def test_a_lag_of_no_sensor_of_the_cylinder_is_refused_naming_the_allowed(bench, name):
    cylinder, _, record = bench
    with pytest.raises(pa.ParameterError, match=rf"free = \['{name}'\]: no sensor lag of "
                                                r"Cylinder.*sensor_position.lag, "
                                                r"sensor_pressure_a.lag, sensor_pressure_b.lag"):
        pa.fit(cylinder, record, [name], signals=["pressure_a"])

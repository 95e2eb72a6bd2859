"""Properties over many inputs (hypothesis): any parameter set that validation accepts
simulates without an exception, with its bounded states inside their bounds; any value
at the boundary is either accepted or refused with a pneumact error; a record written and
read back is the same record, and one bad cell in it is refused as a DataError.

Examples are derandomised (the same on every run) and few: each runs one short cycle on
a kernel compiled once, so the whole file costs seconds.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import pneumact as pa
from pneumact.errors import (
    DataError,
    ParameterError,
    PassivityWarning,
    PlausibilityWarning,
    PneumactError,
)
from pneumact.parameters import catalogue
from reference import (
    BOUND_REL_TOL,
    PROPERTY_EXAMPLES,
    PROPERTY_SIM_EXAMPLES,
    STOP_PENETRATION_TOL,
)

SETTINGS = dict(derandomize=True, database=None, deadline=None,
                suppress_health_check=[HealthCheck.too_slow])


def quietly(call):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PassivityWarning)
        warnings.simplefilter("ignore", PlausibilityWarning)
        return call()


def _factor(low: float = 0.2, high: float = 5.0):
    """A log-uniform factor on a value of vgt-paper."""
    return st.floats(math.log(low), math.log(high)).map(math.exp)


@st.composite
def actuators(draw):
    """Parameter sets around real diaphragm actuators: each value of vgt-paper scaled by
    a factor in [0.2, 5], the Stribeck exponent 1 or 2, friction possibly absent."""
    base = quietly(lambda: pa.load_params("vgt-paper"))
    scaled = {name: base[name] * draw(_factor()) for name in
              ("m", "F0", "k", "sigma0", "sigma1", "sigma2", "vs", "A_res", "A_atm")}
    fc = 0.0 if draw(st.booleans()) and draw(st.booleans()) else base["Fc"] * draw(_factor())
    fs = fc * draw(st.floats(1.0, 2.0))
    scaled.update(Fc=fc, Fs=fs, delta=draw(st.sampled_from([1.0, 2.0])))
    return scaled


def _accepted(values):
    """The set, or None when validation refuses it (then only with a ParameterError)."""
    base = quietly(lambda: pa.load_params("vgt-paper"))
    try:
        return quietly(lambda: base.replace(values))
    except ParameterError:
        return None


@settings(max_examples=PROPERTY_SIM_EXAMPLES, **SETTINGS)
@given(values=actuators(), valve=st.sampled_from(["source", "command"]))
def test_any_accepted_set_simulates_with_bounded_states(values, valve):
    params = _accepted(values)
    if params is None:
        return
    actuator = pa.Actuator(params, valve=pa.PressureSource() if valve == "source"
                           else pa.CommandValve())
    experiment = (pa.PressureCycle(period=2.0, n_points=101) if valve == "source"
                  else pa.CommandCycle(period=2.0, n_points=101))
    result = pa.simulate(actuator, experiment)
    states = [result[n] for n in ("position", "velocity", "bristle", "pressure")]
    assert all(np.all(np.isfinite(s)) for s in states)
    bound = max(params["Fs"], params["Fc"]) / params["sigma0"]
    assert np.max(np.abs(result["bristle"])) <= bound * (1 + BOUND_REL_TOL)
    x = result["position"]
    assert x.min() >= -STOP_PENETRATION_TOL and x.max() <= params["x_max"] + STOP_PENETRATION_TOL
    if valve == "command":  # the chamber stays between the reservoir and the atmosphere
        p = result["pressure"]
        assert p.min() >= params["p_res"] * (1 - BOUND_REL_TOL)
        assert p.max() <= params["p_atm"] * (1 + BOUND_REL_TOL)


NAMES = ("m", "k", "Fc", "Fs", "sigma0", "vs", "p_atm", "x_max", "V0", "delta", "gamma")
ANY_FLOAT = st.one_of(st.floats(allow_nan=True, allow_infinity=True),
                      st.sampled_from([0.0, -1.0, 1e-300, 1e300, 100.0]))


@settings(max_examples=PROPERTY_EXAMPLES, **SETTINGS)
@given(name=st.sampled_from(NAMES), value=ANY_FLOAT)
def test_any_value_is_accepted_or_refused_as_a_parameter_error(name, value):
    base = quietly(lambda: pa.load_params("vgt-paper"))
    try:
        params = quietly(lambda: base.replace({name: value}))
    except ParameterError as exc:
        assert name in str(exc)
        return
    assert math.isfinite(params[name])
    assert catalogue()[name].in_range(params[name])


@settings(max_examples=PROPERTY_EXAMPLES, **SETTINGS)
@given(high=ANY_FLOAT, low=ANY_FLOAT, period=ANY_FLOAT)
def test_any_pressure_cycle_is_built_or_refused(high, low, period):
    try:
        experiment = pa.PressureCycle(high=high, low=low, period=period, n_points=11)
    except PneumactError:
        return
    assert 0 < low < high <= 10e6 and 0 < period < math.inf
    assert experiment.t_end == period


@st.composite
def records(draw):
    """Time from >= 0, strictly increasing; absolute pressures of a vacuum actuator;
    positions within a stroke."""
    n = draw(st.integers(2, 30))
    steps = draw(st.lists(st.floats(1e-4, 1.0), min_size=n - 1, max_size=n - 1))
    time = np.concatenate([[draw(st.floats(0.0, 10.0))], steps]).cumsum()
    pressure = draw(st.lists(st.floats(5e3, 2e5), min_size=n, max_size=n))
    position = draw(st.lists(st.floats(0.0, 0.02), min_size=n, max_size=n))
    return time, np.array(pressure), np.array(position)


@settings(max_examples=PROPERTY_EXAMPLES, **SETTINGS)
@given(data=records(), bad=st.sampled_from(["nan", "", "abc", "-5", "1e12"]),
       where=st.floats(0.0, 1.0))
def test_record_round_trip_and_one_bad_cell(tmp_path_factory, data, bad, where):
    folder = tmp_path_factory.mktemp("records")
    time, pressure, position = data
    record = pa.Record.from_arrays(time, {"pressure": pressure, "position": position})
    path = record.save(folder / "r.csv", {"pressure": "kPa", "position": "mm"})
    back = pa.read_record(path)
    np.testing.assert_allclose(back.time, time, rtol=1e-12)
    np.testing.assert_allclose(back["pressure"], pressure, rtol=1e-12)
    np.testing.assert_allclose(back["position"], position, rtol=1e-12, atol=1e-18)
    lines = path.read_text(encoding="utf-8").splitlines()
    row = 1 + min(int(where * (len(lines) - 1)), len(lines) - 2)
    cells = lines[row].split(",")
    cells[1] = bad  # the pressure [kPa] cell: -5 kPa and 1e12 kPa are impossible
    lines[row] = ",".join(cells)
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    with pytest.raises(DataError, match="pressure"):
        pa.read_record(path)

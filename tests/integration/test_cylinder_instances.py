"""The cylinder's chambers as two instances of one chamber component (issue 41, item 1):
their parameters, ``chamber_a.V_dead`` and ``chamber_b.V_dead``, addressed by name in a
batch, forward sensitivities, a fit, a sensitivity study and the FMU's model description.
The two dead volumes differ, so that a chamber reading the other's block shows."""

from __future__ import annotations

import zipfile
from xml.etree import ElementTree

import numpy as np
import pandas as pd
import pytest

import pneumact as pa
import reference as ref
from conftest import load_quietly
from pneumact import sensitivity as sa
from pneumact.experiments import Experiment, PiecewiseLinear
from pneumact.parameters.catalogue import catalogue

DEAD = ("chamber_a.V_dead", "chamber_b.V_dead")
#: held retracted, the spool opened to 0.3 over 50 ms: chamber A fills, the piston extends
#: (to about 0.18 m in 0.3 s, short of the stop)
EXPERIMENT = Experiment(PiecewiseLinear([0.0, 0.05, 0.1, 0.3], [-1.0, -1.0, 0.3, 0.3]),
                        "spool", 0.3, n_points=301)
SIGNALS = ("position", "pressure_a", "pressure_b")


@pytest.fixture(scope="module")
def cylinder():
    params = load_quietly("iso15552-32")
    return pa.Cylinder(params.replace({"chamber_b.V_dead": 2.5 * params["chamber_a.V_dead"]}))


def test_a_batch_over_the_dead_volumes_equals_single_runs(cylinder):
    """Rows of chamber_a.V_dead and chamber_b.V_dead: each row's signals are those of a
    run of the set with those values, and the rows differ."""
    table = pd.DataFrame({"chamber_a.V_dead": [4e-6, 8e-6, 16e-6],
                          "chamber_b.V_dead": [30e-6, 20e-6, 5e-6]})
    batch = pa.simulate_batch(cylinder, EXPERIMENT, table, signals=list(SIGNALS),
                              t_eval=np.linspace(0.0, 0.3, 301), executor=1)
    assert list(batch.table["status"]) == ["ok"] * 3, batch.table["error"].tolist()
    for i, row in table.iterrows():
        run = pa.simulate(pa.Cylinder(cylinder.params.replace(row.to_dict())), EXPERIMENT,
                          t_eval=batch.time)
        for signal in SIGNALS:
            np.testing.assert_allclose(batch.signals[signal][i], run[signal],
                                       rtol=ref.BATCH_FEATURE_RTOL, err_msg=(i, signal))
    for signal in ("pressure_a", "pressure_b"):  # each chamber feels its own dead volume
        assert np.ptp(batch.signals[signal][:, -1]) > 1e3, signal


@pytest.mark.parametrize("name", DEAD)
def test_forward_sensitivity_to_a_dead_volume_matches_differences(name, cylinder):
    """∂(x, p_a, p_b)/∂ chamber's V_dead carried through the run against central
    differences of two runs given the value by name."""
    sens = pa.simulate_sensitivities(cylinder, EXPERIMENT, [name],
                                     pa.Rodas4(rtol=ref.SENS_RTOL))
    assert sens.units[name] == catalogue()[name].unit == "m^3"
    value = float(cylinder.params[name])
    step = ref.SENS_FD_REL_STEP * value
    tight = pa.Rodas4(rtol=ref.SENS_REFERENCE_RTOL)
    up, down = (pa.simulate(cylinder, EXPERIMENT, tight, values={name: value + s})
                for s in (step, -step))
    for signal in SIGNALS:
        difference = (up[signal] - down[signal]) / (2.0 * step)
        size = np.abs(difference).max()
        rms = np.sqrt(np.mean((sens[signal][:, 0] - difference) ** 2))
        assert size > 0.0 and rms <= ref.SENS_RMS_FRACTION * size, (name, signal, rms, size)


def test_a_fit_finds_a_chamber_s_dead_volume(cylinder):
    """Started 30 % off, the fit finds the chamber_a.V_dead (and Fc) that made its
    record."""
    run = pa.simulate(cylinder, EXPERIMENT)
    record = pa.Record.from_arrays(run.time, {"position": run["position"],
                                              "spool": run["spool"]},
                                   {"position": "m", "spool": "1"}, "nominal")
    truth = {name: float(cylinder.params[name]) for name in ("chamber_a.V_dead", "Fc")}
    result = pa.fit(cylinder, [record], list(truth),
                    start={name: 1.3 * value for name, value in truth.items()},
                    smooth_input=False)
    found = result.to_pandas()["value"]
    for name, value in truth.items():
        assert found[name] == pytest.approx(value, rel=ref.META_FIT_RTOL), name


def test_a_sensitivity_study_varies_a_dead_volume_by_name(cylinder):
    """Standardised regression coefficients of the travel in 0.3 s on ±5 % of
    chamber_a.V_dead and Fc: a larger dead volume fills more slowly, the piston travels
    less (as two runs at the ends say)."""
    problem = sa.Problem.around(cylinder.params, {"chamber_a.V_dead": 0.05, "Fc": 0.05})
    evaluate = sa.model_outputs(cylinder, EXPERIMENT, problem, ["travel"], executor=1)
    indices = sa.src(problem, evaluate, n=ref.META_SRC_N, seed=1).indices.set_index(
        "parameter")
    assert indices["R2"].iloc[0] >= ref.META_SRC_R2_MIN, indices
    value = float(cylinder.params["chamber_a.V_dead"])
    ends = pa.simulate_batch(cylinder, EXPERIMENT,
                             pd.DataFrame({"chamber_a.V_dead": [0.95 * value, 1.05 * value]}),
                             features=["travel"], executor=1).table["travel"]
    assert ends.iloc[1] < ends.iloc[0]
    assert indices.loc["chamber_a.V_dead", "SRC"] < 0


def test_the_fmu_exposes_each_chamber_s_dead_volume(cylinder, tmp_path):
    """The model description (sources only) has a tunable parameter per instance, named
    by FMI's structured convention, with the set's value and the kind's range and unit."""
    fmu = pa.export_fmu(cylinder, tmp_path / "cylinder.fmu", binary=False)
    assert set(DEAD) <= set(fmu.names("parameter"))
    with zipfile.ZipFile(fmu.path) as archive:
        root = ElementTree.fromstring(archive.read("modelDescription.xml"))
    assert root.get("variableNamingConvention") == "structured"
    variables = {v.get("name"): v for v in root.iter("ScalarVariable")}
    for name in DEAD:
        variable, spec = variables[name], catalogue()[name]
        real = variable.find("Real")
        assert variable.get("causality") == "parameter"
        assert float(real.get("start")) == pytest.approx(float(cylinder.params[name]))
        assert float(real.get("min")) == spec.minimum and float(real.get("max")) == spec.maximum
        assert real.get("unit") == spec.unit

"""A fit that frees a sensor's lag (issue 38, item 1): ramps of a drawn actuator seen
through a lagging position sensor; the lag is found with the viscous friction it
would otherwise pass for, and the fitted signal is the model seen through it."""

from __future__ import annotations

import numpy as np
import pytest

import pneumact as pa
import reference as ref
from pneumact.errors import ParameterError
from pneumact.identification import Noise, design_campaign, synthetic_campaign
from pneumact.identification.joint import bench_model
from pneumact.parameters.family import ActuatorFamily

pytestmark = pytest.mark.integration


@pytest.fixture(scope="module")
def lagged():
    truth = ActuatorFamily().draw(1, seed=ref.FAMILY_SEED)[0]
    ramps = [t for t in design_campaign(truth, ramps=3).tests if t.kind == "ramp"][-2:]
    records = synthetic_campaign(truth, ramps, noise=Noise(lag=ref.SENSOR_FIT_LAG),
                                 seed=ref.IDENT_SEED)
    return truth, records, [bench_model(r, truth) for r in records]


def test_a_fit_finds_the_lag_and_the_viscous_friction_together(lagged):
    truth, records, models = lagged
    result = pa.fit(models, records, ["position_lag", "sigma2"],
                    start={"position_lag": ref.SENSOR_FIT_LAG / 3,
                           "sigma2": truth["sigma2"]}, solver=pa.Rodas4(rtol=1e-8))
    values = result.values
    assert values["position_lag"] == pytest.approx(ref.SENSOR_FIT_LAG, rel=0.02)
    assert values["sigma2"] == pytest.approx(truth["sigma2"], rel=0.05)
    assert result.estimates.units[0] == "s"
    # the fitted signal is the model seen through the lag: residuals at the noise
    noise = Noise().position
    for i, record in enumerate(records):
        residual = result.fitted(i, "position") - record["position"]
        assert np.sqrt(np.mean(residual**2)) < ref.MISFIT_NOISE_RATIO * noise


def test_a_lag_is_one_for_every_record_and_needs_its_signal(lagged):
    _, records, models = lagged
    with pytest.raises(ParameterError, match="one for every record"):
        pa.fit(models, records, ["position_lag"], per_record=["position_lag"])
    with pytest.raises(ParameterError, match="pressure_lag"):
        pa.fit(models, records, ["pressure_lag"])

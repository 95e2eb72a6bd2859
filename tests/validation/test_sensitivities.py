"""Forward sensitivities integrated in the kernel agree with central finite differences
where the response is smooth (sliding without velocity reversal)."""

import warnings

import numpy as np
import pytest

import pneumact as pa
from pneumact.experiments import Experiment, Sine
from pneumact.simulation.sensitivity import simulate_sensitivities

pytestmark = pytest.mark.validation

# Tolerances for this file (one place).
SENS_RTOL = 1e-9  # tolerance of the run that carries the sensitivities
REFERENCE_RTOL = 1e-11  # tolerance of the finite-difference runs
FD_RELATIVE_STEP = 1e-5  # central-difference step, relative to the parameter value
MAX_RELATIVE_ERROR = 2e-3  # max |sens - fd| / max |fd| over the record
FRICTION_PARAMETERS = ["sigma1", "sigma2", "Fc", "Fs", "vs"]


@pytest.fixture(scope="module")
def canudas():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", pa.PassivityWarning)
        return pa.load_params("canudas1995")


def _velocity_experiment():
    # always sliding forwards: v = 3 ± 2 mm/s, so the response is smooth in θ
    return Experiment(Sine(0.002, 2.0, offset=0.003), "velocity", 2.0, n_points=401)


def test_rig_friction_sensitivities_match_central_differences(canudas):
    rig = pa.FrictionRig(canudas, drive="velocity")
    exp = _velocity_experiment()
    sens = simulate_sensitivities(rig, exp, FRICTION_PARAMETERS, pa.Rodas4(rtol=SENS_RTOL))
    tight = pa.Rodas4(rtol=REFERENCE_RTOL)
    for k, name in enumerate(FRICTION_PARAMETERS):
        value = canudas[name]
        step = FD_RELATIVE_STEP * value
        up = pa.simulate(pa.FrictionRig(canudas.replace({name: value + step}),
                                        drive="velocity"), exp, tight)
        down = pa.simulate(pa.FrictionRig(canudas.replace({name: value - step}),
                                          drive="velocity"), exp, tight)
        fd = (up["friction"] - down["friction"]) / (2 * step)
        err = np.max(np.abs(sens["friction"][:, k] - fd)) / np.max(np.abs(fd))
        assert err < MAX_RELATIVE_ERROR, f"{name}: relative error {err:.2e}"


def test_sensitivity_of_steady_friction_to_coulomb_level_is_one(canudas):
    # at high constant speed F = Fc + (Fs-Fc)·exp(-(v/vs)^2) + σ2·v → ∂F/∂Fc → 1
    rig = pa.FrictionRig(canudas, drive="velocity")
    exp = Experiment(pa.experiments.Constant(0.05), "velocity", 0.5, n_points=11)
    sens = simulate_sensitivities(rig, exp, ["Fc", "sigma2"], pa.Rodas4(rtol=1e-9))
    assert sens["friction"][-1, 0] == pytest.approx(1.0, rel=1e-5)
    assert sens["friction"][-1, 1] == pytest.approx(0.05, rel=1e-5)


def test_unknown_parameter_is_named(canudas):
    rig = pa.FrictionRig(canudas, drive="velocity")
    with pytest.raises(pa.ParameterError, match=r"sigma_0.*sigma0"):
        simulate_sensitivities(rig, _velocity_experiment(), ["sigma_0"])

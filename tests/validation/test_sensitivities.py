"""Forward sensitivities integrated in the kernel agree with converged central differences:
for every parameter of the valve-driven actuator over a command cycle (sticking, slips,
velocity reversals, the rest stop), on a friction rig sliding smoothly, and with known
closed-form values; the run that carries them is the plain run, step for step."""

import numpy as np
import pytest

import pneumact as pa
from pneumact.experiments import Experiment, Sine
from pneumact.simulation import assemble, simulate_sensitivities
from reference import (
    SENS_FD_REL_STEP,
    SENS_NOISE_FLOOR,
    SENS_REFERENCE_RTOL,
    SENS_RIG_FD_REL_STEP,
    SENS_RIG_MAX_ERROR,
    SENS_RMS_FRACTION,
    SENS_RTOL,
    SENS_STEADY_RTOL,
)

FRICTION_PARAMETERS = ["sigma1", "sigma2", "Fc", "Fs", "vs"]
CYCLE = pa.CommandCycle(period=4.0, n_points=801)


def _central_difference(make_model, params, name, experiment, signals,
                        rel_step=SENS_FD_REL_STEP):
    value = params[name]
    step = rel_step * abs(value)
    tight = pa.Rodas4(rtol=SENS_REFERENCE_RTOL)
    up = pa.simulate(make_model(params.replace({name: value + step})), experiment, tight)
    down = pa.simulate(make_model(params.replace({name: value - step})), experiment, tight)
    return {s: (up[s] - down[s]) / (2 * step) for s in signals}


def _assert_agrees(sens, fd, name, value, signal):
    """RMS error within SENS_RMS_FRACTION of the sensitivity's size, or below the noise
    of the central differences (a parameter that barely moves the signal)."""
    size = np.max(np.abs(fd[signal]))
    rms = np.sqrt(np.mean((sens[signal] - fd[signal]) ** 2))
    allowed = max(SENS_RMS_FRACTION * size, SENS_NOISE_FLOOR[signal] / abs(value))
    assert rms <= allowed, (f"∂{signal}/∂{name}: RMS error {rms:.3e} vs finite differences "
                            f"(largest |∂/∂θ| {size:.3e}, allowed {allowed:.3e})")


@pytest.fixture(scope="module")
def valve_cycle(vgt):
    model = pa.Actuator(vgt, valve=pa.CommandValve())
    names = list(assemble(model).parameter_names)
    return model, names, simulate_sensitivities(model, CYCLE, names,
                                                pa.Rodas4(rtol=SENS_RTOL))


def test_every_actuator_parameter_matches_central_differences(valve_cycle, vgt):
    _, names, sens = valve_cycle
    assert len(names) > 20  # mechanics, friction, chamber and valve: all of them

    def make(params):
        return pa.Actuator(params, valve=pa.CommandValve())

    for k, name in enumerate(names):
        fd = _central_difference(make, vgt, name, CYCLE, ("position", "pressure"))
        for signal in ("position", "pressure"):
            _assert_agrees({signal: sens[signal][:, k]}, fd, name, vgt[name], signal)


def test_the_sensitivity_run_is_the_plain_run(valve_cycle):
    model, _, sens = valve_cycle
    plain = pa.simulate(model, CYCLE, pa.Rodas4(rtol=SENS_RTOL))
    for name in plain.names:
        np.testing.assert_array_equal(sens.result[name], plain[name], err_msg=name)


def test_gamma_with_an_adiabatic_chamber(vgt):
    """γ moves the polytropic index as well as the orifice flows (it used to be missed)."""

    def make(params):
        return pa.Actuator(params, valve=pa.CommandValve(), chamber=pa.Adiabatic())

    sens = simulate_sensitivities(make(vgt), CYCLE, ["gamma"], pa.Rodas4(rtol=SENS_RTOL))
    fd = _central_difference(make, vgt, "gamma", CYCLE, ("pressure",))
    _assert_agrees({"pressure": sens["pressure"][:, 0]}, fd, "gamma", vgt["gamma"],
                   "pressure")


def _velocity_experiment():
    # always sliding forwards: v = 3 ± 2 mm/s, so the response is smooth in θ
    return Experiment(Sine(0.002, 2.0, offset=0.003), "velocity", 2.0, n_points=401)


def test_rig_friction_sensitivities_match_central_differences(canudas):
    def make(params):
        return pa.FrictionRig(params, drive="velocity")

    exp = _velocity_experiment()
    sens = simulate_sensitivities(make(canudas), exp, FRICTION_PARAMETERS,
                                  pa.Rodas4(rtol=SENS_RTOL))
    for k, name in enumerate(FRICTION_PARAMETERS):
        fd = _central_difference(make, canudas, name, exp, ("friction",),
                                 SENS_RIG_FD_REL_STEP)["friction"]
        err = np.max(np.abs(sens["friction"][:, k] - fd)) / np.max(np.abs(fd))
        assert err < SENS_RIG_MAX_ERROR, f"{name}: relative error {err:.2e}"


def test_sensitivity_of_steady_friction_to_coulomb_level_is_one(canudas):
    # at high constant speed F = Fc + (Fs-Fc)·exp(-(v/vs)^2) + σ2·v → ∂F/∂Fc → 1
    rig = pa.FrictionRig(canudas, drive="velocity")
    exp = Experiment(pa.experiments.Constant(0.05), "velocity", 0.5, n_points=11)
    sens = simulate_sensitivities(rig, exp, ["Fc", "sigma2"], pa.Rodas4(rtol=SENS_RTOL))
    assert sens["friction"][-1, 0] == pytest.approx(1.0, rel=SENS_STEADY_RTOL)
    assert sens["friction"][-1, 1] == pytest.approx(0.05, rel=SENS_STEADY_RTOL)


def test_unknown_or_foreign_parameter_is_named(canudas, vgt):
    rig = pa.FrictionRig(canudas, drive="velocity")
    with pytest.raises(pa.ParameterError, match=r"sigma_0.*sigma0"):
        simulate_sensitivities(rig, _velocity_experiment(), ["sigma_0"])
    with pytest.raises(pa.ParameterError, match=r"'V0' is not a parameter of FrictionRig"):
        simulate_sensitivities(rig, _velocity_experiment(), ["V0"])

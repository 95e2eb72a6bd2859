"""Closed loops against linear theory, and the linearised actuator against its nonlinear
model:

(a) a continuous PID on a mass-damper (friction off) equals python-control's closed loop;
(b) the sampled PID (zero-order hold, forward-Euler integrator) converges to the
    continuous one at first order in the sample time;
(c) the presliding linearisation of the command-valve actuator predicts the nonlinear
    model's sine-sweep gain at a small amplitude, and fails at a large one.
"""

from __future__ import annotations

import numpy as np
import pytest

import pneumact as pa
from pneumact.control import PID, ClosedLoop
from pneumact.control.linear import frequency_response, linearise
from pneumact.experiments import SetpointStep
from pneumact.parameters import ParameterSet
from reference import (
    LINEAR_LOOP_GAINS,
    LINEAR_LOOP_MASS_DAMPER,
    LINEAR_LOOP_RTOL,
    LINEAR_LOOP_SAMPLE_TIMES,
    LINEAR_LOOP_STEP,
    LINEAR_LOOP_VS_CONTROL_TOL,
    SAMPLED_ORDER_RATIO_TOL,
    SAMPLED_REFERENCE_RTOL,
    SWEEP_COMMAND,
    SWEEP_FREQUENCIES,
    SWEEP_LARGE_AMPLITUDE,
    SWEEP_LARGE_MIN_GAIN_ERROR,
    SWEEP_PERIODS,
    SWEEP_SMALL_AMPLITUDE,
    SWEEP_SMALL_GAIN_RTOL,
    SWEEP_SMALL_PHASE_TOL,
    SWEEP_SMALL_RESIDUAL,
)


@pytest.fixture(scope="module")
def mass_damper():
    """m·ẍ + c·ẋ = F: a rig whose friction is a pure viscous term. CoulombViscous with
    Fc = 0 is F_f = 0·tanh(v/v_reg) + σ2·v = σ2·v exactly (Fc ≥ 0 is a valid value)."""
    m, c = LINEAR_LOOP_MASS_DAMPER
    params = ParameterSet.from_dict({"m": m, "Fc": 0.0, "sigma2": c}, name="mass-damper")
    return pa.FrictionRig(params, pa.CoulombViscous(), drive="force")


def _pid(sample_time=None):
    kp, ki, kd, tf = LINEAR_LOOP_GAINS
    return PID(kp=kp, ki=ki, kd=kd, derivative="measurement", filter_time=tf,
               sample_time=sample_time)


def _step_experiment():
    t_end, n_points = 2.0, 2001
    return SetpointStep(0.0, LINEAR_LOOP_STEP, 0.0, t_end, n_points)


def test_continuous_pid_matches_python_control(mass_damper):
    control = pytest.importorskip("control")
    m, c = LINEAR_LOOP_MASS_DAMPER
    kp, ki, kd, tf = LINEAR_LOOP_GAINS
    experiment = _step_experiment()
    solver = pa.Rodas4(rtol=LINEAR_LOOP_RTOL)
    result = pa.simulate(ClosedLoop(mass_damper, _pid()), experiment, solver)
    # X = P·[(Kp + Ki/s)·(R − X) − Kd·s/(Tf·s + 1)·X]  =>  X/R = Cr·P/(1 + P·(Cr + Cd))
    plant = control.ss(control.tf([1.0], [m, c, 0.0]))
    c_r = control.tf([kp, ki], [1.0, 0.0])
    c_d = control.tf([kd, 0.0], [tf, 1.0])
    closed = control.feedback(plant, control.ss(c_r + c_d)) * control.ss(c_r)
    t = result.time
    reference = control.forced_response(closed, T=t, U=np.full_like(t, LINEAR_LOOP_STEP)).outputs
    error = np.max(np.abs(result.signals["position"] - reference))
    relative = error / LINEAR_LOOP_STEP
    assert relative <= LINEAR_LOOP_VS_CONTROL_TOL, f"max error {relative:.3g} of the step"
    assert result.signals["position"][-1] == pytest.approx(LINEAR_LOOP_STEP, rel=1e-2)  # settled


def test_sampled_pid_converges_at_first_order(mass_damper):
    experiment = _step_experiment()
    solver = pa.Rodas4(rtol=SAMPLED_REFERENCE_RTOL)
    continuous = pa.simulate(ClosedLoop(mass_damper, _pid()), experiment, solver)
    errors = []
    for ts in LINEAR_LOOP_SAMPLE_TIMES:
        sampled = pa.simulate(ClosedLoop(mass_damper, _pid(ts)), experiment, solver)
        errors.append(np.max(np.abs(sampled.signals["position"]
                                    - continuous.signals["position"])))
    errors = np.array(errors)
    ratios = errors[:-1] / errors[1:]
    assert np.all(np.diff(errors) < 0), f"errors {errors / LINEAR_LOOP_STEP} of the step"
    # halving T_s halves the error: observed order log2(ratio) ≈ 1 (ZOH + forward Euler)
    assert np.all(np.abs(ratios - 2.0) <= SAMPLED_ORDER_RATIO_TOL), f"ratios {ratios}"


@pytest.fixture(scope="module")
def valve_actuator(vgt):
    return pa.Actuator(vgt, pa.LuGre(), valve=pa.CommandValve())


def test_linearisation_holds_at_small_amplitude_only(valve_actuator):
    lin = linearise(valve_actuator, SWEEP_COMMAND)
    expected = lin.frequency_response(SWEEP_FREQUENCIES)
    periods, settle = SWEEP_PERIODS
    small = frequency_response(valve_actuator, SWEEP_COMMAND, SWEEP_SMALL_AMPLITUDE,
                               SWEEP_FREQUENCIES, periods=periods, settle_periods=settle)
    gain_error = small["gain"].to_numpy() / np.abs(expected) - 1.0
    phase_error = (small["phase_deg"].to_numpy() - np.degrees(np.angle(expected)) + 180.0
                   ) % 360.0 - 180.0
    assert np.all(np.abs(gain_error) <= SWEEP_SMALL_GAIN_RTOL), f"gain errors {gain_error}"
    assert np.all(np.abs(phase_error) <= SWEEP_SMALL_PHASE_TOL), f"phase errors {phase_error}"
    assert np.all(small["residual"] <= SWEEP_SMALL_RESIDUAL)
    large = frequency_response(valve_actuator, SWEEP_COMMAND, SWEEP_LARGE_AMPLITUDE,
                               SWEEP_FREQUENCIES, periods=periods, settle_periods=settle)
    large_error = large["gain"].to_numpy() / np.abs(expected) - 1.0
    # sliding frees the diaphragm from the bristle stiffness: the real gain is larger
    assert np.all(large_error >= SWEEP_LARGE_MIN_GAIN_ERROR), f"gain errors {large_error}"
    assert np.all(large["residual"] > SWEEP_SMALL_RESIDUAL)

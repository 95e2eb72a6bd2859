"""Closed loops: the Canudas (1995) hunting experiment, anti-windup, the sampled
controller's zero-order hold, the batch engine against single runs, and bad input."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import pneumact as pa
import reference as ref
from pneumact.control import PID, Cascade, ClosedLoop, Dither, LuGreObserver, StaticCompensation
from pneumact.control.study import canudas_hunting
from pneumact.errors import ExperimentError, ParameterError
from pneumact.experiments import SetpointStep


def _swing(result, t_from):
    """Peak-to-peak of the position after ``t_from``."""
    late = result.time >= t_from
    return float(np.ptp(result.signals["position"][late]))


def test_canudas_experiment_hunts(canudas):
    loop, experiment = canudas_hunting(canudas)
    result = pa.simulate(loop, experiment)
    # a friction-induced limit cycle around xd = 1 m: it still swings at the end
    assert _swing(result, 50.0) > ref.HUNTING_MIN_SWING
    assert _swing(result, 80.0) > ref.HUNTING_MIN_SWING
    late = result.time >= 50.0
    x = result.signals["position"][late]
    assert x.min() < 1.0 < x.max()
    stuck = np.abs(result.signals["velocity"][late]) < ref.HUNTING_STICK_SPEED
    assert 0.3 < stuck.mean() < 0.95  # long stick phases between the slips


def test_no_hunting_without_integral_action(canudas):
    loop, experiment = canudas_hunting(canudas, ki=0.0)
    result = pa.simulate(loop, experiment)
    assert _swing(result, 50.0) < ref.STILL_SWING  # stuck for good, short of the target
    assert abs(result.signals["position"][-1] - 1.0) > ref.HUNTING_MIN_SWING


def test_no_hunting_when_static_equals_coulomb_friction(canudas):
    loop, experiment = canudas_hunting(canudas.replace(Fs=canudas["Fc"]),
                                       t_end=ref.FS_EQUALS_FC_DURATION, n_points=30001)
    result = pa.simulate(loop, experiment)
    # the stick points close in on the set-point instead of cycling around it
    assert _swing(result, ref.FS_EQUALS_FC_DURATION - 100.0) < ref.HUNTING_MIN_SWING / 5
    assert abs(result.signals["position"][-1] - 1.0) < ref.FS_EQUALS_FC_FINAL_ERROR


def test_every_controller_calls_the_plant_kernel_of_an_open_loop_run(canudas):
    """The loop kernel calls its plant's own compiled kernel (no copy of the plant's code
    per controller configuration), and names it in its source, so that a change to the
    plant recompiles the loop."""
    from pneumact.core import codegen
    from pneumact.simulation import assemble

    rig = pa.FrictionRig(canudas, pa.LuGre(), drive="force")
    plant = assemble(rig).numba_kernel
    for controller in (PID(kp=1.0), PID(kp=1.0, kd=1.0, derivative="error"),
                       PID(kp=1.0, sample_time=0.01)):
        loop = ClosedLoop(rig, controller)
        spec = assemble(loop).kernel_spec()
        assert codegen.module_name(assemble(rig).kernel_spec()) in spec.source()
        kernel = assemble(loop).numba_kernel
        for name in ("rhs", "jac", "param_jac", "outputs", "initial_state", "project"):
            assert getattr(kernel, f"plant_{name}") is getattr(plant, name)


def _saturated_step(canudas, anti_windup):
    pid = PID(kp=3.0, ki=4.0, kd=6.0, derivative="velocity", u_min=-ref.WINDUP_LIMIT,
              u_max=ref.WINDUP_LIMIT, anti_windup=anti_windup)
    rig = pa.FrictionRig(canudas, pa.LuGre(), drive="force")
    return pa.simulate(ClosedLoop(rig, pid), SetpointStep(0.0, 5.0, 0.0, 30.0, 3001))


@pytest.mark.parametrize("scheme", ["back-calculation", "clamping"])
def test_anti_windup_limits_the_integrator_in_saturation(canudas, scheme):
    free = _saturated_step(canudas, "none")
    held = _saturated_step(canudas, scheme)
    for result in (free, held):
        command = result.signals["command"]
        assert command.max() <= ref.WINDUP_LIMIT * (1 + 1e-12)
        assert command.min() >= -ref.WINDUP_LIMIT * (1 + 1e-12)
    assert np.abs(free.signals["command"]).max() == pytest.approx(ref.WINDUP_LIMIT)
    wound = np.abs(free.signals["control_integral"]).max()
    limited = np.abs(held.signals["control_integral"]).max()
    assert limited < ref.WINDUP_REDUCTION * wound
    # the wound-up integrator overshoots the target far more
    assert held.signals["position"].max() - 5.0 < free.signals["position"].max() - 5.0


def test_clamping_stops_the_integrator_while_pushing_into_the_limit(canudas):
    result = _saturated_step(canudas, "clamping")
    s = result.signals
    # where the law asks for more than the limit (beyond the clamping layer) and the
    # error pushes further, the integrator must not move
    asked = 3.0 * s["error"] + 4.0 * s["control_integral"] - 6.0 * s["velocity"]
    beyond = (asked > ref.WINDUP_LIMIT * 1.01) & (s["error"] > 0)
    both = beyond[1:] & beyond[:-1]
    assert both.sum() > 10
    np.testing.assert_allclose(np.diff(s["control_integral"])[both], 0.0, atol=1e-12)


def test_sampled_controller_holds_its_output_between_samples(canudas):
    """The hunting loop's gains, sampled: the command is held within each period and
    changes at the samples. The hold is the controller's, whatever the plant: the rig
    has Coulomb-viscous friction and the PID a filtered derivative, the sampled loop of
    test_loop_linear.py (one kernel for both)."""
    period = 0.05
    rig = pa.FrictionRig(canudas, pa.CoulombViscous(), drive="force")
    pid = PID(kp=3.0, ki=4.0, kd=6.0, derivative="measurement", filter_time=period,
              anti_windup="none", sample_time=period)
    experiment = pa.Experiment(pa.experiments.Constant(1.0), "position", 5.0, n_points=101)
    times = np.sort(np.concatenate([np.arange(0, 100) * period + 0.3 * period,
                                    np.arange(0, 100) * period + 0.9 * period]))
    result = pa.simulate(ClosedLoop(rig, pid), experiment, t_eval=times)
    command = result.signals["command"].reshape(-1, 2)
    np.testing.assert_allclose(command[:, 0], command[:, 1], rtol=1e-12)  # held in a period
    assert np.count_nonzero(np.diff(command[:, 0])) > 50  # and changes at the samples
    loop, _ = canudas_hunting(canudas, sample_time=period)  # the experiment samples too
    assert loop.controller.sample_time == period


def test_batch_engine_equals_single_runs_for_a_closed_loop(canudas):
    loop, experiment = canudas_hunting(canudas, t_end=20.0, n_points=201)
    values = [0.8, 1.0, 1.2]
    batch = pa.simulate_batch(loop, experiment, pd.DataFrame({"m": values}),
                              signals=["position"], executor=2)
    for row, mass in enumerate(values):
        single = pa.simulate(loop, experiment, values={"m": mass})
        np.testing.assert_allclose(batch.signals["position"][row], single.signals["position"],
                                   rtol=0, atol=1e-12)


def test_cascade_and_compensation_run_and_reduce_the_error(canudas):
    rig = pa.FrictionRig(canudas, pa.LuGre(), drive="force")
    ramp = pa.experiments.SetpointRamp(0.0, 0.1, 10.0, t_end=12.0)
    plain = Cascade(kx=5.0, kv=20.0, ki=20.0)
    compensated = Cascade(kx=5.0, kv=20.0, ki=20.0, compensation=(
        LuGreObserver.from_parameters(canudas, gain=0.0),))
    errors = [np.abs(pa.simulate(ClosedLoop(rig, c), ramp).signals["error"]).max()
              for c in (plain, compensated)]
    assert errors[1] < 0.5 * errors[0]


def test_bad_input_is_one_clear_message(canudas, vgt):
    rig = pa.FrictionRig(canudas, pa.LuGre(), drive="velocity")
    with pytest.raises(ParameterError, match="drive='force'"):
        ClosedLoop(rig, PID(kp=1.0))
    with pytest.raises(ParameterError, match="u_min"):
        PID(kp=1.0, u_min=2.0, u_max=1.0)
    with pytest.raises(ParameterError, match="anti_windup"):
        PID(kp=1.0, anti_windup="sometimes")
    with pytest.raises(ParameterError, match="sample_time"):
        PID(kp=1.0, sample_time=-1e-3)
    with pytest.raises(ParameterError, match="frequency"):
        Dither(0.1, 0.0)
    actuator = pa.Actuator(vgt, pa.LuGre(), valve=pa.CommandValve())
    with pytest.raises(ParameterError, match="compensation_gain"):
        ClosedLoop(actuator, PID(kp=1.0, compensation=(StaticCompensation(10.0),)))
    with pytest.raises(ExperimentError, match="out of reach"):
        ClosedLoop(actuator, PID(kp=1.0, u_min=0.0, u_max=1.0)).holding_input(0.5)
    loop, experiment = canudas_hunting(canudas, t_end=1.0)
    with pytest.raises(ParameterError, match=r"'kq' is not a parameter.*kp, ki, kd"):
        pa.simulate(loop, experiment, values={"kq": 1.0})
    with pytest.raises(ParameterError, match="kx not among its parameters"):
        loop.controller.with_parameters(kx=1.0)


def test_dither_frees_a_pd_loop_stuck_short_of_the_target(canudas):
    rig = pa.FrictionRig(canudas, pa.LuGre(), drive="force")
    experiment = pa.Experiment(pa.experiments.Constant(1.0), "position", 60.0, n_points=6001)
    late = np.linspace(0.0, 60.0, 6001) > 40.0
    errors = []
    for terms in ((), (Dither(ref.DITHER_AMPLITUDE, ref.DITHER_FREQUENCY),)):
        pd_loop = ClosedLoop(rig, PID(kp=3.0, kd=6.0, derivative="velocity",
                                      compensation=terms))
        x = pa.simulate(pd_loop, experiment).signals["position"]
        errors.append(abs(1.0 - x[late].mean()))
    assert errors[0] > ref.HUNTING_MIN_SWING  # stuck (Fs = 1.5 N holds it at 0.66 m)
    assert errors[1] < errors[0] / 10


def test_coulomb_feedforward_cuts_the_ramp_tracking_error(canudas):
    rig = pa.FrictionRig(canudas, pa.LuGre(), drive="force")
    ramp = pa.experiments.SetpointRamp(0.0, 0.1, 10.0, t_end=12.0)
    worst = []
    for terms in ((), (StaticCompensation(canudas["Fc"]),)):
        pid = PID(kp=30.0, ki=20.0, kd=10.0, derivative="velocity", compensation=terms)
        result = pa.simulate(ClosedLoop(rig, pid), ramp)
        inside = (result.time > 2.0) & (result.time < 10.0)
        worst.append(np.abs(result.signals["error"][inside]).max())
    assert worst[1] < worst[0] / 5


def test_a_plant_with_state_events_is_refused_with_the_reason():
    """A GMS plant's stick/slip switches are located by the open-loop kernel only: a
    closed loop around it is refused, not run with its blocks' memory lost."""
    import pneumact as pa
    from conftest import load_quietly
    from pneumact.errors import ParameterError

    plant = pa.Actuator(load_quietly("vgt-paper-gms4"), friction=pa.GMS(4),
                        valve=pa.PressureSource())
    with pytest.raises(ParameterError, match=r"GMS\(n_elements=4\) switches modes at state "
                                             "events"):
        pa.ClosedLoop(plant, pa.PID(kp=1.0))


@pytest.mark.parametrize(("sample_time", "words"), [
    (10.0, "not shorter than the run"),  # the controller would never act
    (1e-9, "controller samples"),  # 1e9 breakpoints: 8 GB, and no Ctrl-C for an hour
])
def test_a_sample_time_the_run_cannot_use_is_refused(canudas, sample_time, words):
    rig = pa.FrictionRig(canudas, pa.LuGre(), drive="force")
    loop = ClosedLoop(rig, PID(kp=1.0, sample_time=sample_time))
    with pytest.raises(ExperimentError, match=words) as refused:
        loop.breakpoints(np.array([0.0, 1.0]), None, 0.0, 1.0)
    assert f"sample_time = {sample_time:g} s" in str(refused.value)

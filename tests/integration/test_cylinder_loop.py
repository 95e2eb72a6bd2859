"""The double-acting cylinder in a closed loop (issue 41, item 5): position control
through the spool command, by a PID and by the servo-pneumatic state feedback on
position, velocity and the chambers' pressure difference."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

import pneumact as pa
import reference as ref
from conftest import load_quietly
from pneumact.control import PID, ClosedLoop, linearise, loop_metrics
from pneumact.errors import ExperimentError, ParameterError
from pneumact.experiments import SetpointStep

pytestmark = pytest.mark.integration

#: kp [1/m], kd [s/m]: a loop that overshoots by about a fifth without pressure feedback
KP, KD = 100.0, 0.5
#: pressure-difference gains [1/Pa], rising
KDPS = (0.0, 1e-6, 3e-6)
T_STEP, T_END = 1.0, 2.0
START = 0.09


def state_feedback(kdp: float) -> PID:
    """u = kp·(r − x) − kd·v − kdp·Δp, limited to the spool's travel."""
    return PID(kp=KP, kd=KD, kdp=kdp, derivative="velocity", u_min=-1.0, u_max=1.0)


@pytest.fixture(scope="module")
def cylinder():
    return pa.Cylinder(load_quietly("iso15552-32"))


#: a PID with integral action (its derivative on the measured velocity): one kernel with
#: the state feedbacks, the gains being settings
PID_GAINS = {"kp": 60.0, "ki": 300.0, "kd": 0.5}


@pytest.fixture(scope="module")
def runs(cylinder):
    """One 20 mm step per pressure gain, and one under the PID."""
    step = SetpointStep(START, START + ref.CYLINDER_LOOP_STEP, t_step=T_STEP, t_end=T_END,
                        n_points=4001)
    controllers = {kdp: state_feedback(kdp) for kdp in KDPS}
    controllers["pid"] = PID(**PID_GAINS, derivative="velocity", u_min=-1.0, u_max=1.0)
    return {name: pa.simulate(ClosedLoop(cylinder, controller), step)
            for name, controller in controllers.items()}


@pytest.mark.parametrize("name", [*KDPS, "pid"])
def test_a_20mm_step_settles(runs, name):
    """After the set-point's step the position settles into 2 % of the step and stays."""
    run = runs[name]
    metrics = loop_metrics(run, t_step=T_STEP, band=ref.CYLINDER_LOOP_BAND)
    assert np.isfinite(metrics.settling_time), metrics
    assert metrics.settling_time < T_END - T_STEP
    assert not metrics.hunting
    assert np.all(np.abs(run["command"]) <= 1.0)


def test_pressure_feedback_adds_damping(runs):
    """At the same kp and kd, more pressure-difference feedback, less overshoot."""
    overshoot = [loop_metrics(runs[k], t_step=T_STEP).overshoot for k in KDPS]
    assert all(a > b for a, b in itertools.pairwise(overshoot)), overshoot
    assert overshoot[0] - overshoot[-1] > ref.CYLINDER_DAMPING_MIN_POINTS, overshoot


def test_the_command_is_the_state_feedback_law(runs, cylinder):
    """command = clip(kp·e − kd·v − kdp·((p_a − p_atm) − (p_b − p_atm)·A_b/A_a), ±1),
    written out from the run's own signals."""
    kdp = KDPS[-1]
    run = runs[kdp]
    params = cylinder.params
    p_atm = float(params["p_atm"])
    bore, rod = float(params["D_bore"]), float(params["d_rod"])
    area_ratio = (bore**2 - rod**2) / bore**2
    dp = (run["pressure_a"] - p_atm) - (run["pressure_b"] - p_atm) * area_ratio
    law = KP * run["error"] - KD * run["velocity"] - kdp * dp
    expected = np.clip(law, -1.0, 1.0)
    assert np.max(np.abs(run["command"] - expected)) < ref.CYLINDER_LAW_ATOL
    assert np.max(np.abs(kdp * dp)) > 0.05  # the pressure term mattered in this run
    assert np.any(np.abs(law) > 1.0)  # and the limit too


def test_pressure_feedback_needs_two_chambers():
    vgt = load_quietly("vgt-paper")
    with pytest.raises(ParameterError, match=r"kdp = 1e-06.*Cylinder"):
        ClosedLoop(pa.Actuator(vgt, valve=pa.CommandValve()), PID(kp=1.0, kdp=1e-6))
    with pytest.raises(ParameterError, match=r"kdp = -1.*>= 0"):
        PID(kp=1.0, kdp=-1.0)


def test_a_kinematic_rig_has_no_input_to_control():
    rig = pa.FrictionRig(load_quietly("canudas1995"), drive="velocity")
    with pytest.raises(ParameterError, match="kinematic drive has no input"):
        ClosedLoop(rig, PID(kp=1.0))


# ------------------------------------------------------------------------ linearisation
POSITION = 0.1


@pytest.fixture(scope="module")
def linear(cylinder):
    """The cylinder linearised mid-stroke at the spool command that balances its chambers
    (LuGre in presliding: the bristle is a spring σ0 with damping σ1 + σ2)."""
    balanced = ClosedLoop(cylinder, state_feedback(0.0)).holding_input(POSITION)
    return linearise(cylinder, balanced, position=POSITION)


def _chamber_stiffness(params, linear):
    """n·p·A²/V of each chamber at the point (isothermal: n = 1)."""
    bore, rod = float(params["D_bore"]), float(params["d_rod"])
    area_a, area_b = np.pi * bore**2 / 4, np.pi * (bore**2 - rod**2) / 4
    volume_a = float(params["chamber_a.V_dead"]) + area_a * POSITION
    volume_b = float(params["chamber_b.V_dead"]) + area_b * (float(params["x_max"]) - POSITION)
    point = linear.operating_point
    return (point["pressure_a"] * area_a**2 / volume_a,
            point["pressure_b"] * area_b**2 / volume_b)


def test_the_balanced_point_is_an_equilibrium(linear, cylinder):
    assert linear.operating_point["position"] == POSITION
    force_left = abs(linear.rates[linear.state_names.index("velocity")]) * cylinder.params["m"]
    assert force_left < 1e-6  # N: the spool command balances the chambers
    assert "pressure a" in linear.statement and "pressure b" in linear.statement


def test_each_chamber_is_a_gas_spring_n_p_a2_over_v(linear, cylinder):
    """Through the chamber (∂ṗ/∂v) and back on the piston (∂v̇/∂p): −m·A[v, p]·A[p, v]
    is the chamber's pneumatic stiffness n·p·A²/V."""
    names = linear.state_names
    iv = names.index("velocity")
    mass = float(cylinder.params["m"])
    for chamber, closed_form in zip(("pressure_a", "pressure_b"),
                                    _chamber_stiffness(cylinder.params, linear), strict=True):
        ip = names.index(chamber)
        stiffness = -mass * linear.A[iv, ip] * linear.A[ip, iv]
        assert stiffness == pytest.approx(closed_form, rel=ref.CYLINDER_STIFFNESS_RTOL)


def test_the_piston_rings_on_bristle_and_gas_springs(linear, cylinder):
    """The oscillating pole pair: m·s² + (σ1 + σ2)·s + σ0 + k_a + k_b = 0 (the valve's
    leakage, left out, moves it little)."""
    params = cylinder.params
    stiffness = float(params["sigma0"]) + sum(_chamber_stiffness(params, linear))
    roots = np.sort_complex(np.roots([float(params["m"]),
                                      float(params["sigma1"]) + float(params["sigma2"]),
                                      stiffness]))
    poles = linear.poles()
    pair = np.sort_complex(poles[np.abs(poles.imag) > 0])
    assert pair.size == 2
    assert np.max(np.abs(pair - roots)) < ref.CYLINDER_MECHANICAL_POLES_RTOL * abs(roots[0])


def test_the_eigenvalues_are_those_of_a_difference_jacobian(linear, cylinder):
    _eigenvalues_are_those_of_a_difference_jacobian(linear, cylinder)


def test_with_heat_transfer_each_chamber_is_an_adiabatic_gas_spring(cylinder):
    """Chambers with their energy equations (``HeatTransfer``): on the piston's time
    scale each is the adiabatic gas spring γ·p·A²/V (the heat flows through the
    temperature states, whose modes are slow and real), and the eigenvalues are those of
    a difference Jacobian."""
    heated = pa.Cylinder(cylinder.params, chamber=pa.HeatTransfer())
    balanced = ClosedLoop(heated, state_feedback(0.0)).holding_input(POSITION)
    linear = linearise(heated, balanced, position=POSITION)
    assert {"temperature_a", "temperature_b"} <= set(linear.state_names)
    names, gamma = linear.state_names, float(heated.params["gamma"])
    iv = names.index("velocity")
    for chamber, isothermal in zip(("pressure_a", "pressure_b"),
                                   _chamber_stiffness(heated.params, linear), strict=True):
        ip = names.index(chamber)
        stiffness = -float(heated.params["m"]) * linear.A[iv, ip] * linear.A[ip, iv]
        assert stiffness == pytest.approx(gamma * isothermal, rel=ref.CYLINDER_STIFFNESS_RTOL)
    poles = linear.poles()
    ringing = np.abs(poles[np.abs(poles.imag) > 0].real).min()
    assert np.abs(poles[poles.imag == 0].real).max() < ringing  # thermal modes: slower
    _eigenvalues_are_those_of_a_difference_jacobian(linear, heated)


def _eigenvalues_are_those_of_a_difference_jacobian(linear, cylinder) -> None:
    from pneumact.core.assembly import assemble
    from pneumact.core.signals import Constant, pack_channels

    assembly = assemble(cylinder)
    kernel, vector = assembly.kernel, assembly.pack()
    sig, ptr = pack_channels(cylinder.channels(Constant(linear.operating_point["spool"])))
    y = np.array([linear.operating_point[n] for n in linear.state_names])
    jacobian = np.empty((y.size, y.size))
    for j in range(y.size):
        step = 1e-6 * max(abs(y[j]), linear.state_scales[j])
        rates = []
        for sign in (1.0, -1.0):
            moved = y.copy()
            moved[j] += sign * step
            f = np.empty(y.size)
            kernel.rhs(0.0, 0.0, moved, vector, sig, ptr, f)
            rates.append(f)
        jacobian[:, j] = (rates[0] - rates[1]) / (2.0 * step)
    expected = np.sort_complex(np.linalg.eigvals(jacobian))
    found = np.sort_complex(linear.poles())
    worst = np.max(np.abs(found - expected)) / np.max(np.abs(expected))
    assert worst < ref.CYLINDER_FD_EIGENVALUES_RTOL


def test_a_position_beyond_the_stroke_is_refused(cylinder):
    with pytest.raises(ExperimentError, match=r"position = 0.5; allowed: .*\[0, 0.2\]"):
        linearise(cylinder, 0.0, position=0.5)


# ----------------------------------------------------------------------------- summary
def test_a_cylinder_run_summarises_its_move(cylinder):
    """Result.summary() of a cylinder (here in a loop, which summarises as its plant):
    the move from the first position to the last, its overshoot as loop_metrics measures
    it, the top speeds as the velocity's extremes."""
    target = 0.18  # the loop starts at rest on the rod-end stop (0.2 m): a 20 mm move in
    loop = ClosedLoop(cylinder, state_feedback(0.0))
    run = pa.simulate(loop, SetpointStep(target, target, t_step=0.0, t_end=1.0))
    summary = run.summary()
    x = run["position"]
    assert summary["start_position"] == x[0] and summary["final_position"] == x[-1]
    assert summary["travel"] == pytest.approx(target - float(cylinder.params["x_max"]),
                                              abs=ref.CYLINDER_LOOP_BAND * 0.02)
    metrics = loop_metrics(run, start=x[0], target=x[-1], t_step=0.0)
    assert metrics.overshoot > 0.1  # % : it does overshoot (0.86 % measured)
    assert summary["overshoot"] == pytest.approx(
        metrics.overshoot / 100.0 * abs(summary["travel"]), rel=ref.CYLINDER_SUMMARY_RTOL)
    assert summary["position_range"] >= abs(summary["travel"]) + summary["overshoot"] - 1e-15
    assert summary["top_speed_in"] == -run["velocity"].min() > 0.0
    assert summary["top_speed_out"] == max(0.0, run["velocity"].max())


def test_a_state_feedback_survives_its_gains_file(tmp_path):
    """kdp is a gain like the others: written with its unit, read back."""
    from pneumact.control import load_gains, write_gains

    controller = state_feedback(KDPS[-1])
    path = write_gains(controller, tmp_path / "gains.toml",
                       units=controller.parameter_units("1"))
    assert 'kdp = "1/Pa"' in path.read_text()
    back = load_gains(path, command_unit="1")
    assert back.parameters() == controller.parameters()
    assert (back.kdp, back.derivative) == (controller.kdp, "velocity")


def test_a_rig_run_summarises_its_motion_too():
    """A rig driven at v = a·sin(2πft) from rest at 0: x = a/(2πf)·(1 − cos 2πft), so its
    range is a/(πf) and its top speeds a both ways."""
    from pneumact.experiments import Sine

    amplitude, frequency = 0.01, 0.5
    rig = pa.FrictionRig(load_quietly("canudas1995"), drive="velocity")
    run = pa.simulate(rig, pa.Experiment(Sine(amplitude, frequency), "velocity", 4.0,
                                         n_points=801))
    summary = run.summary()
    assert summary["position_range"] == pytest.approx(amplitude / (np.pi * frequency),
                                                      rel=ref.RIG_MOTION_RTOL)
    assert summary["top_speed_out"] == pytest.approx(amplitude, rel=ref.RIG_MOTION_RTOL)
    assert summary["top_speed_in"] == pytest.approx(amplitude, rel=ref.RIG_MOTION_RTOL)
    assert abs(summary["travel"]) < ref.RIG_MOTION_RTOL * amplitude  # two whole periods


def test_the_fmu_export_refuses_a_closed_loop_and_a_cylinder_with_a_load(cylinder):
    """The cylinder exports (tests/integration/test_fmu_cosimulation.py); its closed loop
    does not yet, and says where to read why; a load against time is the FMU's input, and
    a spool command's start outside [-1, 1] is refused."""
    from pneumact.core.signals import Constant
    from pneumact.errors import ArgumentError
    from pneumact.export import export_fmu

    with pytest.raises(ArgumentError, match=r"ClosedLoop.*not yet: docs/fmu-export.md"):
        export_fmu(ClosedLoop(cylinder, state_feedback(0.0)), "loop.fmu")
    with pytest.raises(ArgumentError, match=r"cylinder has a load against time"):
        export_fmu(pa.Cylinder(cylinder.params, load=Constant(10.0)), "cylinder.fmu")
    with pytest.raises(ArgumentError, match=r"spool_command"):  # its range, [-1, 1]
        export_fmu(cylinder, "cylinder.fmu", inputs={"spool_command": 1.5})

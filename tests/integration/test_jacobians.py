"""The generated kernels' analytic Jacobian ``jac`` (∂f/∂y) and parameter Jacobian
``param_jac`` (∂f/∂ every slot of the parameter vector) equal central finite differences of
their ``rhs``, for every valve, at states away from the non-smooth points (v ≠ 0, inside
the stroke or well inside an end stop, u_raw in (0, 1)), with a law of one state and a
law of none (every law's own partials: ``test_friction_registry.py``).

Each component combination is compiled once and cached on disk afterwards.
"""

from __future__ import annotations

import numpy as np
import pytest

from conftest import load_quietly
from pneumact.core.signals import Constant, PiecewiseLinear, Ramp
from pneumact.experiments.actuator import Experiment
from pneumact.models import (
    Actuator,
    Adiabatic,
    CommandValve,
    CoulombViscous,
    Cylinder,
    FrictionRig,
    HeatTransfer,
    Iso6358Valve,
    LuGre,
    PressureRegulator,
    PressureSource,
)
from pneumact.simulation import Rodas4
from pneumact.simulation.simulate import prepare
from reference import JAC_FD_REL_STEP, JAC_RTOL, PARAM_JAC_RTOL

# typical size of each state [x m, v m/s, z m, p Pa, u, i]: sets the FD step and the
# scaling of the comparison (a change of y_j by its scale, seen in f_i)
STATE_SCALES = np.array([1e-3, 1e-2, 1e-5, 1e4, 1.0, 1.0])

# (x, v, z) samples: mid-stroke sliding both ways, presliding, and inside both end stops
# with the stop pushing (-k_stop·x − c_stop·v > 0)
MECHANICAL_STATES = [
    (5e-3, 2e-3, 1.5e-5),
    (12e-3, -7e-4, -2e-5),
    (8e-3, 3e-5, 5e-6),
    (-1e-6, -1e-3, -2.5e-5),
    (20.001e-3, 1e-3, 2.5e-5),
]


def _fd_check(prep, t, ts, y, label, state_scales=STATE_SCALES):
    kernel, prm, sig, ptr = prep.kernel, prep.vector, prep.sig, prep.ptr
    n = y.size
    analytic = np.zeros((n, n))
    kernel.jac(t, ts, y, prm, sig, ptr, analytic)
    numeric = np.zeros((n, n))
    f_plus, f_minus = np.empty(n), np.empty(n)
    for j in range(n):
        h = JAC_FD_REL_STEP * max(abs(y[j]), state_scales[j])
        y_plus, y_minus = y.copy(), y.copy()
        y_plus[j] += h
        y_minus[j] -= h
        kernel.rhs(t, ts, y_plus, prm, sig, ptr, f_plus)
        kernel.rhs(t, ts, y_minus, prm, sig, ptr, f_minus)
        numeric[:, j] = (f_plus - f_minus) / (2.0 * h)
    scales = state_scales[:n]
    row_size = np.max(np.abs(numeric * scales), axis=1, keepdims=True) + 1e-300
    error = np.abs(analytic - numeric) * scales / row_size
    worst = np.unravel_index(np.argmax(error), error.shape)
    assert error.max() <= JAC_RTOL, (
        f"{label}: d f[{worst[0]}] / d y[{worst[1]}] analytic {analytic[worst]:.6g}, "
        f"finite difference {numeric[worst]:.6g} at y = {y.tolist()}"
    )


def _param_fd_check(prep, t, ts, y, label, names=None):
    """∂f/∂prm[k] of ``param_jac`` against central differences of ``rhs`` in each slot
    (derived slots included: the kernel reads them as they are, without re-deriving), or
    in the slots ``names`` only."""
    kernel, prm, sig, ptr = prep.kernel, prep.vector, prep.sig, prep.ptr
    n, n_par = y.size, prm.size
    analytic = np.zeros((n, n_par))
    kernel.param_jac(t, ts, y, prm, sig, ptr, analytic, np.ones(n_par, dtype=np.bool_))
    f0, f_plus, f_minus = np.empty(n), np.empty(n), np.empty(n)
    kernel.rhs(t, ts, y, prm, sig, ptr, f0)
    slots = prep.assembly.entries
    for k in range(n_par):
        if names is not None and slots[k].name not in names:
            continue
        h = JAC_FD_REL_STEP * max(abs(prm[k]), 1e-300)
        plus, minus = prm.copy(), prm.copy()
        plus[k] += h
        minus[k] -= h
        kernel.rhs(t, ts, y, plus, sig, ptr, f_plus)
        kernel.rhs(t, ts, y, minus, sig, ptr, f_minus)
        numeric = (f_plus - f_minus) / (2.0 * h)
        # compare the change of each rate per relative change of the slot with the rate's
        # size (its magnitude, or the largest such change)
        size = np.maximum(np.abs(f0), np.abs(numeric * prm[k])) + 1e-300
        error = np.abs(analytic[:, k] - numeric) * abs(prm[k]) / size
        assert error.max() <= PARAM_JAC_RTOL, (
            f"{label}: d f / d {slots[k].name} ({slots[k].role}) analytic "
            f"{analytic[:, k].tolist()}, finite difference {numeric.tolist()}")


@pytest.mark.parametrize("friction", [LuGre(), CoulombViscous()], ids=lambda f: f.kernel)
def test_actuator_pressure_source_jacobian(friction, vgt):
    # a load map with a slope exercises the ∂F_ext/∂x entry (with one law: the load's code
    # does not depend on it, and a loaded actuator is a kernel of its own); a ramp in
    # pressure the time
    loads = {}
    if isinstance(friction, LuGre):
        loads = {"load_map": PiecewiseLinear([0.0, 0.02], [0.0, 60.0]), "load": Constant(3.0)}
    model = Actuator(vgt, friction=friction, valve=PressureSource(), **loads)
    experiment = Experiment(Ramp(90e3, 30e3, duration=2.0), "pressure", t_end=2.0)
    prep = prepare(model, experiment, Rodas4())
    for x, v, z in MECHANICAL_STATES:
        y = np.array([x, v, *([z] if friction.states else [])])
        _fd_check(prep, 0.7, prep.segment_time, y, friction.kernel)
        _param_fd_check(prep, 0.7, prep.segment_time, y, friction.kernel)


PRESSURES = (20e3, 55e3, 85e3, 99.99e3)  # choked, subsonic, near-laminar, laminar inflow


# the ISO 6358 valve with b and m of a datasheet (not the orifice-like defaults)
ISO_DATASHEET = {"iso_b": 0.3, "iso_m": 0.6, "r_lin": 0.995, "iso_C_atm": 4e-9}


@pytest.mark.parametrize("valve", [CommandValve(), Iso6358Valve()], ids=lambda v: v.prefix)
def test_actuator_command_valve_jacobian(valve, vgt):
    params = vgt.replace(**ISO_DATASHEET) if isinstance(valve, Iso6358Valve) else vgt
    model = Actuator(params, friction=LuGre(), valve=valve)
    for command in (0.2, 0.5, 0.9):
        experiment = Experiment(Constant(command), "command", t_end=1.0)
        prep = prepare(model, experiment, Rodas4())
        for x, v, z in MECHANICAL_STATES:
            for p in PRESSURES:
                y = np.array([x, v, z, p])
                _fd_check(prep, 0.3, 0.5, y, f"{valve.prefix} u={command}")
                _param_fd_check(prep, 0.3, 0.5, y, f"{valve.prefix} u={command}")


def test_actuator_pressure_regulator_jacobian(vgt):
    model = Actuator(vgt, friction=LuGre(), valve=PressureRegulator())
    p_set = 55e3
    experiment = Experiment(Constant(p_set), "pressure", t_end=1.0)
    prep = prepare(model, experiment, Rodas4())
    kp = vgt["reg_kp"]
    for x, v, z in MECHANICAL_STATES:
        for p in PRESSURES:
            for opening in (0.1, 0.6):
                # integral state chosen so that u_raw = kp·(p − p_set)/p_atm + i = 0.5
                integral = 0.5 - kp * (p - p_set) / vgt["p_atm"]
                y = np.array([x, v, z, p, opening, integral])
                _fd_check(prep, 0.3, 0.5, y, "regulator")
                _param_fd_check(prep, 0.3, 0.5, y, "regulator")


@pytest.mark.parametrize("friction", [LuGre(), CoulombViscous()], ids=lambda f: f.kernel)
def test_friction_rig_spring_drive_jacobian(friction, canudas):
    model = FrictionRig(canudas, friction=friction, drive="spring")
    experiment = Experiment(Ramp(0.0, 1.0, duration=10.0), "spring", t_end=10.0)
    prep = prepare(model, experiment, Rodas4())
    for x, v, z in [(0.1, 0.05, 1e-5), (0.3, -0.02, -1.2e-5), (0.2, 2e-4, 3e-6)]:
        y = np.array([x, v, *([z] if friction.states else [])])
        _fd_check(prep, 3.0, 5.0, y, friction.kernel)
        _param_fd_check(prep, 3.0, 5.0, y, friction.kernel)


# the cylinder's states [x m, v m/s, p_a Pa, p_b Pa, z m, spool position]; (x, v, z)
# mid-stroke both ways, presliding, and inside both end stops pushing out; (p_a, p_b)
# choked and subsonic
CYLINDER_SCALES = np.array([1e-3, 1e-2, 1e4, 1e4, 1e-5, 1.0])
CYLINDER_MECHANICAL = [(0.05, 0.4, 5e-5), (0.15, -0.3, -6e-5), (0.1, 1e-4, 2e-5),
                       (-1e-6, -1e-3, -2e-5), (0.200001, 1e-3, 2e-5)]
CYLINDER_PRESSURES = [(1.3e5, 6.5e5), (5.2e5, 2.4e5), (3.5e5, 3.5e5)]


@pytest.mark.parametrize("spool_lag", [False, True], ids=["ideal spool", "spool lag"])
def test_cylinder_jacobian(spool_lag):
    """The double-acting cylinder behind its 5/3 valve (both spool directions, the closed
    centre with its leakage; the spool at once or lagged, a state off its command), a
    load against time, adiabatic chambers."""
    params = load_quietly("iso15552-32").replace(iso_b=0.25, iso_m=0.6)
    model = Cylinder(params, chamber=Adiabatic(), load=Ramp(0.0, 80.0, duration=1.0),
                     spool_lag=spool_lag)
    for u in (0.45, -0.8, 0.0):
        prep = prepare(model, Experiment(Constant(u), "spool", t_end=1.0), Rodas4())
        for x, v, z in CYLINDER_MECHANICAL:
            for pa, pb in CYLINDER_PRESSURES:
                spool = [0.6 * u - 0.2] if spool_lag else []  # off its command, not 0
                y = np.array([x, v, pa, pb, z, *spool])
                label = f"cylinder u={u}"
                _fd_check(prep, 0.3, 0.5, y, label, CYLINDER_SCALES)
                _param_fd_check(prep, 0.3, 0.5, y, label)


def test_cylinder_jacobian_with_two_3_2_valves():
    """The cylinder fed by a 3/2 valve per chamber (Cylinder(valves="two-3/2")): each
    valve's command either way, inside its overlap's band (A) or its underlap's (B), and
    fully open; ∂f/∂θ includes each valve's own C, leak and overlap columns."""
    params = load_quietly("iso15552-32").replace({
        "iso_b": 0.25, "iso_m": 0.6, "valve_a.overlap": 0.1, "valve_b.overlap": -0.1,
        "valve_b.C": 0.7 * load_quietly("iso15552-32")["valve_a.C"]})
    model = Cylinder(params, chamber=Adiabatic(), load=Ramp(0.0, 80.0, duration=1.0),
                     valves="two-3/2")
    for ua, ub in ((0.45, -0.8), (-0.7, 0.05), (0.05, 1.0), (-1.0, -0.04)):
        experiment = Experiment(Constant(ua), "command_a", t_end=1.0,
                                drives={"command_b": Constant(ub)})
        prep = prepare(model, experiment, Rodas4())
        for x, v, z in CYLINDER_MECHANICAL:
            for pa, pb in CYLINDER_PRESSURES:
                y = np.array([x, v, pa, pb, z])
                label = f"cylinder 3/2 valves u_a={ua} u_b={ub}"
                _fd_check(prep, 0.3, 0.5, y, label, CYLINDER_SCALES[:5])
                _param_fd_check(prep, 0.3, 0.5, y, label)


@pytest.mark.parametrize("overlap", [0.1, -0.1], ids=["overlap", "underlap"])
def test_cylinder_jacobian_with_an_overlap(overlap):
    """The 5/3 valve's overlap and underlap: ∂f/∂u (the lagged spool's column) and
    ∂f/∂spool_overlap with the spool inside the band (only the leakage flows, or, under-
    lapped, both paths of each chamber), outside it either way, and fully open."""
    params = load_quietly("iso15552-32").replace(iso_b=0.25, iso_m=0.6,
                                                 spool_overlap=overlap)
    model = Cylinder(params, chamber=Adiabatic(), spool_lag=True)
    prep = prepare(model, Experiment(Constant(0.3), "spool", t_end=1.0), Rodas4())
    x, v, z = CYLINDER_MECHANICAL[0]
    for spool in (0.05, -0.04, 0.45, -0.7):
        for pa, pb in CYLINDER_PRESSURES:
            y = np.array([x, v, pa, pb, z, spool])
            label = f"cylinder overlap={overlap} u={spool}"
            _fd_check(prep, 0.3, 0.5, y, label, CYLINDER_SCALES)
            _param_fd_check(prep, 0.3, 0.5, y, label)


# the states of a cylinder with heat transfer behind a second-order spool: the cylinder's,
# then the spool's position and velocity [1/s], the chambers' temperatures [K]
THERMAL_SCALES = np.array([*CYLINDER_SCALES, 100.0, 10.0, 10.0])
# (p_a, p_b, T_a, T_b): filling and venting at temperatures off the wall's, and a chamber
# above the supply (its flow back at its own temperature)
THERMAL_GAS = [(1.3e5, 6.5e5, 330.0, 250.0), (5.2e5, 2.4e5, 280.0, 320.0),
               (7.3e5, 0.9e5, 360.0, 293.15)]


@pytest.mark.parametrize("overlap", [0.0, -0.1], ids=["critical", "underlap"])
def test_cylinder_jacobian_with_heat_transfer_and_a_second_order_spool(overlap):
    """The chambers' energy equations (pressure and temperature rows, the outflows at the
    chambers' temperatures) behind a second-order spool, ∂f/∂y against differences; of
    ∂f/∂θ the spool's entries (the chambers' are not written: their sensitivities are
    refused)."""
    params = load_quietly("iso15552-32").replace(iso_b=0.25, iso_m=0.6,
                                                 spool_overlap=overlap)
    model = Cylinder(params, chamber=HeatTransfer(), spool_lag=2)
    prep = prepare(model, Experiment(Constant(0.3), "spool", t_end=1.0), Rodas4())
    for x, v, z in CYLINDER_MECHANICAL[:3]:
        for pa, pb, ta, tb in THERMAL_GAS:
            for spool, speed in ((0.05, 40.0), (0.45, -3.0), (-0.7, -60.0)):
                y = np.array([x, v, pa, pb, z, spool, speed, ta, tb])
                label = f"cylinder heat overlap={overlap} u={spool}"
                _fd_check(prep, 0.3, 0.5, y, label, THERMAL_SCALES)
                _param_fd_check(prep, 0.3, 0.5, y, label)

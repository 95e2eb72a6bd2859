"""The assembled actuator in simulation: physical invariants along computed trajectories.

Chamber mass balance (isothermal and adiabatic), end stops that neither inject energy nor
pull, regulator tracking, an equilibrium start that stays put, and the static shift of a
constant external load.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import cumulative_trapezoid

from pneumact.core.signals import Constant, Ramp, Step, Triangle
from pneumact.experiments.actuator import Experiment
from pneumact.models import (
    Actuator,
    Adiabatic,
    CommandValve,
    CoulombViscous,
    Isothermal,
    PressureRegulator,
    PressureSource,
)
from pneumact.simulation import Rodas4, simulate
from reference import (
    ADIABATIC_INVARIANT_RTOL,
    EQUILIBRIUM_DRIFT_POSITION,
    EQUILIBRIUM_DRIFT_VELOCITY,
    LOAD_SHIFT_RTOL,
    MASS_BALANCE_INTEGRAL_RTOL,
    MASS_BALANCE_RATE_RTOL,
    REGULATOR_RAMP_ERROR,
    REGULATOR_STEADY_ERROR,
    STOP_DAMPING_LOOP_WIDTH_CHANGE,
    STOP_ENERGY_RTOL,
    STOP_REST_FASTEST_POLE,
    TIGHT_RTOL,
)

SOLVER = Rodas4(rtol=TIGHT_RTOL)


def _volume(params, x):
    return params["V0"] - params["A_d"] * x


# ------------------------------------------------------------------ chamber mass balance
def test_isothermal_chamber_mass_balance(vgt):
    """d(p·V)/dt = R·T·(ṁ_in − ṁ_out), and its integral, along a command cycle."""
    model = Actuator(vgt, valve=CommandValve(), chamber=Isothermal())
    experiment = Experiment(Triangle(0.0, 1.0, period=2.0), "command", t_end=2.0,
                            n_points=20001)
    r = simulate(model, experiment, SOLVER)
    pv = r["pressure"] * _volume(vgt, r["position"])
    gas_rate = vgt["R"] * vgt["T"] * (r["mass_flow_in"] - r["mass_flow_out"])
    assert np.ptp(r["position"]) > 0.01, "the diaphragm must move for this test to bite"
    rate_error = np.abs(np.gradient(pv, r.time) - gas_rate)
    assert rate_error.max() <= MASS_BALANCE_RATE_RTOL * np.abs(gas_rate).max()
    integral = cumulative_trapezoid(gas_rate, r.time, initial=0.0)
    assert np.abs(pv - pv[0] - integral).max() <= MASS_BALANCE_INTEGRAL_RTOL * np.ptp(pv)


@pytest.mark.parametrize("chamber", [Isothermal(), Adiabatic()], ids=["isothermal",
                                                                      "adiabatic"])
def test_closed_chamber_follows_its_polytropic_law(chamber, vgt):
    """Valves shut (areas 0): p·V^n is constant while the diaphragm oscillates."""
    params = vgt.replace(A_res=0.0, A_atm=0.0)
    model = Actuator(params, valve=CommandValve(), chamber=chamber)
    experiment = Experiment(Constant(0.5), "command", t_end=0.5, n_points=5001)
    p0 = 50e3
    x_eq = ((params["p_atm"] - p0) * params["A_d"] - params["F0"]) / params["k"]
    y0 = np.array([x_eq - 3e-3, 0.0, 0.0, p0])  # released off equilibrium
    r = simulate(model, experiment, SOLVER, y0=y0)
    n = chamber.polytropic_index(params)
    invariant = r["pressure"] * _volume(params, r["position"]) ** n
    assert np.ptp(r["position"]) > 1e-3
    assert np.all(r["mass_flow_in"] == 0.0) and np.all(r["mass_flow_out"] == 0.0)
    assert np.ptp(invariant) <= ADIABATIC_INVARIANT_RTOL * invariant[0]


# ----------------------------------------------------------------------------- end stops
def _mechanical_energy(params, r, p_const):
    """½mv² + spring (F0·x + ½kx²) − pressure work (p_atm − p)·A_d·x + stop penetration."""
    x, v = r["position"], r["velocity"]
    x_max, k_stop = params["x_max"], params["k_stop"]
    penetration = np.where(x < 0.0, -x, np.where(x > x_max, x - x_max, 0.0))
    return (0.5 * params["m"] * v**2 + params["F0"] * x + 0.5 * params["k"] * x**2
            - (params["p_atm"] - p_const) * params["A_d"] * x
            + 0.5 * k_stop * penetration**2)


@pytest.mark.parametrize(("pressure", "x_start", "stop"), [
    (100e3, 5e-3, "rest"),   # spring preload throws the diaphragm onto the rest stop
    (5e3, 15e-3, "far"),     # deep vacuum swings it past x_max (equilibrium 19.06 mm)
])
def test_end_stops_create_no_energy_and_never_pull(pressure, x_start, stop, vgt):
    params = vgt.replace(Fc=0.0, sigma2=0.0)  # frictionless: only the stops dissipate
    model = Actuator(params, friction=CoulombViscous(), valve=PressureSource())
    experiment = Experiment(Constant(pressure), "pressure", t_end=0.3, n_points=30001)
    r = simulate(model, experiment, SOLVER, y0={"position": x_start, "velocity": 0.0})
    x, f_stop = r["position"], r["stop_force"]
    x_max = params["x_max"]
    hit = x < 0.0 if stop == "rest" else x > x_max
    assert hit.any(), f"the diaphragm never reached the {stop} stop"
    energy = _mechanical_energy(params, r, pressure)
    scale = abs(energy[0]) + 0.5 * params["k"] * x_max**2
    assert np.max(energy - energy[0]) <= STOP_ENERGY_RTOL * scale
    # energy never rises from one sample to a later one (up to the integration error)
    assert np.max(energy - np.minimum.accumulate(energy)) <= STOP_ENERGY_RTOL * scale
    assert energy[-1] < energy[0] - 10 * STOP_ENERGY_RTOL * scale, "contacts must dissipate"
    assert np.all(f_stop[x <= 0.0] >= 0.0), "the rest stop pulled"
    assert np.all(f_stop[x >= x_max] <= 0.0), "the far stop pulled"
    assert np.all(f_stop[(x > 0.0) & (x < x_max)] == 0.0), "stop force inside the stroke"


def _jacobian_at_rest(params, friction=None):
    """The kernel's Jacobian at the rest state under atmospheric pressure (on the stop)."""
    from pneumact.core.assembly import assemble
    from pneumact.core.signals import pack_channels

    model = Actuator(params, valve=PressureSource(), load=Constant(0.0),
                     **({"friction": friction} if friction is not None else {}))
    asm = assemble(model)
    vec = asm.pack()
    sig, ptr = pack_channels(model.channels(Constant(params["p_atm"])))
    n = len(asm.states)
    rest, jac = np.zeros(n), np.zeros((n, n))
    asm.kernel.initial_state(0.0, 0.0, vec, sig, ptr, rest)
    assert rest[asm.state_index("position")] < 0.0  # on the stop, under the preload
    asm.kernel.jac(0.0, 0.0, rest, vec, sig, ptr, jac)
    return jac


def test_the_default_stop_holds_the_resting_diaphragm_without_a_fast_pole(vgt):
    """Issue 39: vgt-paper resting on its stop under the preload has no pole faster than
    2e4 1/s (the former c_stop = 1e12 put one at -5.2e5, where forward Euler needs steps
    under 3.9 µs); ``explicit_step_limit`` is the Euler limit of the contact's poles."""
    from pneumact.models.mechanics import explicit_step_limit

    assert np.linalg.eigvals(_jacobian_at_rest(vgt)).real.min() > -STOP_REST_FASTEST_POLE
    for c_stop in (vgt["c_stop"], 1e12, 1e9):  # critical, overdamped, underdamped
        params = vgt.replace(c_stop=c_stop, Fc=0.0, sigma2=0.0)  # the stop and spring alone
        jac = _jacobian_at_rest(params, CoulombViscous())
        poles = np.linalg.eigvals(jac[:2, :2])
        euler = min(2.0 * -lam.real / abs(lam) ** 2 for lam in poles)
        limit = explicit_step_limit(params["m"], params["k"], params["F0"], params["k_stop"],
                                    c_stop)
        assert limit == pytest.approx(euler, rel=1e-6)


@pytest.mark.parametrize("valve", ["source", "command"])
def test_the_softer_stop_damping_leaves_the_loop_as_it_was(valve, vgt):
    """Issue 39: the default c_stop went from 1e12 to 5e10; the loop width of the default
    cycle moves by less than 1e-5, the rest position not at all."""
    from pneumact.core.features import loop_width_pressure
    from pneumact.experiments.actuator import CommandCycle, PressureCycle

    runs = []
    for params in (vgt.replace(c_stop=1e12), vgt):
        model = Actuator(params, valve=PressureSource() if valve == "source" else CommandValve())
        r = simulate(model, PressureCycle() if valve == "source" else CommandCycle())
        runs.append((loop_width_pressure(r["pressure"], r["position"]), r["position"][0]))
    (width_before, rest_before), (width, rest) = runs
    assert abs(width - width_before) <= STOP_DAMPING_LOOP_WIDTH_CHANGE * width_before
    assert rest == rest_before


# ----------------------------------------------------------------------------- regulator
def test_regulator_settles_on_a_constant_set_point(vgt):
    model = Actuator(vgt, valve=PressureRegulator())
    experiment = Experiment(Step(0.2, 90e3, 50e3), "pressure", t_end=3.0, n_points=3001)
    r = simulate(model, experiment, SOLVER)
    late = r.time >= 2.0
    assert np.abs(r["pressure"][late] - 50e3).max() <= REGULATOR_STEADY_ERROR


def test_regulator_follows_a_slow_ramp(vgt):
    model = Actuator(vgt, valve=PressureRegulator())
    drive = Ramp(90e3, 30e3, duration=10.0, t_start=0.5)
    experiment = Experiment(drive, "pressure", t_end=12.0, n_points=6001)
    r = simulate(model, experiment, SOLVER)
    error = np.abs(r["pressure"] - drive(r.time))
    on_ramp = (r.time >= 1.5) & (r.time <= 10.5)  # after the start-up transient
    assert error[on_ramp].max() <= REGULATOR_RAMP_ERROR
    assert error[-1] <= REGULATOR_STEADY_ERROR


# --------------------------------------------------------------------- static equilibria
@pytest.mark.parametrize(("valve", "quantity", "value"), [
    (PressureSource(), "pressure", 60e3),
    (CommandValve(), "command", 0.5),
    (PressureRegulator(), "pressure", 60e3),
], ids=["source", "command", "regulator"])
def test_equilibrium_start_stays_still(valve, quantity, value, vgt):
    model = Actuator(vgt, valve=valve)
    r = simulate(model, Experiment(Constant(value), quantity, t_end=2.0), SOLVER)
    assert 0.0 < r["position"][0] < vgt["x_max"]
    assert np.ptp(r["position"]) <= EQUILIBRIUM_DRIFT_POSITION
    assert np.abs(r["velocity"]).max() <= EQUILIBRIUM_DRIFT_VELOCITY


def test_constant_external_load_shifts_the_rest_position_by_load_over_stiffness(vgt):
    """A load present from the start: the actuator starts at rest −F_ext/k from where it
    rests without it, and stays there (the net force, friction's included, is zero)."""
    load = 10.0  # N, opposing motion towards larger x
    experiment = Experiment(Constant(60e3), "pressure", t_end=2.0, n_points=201)
    x_free = simulate(Actuator(vgt), experiment, SOLVER)["position"]
    x_loaded = simulate(Actuator(vgt, load=Constant(load)), experiment, SOLVER)["position"]
    assert x_loaded[0] - x_free[0] == pytest.approx(-load / vgt["k"], rel=LOAD_SHIFT_RTOL)
    assert np.ptp(x_loaded) <= EQUILIBRIUM_DRIFT_POSITION


def test_a_load_step_moves_the_actuator_until_friction_holds_it(vgt):
    """A load applied at 0.5 s (60 N, about 20 Fs): the actuator moves and comes to rest
    within ±Fs/k of −F_ext/k from where it was (LuGre's band of rest positions; a tenth
    of the load lost is twice that band)."""
    load = 60.0
    experiment = Experiment(Constant(60e3), "pressure", t_end=2.0, n_points=201)
    x_loaded = simulate(Actuator(vgt, load=Step(0.5, 0.0, load)), experiment,
                        SOLVER)["position"]
    shift = x_loaded[-1] - x_loaded[0]
    assert abs(shift) > 0.5 * load / vgt["k"]  # it moved
    assert abs(shift + load / vgt["k"]) <= vgt["Fs"] / vgt["k"]
    assert abs(x_loaded[-1] - x_loaded[-20]) <= EQUILIBRIUM_DRIFT_POSITION  # at rest

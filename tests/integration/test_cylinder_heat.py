"""The cylinder's chambers with heat transfer (issue 41, item 4): known answers.

The energy equation with the gas temperature as a state and Newton's heat transfer to
walls at the set's T (``HeatTransfer()``): a closed chamber relaxes to the wall
temperature with the time constant m·c_v/(h·A_w); without heat transfer closed chambers
follow the adiabatic closed form, with a large one the isothermal; each chamber's mass
and energy balance in the right-hand side, and its mass balance along a run; forward
sensitivities against differences. One kernel (LuGre, the second-order spool, heat
transfer), shared with the spool's step response.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import cumulative_simpson

import pneumact as pa
from conftest import load_quietly
from pneumact.core.signals import Constant, Sine
from pneumact.experiments import SpoolStep
from pneumact.models import HeatTransfer
from pneumact.simulation import Rodas4
from pneumact.simulation.simulate import prepare
from reference import (
    CYLINDER_HEAT_ISOTHERMAL_RTOL,
    CYLINDER_MASS_BALANCE_RTOL,
    CYLINDER_MASS_RATE_RTOL,
    CYLINDER_POLYTROPIC_RTOL,
    CYLINDER_RELAXATION_RTOL,
    CYLINDER_RTOL,
    ISO_RHO0,
    ISO_T0,
    SENS_FD_REL_STEP,
    SENS_REFERENCE_RTOL,
    SENS_RMS_FRACTION,
    SENS_RTOL,
)

SOLVER = Rodas4(rtol=CYLINDER_RTOL)
LOAD = 200.0  # N against extension
HEAT_PLAUSIBLE_MAX = 2000.0  # W/(m²·K): a larger h warns
START = {"position": 0.1, "velocity": 0.0, "pressure_a": 4e5, "pressure_b": 4e5}


def _cylinder(params, **kwargs):
    """The one heat-transfer kernel of these tests."""
    return pa.Cylinder(params, chamber=HeatTransfer(), spool_lag=2, **kwargs)


@pytest.fixture(scope="module")
def cylinder_set():
    return load_quietly("iso15552-32")


def _geometry(params, x):
    """(V_a, V_b, A_w,a, A_w,b): volumes and wall areas, the chambers as bore-sized
    cylinders of length V/A with both ends (docs/model.md)."""
    bore, rod = params["D_bore"], params["d_rod"]
    area_a, area_b = math.pi * bore**2 / 4.0, math.pi * (bore**2 - rod**2) / 4.0
    vol_a = params["chamber_a.V_dead"] + area_a * x
    vol_b = params["chamber_b.V_dead"] + area_b * (params["x_max"] - x)
    return (vol_a, vol_b, 2.0 * area_a + math.pi * bore * vol_a / area_a,
            2.0 * area_b + math.pi * (bore + rod) * vol_b / area_b)


def test_a_closed_chamber_relaxes_to_the_wall_with_its_time_constant(cylinder_set):
    """A rodless piston mid-stroke between two equal closed chambers of hot air stays put
    (equal pressures), and each chamber's temperature falls to the wall's as
    T_w + (T0 − T_w)·exp(−t/τ), τ = m·c_v/(h·A_w), its pressure as m·R·T/V."""
    params = cylinder_set.replace(d_rod=0.0, valve_leak=0.0)
    hot, p0 = 350.0, 4e5
    start = {**START, "temperature_a": hot, "temperature_b": hot}
    run = pa.simulate(_cylinder(params), pa.Experiment(Constant(0.0), "spool", 2.0,
                                                       n_points=2001), SOLVER, y0=start)
    assert np.ptp(run["position"]) < 1e-12
    volume, _, wall, _ = _geometry(params, START["position"])
    gas_r, t_wall = params["R"], params["T"]
    mass = p0 * volume / (gas_r * hot)
    tau = mass * gas_r / (params["gamma"] - 1.0) / (params["heat_transfer_coefficient"]
                                                    * wall)
    assert run.time[-1] > 4.0 * tau, "the temperature must relax for this test to bite"
    closed_form = t_wall + (hot - t_wall) * np.exp(-run.time / tau)
    for side in ("a", "b"):
        temperature = run[f"temperature_{side}"]
        assert np.abs(temperature - closed_form).max() <= CYLINDER_RELAXATION_RTOL * hot
        pressure = mass * gas_r * closed_form / volume
        assert np.abs(run[f"pressure_{side}"] - pressure).max() <= (
            CYLINDER_RELAXATION_RTOL * p0)


def _closed_run(params, h):
    """The valve closed without leakage, no friction but viscous, a load on the rod: the
    piston, released mid-stroke, moves onto two gas springs."""
    changes = {"Fc": 0.0, "Fs": 0.0, "valve_leak": 0.0, "heat_transfer_coefficient": h}
    if h > HEAT_PLAUSIBLE_MAX:
        with pytest.warns(pa.PlausibilityWarning, match="heat_transfer_coefficient"):
            params = params.replace(**changes)
    else:
        params = params.replace(**changes)
    model = _cylinder(params, load=Constant(LOAD))
    experiment = pa.Experiment(Constant(0.0), "spool", 1.0, n_points=2001)
    return params, pa.simulate(model, experiment, SOLVER, y0=START)


def test_without_heat_transfer_closed_chambers_are_adiabatic(cylinder_set):
    """h = 0: each closed chamber's pressure is p0·(V0/V)^γ and its temperature
    T0·(V0/V)^(γ−1) as the load pushes the piston in."""
    params, run = _closed_run(cylinder_set, 0.0)
    assert np.ptp(run["position"]) > 0.01, "the piston must move for this test to bite"
    gamma, t0 = params["gamma"], params["T"]
    vol_a, vol_b, _, _ = _geometry(params, run["position"])
    for side, volume in (("a", vol_a), ("b", vol_b)):
        ratio = volume[0] / volume
        p0 = START[f"pressure_{side}"]
        assert np.abs(run[f"pressure_{side}"] - p0 * ratio**gamma).max() <= (
            CYLINDER_POLYTROPIC_RTOL * p0)
        assert np.abs(run[f"temperature_{side}"] - t0 * ratio ** (gamma - 1.0)).max() <= (
            CYLINDER_POLYTROPIC_RTOL * t0)


def test_a_large_heat_transfer_approaches_the_isothermal_chamber(cylinder_set):
    """As h grows the closed chambers' pressures approach the isothermal p0·V0/V, the
    departure shrinking as 1/h (h far beyond real walls': the limit, not a cylinder)."""
    departures = []
    for h in (1e7, 1e9):
        params, run = _closed_run(cylinder_set, h)
        vol_a, vol_b, _, _ = _geometry(params, run["position"])
        departures.append(max(
            np.abs(run[f"pressure_{side}"] - START[f"pressure_{side}"] * vol[0] / vol).max()
            / START[f"pressure_{side}"] for side, vol in (("a", vol_a), ("b", vol_b))))
    assert departures[1] <= CYLINDER_HEAT_ISOTHERMAL_RTOL
    assert 50.0 <= departures[0] / departures[1] <= 200.0


def _iso6358(p_up, p_down, t_up, params):
    """ISO 6358 mass flow per unit conductance from p_up to p_down at the upstream
    temperature t_up, written out (choked or subsonic)."""
    r, b = p_down / p_up, params["iso_b"]
    phi = 1.0 if r <= b else (1.0 - ((r - b) / (1.0 - b)) ** 2) ** params["iso_m"]
    return ISO_RHO0 * p_up * math.sqrt(ISO_T0 / t_up) * phi


def _path_inflow(p_node, pressure, temperature, params):
    """(mass inflow, T_up·mass inflow) per unit conductance from a node at the set's T
    into a chamber at (pressure, temperature), the upstream side's temperature."""
    t_node = params["T"]
    if p_node >= pressure:
        q = _iso6358(p_node, pressure, t_node, params)
        return q, t_node * q
    q = -_iso6358(pressure, p_node, temperature, params)
    return q, temperature * q


# (x, v, p_a, p_b, T_a, T_b): filling A while B vents, the reverse, and a flow back into
# the supply from a chamber above it (A at 7.3 bar, hot)
STATES = [(0.05, 0.3, 2e5, 6e5, 330.0, 260.0), (0.15, -0.8, 5.5e5, 1.3e5, 280.0, 310.0),
          (0.1, 0.2, 7.3e5, 4e5, 360.0, 293.15)]


@pytest.mark.parametrize("u", [0.4, -0.7])
def test_mass_and_energy_balance_of_each_chamber_in_the_right_hand_side(u, cylinder_set):
    """At any state: d(p·V/(R·T))/dt = ṁ, the sum of the ISO 6358 path flows at their
    upstream temperatures, and d(p·V)/dt/(γ − 1) = c_p·Σ T_up·q + h·A_w·(T_w − T) − p·dV/dt,
    the chamber's internal energy balance."""
    params = cylinder_set.replace(iso_b=0.25)
    prep = prepare(_cylinder(params), pa.Experiment(Constant(u), "spool", 1.0), SOLVER)
    kernel, names = prep.kernel, prep.assembly.output_names
    state_names = prep.assembly.state_names
    gamma, gas_r, h = params["gamma"], params["R"], params["heat_transfer_coefficient"]
    c, leak = params["valve_C"], params["valve_leak"]
    area_a = math.pi * params["D_bore"] ** 2 / 4.0
    area_b = area_a - math.pi * params["d_rod"] ** 2 / 4.0
    openings = {"a": (max(u, 0.0) + leak, max(-u, 0.0) + leak),
                "b": (max(-u, 0.0) + leak, max(u, 0.0) + leak)}
    for x, v, p_a, p_b, t_a, t_b in STATES:
        y = np.zeros(kernel.NSTATE)
        values = {"position": x, "velocity": v, "pressure_a": p_a, "pressure_b": p_b,
                  "temperature_a": t_a, "temperature_b": t_b, "spool_position": u}
        for name, value in values.items():
            y[state_names.index(name)] = value
        dydt, out = np.empty(kernel.NSTATE), np.empty(kernel.NOUT)
        kernel.rhs(0.5, 0.5, y, prep.vector, prep.sig, prep.ptr, dydt)
        kernel.outputs(0.5, 0.5, y, prep.vector, prep.sig, prep.ptr, out)
        vol_a, vol_b, wall_a, wall_b = _geometry(params, x)
        for side, volume, vol_rate, wall in (("a", vol_a, area_a * v, wall_a),
                                             ("b", vol_b, -area_b * v, wall_b)):
            pressure, temperature = values[f"pressure_{side}"], values[f"temperature_{side}"]
            p_rate = dydt[state_names.index(f"pressure_{side}")]
            t_rate = dydt[state_names.index(f"temperature_{side}")]
            fill, vent = openings[side]
            supply = _path_inflow(params["p_supply"], pressure, temperature, params)
            exhaust = _path_inflow(params["p_atm"], pressure, temperature, params)
            mdot = c * (fill * supply[0] + vent * exhaust[0])
            carried = c * (fill * supply[1] + vent * exhaust[1])
            mass_rate = ((p_rate * volume + pressure * vol_rate) / (gas_r * temperature)
                         - pressure * volume * t_rate / (gas_r * temperature**2))
            flow = out[names.index(f"mass_flow_{side}")]
            scale = max(abs(mdot), c * leak * ISO_RHO0 * 1e5)
            assert abs(flow - mdot) <= CYLINDER_MASS_RATE_RTOL * scale, (side, x)
            assert abs(mass_rate - mdot) <= CYLINDER_MASS_RATE_RTOL * scale, (side, x)
            energy_rate = (p_rate * volume + pressure * vol_rate) / (gamma - 1.0)
            c_p = gamma * gas_r / (gamma - 1.0)
            balance = (c_p * carried + h * wall * (params["T"] - temperature)
                       - pressure * vol_rate)
            terms = max(abs(c_p * carried), abs(pressure * vol_rate), abs(energy_rate))
            assert abs(energy_rate - balance) <= CYLINDER_MASS_RATE_RTOL * terms, (side, x)


def test_mass_balance_of_each_chamber_along_a_run(cylinder_set):
    """∫ṁ dt equals the change of the gas mass p·V/(R·T) of each chamber, T its state,
    while the spool swings both ways and the piston travels."""
    experiment = pa.Experiment(Sine(0.3, 2.0), "spool", 1.0, n_points=40001)
    run = pa.simulate(_cylinder(cylinder_set), experiment, SOLVER)
    assert np.ptp(run["position"]) > 0.05, "the piston must travel for this test to bite"
    assert np.ptp(run["temperature_a"]) > 10.0, "and the gas's temperature change"
    vol_a, vol_b, _, _ = _geometry(cylinder_set, run["position"])
    for side, volume in (("a", vol_a), ("b", vol_b)):
        mass = run[f"pressure_{side}"] * volume / (cylinder_set["R"]
                                                   * run[f"temperature_{side}"])
        inflow = cumulative_simpson(run[f"mass_flow_{side}"], x=run.time, initial=0.0)
        assert np.abs(mass - mass[0] - inflow).max() <= CYLINDER_MASS_BALANCE_RTOL * np.ptp(
            mass)


def test_the_actuator_refuses_heat_transfer(vgt):
    """The diaphragm actuator's chamber has no temperature state: one error saying so."""
    with pytest.raises(pa.ArgumentError, match="only the cylinder's chambers carry a "
                                               "temperature"):
        pa.Actuator(vgt, valve=pa.CommandValve(), chamber=HeatTransfer())


@pytest.mark.parametrize("name", ["heat_transfer_coefficient", "valve_C", "D_bore",
                                  "chamber_a.V_dead"])
def test_forward_sensitivities_match_central_differences(name, cylinder_set):
    """∂(p_a, T_a, x)/∂θ carried through a spool step against central differences of two
    runs: the heat transfer coefficient, a flow entry, the bore (the wall's perimeter) and
    chamber A's dead volume (an instance's parameter)."""
    experiment = SpoolStep(before=-0.3, after=0.4, t_step=0.02, t_end=0.15, n_points=151)
    signals = ("pressure_a", "temperature_a", "position")
    sens = pa.simulate_sensitivities(_cylinder(cylinder_set), experiment, [name],
                                     Rodas4(rtol=SENS_RTOL))
    value = cylinder_set[name]
    step = SENS_FD_REL_STEP * value
    runs = [pa.simulate(_cylinder(cylinder_set.replace({name: value + sign * step})),
                        experiment, Rodas4(rtol=SENS_REFERENCE_RTOL)) for sign in (1, -1)]
    for signal in signals:
        difference = (runs[0][signal] - runs[1][signal]) / (2.0 * step)
        size = np.abs(difference).max()
        rms = np.sqrt(np.mean((sens[signal][:, 0] - difference) ** 2))
        assert size > 0.0 and rms <= SENS_RMS_FRACTION * size, (name, signal, rms, size)

"""The double-acting cylinder behind a 5/3 valve (issue 41, item 4): known answers.

Each chamber's mass balance (its right-hand side at any state, and ∫ṁ dt along a run),
the closed chambers' polytropic law against p0·(V0/V)^n, the static force balance at rest
against the closed-form rest position of two isothermal gas springs, and the valve's flows
against the ISO 6358 law written out here, at choked and subsonic ratios. Two kernels
(LuGre, the spool ideal or lagged): the chamber law and the parameters are values, not
compile-time choices.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import cumulative_simpson
from scipy.optimize import brentq

import pneumact as pa
from conftest import load_quietly
from pneumact.core.signals import Constant, Sine
from pneumact.experiments import SpoolStep
from pneumact.models import HeatTransfer
from pneumact.simulation import Rodas4
from pneumact.simulation.simulate import prepare
from reference import (
    CYLINDER_MASS_BALANCE_RTOL,
    CYLINDER_MASS_RATE_RTOL,
    CYLINDER_POLYTROPIC_RTOL,
    CYLINDER_REST_POSITION_ATOL,
    CYLINDER_RTOL,
    CYLINDER_SPOOL_LAG_ATOL,
    CYLINDER_STATIC_RTOL,
    CYLINDER_VALVE_FLOW_RTOL,
    ISO_RHO0,
    ISO_T0,
)

SOLVER = Rodas4(rtol=CYLINDER_RTOL)
LOAD = 200.0  # N against extension
START = {"position": 0.1, "velocity": 0.0, "pressure_a": 4e5, "pressure_b": 4e5}


@pytest.fixture(scope="module")
def cylinder_set():
    return load_quietly("iso15552-32")


def _areas(params):
    bore, rod = params["D_bore"], params["d_rod"]
    return math.pi * bore**2 / 4.0, math.pi * (bore**2 - rod**2) / 4.0


def _unequal_chambers(params):
    """``params`` with chamber B's dead volume 2.5 times chamber A's: a chamber reading
    the other's instance shows."""
    return params.replace({"chamber_b.V_dead": 2.5 * params["chamber_a.V_dead"]})


def _volumes(params, x):
    area_a, area_b = _areas(params)
    return (params["chamber_a.V_dead"] + area_a * x,
            params["chamber_b.V_dead"] + area_b * (params["x_max"] - x))


# ------------------------------------------------------------------ chamber mass balance
def test_mass_balance_of_each_chamber_in_the_right_hand_side(cylinder_set):
    """Isothermal: d(p·V)/dt = R·T·ṁ for each chamber at states across the stroke, the
    spool both ways, choked and subsonic; the chambers' dead volumes differ."""
    cylinder_set = _unequal_chambers(cylinder_set)
    model = pa.Cylinder(cylinder_set)
    rt = cylinder_set["R"] * cylinder_set["T"]
    area_a, area_b = _areas(cylinder_set)
    for u in (-0.7, 0.0, 0.4):
        prep = prepare(model, pa.Experiment(Constant(u), "spool", 1.0), SOLVER)
        kernel = prep.kernel
        for x, v, pa_, pb_ in ((0.05, 0.3, 2e5, 6e5), (0.15, -0.8, 5.5e5, 1.3e5),
                               (0.1, 0.0, 4e5, 4e5)):
            y = np.array([x, v, pa_, pb_, 1e-5])
            dydt, out = np.empty(5), np.empty(kernel.NOUT)
            kernel.rhs(0.5, 0.5, y, prep.vector, prep.sig, prep.ptr, dydt)
            kernel.outputs(0.5, 0.5, y, prep.vector, prep.sig, prep.ptr, out)
            names = prep.assembly.output_names
            vol_a, vol_b = _volumes(cylinder_set, x)
            rate_a = dydt[2] * vol_a + pa_ * area_a * v
            rate_b = dydt[3] * vol_b - pb_ * area_b * v
            for rate, flow in ((rate_a, out[names.index("mass_flow_a")]),
                               (rate_b, out[names.index("mass_flow_b")])):
                scale = max(abs(rate), abs(rt * flow), 1e-30)
                assert abs(rate - rt * flow) <= CYLINDER_MASS_RATE_RTOL * scale, (u, x, v)


def test_mass_balance_of_each_chamber_along_a_run(cylinder_set):
    """Isothermal: ∫ṁ dt equals the change of the gas mass p·V/(R·T) of each chamber,
    while the spool swings both ways and the piston travels."""
    model = pa.Cylinder(cylinder_set)
    experiment = pa.Experiment(Sine(0.3, 2.0), "spool", 1.0, n_points=40001)
    r = pa.simulate(model, experiment, SOLVER)
    assert np.ptp(r["position"]) > 0.05, "the piston must travel for this test to bite"
    rt = cylinder_set["R"] * cylinder_set["T"]
    vol_a, vol_b = _volumes(cylinder_set, r["position"])
    for pressure, volume, flow in ((r["pressure_a"], vol_a, r["mass_flow_a"]),
                                   (r["pressure_b"], vol_b, r["mass_flow_b"])):
        mass = pressure * volume / rt
        inflow = cumulative_simpson(flow, x=r.time, initial=0.0)
        error = np.abs(mass - mass[0] - inflow).max()
        assert error <= CYLINDER_MASS_BALANCE_RTOL * np.ptp(mass)


# ------------------------------------------------------ closed chambers and the rest state
@pytest.fixture(scope="module")
def closed_runs(cylinder_set):
    """Valve closed without leakage, no friction but viscous, a load on the rod: the
    piston, released mid-stroke with equal pressures, settles on two gas springs."""
    params = _unequal_chambers(cylinder_set).replace(Fc=0.0, Fs=0.0, valve_leak=0.0)
    experiment = pa.Experiment(Constant(0.0), "spool", 1.0, n_points=5001)
    runs = {}
    for chamber in (pa.Isothermal(), pa.Adiabatic()):
        model = pa.Cylinder(params, chamber=chamber, load=Constant(LOAD))
        runs[type(chamber).__name__] = pa.simulate(model, experiment, SOLVER, y0=START)
    return params, runs


@pytest.mark.parametrize("chamber", ["Isothermal", "Adiabatic"])
def test_closed_chamber_compression_follows_the_closed_form(chamber, closed_runs):
    """No flow through the closed valve, and each chamber's pressure is p0·(V0/V)^n
    (n = 1, γ) as the load pushes the piston in."""
    params, runs = closed_runs
    r = runs[chamber]
    n = 1.0 if chamber == "Isothermal" else params["gamma"]
    x = r["position"]
    assert np.ptp(x) > 0.01, "the piston must move for this test to bite"
    assert np.all(r["mass_flow_a"] == 0.0) and np.all(r["mass_flow_b"] == 0.0)
    vol_a, vol_b = _volumes(params, x)
    for pressure, volume, p0 in ((r["pressure_a"], vol_a, START["pressure_a"]),
                                 (r["pressure_b"], vol_b, START["pressure_b"])):
        closed_form = p0 * (volume[0] / volume) ** n
        assert np.abs(pressure - closed_form).max() <= CYLINDER_POLYTROPIC_RTOL * p0


def test_static_force_balance_at_rest(closed_runs):
    """At rest (p_a − p_atm)·A_a − (p_b − p_atm)·A_b = F_load, at the position where two
    isothermal gas springs, p·V constant, hold the load."""
    params, runs = closed_runs
    r = runs["Isothermal"]
    area_a, area_b = _areas(params)
    p_atm = params["p_atm"]
    assert abs(r["velocity"][-1]) < 1e-9
    force = (r["pressure_a"][-1] - p_atm) * area_a - (r["pressure_b"][-1] - p_atm) * area_b
    assert abs(force - LOAD) <= CYLINDER_STATIC_RTOL * LOAD
    assert abs(r["pressure_force"][-1] - LOAD) <= CYLINDER_STATIC_RTOL * LOAD
    vol_a0, vol_b0 = _volumes(params, START["position"])

    def net(x):
        vol_a, vol_b = _volumes(params, x)
        return ((START["pressure_a"] * vol_a0 / vol_a - p_atm) * area_a
                - (START["pressure_b"] * vol_b0 / vol_b - p_atm) * area_b - LOAD)

    x_rest = brentq(net, 0.0, params["x_max"], xtol=1e-15)
    assert abs(r["position"][-1] - x_rest) <= CYLINDER_REST_POSITION_ATOL


# ------------------------------------------------------------------------ the 5/3 valve
def _iso6358(conductance, p_up, p_down, params):
    """ISO 6358 mass flow from p_up to p_down, written out (subsonic or choked)."""
    r, b = p_down / p_up, params["iso_b"]
    phi = 1.0 if r <= b else (1.0 - ((r - b) / (1.0 - b)) ** 2) ** params["iso_m"]
    return conductance * ISO_RHO0 * p_up * math.sqrt(ISO_T0 / params["T"]) * phi


def _opening(travel, overlap):
    """A path's opening as docs/model.md writes it: a(w) = max(w − e, 0)/(1 − e)."""
    return max(travel - overlap, 0.0) / (1.0 - overlap)


def _valve_outputs(params, u, p_a, p_b):
    """(ṁ_a, ṁ_b) of the kernel at spool position u (the lagged spool's state: one kernel
    for every u) and chamber pressures p_a, p_b."""
    model = pa.Cylinder(params, spool_lag=True)
    prep = prepare(model, pa.Experiment(Constant(0.0), "spool", 1.0), SOLVER)
    kernel, names = prep.kernel, prep.assembly.output_names
    out = np.empty(kernel.NOUT)
    kernel.outputs(0.5, 0.5, np.array([0.1, 0.0, p_a, p_b, 0.0, u]), prep.vector, prep.sig,
                   prep.ptr, out)
    return out[names.index("mass_flow_a")], out[names.index("mass_flow_b")]


def _expected_flows(params, u, p_a, p_b):
    """Each chamber's supply path minus its exhaust path, ISO 6358 written out, with the
    opening of docs/model.md (the leakage included); pressures between p_atm and p_s."""
    c, leak, overlap = params["valve_C"], params["valve_leak"], params["spool_overlap"]
    p_s, p_e = params["p_supply"], params["p_atm"]
    extend, retract = _opening(u, overlap) + leak, _opening(-u, overlap) + leak
    return (_iso6358(c * extend, p_s, p_a, params) - _iso6358(c * retract, p_a, p_e, params),
            _iso6358(c * retract, p_s, p_b, params) - _iso6358(c * extend, p_b, p_e, params))


# (u, p_a, p_b): supply → A choked (r = 0.2) and B → exhaust subsonic (r = 0.8), then the
# reverse; and retracting: A → exhaust choked, supply → B subsonic
VALVE_CASES = [(0.6, 1.4e5, 1.25e5), (0.6, 4.9e5, 6e5), (-0.35, 6e5, 4.9e5),
               (-1.0, 1.25e5, 1.4e5)]


@pytest.mark.parametrize("overlap", [0.0, 0.15, -0.1], ids=["critical", "overlap",
                                                            "underlap"])
@pytest.mark.parametrize(("u", "p_a", "p_b"), VALVE_CASES)
def test_valve_flows_follow_iso6358(u, p_a, p_b, overlap, cylinder_set):
    """Each open path of the 5/3 valve is an ISO 6358 flow of conductance C·a(±u) (no
    leakage; a gas temperature off T0 and a datasheet's b and m), a the opening past the
    spool's overlap."""
    params = cylinder_set.replace(valve_leak=0.0, T=313.15, iso_b=0.25, iso_m=0.6,
                                  spool_overlap=overlap)
    prep = prepare(pa.Cylinder(params), pa.Experiment(Constant(u), "spool", 1.0), SOLVER)
    kernel, names = prep.kernel, prep.assembly.output_names
    out = np.empty(kernel.NOUT)
    y = np.array([0.1, 0.0, p_a, p_b, 0.0])
    kernel.outputs(0.5, 0.5, y, prep.vector, prep.sig, prep.ptr, out)
    conductance = params["valve_C"] * _opening(abs(u), overlap)
    p_s, p_e = params["p_supply"], params["p_atm"]
    if u > 0:
        expected_a = _iso6358(conductance, p_s, p_a, params)
        expected_b = -_iso6358(conductance, p_b, p_e, params)
    else:
        expected_a = -_iso6358(conductance, p_a, p_e, params)
        expected_b = _iso6358(conductance, p_s, p_b, params)
    ratios = (p_a / p_s, p_e / p_b) if u > 0 else (p_e / p_a, p_b / p_s)
    assert min(ratios) <= params["iso_b"] < max(ratios)  # one choked, one subsonic path
    for name, expected in (("mass_flow_a", expected_a), ("mass_flow_b", expected_b)):
        got = out[names.index(name)]
        assert abs(got - expected) <= CYLINDER_VALVE_FLOW_RTOL * abs(expected), name


def test_an_overlapped_spool_passes_only_its_leakage_inside_the_band(cylinder_set):
    """Overlap 0.15: for |u| ≤ 0.15 only the leakage flows (as at the centre), none
    without it; just past the band the paths open."""
    params = cylinder_set.replace(spool_overlap=0.15)
    p_a, p_b = 2.5e5, 4.5e5
    centre = _valve_outputs(params, 0.0, p_a, p_b)
    expected = _expected_flows(params, 0.0, p_a, p_b)
    for u in (-0.15, -0.08, 0.1, 0.15):
        got = _valve_outputs(params, u, p_a, p_b)
        assert got == centre, u
        for flow, closed_form in zip(got, expected, strict=True):
            assert abs(flow - closed_form) <= CYLINDER_VALVE_FLOW_RTOL * abs(closed_form)
    assert _valve_outputs(params.replace(valve_leak=0.0), 0.12, p_a, p_b) == (0.0, 0.0)
    past = _valve_outputs(params.replace(valve_leak=0.0), 0.2, p_a, p_b)
    assert past[0] > 0.0 > past[1]  # supply → A and B → exhaust open


def test_an_underlapped_spool_opens_both_paths_of_each_chamber_at_the_centre(
        cylinder_set):
    """Underlap 0.1, centred, no leakage: each chamber is fed from the supply and vented
    to the exhaust, both paths by C·0.1/1.1 (ISO 6358 written out), so a chamber at
    supply pressure empties and one at exhaust pressure fills; the two chambers see the
    same valve."""
    params = cylinder_set.replace(spool_overlap=-0.1, valve_leak=0.0)
    p_s, p_e = params["p_supply"], params["p_atm"]
    c_open = params["valve_C"] * 0.1 / 1.1
    for p_a, p_b in ((2e5, 5e5), (4e5, 4e5)):
        got = _valve_outputs(params, 0.0, p_a, p_b)
        for flow, p in zip(got, (p_a, p_b), strict=True):
            expected = _iso6358(c_open, p_s, p, params) - _iso6358(c_open, p, p_e, params)
            assert abs(flow - expected) <= CYLINDER_VALVE_FLOW_RTOL * abs(expected)
    flow_a, flow_b = _valve_outputs(params, 0.0, p_s, p_e)
    assert flow_a < 0.0 < flow_b


@pytest.mark.parametrize("overlap", [0.15, -0.1], ids=["overlap", "underlap"])
def test_the_valve_opens_continuously_in_the_spool_position(overlap, cylinder_set):
    """No jump in either chamber's flow as the spool crosses the edges ±e of the band:
    across each edge the flow changes by at most the largest slope, two paths of flow at
    most q_max (choked from the supply) opening by 1/(1 − e) per unit u, times the step
    (2e-9), and it follows the written-out opening on both sides."""
    params = cylinder_set.replace(spool_overlap=overlap)
    p_a, p_b, step = 2.5e5, 4.5e5, 1e-9
    q_max = _iso6358(params["valve_C"], params["p_supply"], params["p_atm"], params)
    for edge in (overlap, -overlap):
        below, above = (_valve_outputs(params, edge + sign * step, p_a, p_b)
                        for sign in (-1.0, 1.0))
        for lo, hi in zip(below, above, strict=True):
            assert abs(hi - lo) <= 2.0 * q_max / (1.0 - overlap) * 2.0 * step
        for u in (edge - step, edge + step):
            got, expected = _valve_outputs(params, u, p_a, p_b), _expected_flows(
                params, u, p_a, p_b)
            for flow, closed_form in zip(got, expected, strict=True):
                assert abs(flow - closed_form) <= CYLINDER_VALVE_FLOW_RTOL * abs(closed_form)


def test_valve_command_outside_its_range_is_refused(cylinder_set):
    """A spool command beyond ±1 is impossible: one error naming the range."""
    experiment = pa.Experiment(Constant(1.5), "spool", 1.0)
    with pytest.raises(pa.ExperimentError, match=r"\[-1, 1\]"):
        pa.simulate(pa.Cylinder(cylinder_set), experiment)


@pytest.mark.parametrize(("field", "value", "allowed"), [
    ("d_rod", 0.04, "must be < D_bore"), ("p_supply", 0.9e5, "must be > p_atm"),
    ("valve_leak", 2.0, "must be <= 1"), ("D_bore", 0.0, "must be > 0"),
    ("spool_overlap", 0.7, "must be <= 0.5")])
def test_impossible_cylinders_are_refused(field, value, allowed, cylinder_set):
    """A rod wider than the bore, a supply below the atmosphere, a leakage above the
    valve's own conductance, no bore: one error naming the field, value and range."""
    with pytest.raises(pa.ParameterError, match=allowed) as err:
        cylinder_set.replace(**{field: value})
    assert f"{field} = {value:g}" in str(err.value)


def test_a_set_without_a_cylinder_is_refused(vgt):
    """A diaphragm actuator's set lacks the bore, rod, dead volumes, supply and valve."""
    with pytest.raises(pa.ParameterError, match="lacks D_bore, d_rod"):
        pa.Cylinder(vgt)


def test_the_lagged_spool_follows_its_first_order_law(cylinder_set):
    """Cylinder(spool_lag=True): after a step of its command the spool moves as
    u(t) = u1 + (u0 − u1)·exp(−(t − t_step)/τ), and the piston starts later than behind an
    ideal spool."""
    experiment = SpoolStep(before=-1.0, after=0.5, t_step=0.1, t_end=0.4, n_points=3001)
    lagged = pa.simulate(pa.Cylinder(cylinder_set, spool_lag=True), experiment, SOLVER)
    ideal = pa.simulate(pa.Cylinder(cylinder_set), experiment, SOLVER)
    tau, t = cylinder_set["spool_tau"], lagged.time
    expected = np.where(t < 0.1, -1.0, 0.5 - 1.5 * np.exp(-(t - 0.1) / tau))
    assert np.abs(lagged["spool"] - expected).max() <= CYLINDER_SPOOL_LAG_ATOL
    started = [run.time[np.argmax(run["position"] > 1e-3)] for run in (lagged, ideal)]
    assert started[0] > started[1]


@pytest.mark.parametrize("zeta", [0.3, 1.5], ids=["underdamped", "overdamped"])
def test_the_second_order_spool_follows_its_step_response(zeta, cylinder_set):
    """Cylinder(spool_lag=2): after a step of its command from u0 to u1 the spool moves as
    the closed-form step response of ü = ω²·(u1 − u) − 2·ζ·ω·u̇ from rest, under- and
    overdamped, overshooting the command when ζ < 1."""
    params = cylinder_set.replace(spool_zeta=zeta)
    u0, u1, t_step = -0.5, 0.4, 0.05
    experiment = SpoolStep(before=u0, after=u1, t_step=t_step, t_end=0.1, n_points=2001)
    model = pa.Cylinder(params, chamber=HeatTransfer(), spool_lag=2)  # one kernel with
    run = pa.simulate(model, experiment, SOLVER)  # test_cylinder_heat.py's
    omega, t = params["spool_omega"], np.maximum(run.time - t_step, 0.0)
    if zeta < 1.0:
        damped = omega * math.sqrt(1.0 - zeta**2)
        shape = np.exp(-zeta * omega * t) * (np.cos(damped * t) + zeta * omega / damped
                                             * np.sin(damped * t))
    else:
        root = omega * math.sqrt(zeta**2 - 1.0)
        fast, slow = -zeta * omega - root, -zeta * omega + root
        shape = (fast * np.exp(slow * t) - slow * np.exp(fast * t)) / (fast - slow)
    expected = u1 + (u0 - u1) * shape
    assert np.abs(run["spool"] - expected).max() <= CYLINDER_SPOOL_LAG_ATOL
    overshoot = run["spool"].max() - u1
    assert (overshoot > 0.1) if zeta < 1.0 else (overshoot <= 0.0)


def test_a_spool_lag_of_no_known_order_is_refused(cylinder_set):
    with pytest.raises(pa.ArgumentError, match=r"spool_lag = 3: must be False or 0"):
        pa.Cylinder(cylinder_set, spool_lag=3)


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"after": 1.5}, r"after = 1.5: must be in \[-1, 1\]"),
    ({"t_step": 0.0}, "t_step"), ({"t_step": 0.5, "t_end": 0.4}, "t_end = 0.4 s")])
def test_impossible_spool_steps_are_refused(kwargs, message):
    with pytest.raises(pa.ExperimentError, match=message):
        SpoolStep(**kwargs)

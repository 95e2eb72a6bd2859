"""Orifice flow function Φ(r) and mass flow (paper eqs. 3-5): known answers and
invariants (continuity, choking, reversal, antisymmetry, finite slope at r → 1)."""

from __future__ import annotations

import numpy as np
import pytest

from pneumact.models import flow_function_values, orifice_mass_flow
from reference import (
    CHOKED_FLOW_COEFF,
    CHOKED_FLOW_RTOL,
    CHOKED_PHI,
    CHOKED_PHI_4_DIGITS,
    COMMAND_STROKE_TOP,
    CRITICAL_RATIO,
    CRITICAL_RATIO_4_DIGITS,
    EXPONENTIAL_DECAY_RTOL,
    FLOW_ANTISYMMETRY_RTOL,
    FLOW_ROUND_OFF_RTOL,
    FREE_FREQUENCY_HZ,
    GAMMA_AIR,
    HAND_VALUE_RTOL,
    LAMINAR_CONDUCTANCE_RTOL,
    PHI_GRID_POINTS,
    PHI_JUMP_SLACK,
    R_AIR,
    ROUND_OFF_ATOL,
    STUCK_FREQUENCY_HZ,
    TEXTBOOK_CRITICAL_RATIO,
    TEXTBOOK_DIGITS,
    TIME_CONSTANT_RATIO_ALONG_STROKE,
    VOLUME_AT_X_MAX,
)

AREA = 1.5e-6  # m², the vgt-paper valve area (any positive value works)


@pytest.fixture
def gas(vgt):
    return vgt.replace(gamma=GAMMA_AIR, R=R_AIR)


def test_critical_ratio_value():
    assert CRITICAL_RATIO == pytest.approx(TEXTBOOK_CRITICAL_RATIO, abs=TEXTBOOK_DIGITS)


def test_phi_is_the_choked_constant_below_critical_ratio(gas):
    r = np.linspace(0.0, CRITICAL_RATIO, 1001)
    phi = flow_function_values(r, gas["gamma"], gas["r_lin"])
    np.testing.assert_allclose(phi, CHOKED_PHI, rtol=FLOW_ROUND_OFF_RTOL)


def test_phi_is_continuous_everywhere(gas):
    r_lin = gas["r_lin"]
    r = np.linspace(0.0, 1.0, PHI_GRID_POINTS)
    phi = flow_function_values(r, gas["gamma"], r_lin)
    # steepest part of the curve: the laminar branch slope Φ(r_lin)/(1 − r_lin)
    max_slope = flow_function_values(r_lin, gas["gamma"], r_lin)[0] / (1.0 - r_lin)
    dr = r[1] - r[0]
    assert np.max(np.abs(np.diff(phi))) <= PHI_JUMP_SLACK * max_slope * dr
    eps = 1e-10
    for corner in (CRITICAL_RATIO, r_lin):
        left, right = flow_function_values([corner - eps, corner + eps], gas["gamma"], r_lin)
        assert abs(right - left) <= PHI_JUMP_SLACK * max_slope * 2 * eps, corner
    assert flow_function_values(1.0, gas["gamma"], r_lin)[0] == 0.0


def test_phi_decreases_from_critical_ratio_to_one(gas):
    r = np.linspace(CRITICAL_RATIO, 1.0, 20001)
    phi = flow_function_values(r, gas["gamma"], gas["r_lin"])
    assert np.all(np.diff(phi) <= ROUND_OFF_ATOL)


def test_choked_mass_flow_textbook_constant(gas):
    p_up = np.array([1e5, 2e5, 5e5])
    mdot = orifice_mass_flow(p_up, 0.3 * p_up, AREA, gas)
    expected = CHOKED_FLOW_COEFF * AREA * p_up / np.sqrt(gas["T"])
    np.testing.assert_allclose(mdot, expected, rtol=CHOKED_FLOW_RTOL)


def test_flow_reverses_and_is_antisymmetric(gas):
    rng = np.random.default_rng(3)
    p1 = rng.uniform(5e3, 2e5, 300)
    p2 = rng.uniform(5e3, 2e5, 300)
    forward = orifice_mass_flow(p1, p2, AREA, gas)
    backward = orifice_mass_flow(p2, p1, AREA, gas)
    np.testing.assert_allclose(forward, -backward, rtol=FLOW_ANTISYMMETRY_RTOL)
    assert np.all(np.sign(forward) == np.sign(p1 - p2))


def test_no_flow_at_equal_pressures(gas):
    p = np.array([1e4, 5e4, 1e5])
    assert np.all(orifice_mass_flow(p, p, AREA, gas) == 0.0)


def test_finite_slope_at_pressure_ratio_one(gas):
    """The laminar branch: ṁ/Δp is the same finite number for tiny Δp."""
    p_up = 1e5
    dp = np.array([1e-2, 1e-1, 1.0, 10.0])  # inside the laminar band (r > r_lin)
    assert np.all(dp / p_up < 1.0 - gas["r_lin"])
    conductance = orifice_mass_flow(np.full_like(dp, p_up), p_up - dp, AREA, gas) / dp
    assert np.all(np.isfinite(conductance)) and np.all(conductance > 0)
    np.testing.assert_allclose(conductance, conductance[-1], rtol=LAMINAR_CONDUCTANCE_RTOL)


def test_flow_decreases_monotonically_with_downstream_pressure(gas):
    p_down = np.linspace(1e3, 3e5, 30001)
    mdot = orifice_mass_flow(np.full_like(p_down, 1e5), p_down, AREA, gas)
    assert np.all(np.diff(mdot) <= 0.0)
    choked = p_down <= CRITICAL_RATIO * 1e5
    np.testing.assert_allclose(mdot[choked], mdot[0], rtol=FLOW_ROUND_OFF_RTOL)


def test_choked_flow_stays_proportional_to_the_upstream_pressure(gas):
    """Issue #40: the paper's 'flow becomes constant when choked' holds for Φ only: at a
    fixed choked ratio, doubling p_up doubles the flow, which is A·p_up·sqrt(γ/(R·T))·Φ*."""
    from pneumact.analysis import choked_limit

    ratio, phi = choked_limit(gas["gamma"])
    assert ratio == pytest.approx(CRITICAL_RATIO_4_DIGITS, abs=5e-5)
    assert phi == pytest.approx(CHOKED_PHI_4_DIGITS, abs=5e-5)
    upstream = np.array([30e3, 60e3, 100e3])
    flow = orifice_mass_flow(upstream, 10e3, AREA, gas)  # r ≤ 1/3: choked
    expected = AREA * upstream * np.sqrt(gas["gamma"] / (gas["R"] * gas["T"])) * phi
    np.testing.assert_allclose(flow, expected, rtol=FLOW_ROUND_OFF_RTOL)
    assert flow[1] / flow[0] == pytest.approx(2.0, rel=FLOW_ROUND_OFF_RTOL)


def test_the_chamber_time_constant_follows_its_volume(vgt):
    """τ(x) = (V0 − A_d·x)/(n·A_res·Φ*·sqrt(γ·R·T)): 7.2× shorter at the top of the
    command stroke than at rest, the chamber 1.55 cm³ at x_max; adiabatic n = γ."""
    from pneumact.analysis import chamber_time_constant, chamber_volume, choked_limit

    tau = chamber_time_constant(vgt, [0.0, COMMAND_STROKE_TOP])
    speed = np.sqrt(vgt["gamma"] * vgt["R"] * vgt["T"])
    at_rest = vgt["V0"] / (vgt["A_res"] * choked_limit(vgt["gamma"])[1] * speed)
    assert tau[0] == pytest.approx(at_rest, rel=FLOW_ROUND_OFF_RTOL)
    assert tau[0] / tau[1] == pytest.approx(TIME_CONSTANT_RATIO_ALONG_STROKE, rel=1e-2)
    assert chamber_volume(vgt, vgt["x_max"]) == pytest.approx(VOLUME_AT_X_MAX, rel=1e-2)
    adiabatic = chamber_time_constant(vgt, 0.0, exponent=vgt["gamma"])
    assert adiabatic == pytest.approx(tau[0] / vgt["gamma"])


def test_natural_frequencies_free_and_stuck_on_the_bristles(vgt):
    from pneumact.analysis import natural_frequencies

    cases = natural_frequencies(vgt)
    assert cases["free"]["frequency"] == pytest.approx(FREE_FREQUENCY_HZ, rel=HAND_VALUE_RTOL)
    stuck = cases["stuck on the bristles"]
    assert stuck["frequency"] == pytest.approx(STUCK_FREQUENCY_HZ, rel=HAND_VALUE_RTOL)
    assert stuck["stiffness"] == vgt["k"] + vgt["sigma0"]
    assert cases["free, closed chamber"]["frequency"] > cases["free"]["frequency"]


def test_a_held_chamber_empties_as_the_choked_time_constant_says(vgt):
    """The model's chamber through the command valve, fully open to the reservoir with the
    diaphragm held at rest: p = p_atm·exp(−t/τ(0)) while the flow is choked."""
    from pneumact.analysis import chamber_time_constant
    from pneumact.experiments import Experiment, Step
    from pneumact.models import Actuator, CommandValve
    from pneumact.simulation import simulate

    run = simulate(Actuator(vgt, valve=CommandValve()),
                   Experiment(Step(0.05, 0.0, 1.0), "command", 0.65, n_points=601),
                   values={"F0": 10 * vgt["p_atm"] * vgt["A_d"]})
    assert np.abs(run["position"]).max() < 1e-4  # held: on the rest stop's contact
    choked = (run.time >= 0.05) & (run["pressure"] > vgt["p_res"] / CRITICAL_RATIO)
    tau = chamber_time_constant(vgt, 0.0)
    expected = vgt["p_atm"] * np.exp(-(run.time[choked] - 0.05) / tau)
    np.testing.assert_allclose(run["pressure"][choked], expected, rtol=EXPONENTIAL_DECAY_RTOL)
    assert choked.sum() > 100

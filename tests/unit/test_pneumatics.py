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
    CRITICAL_RATIO,
    FLOW_ANTISYMMETRY_RTOL,
    FLOW_ROUND_OFF_RTOL,
    GAMMA_AIR,
    LAMINAR_CONDUCTANCE_RTOL,
    PHI_GRID_POINTS,
    PHI_JUMP_SLACK,
    R_AIR,
    ROUND_OFF_ATOL,
    TEXTBOOK_CRITICAL_RATIO,
    TEXTBOOK_DIGITS,
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

"""The ISO 6358 flow law of ``Iso6358Valve`` (issue 41, item 3): the kernel's flow
function against the standard's closed form, its invariants, its joins at r = b and
r = r_lam, and its partial derivatives against central differences."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pneumact.models import conductance_of_area, iso6358_mass_flow, orifice_mass_flow
from pneumact.models.pneumatics import iso_flow, iso_flow_params
from reference import (
    FD_REL_STEP,
    FLOW_ANTISYMMETRY_RTOL,
    ISO_FD_RTOL,
    ISO_FORMULA_RTOL,
    ISO_RHO0,
    ISO_T0,
    ISO_VS_ORIFICE_RTOL,
    LAMINAR_CONDUCTANCE_RTOL,
)

CONDUCTANCE = 3e-9  # m³/(s·Pa): about the vgt-paper valve's 1.5 mm² (any positive value)
# a valve of a datasheet (b, m away from the defaults) and the ISO 6358-1 defaults
DATASHEET = {"iso_b": 0.3, "iso_m": 0.6, "r_lin": 0.995, "T": 300.0}
DEFAULTS = {"iso_b": 0.528, "iso_m": 0.5, "r_lin": 0.999, "T": 293.15}


def closed_form(p_up: float, p_down: float, c: float, b: float, m: float, r_lam: float,
                temperature: float) -> float:
    """ISO 6358-1 (choked, subsonic with ISO 6358-3's index m) and the laminar branch
    q = k·p_up·(1 − r), k chosen so that the flow is continuous at r_lam, written again."""
    r = p_down / p_up
    choked = c * ISO_RHO0 * p_up * math.sqrt(ISO_T0 / temperature)
    if r <= b:
        return choked
    if r < r_lam:
        return choked * (1.0 - ((r - b) / (1.0 - b)) ** 2) ** m
    at_lam = (1.0 - ((r_lam - b) / (1.0 - b)) ** 2) ** m
    return choked * at_lam * (1.0 - r) / (1.0 - r_lam)


@pytest.mark.parametrize("gas", [DATASHEET, DEFAULTS], ids=["datasheet", "defaults"])
@pytest.mark.parametrize("p_down", [0.0, 20e3, 45e3, 70e3, 95e3, 99.6e3, 99.95e3, 100e3],
                         ids=lambda p: f"{p / 1e3:g}kPa")
def test_the_kernel_flow_is_the_iso_formula(gas, p_down):
    """Choked, subsonic and laminar points from 100 kPa upstream."""
    expected = closed_form(100e3, p_down, CONDUCTANCE, gas["iso_b"], gas["iso_m"],
                           gas["r_lin"], gas["T"])
    flow = iso6358_mass_flow(100e3, p_down, CONDUCTANCE, gas)[0]
    assert flow == pytest.approx(expected, rel=ISO_FORMULA_RTOL, abs=1e-30)


def test_choked_flow_is_c_rho0_p_sqrt_t0_over_t():
    """b = 0.528, m = 0.5: below b the flow is C·ρ0·p_up·sqrt(T0/T_up), whatever p_down."""
    p_up = np.array([30e3, 100e3, 600e3])
    for ratio in (0.0, 0.2, 0.528):
        flow = iso6358_mass_flow(p_up, ratio * p_up, CONDUCTANCE, DEFAULTS)
        expected = CONDUCTANCE * ISO_RHO0 * p_up * math.sqrt(ISO_T0 / DEFAULTS["T"])
        np.testing.assert_allclose(flow, expected, rtol=ISO_FORMULA_RTOL)


@pytest.mark.parametrize("gas", [DATASHEET, DEFAULTS], ids=["datasheet", "defaults"])
def test_flow_is_zero_at_equal_pressures_and_follows_the_difference(gas):
    rng = np.random.default_rng(41)
    p1, p2 = rng.uniform(1e3, 7e5, 400), rng.uniform(1e3, 7e5, 400)
    p2[:20] = p1[:20] * (1.0 - rng.uniform(0.0, 1e-3, 20))  # the laminar band too
    forward = iso6358_mass_flow(p1, p2, CONDUCTANCE, gas)
    backward = iso6358_mass_flow(p2, p1, CONDUCTANCE, gas)
    np.testing.assert_allclose(forward, -backward, rtol=FLOW_ANTISYMMETRY_RTOL)
    assert np.all(np.sign(forward) == np.sign(p1 - p2))
    p = np.array([1e4, 1e5, 5e5])
    assert np.all(iso6358_mass_flow(p, p, CONDUCTANCE, gas) == 0.0)


@pytest.mark.parametrize("gas", [DATASHEET, DEFAULTS], ids=["datasheet", "defaults"])
def test_flow_falls_monotonically_with_the_downstream_pressure(gas):
    p_down = np.linspace(0.0, 2e5, 40001)
    flow = iso6358_mass_flow(np.full_like(p_down, 1e5), p_down, CONDUCTANCE, gas)
    assert np.all(np.diff(flow) <= 0.0)
    assert np.all(np.diff(flow)[p_down[1:] > gas["iso_b"] * 1e5 + 10.0] < 0.0)


@pytest.mark.parametrize("gas", [DATASHEET, DEFAULTS], ids=["datasheet", "defaults"])
def test_the_branches_join_continuously(gas):
    """At r = b the flow and its slope are continuous (the ellipse leaves 1 with slope 0);
    at r = r_lam the flow is continuous and the laminar slope is finite, k·p_up per unit
    of Δp, up to r = 1 (ISO's linear correction matches the value, not the slope)."""
    p_up, eps = 1e5, 1e-9
    b, r_lam = gas["iso_b"], gas["r_lin"]
    args = (gas["iso_b"], gas["iso_m"], gas["r_lin"], gas["T"])
    for corner in (b, r_lam):
        left, right = (iso_flow(p_up, (corner + d) * p_up, *args) for d in (-eps, eps))
        slope_scale = abs(iso_flow(p_up, 0.999999 * p_up, *args)[2])  # the steepest
        assert abs(right[0] - left[0]) <= 2.0 * eps * p_up * slope_scale, corner
    left, right = (iso_flow(p_up, (b + d) * p_up, *args) for d in (-eps, eps))
    assert left[2] == 0.0 and abs(right[2]) <= 1e-3 * slope_scale  # C¹ at b
    dp = np.array([1e-3, 1e-1, 10.0, (1.0 - r_lam) * p_up * 0.999])
    conductance = iso6358_mass_flow(np.full_like(dp, p_up), p_up - dp, CONDUCTANCE, gas) / dp
    np.testing.assert_allclose(conductance, conductance[0], rtol=LAMINAR_CONDUCTANCE_RTOL)


def _fd_points(gas):
    """(p1, p2) pairs in every branch and both directions, away from r = b and r_lam."""
    rng = np.random.default_rng(6358)
    up = rng.uniform(2e4, 6e5, 60)
    ratios = np.concatenate([rng.uniform(0.0, gas["iso_b"] - 0.02, 20),
                             rng.uniform(gas["iso_b"] + 0.02, gas["r_lin"] - 2e-4, 20),
                             rng.uniform(gas["r_lin"] + 1e-4, 1.0 - 1e-5, 20)])
    pairs = [(p, r * p) for p, r in zip(up, ratios, strict=True)]
    return pairs + [(b, a) for a, b in pairs]


def _central(function, values, k, step):
    plus, minus = list(values), list(values)
    plus[k] += step
    minus[k] -= step
    return (function(*plus)[0] - function(*minus)[0]) / (2.0 * step)


@pytest.mark.parametrize("gas", [DATASHEET, DEFAULTS], ids=["datasheet", "defaults"])
def test_partials_equal_central_differences(gas):
    """∂q/∂p1, ∂q/∂p2 (the kernel's Jacobian) and ∂q/∂b, ∂q/∂m, ∂q/∂r_lam, ∂q/∂T (its
    parameter sensitivities), each against a central difference of the flow; a change of
    one variable by its scale is compared with the flow."""
    names = ("p1", "p2", "b", "m", "r_lam", "T")
    for p1, p2 in _fd_points(gas):
        values = [p1, p2, gas["iso_b"], gas["iso_m"], gas["r_lin"], gas["T"]]
        q, d_p1, d_p2 = iso_flow(*values)
        analytic = (d_p1, d_p2, *iso_flow_params(*values))
        scales = (max(p1, p2), max(p1, p2), 1.0, 1.0, 1.0, gas["T"])
        for k, name in enumerate(names):
            # r_lam: a step that keeps every point on its side of r_lam
            step = 1e-8 if name == "r_lam" else FD_REL_STEP * scales[k]
            numeric = _central(iso_flow, values, k, step)
            error = abs(analytic[k] - numeric) * scales[k]
            assert error <= ISO_FD_RTOL * (abs(q) + abs(numeric) * scales[k]), (
                f"∂q/∂{name} at p1 = {p1:g}, p2 = {p2:g}: analytic {analytic[k]:.8g}, "
                f"central difference {numeric:.8g}")


def test_the_default_conductance_matches_the_orifice_area(vgt):
    """C = A·Φ*·sqrt(γ/R)/(ρ0·sqrt(T0)): the ISO flow of the vgt-paper's 1.5 mm² chokes at
    the orifice law's flow, and with b = 0.528, m = 0.5 follows it within 0.5 %."""
    area = vgt["A_res"]
    conductance = conductance_of_area(area, vgt)
    gas = {**DEFAULTS, "T": vgt["T"]}
    p_down = np.linspace(0.0, 0.99, 991) * 1e5
    iso = iso6358_mass_flow(1e5, p_down, conductance, gas)
    orifice = orifice_mass_flow(1e5, p_down, area, vgt)
    assert iso[0] == pytest.approx(orifice[0], rel=ISO_FORMULA_RTOL)
    assert np.max(np.abs(iso - orifice)) <= ISO_VS_ORIFICE_RTOL * orifice[0]
    from pneumact.parameters import catalogue

    for name in ("iso_C_res", "iso_C_atm"):  # the catalogue's default: this C, 3 digits
        assert catalogue()[name].default == pytest.approx(conductance, rel=5e-3)


@pytest.mark.parametrize(("change", "message"), [
    ({"iso_b": 0.9995}, r"iso_b = 0.9995: must be < r_lin = 0.999"),
    ({"r_lin": 1.0}, r"r_lin = 1: must be < 1"),
    ({"iso_m": 0.0}, r"iso_m = 0: must be > 0"),
    ({"iso_b": -0.1}, r"iso_b = -0.1: must be >= 0"),
    ({"iso_C_atm": -1e-9}, r"iso_C_atm = -1e-09 m\^3/\(s\*Pa\): must be >= 0"),
])
def test_impossible_iso_values_are_refused_naming_field_value_and_limit(vgt, change, message):
    import pneumact as pa

    with pytest.raises(pa.ParameterError, match=message):
        vgt.replace(**change)

"""Friction laws evaluated on arrays (no simulation): steady states, bounds and
equivalences (their partial derivatives: ``tests/integration/test_friction_registry.py``)."""

from __future__ import annotations

import numpy as np
import pytest

from pneumact.errors import ArgumentError
from pneumact.models import GMS, BoucWen, CoulombViscous, Dahl, ElastoPlastic, LuGre, StribeckMap
from reference import (
    FRICTION_RTOL,
    ROUND_OFF_ATOL,
    SLIDING_VELOCITIES,
    STATIC_MAP_MIN_SPEED_FACTOR,
    STEADY_ZDOT_RTOL,
)


def _speeds() -> np.ndarray:
    lo, hi, n = SLIDING_VELOCITIES
    s = np.logspace(np.log10(lo), np.log10(hi), n)
    return np.concatenate([-s[::-1], s])


def _stribeck(v: np.ndarray, p) -> np.ndarray:
    """g(v) = Fc + (Fs − Fc)·exp(−(|v|/vs)^δ) written out independently of the library."""
    return p["Fc"] + (p["Fs"] - p["Fc"]) * np.exp(-((np.abs(v) / p["vs"]) ** p["delta"]))


@pytest.fixture(params=[1.0, 2.0], ids=["delta1", "delta2"])
def lugre_params(request, vgt):
    return vgt.replace(delta=request.param)


@pytest.mark.parametrize("model", [LuGre(), LuGre(decaying_damping=True)],
                         ids=["constant_sigma1", "decaying_sigma1"])
def test_lugre_steady_state_is_stribeck_curve_plus_viscous(model, lugre_params):
    v = _speeds()
    expected = np.sign(v) * _stribeck(v, lugre_params) + lugre_params["sigma2"] * v
    np.testing.assert_allclose(model.steady_force(v, lugre_params), expected,
                               rtol=FRICTION_RTOL)


@pytest.mark.parametrize("model", [LuGre(), LuGre(decaying_damping=True)],
                         ids=["constant_sigma1", "decaying_sigma1"])
def test_lugre_bristle_rate_vanishes_at_steady_deflection(model, lugre_params):
    v = _speeds()
    z_steady = np.sign(v) * _stribeck(v, lugre_params) / lugre_params["sigma0"]
    zdot = model.evaluate(v, z_steady, lugre_params)["rates"][:, 0]
    assert np.all(np.abs(zdot) <= STEADY_ZDOT_RTOL * np.abs(v))
    np.testing.assert_allclose(model.steady_states(v, lugre_params)[:, 0], z_steady,
                               rtol=FRICTION_RTOL)


def test_lugre_sliding_level_between_coulomb_and_static(lugre_params):
    v = _speeds()
    g = (LuGre().steady_force(v, lugre_params) - lugre_params["sigma2"] * v) * np.sign(v)
    tol = FRICTION_RTOL * lugre_params["Fs"]
    assert np.all(g >= lugre_params["Fc"] - tol)
    assert np.all(g <= lugre_params["Fs"] + tol)
    speed_order = np.argsort(np.abs(v))
    assert np.all(np.diff(g[speed_order]) <= tol), "g(|v|) must not rise with speed"


@pytest.mark.parametrize("model", [Dahl(), BoucWen()], ids=["Dahl", "BoucWen"])
def test_rate_independent_models_slide_at_coulomb_level(model, vgt):
    v = _speeds()
    expected = np.sign(v) * vgt["Fc"] + vgt["sigma2"] * v
    np.testing.assert_allclose(model.steady_force(v, vgt), expected, rtol=FRICTION_RTOL)
    z_steady = np.sign(v) * vgt["Fc"] / vgt["sigma0"]
    zdot = model.evaluate(v, z_steady, vgt)["rates"][:, 0]
    assert np.all(np.abs(zdot) <= STEADY_ZDOT_RTOL * np.abs(v))
    np.testing.assert_allclose(model.steady_states(v, vgt)[:, 0], z_steady,
                               rtol=FRICTION_RTOL)


def test_bouc_wen_with_beta1_gamma0_n1_is_dahl(vgt):
    params = vgt.replace(bw_beta=1.0, bw_gamma=0.0, bw_n=1.0, dahl_alpha=1.0)
    rng = np.random.default_rng(1)
    v = rng.uniform(-0.05, 0.05, 500)
    z = rng.uniform(-2.0, 2.0, 500) * vgt["Fs"] / vgt["sigma0"]
    bw = BoucWen().evaluate(v, z, params)
    dahl = Dahl().evaluate(v, z, params)
    for key in ("rates", "force", "drates_dv", "drates_dy", "dforce_dv", "dforce_dy"):
        np.testing.assert_allclose(bw[key], dahl[key], rtol=FRICTION_RTOL, atol=ROUND_OFF_ATOL,
                                   err_msg=key)


def _fast_speeds(params) -> np.ndarray:
    v = _speeds()
    return v[np.abs(v) >= STATIC_MAP_MIN_SPEED_FACTOR * params["v_reg"]]


def test_coulomb_viscous_map_far_from_zero(vgt):
    v = _fast_speeds(vgt)
    expected = np.sign(v) * vgt["Fc"] + vgt["sigma2"] * v
    np.testing.assert_allclose(CoulombViscous().steady_force(v, vgt), expected,
                               rtol=FRICTION_RTOL)


def test_stribeck_map_equals_lugre_steady_state_far_from_zero(lugre_params):
    v = _fast_speeds(lugre_params)
    np.testing.assert_allclose(StribeckMap().steady_force(v, lugre_params),
                               LuGre().steady_force(v, lugre_params), rtol=FRICTION_RTOL)


def test_static_maps_are_odd_and_zero_at_rest(vgt):
    v = _speeds()
    for model in (CoulombViscous(), StribeckMap()):
        f = model.steady_force(v, vgt)
        np.testing.assert_allclose(f, -f[::-1], rtol=FRICTION_RTOL, err_msg=model.name)
        assert model.steady_force(0.0, vgt)[0] == 0.0


# ----------------------------------------------------- elasto-plastic (Dupont et al. 2002)
@pytest.fixture
def ep_params(lugre_params):
    return lugre_params.replace(z_ba_ratio=0.4)


def _ep_rates(v, z, params) -> np.ndarray:
    return ElastoPlastic().evaluate(np.asarray(v, float), np.asarray(z, float)[:, None],
                                    params)["rates"][:, 0]


def test_elasto_plastic_unloads_elastically(ep_params):
    """Moving against the bristle's deflection, dz/dt = v exactly (α = 0), however deep
    the bristle is in its transition or saturated: unloading is a pure spring."""
    v = _speeds()
    steady = np.abs(ElastoPlastic().steady_states(v, ep_params)[:, 0])
    for fraction in (0.2, 0.6, 0.9, 1.0):
        z = -np.sign(v) * fraction * steady
        np.testing.assert_array_equal(_ep_rates(v, z, ep_params), v)


def test_elasto_plastic_is_elastic_below_break_away_and_lugre_past_steady(ep_params):
    v = _speeds()
    z_ss = ElastoPlastic().steady_states(v, ep_params)[:, 0]
    z_ba = ep_params["z_ba_ratio"] * min(ep_params["Fc"], ep_params["Fs"]) / ep_params["sigma0"]
    np.testing.assert_array_equal(_ep_rates(v, 0.99 * np.sign(v) * z_ba, ep_params), v)
    past = 1.2 * z_ss
    np.testing.assert_allclose(_ep_rates(v, past, ep_params),
                               LuGre().evaluate(v, past[:, None], ep_params)["rates"][:, 0],
                               rtol=FRICTION_RTOL)


def test_elasto_plastic_transition_uses_the_deflection_magnitude(ep_params):
    """The law is odd in (v, z), and across the transition α rises from 0 at z_ba to 1 at
    z_ss(v) in |z| for either direction of sliding: (1 − ż/v)·z_ss/z = α climbs 0 → 1."""
    v = _speeds()
    z_ss = ElastoPlastic().steady_states(v, ep_params)[:, 0]
    z_ba = ep_params["z_ba_ratio"] * min(ep_params["Fc"], ep_params["Fs"]) / ep_params["sigma0"]
    for w in np.linspace(0.05, 0.95, 7):
        z = np.sign(v) * (z_ba + w * (np.abs(z_ss) - z_ba))
        rates = _ep_rates(v, z, ep_params)
        np.testing.assert_allclose(_ep_rates(-v, -z, ep_params), -rates, rtol=FRICTION_RTOL)
        alpha = (1.0 - rates / v) * z_ss / z
        np.testing.assert_allclose(alpha, 0.5 - 0.5 * np.cos(np.pi * w), rtol=1e-9)


def test_elasto_plastic_steady_state_is_stribeck_curve_plus_viscous(ep_params):
    """Steady sliding at z_ss(v) = sgn(v)·g(v)/σ0, the speed's own steady deflection (not
    one fixed for all speeds): dz/dt = 0 there and F = g(v)·sgn(v) + σ2·v."""
    v = _speeds()
    z_ss = ElastoPlastic().steady_states(v, ep_params)
    values = ElastoPlastic().evaluate(v, z_ss, ep_params)
    assert np.all(np.abs(values["rates"][:, 0]) <= STEADY_ZDOT_RTOL * np.abs(v))
    np.testing.assert_allclose(values["force"], np.sign(v) * _stribeck(v, ep_params)
                               + ep_params["sigma2"] * v, rtol=FRICTION_RTOL)


# ------------------------------------------------ generalized Maxwell-slip (Al-Bender 2005)
def test_gms_steady_state_is_stribeck_curve_plus_viscous(lugre_params):
    """Every block slipping at its share νᵢ·g(v)/Σν: the rates rest and the blocks
    together give F = g(v)·sgn(v) + σ2·v, whatever their number and shares (one block,
    and the four of the shipped sets; each count is a kernel of its own)."""
    for law in (GMS(1), GMS(4)):
        params = lugre_params.replace(law.matched_values(lugre_params))
        v = _speeds()
        steady = law.steady_states(v, params)
        values = law.evaluate(v, steady, params)
        assert np.all(np.abs(values["rates"]) <= STEADY_ZDOT_RTOL * np.abs(v)[:, None])
        np.testing.assert_allclose(values["force"], np.sign(v) * _stribeck(v, params)
                                   + params["sigma2"] * v, rtol=FRICTION_RTOL)


def test_gms_refuses_a_block_count_out_of_range():
    with pytest.raises(ArgumentError, match=r"n_elements = 9: must be a whole number in "
                                            r"\[1, 8\]"):
        GMS(9)


def test_elasto_plastic_break_away_follows_the_smaller_of_fc_and_fs(ep_params):
    """With Fs < Fc (a curve that rises with speed: no parameter set has it, but a fit
    tries it) the smallest steady deflection is Fs/σ0: z_ba is the ratio of it, and its
    partials in Fc, Fs and the ratio follow (by central differences, in the transition,
    where α depends on z_ba)."""
    from reference import FD_REL_STEP, PARAM_JAC_RTOL

    params = _Values({**ep_params, "Fs": 0.5 * ep_params["Fc"]})
    law = ElastoPlastic()
    z_ba = params["z_ba_ratio"] * params["Fs"] / params["sigma0"]
    v = np.array([-3e-3, -1e-4, 2e-4, 5e-3])
    z_ss = law.steady_states(v, params)[:, 0]
    np.testing.assert_array_equal(_ep_rates(v, 0.99 * np.sign(v) * z_ba, params), v)
    z = (0.5 * (z_ba + np.abs(z_ss)) * np.sign(v))[:, None]
    partials = law.parameter_derivatives(v, z, params)
    for name in ("Fc", "Fs", "z_ba_ratio"):
        h = FD_REL_STEP * params[name]
        numeric = (law.evaluate(v, z, params.replace({name: params[name] + h}))["rates"]
                   - law.evaluate(v, z, params.replace({name: params[name] - h}))["rates"]
                   ) / (2 * h)
        np.testing.assert_allclose(partials[name][:, 0], numeric[:, 0], rtol=PARAM_JAC_RTOL,
                                   atol=1e-12 * np.max(np.abs(numeric)))


class _Values(dict):
    """Values a fit may try that no parameter set holds (unvalidated)."""

    def replace(self, changes):
        return _Values({**self, **changes})

"""Friction laws evaluated on arrays (no simulation): steady states, bounds, equivalences
and the partial derivatives that the analytic Jacobian is built from."""

from __future__ import annotations

import numpy as np
import pytest

from pneumact.models import BoucWen, CoulombViscous, Dahl, LuGre, StribeckMap
from reference import (
    FD_REL_STEP,
    FD_RTOL,
    FD_SAMPLES,
    FD_SPEED_RANGE,
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
    np.testing.assert_allclose(model.steady_state(v, lugre_params), expected,
                               rtol=FRICTION_RTOL)


@pytest.mark.parametrize("model", [LuGre(), LuGre(decaying_damping=True)],
                         ids=["constant_sigma1", "decaying_sigma1"])
def test_lugre_bristle_rate_vanishes_at_steady_deflection(model, lugre_params):
    v = _speeds()
    z_steady = np.sign(v) * _stribeck(v, lugre_params) / lugre_params["sigma0"]
    zdot = model.evaluate(v, z_steady, lugre_params)["zdot"]
    assert np.all(np.abs(zdot) <= STEADY_ZDOT_RTOL * np.abs(v))


def test_lugre_sliding_level_between_coulomb_and_static(lugre_params):
    v = _speeds()
    g = (LuGre().steady_state(v, lugre_params) - lugre_params["sigma2"] * v) * np.sign(v)
    tol = FRICTION_RTOL * lugre_params["Fs"]
    assert np.all(g >= lugre_params["Fc"] - tol)
    assert np.all(g <= lugre_params["Fs"] + tol)
    speed_order = np.argsort(np.abs(v))
    assert np.all(np.diff(g[speed_order]) <= tol), "g(|v|) must not rise with speed"


@pytest.mark.parametrize("model", [Dahl(), BoucWen()], ids=["Dahl", "BoucWen"])
def test_rate_independent_models_slide_at_coulomb_level(model, vgt):
    v = _speeds()
    expected = np.sign(v) * vgt["Fc"] + vgt["sigma2"] * v
    np.testing.assert_allclose(model.steady_state(v, vgt), expected, rtol=FRICTION_RTOL)
    z_steady = np.sign(v) * vgt["Fc"] / vgt["sigma0"]
    zdot = model.evaluate(v, z_steady, vgt)["zdot"]
    assert np.all(np.abs(zdot) <= STEADY_ZDOT_RTOL * np.abs(v))


def test_bouc_wen_with_beta1_gamma0_n1_is_dahl(vgt):
    params = vgt.replace(bw_beta=1.0, bw_gamma=0.0, bw_n=1.0, dahl_alpha=1.0)
    rng = np.random.default_rng(1)
    v = rng.uniform(-0.05, 0.05, 500)
    z = rng.uniform(-2.0, 2.0, 500) * vgt["Fs"] / vgt["sigma0"]
    bw = BoucWen().evaluate(v, z, params)
    dahl = Dahl().evaluate(v, z, params)
    for key in ("zdot", "force", "dzdot_dv", "dzdot_dz", "dforce_dv", "dforce_dz"):
        np.testing.assert_allclose(bw[key], dahl[key], rtol=FRICTION_RTOL, atol=ROUND_OFF_ATOL,
                                   err_msg=key)


def _fast_speeds(params) -> np.ndarray:
    v = _speeds()
    return v[np.abs(v) >= STATIC_MAP_MIN_SPEED_FACTOR * params["v_reg"]]


def test_coulomb_viscous_map_far_from_zero(vgt):
    v = _fast_speeds(vgt)
    expected = np.sign(v) * vgt["Fc"] + vgt["sigma2"] * v
    np.testing.assert_allclose(CoulombViscous().steady_state(v, vgt), expected,
                               rtol=FRICTION_RTOL)


def test_stribeck_map_equals_lugre_steady_state_far_from_zero(lugre_params):
    v = _fast_speeds(lugre_params)
    np.testing.assert_allclose(StribeckMap().steady_state(v, lugre_params),
                               LuGre().steady_state(v, lugre_params), rtol=FRICTION_RTOL)


def test_static_maps_are_odd_and_zero_at_rest(vgt):
    v = _speeds()
    for model in (CoulombViscous(), StribeckMap()):
        f = model.steady_state(v, vgt)
        np.testing.assert_allclose(f, -f[::-1], rtol=FRICTION_RTOL, err_msg=model.name)
        assert model.steady_state(0.0, vgt)[0] == 0.0


# ------------------------------------------------------- partial derivatives vs FD
MODEL_VARIANTS = [
    ("LuGre_delta1", LuGre(), {"delta": 1.0}),
    ("LuGre_delta2", LuGre(), {"delta": 2.0}),
    ("LuGre_decaying", LuGre(decaying_damping=True), {"delta": 1.0}),
    ("Dahl_alpha1", Dahl(), {"dahl_alpha": 1.0}),
    ("Dahl_alpha2", Dahl(), {"dahl_alpha": 2.0}),
    ("BoucWen_default", BoucWen(), {}),
    ("BoucWen_n2", BoucWen(), {"bw_n": 2.0, "bw_beta": 0.7, "bw_gamma": -0.3}),
    ("CoulombViscous", CoulombViscous(), {}),
    ("StribeckMap", StribeckMap(), {"delta": 1.0}),
]


@pytest.mark.parametrize(("label", "model", "changes"), MODEL_VARIANTS,
                         ids=[m[0] for m in MODEL_VARIANTS])
def test_partial_derivatives_match_central_differences(label, model, changes, vgt):
    params = vgt.replace(**changes) if changes else vgt
    rng = np.random.default_rng(7)
    lo, hi = FD_SPEED_RANGE
    v = rng.choice([-1.0, 1.0], FD_SAMPLES) * np.exp(rng.uniform(np.log(lo), np.log(hi),
                                                                 FD_SAMPLES))
    z_scale = params["Fs"] / params["sigma0"]
    # |z| in [0.05, 1.5]·Fs/σ0: Dahl and Bouc-Wen have |s| kinks at z = 0 and z = ±Fc/σ0.
    z = rng.choice([-1.0, 1.0], FD_SAMPLES) * rng.uniform(0.05, 1.5, FD_SAMPLES) * z_scale
    if label.startswith(("Dahl", "BoucWen")):
        s = params["sigma0"] * z * np.sign(v) / params["Fc"]
        keep = np.abs(1.0 - s) > 0.05
        v, z = v[keep], z[keep]
    here = model.evaluate(v, z, params)
    hv = FD_REL_STEP * np.abs(v)
    hz = FD_REL_STEP * z_scale
    v_plus, v_minus = model.evaluate(v + hv, z, params), model.evaluate(v - hv, z, params)
    z_plus, z_minus = model.evaluate(v, z + hz, params), model.evaluate(v, z - hz, params)
    for out in ("zdot", "force"):
        d_dv = (v_plus[out] - v_minus[out]) / (2.0 * hv)
        d_dz = (z_plus[out] - z_minus[out]) / (2.0 * hz)
        name = "dzdot" if out == "zdot" else "dforce"
        # scale each difference by the variable's size: compare changes of the output
        scale = np.maximum(np.abs(d_dv * v), np.abs(d_dz * z_scale))
        scale = np.maximum(scale, np.abs(here[out]) + 1e-300)
        err_v = np.abs(here[f"{name}_dv"] - d_dv) * np.abs(v) / scale
        err_z = np.abs(here[f"{name}_dz"] - d_dz) * z_scale / scale
        assert err_v.max() <= FD_RTOL, f"{label}: ∂{out}/∂v off by {err_v.max():.2e}"
        assert err_z.max() <= FD_RTOL, f"{label}: ∂{out}/∂z off by {err_z.max():.2e}"


# central differences need both neighbours valid: Bouc-Wen's default sits on |γ| = β
PARAMETER_VARIANTS = [(label, model, {"bw_beta": 0.6} if label == "BoucWen_default" else ch)
                      for label, model, ch in MODEL_VARIANTS]


@pytest.mark.parametrize(("label", "model", "changes"), PARAMETER_VARIANTS,
                         ids=[m[0] for m in PARAMETER_VARIANTS])
def test_parameter_derivatives_match_central_differences(label, model, changes, vgt):
    """The analytic ∂(dz/dt)/∂θ and ∂F/∂θ that forward sensitivities are built from."""
    params = vgt.replace(**changes) if changes else vgt
    rng = np.random.default_rng(11)
    lo, hi = FD_SPEED_RANGE
    n = FD_SAMPLES // 4
    v = rng.choice([-1.0, 1.0], n) * np.exp(rng.uniform(np.log(lo), np.log(hi), n))
    z_scale = params["Fs"] / params["sigma0"]
    z = rng.choice([-1.0, 1.0], n) * rng.uniform(0.05, 1.5, n) * z_scale
    if label.startswith(("Dahl", "BoucWen")):  # away from the kinks of |s|
        s = params["sigma0"] * z * np.sign(v) / params["Fc"]
        keep = (np.abs(1.0 - s) > 0.05) & (np.abs(s) > 0.05)
        v, z = v[keep], z[keep]
    analytic = model.parameter_derivatives(v, z, params)
    assert set(analytic) == set(model.block.names)
    for name, columns in analytic.items():
        value = params[name]
        h = FD_REL_STEP * abs(value)
        plus = model.evaluate(v, z, params.replace({name: value + h}))
        minus = model.evaluate(v, z, params.replace({name: value - h}))
        for k, out in enumerate(("zdot", "force")):
            fd = (plus[out] - minus[out]) / (2.0 * h)
            here = model.evaluate(v, z, params)[out]
            scale = np.maximum(np.abs(fd * value), np.abs(here)) + 1e-300
            err = np.abs(columns[:, k] - fd) * abs(value) / scale
            assert err.max() <= FD_RTOL, f"{label}: ∂{out}/∂{name} off by {err.max():.2e}"

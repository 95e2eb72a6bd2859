"""Friction laws behind one interface: LuGre, Dahl, Bouc-Wen and two static maps.

Each law is a compiled scalar function ``law(v, z, p, o)`` of the sliding velocity
``v``, one internal state ``z`` (bristle deflection; unused and constant for static
maps) and the law's parameter block, which starts at offset ``o`` of the vector ``p``
(``p[o + LG_SIGMA0]``; whole vectors and offsets, not slices). It returns

    (dz/dt, F, ∂(dz/dt)/∂v, ∂(dz/dt)/∂z, ∂F/∂v, ∂F/∂z),

and ``law_params(v, z, p, o, g, rz, rf)`` fills g[rz, o + k] = ∂(dz/dt)/∂p_k and
g[rf, o + k] = ∂F/∂p_k for every entry k of the block (analytic, for forward
sensitivities and identification).

Speed: numba counts references on every array passed to a call that it does not inline
(two atomic operations per array). So the functions the hot loop calls are thin
wrappers inlined by numba (``inline="always"``) that read the block and call the law's
scalar-only function (``lugre_law``), which needs no reference counting. A strategy
object per law names its block, its functions and its command-line name; the same
object is passed to an ``Actuator`` or a ``FrictionRig``. Adding a law means adding its
functions and class here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from numba import njit

from ..parameters.catalogue import ParameterSpec, declare, declare_relation
from .component import Block, Part, StateSpec

P = ParameterSpec
declare(
    P("sigma0", "N/m", "bristle stiffness", None, 0.0, True, 1e12, group="friction",
      plausible=(10.0, 1e10)),
    P("sigma1", "N*s/m", "bristle (micro-)damping", 0.0, 0.0, False, 1e8, group="friction",
      plausible=(0.0, 1e6)),
    P("sigma2", "N*s/m", "viscous friction coefficient (the only viscous term)", 0.0, 0.0,
      False, 1e8, group="friction", plausible=(0.0, 1e6)),
    P("Fc", "N", "Coulomb friction force (0: frictionless)", None, 0.0, False, 1e7,
      group="friction", plausible=(0.0, 1e5)),
    P("Fs", "N", "static (break-away) friction force, Fs >= Fc", None, 0.0, False, 1e7,
      group="friction", plausible=(0.0, 1e5)),
    P("vs", "m/s", "Stribeck velocity", None, 0.0, True, 100.0, group="friction",
      plausible=(1e-7, 1.0)),
    P("delta", "", "Stribeck exponent (paper eq. 8: 1; usual LuGre: 2)", 2.0, 0.0, True,
      100.0, group="friction", plausible=(0.2, 5.0)),
    P("v_reg", "m/s", "sign regularisation velocity of the static friction maps", 1e-4, 0.0,
      True, 10.0, group="friction", plausible=(1e-9, 0.1)),
    P("dahl_alpha", "", "Dahl shape exponent", 1.0, 0.0, True, 100.0, group="friction",
      plausible=(0.1, 10.0)),
    P("bw_beta", "", "Bouc-Wen shape parameter beta", 0.5, 0.0, True, 1e3,
      group="friction"),
    P("bw_gamma", "", "Bouc-Wen shape parameter gamma (-beta <= gamma <= beta)", 0.5,
      -1e3, False, 1e3, group="friction"),
    P("bw_n", "", "Bouc-Wen exponent n", 1.0, 0.0, True, 100.0, group="friction",
      plausible=(0.1, 10.0)),
)
declare_relation(("Fs", "Fc"), lambda fs, fc: fs >= fc,
                 lambda fs, fc: f"must be >= Fc = {fc:g} N (static friction is at least "
                                "the Coulomb friction)")
declare_relation(("bw_gamma", "bw_beta"), lambda g, b: abs(g) <= b,
                 lambda g, b: f"must be within [-bw_beta, bw_beta] = [{-b:g}, {b:g}]")

#: Friction level g(v) below this fraction of Fs counts as none: the bristles then relax
#: within g/(σ0·|v|), attoseconds, far below any step, and the law takes its limit.
RELAXED_LEVEL = 1e-12

LUGRE_BLOCK = Block.of("sigma0", "sigma1", "sigma2", "Fc", "Fs", "vs", "delta")
LG_SIGMA0 = LUGRE_BLOCK.index("sigma0")
LG_SIGMA1 = LUGRE_BLOCK.index("sigma1")
LG_SIGMA2 = LUGRE_BLOCK.index("sigma2")
LG_FC = LUGRE_BLOCK.index("Fc")
LG_FS = LUGRE_BLOCK.index("Fs")
LG_VS = LUGRE_BLOCK.index("vs")
LG_DELTA = LUGRE_BLOCK.index("delta")
LUGRE_SIZE = len(LUGRE_BLOCK)

DAHL_BLOCK = Block.of("sigma0", "Fc", "sigma2", "dahl_alpha")
DH_SIGMA0 = DAHL_BLOCK.index("sigma0")
DH_FC = DAHL_BLOCK.index("Fc")
DH_SIGMA2 = DAHL_BLOCK.index("sigma2")
DH_ALPHA = DAHL_BLOCK.index("dahl_alpha")
DAHL_SIZE = len(DAHL_BLOCK)

BOUC_WEN_BLOCK = Block.of("sigma0", "Fc", "sigma2", "bw_beta", "bw_gamma", "bw_n")
BW_SIGMA0 = BOUC_WEN_BLOCK.index("sigma0")
BW_FC = BOUC_WEN_BLOCK.index("Fc")
BW_SIGMA2 = BOUC_WEN_BLOCK.index("sigma2")
BW_BETA = BOUC_WEN_BLOCK.index("bw_beta")
BW_GAMMA = BOUC_WEN_BLOCK.index("bw_gamma")
BW_N = BOUC_WEN_BLOCK.index("bw_n")
BOUC_WEN_SIZE = len(BOUC_WEN_BLOCK)

COULOMB_BLOCK = Block.of("Fc", "sigma2", "v_reg")
CV_FC = COULOMB_BLOCK.index("Fc")
CV_SIGMA2 = COULOMB_BLOCK.index("sigma2")
CV_VREG = COULOMB_BLOCK.index("v_reg")
COULOMB_SIZE = len(COULOMB_BLOCK)

STRIBECK_BLOCK = Block.of("Fc", "Fs", "vs", "delta", "sigma2", "v_reg")
SM_FC = STRIBECK_BLOCK.index("Fc")
SM_FS = STRIBECK_BLOCK.index("Fs")
SM_VS = STRIBECK_BLOCK.index("vs")
SM_DELTA = STRIBECK_BLOCK.index("delta")
SM_SIGMA2 = STRIBECK_BLOCK.index("sigma2")
SM_VREG = STRIBECK_BLOCK.index("v_reg")
STRIBECK_SIZE = len(STRIBECK_BLOCK)


@njit(cache=True)
def _sign(v):  # pragma: no cover - compiled
    return 1.0 if v > 0.0 else (-1.0 if v < 0.0 else 0.0)


@njit(cache=True, inline="always")
def _power(a, exponent):  # pragma: no cover - compiled
    """a**exponent, without a pow() call for the exponents 1 and 2 (the paper's δ, and
    Canudas de Wit's): the Stribeck curve is evaluated at every stage of every step."""
    if exponent == 1.0:
        return a
    if exponent == 2.0:
        return a * a
    return a**exponent


@njit(cache=True)
def stribeck_curve(v, fc, fs, vs, delta):  # pragma: no cover - compiled
    """g(v) = Fc + (Fs − Fc)·exp(−(|v|/vs)^δ) and its derivative dg/dv."""
    ds = fs - fc
    a = abs(v) / vs
    if a == 0.0:
        return fc + ds, 0.0
    ad = _power(a, delta)
    e = math.exp(-ad)
    return fc + ds * e, -ds * e * delta * ad / a * _sign(v) / vs


@njit(cache=True)
def stribeck_curve_params(v, fc, fs, vs, delta):  # pragma: no cover - compiled
    """g(v) and its derivatives (∂g/∂Fc, ∂g/∂Fs, ∂g/∂vs, ∂g/∂δ)."""
    a = abs(v) / vs
    if a == 0.0:
        return fs, 0.0, 1.0, 0.0, 0.0
    ad = _power(a, delta)
    e = math.exp(-ad)
    ds = fs - fc
    return fc + ds * e, 1.0 - e, e, ds * e * delta * ad / vs, -ds * e * ad * math.log(a)


# --------------------------------------------------------------------------- LuGre
@njit(cache=True)
def lugre_law(v, z, s0, s1, ds1_dv, s2, fc, fs, vs, delta):  # pragma: no cover - compiled
    """LuGre with micro-damping s1 (and its derivative ds1_dv along v).

    Where the friction level g(v) vanishes (Fc = Fs = 0, a frictionless actuator; or
    Fc = 0 far above vs, where exp(−(|v|/vs)^δ) underflows) the law is its limit: the
    bristles relax at the rate σ0·|v|/g → ∞ to z = sgn(v)·g/σ0 → 0 and carry no force,
    so dz/dt = 0 and F = σ2·v (the bound Fs/σ0 holds z at 0 there).
    """
    g, dg = stribeck_curve(v, fc, fs, vs, delta)
    if g <= RELAXED_LEVEL * fs:
        return 0.0, s2 * v, 0.0, 0.0, s2, 0.0
    av = abs(v)
    zdot = v - s0 * av * z / g
    dzdot_dv = 1.0 - s0 * z * (_sign(v) * g - av * dg) / (g * g)
    dzdot_dz = -s0 * av / g
    force = s0 * z + s1 * zdot + s2 * v
    df_dv = ds1_dv * zdot + s1 * dzdot_dv + s2
    return zdot, force, dzdot_dv, dzdot_dz, df_dv, s0 + s1 * dzdot_dz


@njit(cache=True)
def _lugre_rate_params(v, z, s0, fc, fs, vs, delta):  # pragma: no cover - compiled
    """dz/dt and its derivatives in σ0, Fc, Fs, vs, δ (σ1, σ2 do not enter it)."""
    g, dg_dfc, dg_dfs, dg_dvs, dg_ddelta = stribeck_curve_params(v, fc, fs, vs, delta)
    if g <= RELAXED_LEVEL * fs:  # no friction level: dz/dt = 0 whatever the parameters
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    av = abs(v)
    dz_dg = s0 * av * z / (g * g)
    return (v - s0 * av * z / g, -av * z / g, dz_dg * dg_dfc, dz_dg * dg_dfs,
            dz_dg * dg_dvs, dz_dg * dg_ddelta)


@njit(cache=True)
def _lugre_params(v, z, p, o, s1, ds1_dsigma1, ds1_dvs, g, rz, rf):  # pragma: no cover
    zdot, d_s0, d_fc, d_fs, d_vs, d_delta = _lugre_rate_params(
        v, z, p[o + LG_SIGMA0], p[o + LG_FC], p[o + LG_FS], p[o + LG_VS], p[o + LG_DELTA])
    g[rz, o + LG_SIGMA0] = d_s0
    g[rz, o + LG_SIGMA1] = 0.0
    g[rz, o + LG_SIGMA2] = 0.0
    g[rz, o + LG_FC] = d_fc
    g[rz, o + LG_FS] = d_fs
    g[rz, o + LG_VS] = d_vs
    g[rz, o + LG_DELTA] = d_delta
    for k in range(LUGRE_SIZE):
        g[rf, o + k] = s1 * g[rz, o + k]
    g[rf, o + LG_SIGMA0] += z
    g[rf, o + LG_SIGMA1] = ds1_dsigma1 * zdot
    g[rf, o + LG_SIGMA2] = v
    g[rf, o + LG_VS] += ds1_dvs * zdot


@njit(cache=True, inline="always")
def lugre(v, z, p, o):  # pragma: no cover - compiled
    """LuGre (paper eqs. 6-8) with constant micro-damping σ1."""
    return lugre_law(v, z, p[o + LG_SIGMA0], p[o + LG_SIGMA1], 0.0, p[o + LG_SIGMA2],
                     p[o + LG_FC], p[o + LG_FS], p[o + LG_VS], p[o + LG_DELTA])


@njit(cache=True)
def lugre_params(v, z, p, o, g, rz, rf):  # pragma: no cover - compiled
    _lugre_params(v, z, p, o, p[o + LG_SIGMA1], 1.0, 0.0, g, rz, rf)


@njit(cache=True)
def _decaying_damping(v, sigma1, vs):  # pragma: no cover - compiled
    """σ1(v) = σ1·exp(−(v/vs)²) and its derivatives in v, σ1 and vs."""
    w = math.exp(-((v / vs) ** 2))
    s1 = sigma1 * w
    return s1, -2.0 * v / (vs * vs) * s1, w, s1 * 2.0 * v * v / (vs * vs * vs)


@njit(cache=True, inline="always")
def lugre_decaying(v, z, p, o):  # pragma: no cover - compiled
    """LuGre with σ1(v) = σ1·exp(−(v/vs)²): micro-damping that fades once sliding."""
    s1, ds1_dv, _, _ = _decaying_damping(v, p[o + LG_SIGMA1], p[o + LG_VS])
    return lugre_law(v, z, p[o + LG_SIGMA0], s1, ds1_dv, p[o + LG_SIGMA2], p[o + LG_FC],
                     p[o + LG_FS], p[o + LG_VS], p[o + LG_DELTA])


@njit(cache=True)
def lugre_decaying_params(v, z, p, o, g, rz, rf):  # pragma: no cover - compiled
    s1, _, w, ds1_dvs = _decaying_damping(v, p[o + LG_SIGMA1], p[o + LG_VS])
    _lugre_params(v, z, p, o, s1, w, ds1_dvs, g, rz, rf)


@njit(cache=True)
def presliding_scale(level, s0):  # pragma: no cover - compiled
    """Typical bristle deflection level/σ0; with no friction level (a frictionless law,
    whose z stays 0) the deflection under 1 N, so the tolerance on z stays positive."""
    return (level if level > 0.0 else 1.0) / s0


@njit(cache=True)
def lugre_scales(p, o):  # pragma: no cover - compiled
    """(typical bristle deflection Fs/σ0, bristle stiffness σ0, regularisation speed 0)."""
    s0 = p[o + LG_SIGMA0]
    return presliding_scale(max(p[o + LG_FS], p[o + LG_FC]), s0), s0, 0.0


@njit(cache=True)
def lugre_bound(p, o):  # pragma: no cover - compiled
    """Largest |z| the law allows: the set |σ0·z| <= max(Fs, Fc) is invariant."""
    return max(p[o + LG_FS], p[o + LG_FC]) / p[o + LG_SIGMA0]


@njit(cache=True)
def _clear(g, rz, rf, o, size):  # pragma: no cover - compiled
    for k in range(size):
        g[rz, o + k] = 0.0
        g[rf, o + k] = 0.0


# --------------------------------------------------------------------------- Dahl
@njit(cache=True)
def _dahl_shape(v, z, s0, fc, alpha):  # pragma: no cover - compiled
    """s = 1 − σ0·z·sgn(v)/Fc, φ(s) = |s|^α·sgn(s) and dφ/ds."""
    s = 1.0 - s0 * z * _sign(v) / fc
    a = max(abs(s), 1e-300)
    return s, a**alpha * _sign(s), alpha * a ** (alpha - 1.0)


@njit(cache=True)
def dahl_law(v, z, s0, fc, s2, alpha):  # pragma: no cover - compiled
    if fc <= 0.0:  # frictionless: the bristle bound Fc/σ0 is 0, F = σ2·v (see LuGre)
        return 0.0, s2 * v, 0.0, 0.0, s2, 0.0
    _, phi, dphi = _dahl_shape(v, z, s0, fc, alpha)
    return v * phi, s0 * z + s2 * v, phi, -s0 * abs(v) * dphi / fc, s2, s0


@njit(cache=True, inline="always")
def dahl(v, z, p, o):  # pragma: no cover - compiled
    """Dahl: dz/dt = v·φ(1 − σ0·z·sgn(v)/Fc), φ(s) = |s|^α·sgn(s); F = σ0·z + σ2·v."""
    return dahl_law(v, z, p[o + DH_SIGMA0], p[o + DH_FC], p[o + DH_SIGMA2], p[o + DH_ALPHA])


@njit(cache=True)
def dahl_params(v, z, p, o, g, rz, rf):  # pragma: no cover - compiled
    s0, fc = p[o + DH_SIGMA0], p[o + DH_FC]
    _clear(g, rz, rf, o, DAHL_SIZE)
    if fc <= 0.0:
        g[rf, o + DH_SIGMA2] = v
        return
    s, phi, dphi = _dahl_shape(v, z, s0, fc, p[o + DH_ALPHA])
    sv = _sign(v)
    g[rz, o + DH_SIGMA0] = v * dphi * (-z * sv / fc)
    g[rz, o + DH_FC] = v * dphi * (s0 * z * sv / (fc * fc))
    g[rz, o + DH_ALPHA] = v * phi * math.log(abs(s)) if s != 0.0 else 0.0
    g[rf, o + DH_SIGMA0] = z
    g[rf, o + DH_SIGMA2] = v


@njit(cache=True)
def dahl_scales(p, o):  # pragma: no cover - compiled
    return presliding_scale(p[o + DH_FC], p[o + DH_SIGMA0]), p[o + DH_SIGMA0], 0.0


@njit(cache=True)
def dahl_bound(p, o):  # pragma: no cover - compiled
    """|σ0·z| <= Fc is invariant (dz/dt = 0 on its edge when sliding outwards)."""
    return p[o + DH_FC] / p[o + DH_SIGMA0]


# --------------------------------------------------------------------------- Bouc-Wen
@njit(cache=True)
def _bouc_wen_terms(v, z, s0, fc, beta, gam, n):  # pragma: no cover - compiled
    """s = σ0·z/Fc, |s|^(n−1), the hysteretic numerator N and the norm β + γ."""
    s = s0 * z / fc
    an1 = max(abs(s), 1e-300) ** (n - 1.0)
    numerator = beta * abs(v) * an1 * s + gam * v * abs(s) * an1
    return s, an1, numerator, beta + gam


@njit(cache=True)
def bouc_wen_law(v, z, s0, fc, s2, beta, gam, n):  # pragma: no cover - compiled
    if fc <= 0.0:  # frictionless: the bound Fc/σ0 is 0, F = σ2·v (see LuGre)
        return 0.0, s2 * v, 0.0, 0.0, s2, 0.0
    s, an1, numerator, norm = _bouc_wen_terms(v, z, s0, fc, beta, gam, n)
    an = abs(s) * an1
    zdot = v - numerator / norm
    dzdot_dv = 1.0 - (beta * _sign(v) * an1 * s + gam * an) / norm
    dzdot_dz = -(s0 / fc) * n * an1 * (beta * abs(v) + gam * v * _sign(s)) / norm
    return zdot, s0 * z + s2 * v, dzdot_dv, dzdot_dz, s2, s0


@njit(cache=True, inline="always")
def bouc_wen(v, z, p, o):  # pragma: no cover - compiled
    """Bouc-Wen, normalised so that steady sliding gives F = ±Fc + σ2·v.

    dz/dt = v − (β·|v|·|s|^(n−1)·s + γ·v·|s|^n)/(β + γ), s = σ0·z/Fc; F = σ0·z + σ2·v.
    With β = 1, γ = 0, n = 1 it is the Dahl model.
    """
    return bouc_wen_law(v, z, p[o + BW_SIGMA0], p[o + BW_FC], p[o + BW_SIGMA2],
                        p[o + BW_BETA], p[o + BW_GAMMA], p[o + BW_N])


@njit(cache=True)
def bouc_wen_params(v, z, p, o, g, rz, rf):  # pragma: no cover - compiled
    s0, fc = p[o + BW_SIGMA0], p[o + BW_FC]
    beta, gam, n = p[o + BW_BETA], p[o + BW_GAMMA], p[o + BW_N]
    _clear(g, rz, rf, o, BOUC_WEN_SIZE)
    if fc <= 0.0:
        g[rf, o + BW_SIGMA2] = v
        return
    s, an1, numerator, norm = _bouc_wen_terms(v, z, s0, fc, beta, gam, n)
    an = abs(s) * an1
    dzdot_ds = -n * an1 * (beta * abs(v) + gam * v * _sign(s)) / norm
    g[rz, o + BW_SIGMA0] = dzdot_ds * z / fc
    g[rz, o + BW_FC] = -dzdot_ds * s / fc
    g[rz, o + BW_BETA] = -(abs(v) * an1 * s - numerator / norm) / norm
    g[rz, o + BW_GAMMA] = -(v * an - numerator / norm) / norm
    g[rz, o + BW_N] = -math.log(abs(s)) * numerator / norm if s != 0.0 else 0.0
    g[rf, o + BW_SIGMA0] = z
    g[rf, o + BW_SIGMA2] = v


@njit(cache=True)
def bouc_wen_scales(p, o):  # pragma: no cover - compiled
    return presliding_scale(p[o + BW_FC], p[o + BW_SIGMA0]), p[o + BW_SIGMA0], 0.0


@njit(cache=True)
def bouc_wen_bound(p, o):  # pragma: no cover - compiled
    """|s| = |σ0·z/Fc| <= 1 is invariant (normalised Bouc-Wen with β > 0, β + γ > 0)."""
    return p[o + BW_FC] / p[o + BW_SIGMA0]


@njit(cache=True)
def unbounded(p, o):  # pragma: no cover - compiled
    """A static map has no internal state to bound."""
    return math.inf


# --------------------------------------------------------------------------- static maps
@njit(cache=True)
def coulomb_viscous_law(v, fc, s2, vr):  # pragma: no cover - compiled
    th = math.tanh(v / vr)
    return 0.0, fc * th + s2 * v, 0.0, 0.0, fc * (1.0 - th * th) / vr + s2, 0.0


@njit(cache=True, inline="always")
def coulomb_viscous(v, z, p, o):  # pragma: no cover - compiled
    """Static map F = Fc·sgn(v) + σ2·v, sign regularised as tanh(v/v_reg)."""
    return coulomb_viscous_law(v, p[o + CV_FC], p[o + CV_SIGMA2], p[o + CV_VREG])


@njit(cache=True)
def coulomb_viscous_params(v, z, p, o, g, rz, rf):  # pragma: no cover - compiled
    vr = p[o + CV_VREG]
    th = math.tanh(v / vr)
    _clear(g, rz, rf, o, COULOMB_SIZE)
    g[rf, o + CV_FC] = th
    g[rf, o + CV_SIGMA2] = v
    g[rf, o + CV_VREG] = -p[o + CV_FC] * (1.0 - th * th) * v / (vr * vr)


@njit(cache=True)
def static_scales_coulomb(p, o):  # pragma: no cover - compiled
    return 1.0, 0.0, p[o + CV_VREG]


@njit(cache=True)
def stribeck_map_law(v, fc, fs, vs, delta, s2, vr):  # pragma: no cover - compiled
    th = math.tanh(v / vr)
    g, dg = stribeck_curve(v, fc, fs, vs, delta)
    df_dv = dg * th + g * (1.0 - th * th) / vr + s2
    return 0.0, g * th + s2 * v, 0.0, 0.0, df_dv, 0.0


@njit(cache=True, inline="always")
def stribeck_map(v, z, p, o):  # pragma: no cover - compiled
    """Static map F = g(v)·sgn(v) + σ2·v (the LuGre steady state), sign regularised."""
    return stribeck_map_law(v, p[o + SM_FC], p[o + SM_FS], p[o + SM_VS], p[o + SM_DELTA],
                            p[o + SM_SIGMA2], p[o + SM_VREG])


@njit(cache=True)
def stribeck_map_params(v, z, p, o, g, rz, rf):  # pragma: no cover - compiled
    vr = p[o + SM_VREG]
    th = math.tanh(v / vr)
    fc, fs, vs, delta = p[o + SM_FC], p[o + SM_FS], p[o + SM_VS], p[o + SM_DELTA]
    gv, dg_dfc, dg_dfs, dg_dvs, dg_ddelta = stribeck_curve_params(v, fc, fs, vs, delta)
    _clear(g, rz, rf, o, STRIBECK_SIZE)
    g[rf, o + SM_FC] = dg_dfc * th
    g[rf, o + SM_FS] = dg_dfs * th
    g[rf, o + SM_VS] = dg_dvs * th
    g[rf, o + SM_DELTA] = dg_ddelta * th
    g[rf, o + SM_SIGMA2] = v
    g[rf, o + SM_VREG] = -gv * (1.0 - th * th) * v / (vr * vr)


@njit(cache=True)
def static_scales_stribeck(p, o):  # pragma: no cover - compiled
    return 1.0, 0.0, p[o + SM_VREG]


# --------------------------------------------------------------------------- strategies
_BY_CLI_NAME: dict[str, type[FrictionModel]] = {}


class FrictionModel:
    """Strategy object: which compiled friction law a model uses, and its parameters.

    Subclasses set ``block`` (the parameters, in the order the law reads them),
    ``functions`` (the law, its parameter derivatives and its scales, by name in this
    module) and ``cli_name`` (the ``--friction`` choice of the command line).
    """

    block: ClassVar[Block]
    law: ClassVar[str]
    cli_name: ClassVar[str]
    has_state: ClassVar[bool] = True

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        if "cli_name" in cls.__dict__:
            _BY_CLI_NAME[cls.cli_name] = cls

    @property
    def required(self) -> tuple[str, ...]:
        """The parameters this law reads."""
        return self.block.parameters

    @property
    def kernel(self) -> str:
        """Name of the compiled law in this module (part of the kernel's key)."""
        return self.law

    def part(self) -> Part:
        module = __name__
        scales = getattr(self, "scales", f"{self.law}_scales")
        bound = getattr(self, "bound", f"{self.law}_bound")
        return Part(
            role="friction", block=self.block,
            states=(StateSpec("bristle", "m", monotone=self.has_state),),
            functions={"friction_eval": f"{module}:{self.law}",
                       "friction_params": f"{module}:{self.law}_params",
                       "friction_scales": f"{module}:{scales}",
                       "friction_bound": f"{module}:{bound}"},
            label=repr(self), key=self.law,
        )

    # -- evaluation outside a simulation (tests, plots) ------------------------------
    def evaluate(self, v, z, params) -> dict[str, np.ndarray]:
        """The law at arrays ``v``, ``z``: dz/dt, force and the partial derivatives."""
        from ..simulation.assembly import friction_law_values

        return friction_law_values(self, v, z, params)

    def parameter_derivatives(self, v, z, params) -> dict[str, np.ndarray]:
        """∂(dz/dt)/∂θ and ∂F/∂θ of the law at arrays ``v``, ``z``: name -> (n, 2) array."""
        from ..simulation.assembly import friction_law_parameter_derivatives

        return friction_law_parameter_derivatives(self, v, z, params)

    def steady_state(self, v, params) -> np.ndarray:
        """Friction force in steady sliding at velocity ``v`` (dz/dt = 0)."""
        v = np.atleast_1d(np.asarray(v, dtype=np.float64))
        if not self.has_state:
            return self.evaluate(v, 0.0, params)["force"]
        z = np.sign(v) * self.steady_deflection(np.abs(v), params)
        return self.evaluate(v, z, params)["force"]

    def steady_deflection(self, speed, params) -> np.ndarray:
        """Bristle deflection |z| in steady sliding at ``speed``: Fc/σ0 unless overridden."""
        return params["Fc"] / params["sigma0"] * np.ones_like(np.asarray(speed, float))

    @property
    def name(self) -> str:
        return type(self).__name__

    def __repr__(self) -> str:
        return f"{self.name}()"

    def __eq__(self, other: object) -> bool:
        return type(self) is type(other) and self.law == other.law

    def __hash__(self) -> int:
        return hash((type(self).__name__, self.law))


@dataclass(frozen=True, eq=False)
class LuGre(FrictionModel):
    """LuGre friction (Canudas de Wit et al. 1995; paper eqs. 6-8).

    ``decaying_damping=True`` uses σ1(v) = σ1·exp(−(v/vs)²) instead of a constant σ1.
    """

    decaying_damping: bool = False
    block: ClassVar[Block] = LUGRE_BLOCK
    cli_name: ClassVar[str] = "lugre"
    scales: ClassVar[str] = "lugre_scales"
    bound: ClassVar[str] = "lugre_bound"

    def __post_init__(self):
        from ..checks import check_bool

        check_bool("decaying_damping", self.decaying_damping, where="LuGre")

    @property
    def law(self) -> str:  # type: ignore[override]
        return "lugre_decaying" if self.decaying_damping else "lugre"

    def steady_deflection(self, speed, params) -> np.ndarray:
        speed = np.asarray(speed, dtype=float)
        g = params["Fc"] + (params["Fs"] - params["Fc"]) * np.exp(
            -((speed / params["vs"]) ** params["delta"]))
        return g / params["sigma0"]

    def __repr__(self) -> str:
        return f"LuGre(decaying_damping={self.decaying_damping})"


class Dahl(FrictionModel):
    """Dahl friction (Dahl 1976): a rate-independent hysteresis with no Stribeck dip."""

    block = DAHL_BLOCK
    law = "dahl"
    cli_name = "dahl"


class BoucWen(FrictionModel):
    """Bouc-Wen hysteresis used as a friction model (normalised to slide at ±Fc)."""

    block = BOUC_WEN_BLOCK
    law = "bouc_wen"
    cli_name = "bouc-wen"


class CoulombViscous(FrictionModel):
    """Static Coulomb + viscous map, sign regularised over ``v_reg``."""

    block = COULOMB_BLOCK
    law = "coulomb_viscous"
    cli_name = "coulomb"
    has_state = False
    scales = "static_scales_coulomb"
    bound = "unbounded"


class StribeckMap(FrictionModel):
    """Static Stribeck map g(v)·sgn(v) + σ2·v, sign regularised over ``v_reg``."""

    block = STRIBECK_BLOCK
    law = "stribeck_map"
    cli_name = "stribeck"
    has_state = False
    scales = "static_scales_stribeck"
    bound = "unbounded"


def friction_models() -> dict[str, type[FrictionModel]]:
    """Command-line name -> friction model class, for every law defined here."""
    return dict(_BY_CLI_NAME)

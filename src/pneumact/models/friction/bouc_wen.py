"""Bouc-Wen hysteresis as a friction model, normalised so that steady sliding gives
F = ±Fc + σ2·v.

dz/dt = v − (β·|v|·|s|^(n−1)·s + γ·v·|s|^n)/(β + γ), s = σ0·z/Fc; F = σ0·z + σ2·v.
With β = 1, γ = 0, n = 1 it is the Dahl model.
"""

from __future__ import annotations

import math

from ...core.component import Block
from ...core.jit import njit
from ...parameters.catalogue import ParameterSpec, declare, declare_relation
from .base import CoulombBristleLaw, clear_block, presliding_scale, sign

P = ParameterSpec
declare(
    P("bw_beta", "", "Bouc-Wen shape parameter beta", 0.5, 0.0, True, 1e3,
      group="friction"),
    P("bw_gamma", "", "Bouc-Wen shape parameter gamma (-beta <= gamma <= beta)", 0.5,
      -1e3, False, 1e3, group="friction"),
    P("bw_n", "", "Bouc-Wen exponent n", 1.0, 0.0, True, 100.0, group="friction",
      plausible=(0.1, 10.0)),
)
declare_relation(("bw_gamma", "bw_beta"), lambda g, b: abs(g) <= b,
                 lambda g, b: f"must be within [-bw_beta, bw_beta] = [{-b:g}, {b:g}]")

BOUC_WEN_BLOCK = Block.of("sigma0", "Fc", "sigma2", "bw_beta", "bw_gamma", "bw_n")
BW_SIGMA0 = BOUC_WEN_BLOCK.index("sigma0")
BW_FC = BOUC_WEN_BLOCK.index("Fc")
BW_SIGMA2 = BOUC_WEN_BLOCK.index("sigma2")
BW_BETA = BOUC_WEN_BLOCK.index("bw_beta")
BW_GAMMA = BOUC_WEN_BLOCK.index("bw_gamma")
BW_N = BOUC_WEN_BLOCK.index("bw_n")
BOUC_WEN_SIZE = len(BOUC_WEN_BLOCK)


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
    dzdot_dv = 1.0 - (beta * sign(v) * an1 * s + gam * an) / norm
    dzdot_dz = -(s0 / fc) * n * an1 * (beta * abs(v) + gam * v * sign(s)) / norm
    return zdot, s0 * z + s2 * v, dzdot_dv, dzdot_dz, s2, s0


@njit(cache=True, inline="always")
def bouc_wen(v, z, p, o):  # pragma: no cover - compiled
    return bouc_wen_law(v, z, p[o + BW_SIGMA0], p[o + BW_FC], p[o + BW_SIGMA2],
                        p[o + BW_BETA], p[o + BW_GAMMA], p[o + BW_N])


@njit(cache=True)
def bouc_wen_params(v, z, p, o, g, rz, rf):  # pragma: no cover - compiled
    s0, fc = p[o + BW_SIGMA0], p[o + BW_FC]
    beta, gam, n = p[o + BW_BETA], p[o + BW_GAMMA], p[o + BW_N]
    clear_block(g, rz, rf, o, BOUC_WEN_SIZE)
    if fc <= 0.0:
        g[rf, o + BW_SIGMA2] = v
        return
    s, an1, numerator, norm = _bouc_wen_terms(v, z, s0, fc, beta, gam, n)
    an = abs(s) * an1
    dzdot_ds = -n * an1 * (beta * abs(v) + gam * v * sign(s)) / norm
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


class BoucWen(CoulombBristleLaw):
    """Bouc-Wen hysteresis used as a friction model (normalised to slide at ±Fc)."""

    block = BOUC_WEN_BLOCK
    law = "bouc_wen"
    cli_name = "bouc-wen"
    held_in_comparison = ("bw_n",)  # the shape exponent

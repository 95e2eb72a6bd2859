"""Elasto-plastic friction (Dupont, Hayward, Armstrong & Altpeter, "Single state
elastoplastic friction models", IEEE TAC 47(5), 787-792, 2002): LuGre whose bristle
creeps only past a break-away deflection.

dz/dt = v·(1 − α(z, v)·z/z_ss(v)),  z_ss(v) = sgn(v)·g(v)/σ0,
F = σ0·z + σ1·dz/dt + σ2·v,  g(v) = Fc + (Fs − Fc)·e^(−(|v|/vs)^δ),

α(z, v) = 0                                   if sgn(z) ≠ sgn(v) (unloading is elastic),
α(z, v) = 0                                   if |z| ≤ z_ba (elastic presliding: no drift),
α(z, v) = ½ − ½·cos(π·(|z| − z_ba)/(|z_ss(v)| − z_ba))   if z_ba < |z| < |z_ss(v)|,
α(z, v) = 1                                   if |z| ≥ |z_ss(v)| (LuGre).

Dupont et al. write the transition as ½·sin(π·(|z| − (z_max + z_ba)/2)/(z_max − z_ba)) + ½
with z_max = |z_ss(v)|: the same function. The break-away deflection is a fraction of the
smallest steady deflection, z_ba = z_ba_ratio·min(Fc, Fs)/σ0 (0 <= ratio < 1), so that
0 <= z_ba < |z_ss(v)| at every speed, as the model needs, whatever σ0, Fc and Fs a fit
tries (g(v) lies between Fs and Fc; a fit that tries Fs < Fc with z_ba a fraction of Fc
alone crossed z_ss at low speeds, and α stepping there took millions of steps a run).
α is continuous with a continuous slope in |z|, so the rates are C1 in z.
"""

from __future__ import annotations

import math
from typing import ClassVar

from ...core.component import Block
from ...core.jit import njit
from ...parameters.catalogue import ParameterSpec, declare
from .base import (
    RELAXED_LEVEL,
    StribeckBristleLaw,
    sign,
    stribeck_curve,
    stribeck_curve_params,
)
from .lugre import LUGRE_BLOCK, lugre_bound, lugre_scales

declare(ParameterSpec(
    "z_ba_ratio", "", "elasto-plastic break-away deflection z_ba as a fraction of the "
    "smallest steady deflection min(Fc, Fs)/sigma0 (0 <= ratio < 1)", 0.5, 0.0, False, 0.999,
    group="friction", plausible=(0.05, 0.95)))

ELASTO_PLASTIC_BLOCK = LUGRE_BLOCK + Block.of("z_ba_ratio")
EP_SIGMA0 = ELASTO_PLASTIC_BLOCK.index("sigma0")
EP_SIGMA1 = ELASTO_PLASTIC_BLOCK.index("sigma1")
EP_SIGMA2 = ELASTO_PLASTIC_BLOCK.index("sigma2")
EP_FC = ELASTO_PLASTIC_BLOCK.index("Fc")
EP_FS = ELASTO_PLASTIC_BLOCK.index("Fs")
EP_VS = ELASTO_PLASTIC_BLOCK.index("vs")
EP_DELTA = ELASTO_PLASTIC_BLOCK.index("delta")
EP_RATIO = ELASTO_PLASTIC_BLOCK.index("z_ba_ratio")
ELASTO_PLASTIC_SIZE = len(ELASTO_PLASTIC_BLOCK)


@njit(cache=True)
def transition(a, a_ba, a_ss):  # pragma: no cover - compiled
    """α at the bristle force a = σ0·|z| between the break-away force a_ba = σ0·z_ba and
    the steady force a_ss = g(v), and its derivatives in a, a_ba and a_ss."""
    if a <= a_ba:
        return 0.0, 0.0, 0.0, 0.0
    if a >= a_ss:
        return 1.0, 0.0, 0.0, 0.0
    width = a_ss - a_ba
    u = (a - a_ba) / width
    slope = 0.5 * math.pi * math.sin(math.pi * u) / width  # dα/da
    return (0.5 - 0.5 * math.cos(math.pi * u), slope, slope * (a - a_ss) / width,
            -slope * (a - a_ba) / width)


@njit(cache=True)
def _creep(v, z, s0, a_ba, g):  # pragma: no cover - compiled
    """Q = α·σ0·|z|/g (dz/dt = v·(1 − Q)) and its derivatives in a = σ0·|z|, a_ba and g;
    Q = 0 where the bristle unloads (sgn(z) ≠ sgn(v))."""
    if z * v <= 0.0:
        return 0.0, 0.0, 0.0, 0.0
    a = s0 * abs(z)
    alpha, da, dba, dss = transition(a, a_ba, g)
    return (alpha * a / g, (da * a + alpha) / g, dba * a / g,
            dss * a / g - alpha * a / (g * g))


@njit(cache=True)
def elasto_plastic_law(v, z, s0, s1, s2, fc, fs, vs, delta, ratio):  # pragma: no cover
    """(ż, F, ∂ż/∂v, ∂ż/∂z, ∂F/∂v, ∂F/∂z); the frictionless limit as LuGre's."""
    g, dg = stribeck_curve(v, fc, fs, vs, delta)
    if g <= RELAXED_LEVEL * fs:
        return 0.0, s2 * v, 0.0, 0.0, s2, 0.0
    q, dq_da, _, dq_dg = _creep(v, z, s0, ratio * min(fc, fs), g)
    zdot = v * (1.0 - q)
    dzdot_dv = 1.0 - q - v * dq_dg * dg
    dzdot_dz = -v * dq_da * s0 * sign(z)
    return (zdot, s0 * z + s1 * zdot + s2 * v, dzdot_dv, dzdot_dz, s1 * dzdot_dv + s2,
            s0 + s1 * dzdot_dz)


@njit(cache=True, inline="always")
def elasto_plastic(v, z, p, o):  # pragma: no cover - compiled
    return elasto_plastic_law(v, z, p[o + EP_SIGMA0], p[o + EP_SIGMA1], p[o + EP_SIGMA2],
                              p[o + EP_FC], p[o + EP_FS], p[o + EP_VS], p[o + EP_DELTA],
                              p[o + EP_RATIO])


@njit(cache=True)
def elasto_plastic_params(v, z, p, o, g, rz, rf):  # pragma: no cover - compiled
    """∂ż/∂θ into row rz and ∂F/∂θ into row rf for every θ of the block."""
    s0, s1, fc, ratio = p[o + EP_SIGMA0], p[o + EP_SIGMA1], p[o + EP_FC], p[o + EP_RATIO]
    fs = p[o + EP_FS]
    level, dg_dfc, dg_dfs, dg_dvs, dg_ddelta = stribeck_curve_params(
        v, fc, fs, p[o + EP_VS], p[o + EP_DELTA])
    # a_ba = ratio·min(Fc, Fs): its slope in Fc or in Fs, whichever is the smaller
    dba_dfc, dba_dfs = (ratio, 0.0) if fc <= fs else (0.0, ratio)
    for k in range(ELASTO_PLASTIC_SIZE):
        g[rz, o + k] = 0.0
    if level > RELAXED_LEVEL * p[o + EP_FS]:
        q, dq_da, dq_dba, dq_dg = _creep(v, z, s0, ratio * min(fc, fs), level)
        g[rz, o + EP_SIGMA0] = -v * dq_da * abs(z)
        g[rz, o + EP_FC] = -v * (dq_dba * dba_dfc + dq_dg * dg_dfc)
        g[rz, o + EP_FS] = -v * (dq_dba * dba_dfs + dq_dg * dg_dfs)
        g[rz, o + EP_VS] = -v * dq_dg * dg_dvs
        g[rz, o + EP_DELTA] = -v * dq_dg * dg_ddelta
        g[rz, o + EP_RATIO] = -v * dq_dba * min(fc, fs)
        zdot = v * (1.0 - q)
    else:
        zdot = 0.0
        z = 0.0
    for k in range(ELASTO_PLASTIC_SIZE):
        g[rf, o + k] = s1 * g[rz, o + k]
    g[rf, o + EP_SIGMA0] += z
    g[rf, o + EP_SIGMA1] = zdot
    g[rf, o + EP_SIGMA2] = v


#: the typical deflection, stiffness and bound of LuGre's bristle: the block starts with
#: LuGre's, and past |z_ss(v)| the law is LuGre's (α = 1), so |σ0·z| <= max(Fs, Fc) holds
elasto_plastic_scales = lugre_scales
elasto_plastic_bound = lugre_bound


class ElastoPlastic(StribeckBristleLaw):
    """Elasto-plastic friction (Dupont et al. 2002): LuGre without presliding drift. The
    bristle is a pure spring below the break-away deflection z_ba = z_ba_ratio·min(Fc,
    Fs)/σ0 and whenever it unloads; it creeps as LuGre's only near its steady deflection."""

    block: ClassVar[Block] = ELASTO_PLASTIC_BLOCK
    law: ClassVar[str] = "elasto_plastic"
    cli_name: ClassVar[str] = "elasto-plastic"

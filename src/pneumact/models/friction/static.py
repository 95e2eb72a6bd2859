"""Static friction maps, no internal state: Coulomb + viscous, and the Stribeck curve.

The sign is regularised as tanh(v/v_reg), so the map is smooth for the integrator.
"""

from __future__ import annotations

import math

import numpy as np

from ...core.component import Block
from ...core.jit import njit
from .base import STATELESS_LAW, FrictionModel, clear_block, stribeck_curve, stribeck_curve_params

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
    clear_block(g, rz, rf, o, COULOMB_SIZE)
    g[rf, o + CV_FC] = th
    g[rf, o + CV_SIGMA2] = v
    g[rf, o + CV_VREG] = -p[o + CV_FC] * (1.0 - th * th) * v / (vr * vr)


@njit(cache=True)
def coulomb_viscous_scales(p, o):  # pragma: no cover - compiled
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
    clear_block(g, rz, rf, o, STRIBECK_SIZE)
    g[rf, o + SM_FC] = dg_dfc * th
    g[rf, o + SM_FS] = dg_dfs * th
    g[rf, o + SM_VS] = dg_dvs * th
    g[rf, o + SM_DELTA] = dg_ddelta * th
    g[rf, o + SM_SIGMA2] = v
    g[rf, o + SM_VREG] = -gv * (1.0 - th * th) * v / (vr * vr)


@njit(cache=True)
def stribeck_map_scales(p, o):  # pragma: no cover - compiled
    return 1.0, 0.0, p[o + SM_VREG]


class StaticMap(FrictionModel):
    """A friction map F(v) with no internal state: no presliding, no hysteresis of its own."""

    states = ()
    template = STATELESS_LAW
    compiled = ("", "_params", "_scales")

    def steady_states(self, v, params) -> np.ndarray:
        return np.zeros((np.atleast_1d(np.asarray(v)).shape[0], 0))

    def presliding_stiffness(self, params) -> float:
        return 0.0

    def presliding_range(self, params) -> float:
        return 0.0


class CoulombViscous(StaticMap):
    """Static Coulomb + viscous map, sign regularised over ``v_reg``."""

    block = COULOMB_BLOCK
    law = "coulomb_viscous"
    cli_name = "coulomb-viscous"


class StribeckMap(StaticMap):
    """Static Stribeck map g(v)·sgn(v) + σ2·v, sign regularised over ``v_reg``."""

    block = STRIBECK_BLOCK
    law = "stribeck_map"
    cli_name = "stribeck"

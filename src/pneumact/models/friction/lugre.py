"""LuGre friction (Canudas de Wit et al. 1995; paper eqs. 6-8), with constant or
decaying micro-damping.

dz/dt = v − σ0·|v|·z/g(v), F = σ0·z + σ1·dz/dt + σ2·v, g(v) = Fc + (Fs − Fc)·e^(−(|v|/vs)^δ).

Speed: numba counts references on every array passed to a call it does not inline (two
atomic operations per array), so ``lugre``, the function the hot loop calls, is inlined
(``inline="always"``), reads the block and calls ``lugre_law``, which takes scalars only.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

from ...core.component import Block
from ...core.jit import njit
from .base import (
    RELAXED_LEVEL,
    StribeckBristleLaw,
    presliding_scale,
    sign,
    stribeck_curve,
    stribeck_curve_params,
)

LUGRE_BLOCK = Block.of("sigma0", "sigma1", "sigma2", "Fc", "Fs", "vs", "delta")
LG_SIGMA0 = LUGRE_BLOCK.index("sigma0")
LG_SIGMA1 = LUGRE_BLOCK.index("sigma1")
LG_SIGMA2 = LUGRE_BLOCK.index("sigma2")
LG_FC = LUGRE_BLOCK.index("Fc")
LG_FS = LUGRE_BLOCK.index("Fs")
LG_VS = LUGRE_BLOCK.index("vs")
LG_DELTA = LUGRE_BLOCK.index("delta")
LUGRE_SIZE = len(LUGRE_BLOCK)


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
    dzdot_dv = 1.0 - s0 * z * (sign(v) * g - av * dg) / (g * g)
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
def lugre_scales(p, o):  # pragma: no cover - compiled
    """(typical bristle deflection Fs/σ0, bristle stiffness σ0, regularisation speed 0)."""
    s0 = p[o + LG_SIGMA0]
    return presliding_scale(max(p[o + LG_FS], p[o + LG_FC]), s0), s0, 0.0


@njit(cache=True)
def lugre_bound(p, o):  # pragma: no cover - compiled
    """Largest |z| the law allows: the set |σ0·z| <= max(Fs, Fc) is invariant."""
    return max(p[o + LG_FS], p[o + LG_FC]) / p[o + LG_SIGMA0]


lugre_decaying_scales = lugre_scales
lugre_decaying_bound = lugre_bound


@dataclass(frozen=True, eq=False)
class LuGre(StribeckBristleLaw):
    """LuGre friction (Canudas de Wit et al. 1995; paper eqs. 6-8).

    ``decaying_damping=True`` uses σ1(v) = σ1·exp(−(v/vs)²) instead of a constant σ1.
    """

    decaying_damping: bool = False
    block: ClassVar[Block] = LUGRE_BLOCK
    cli_name: ClassVar[str] = "lugre"

    @property
    def spec(self) -> str:
        return "lugre (decaying damping)" if self.decaying_damping else "lugre"

    def __post_init__(self):
        from ...checks import check_bool

        check_bool("decaying_damping", self.decaying_damping, where="LuGre")

    @property
    def law(self) -> str:  # type: ignore[override]
        return "lugre_decaying" if self.decaying_damping else "lugre"

    def __repr__(self) -> str:
        return f"LuGre(decaying_damping={self.decaying_damping})"

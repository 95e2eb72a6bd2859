"""Dahl friction (Dahl 1976): a rate-independent hysteresis with no Stribeck dip.

dz/dt = v·φ(1 − σ0·z·sgn(v)/Fc), φ(s) = |s|^α·sgn(s); F = σ0·z + σ2·v.
"""

from __future__ import annotations

import math
from typing import ClassVar

from ...core.component import Block
from ...core.jit import njit
from ...parameters.catalogue import ParameterSpec, declare
from .base import CoulombBristleLaw, clear_block, presliding_scale, sign

declare(ParameterSpec("dahl_alpha", "", "Dahl shape exponent", 1.0, 0.0, True, 100.0,
                      group="friction", plausible=(0.1, 10.0)))

DAHL_BLOCK = Block.of("sigma0", "Fc", "sigma2", "dahl_alpha")
DH_SIGMA0 = DAHL_BLOCK.index("sigma0")
DH_FC = DAHL_BLOCK.index("Fc")
DH_SIGMA2 = DAHL_BLOCK.index("sigma2")
DH_ALPHA = DAHL_BLOCK.index("dahl_alpha")
DAHL_SIZE = len(DAHL_BLOCK)


@njit(cache=True)
def _dahl_shape(v, z, s0, fc, alpha):  # pragma: no cover - compiled
    """s = 1 − σ0·z·sgn(v)/Fc, φ(s) = |s|^α·sgn(s) and dφ/ds."""
    s = 1.0 - s0 * z * sign(v) / fc
    a = max(abs(s), 1e-300)
    return s, a**alpha * sign(s), alpha * a ** (alpha - 1.0)


@njit(cache=True)
def dahl_law(v, z, s0, fc, s2, alpha):  # pragma: no cover - compiled
    if fc <= 0.0:  # frictionless: the bristle bound Fc/σ0 is 0, F = σ2·v (see LuGre)
        return 0.0, s2 * v, 0.0, 0.0, s2, 0.0
    _, phi, dphi = _dahl_shape(v, z, s0, fc, alpha)
    return v * phi, s0 * z + s2 * v, phi, -s0 * abs(v) * dphi / fc, s2, s0


@njit(cache=True, inline="always")
def dahl(v, z, p, o):  # pragma: no cover - compiled
    return dahl_law(v, z, p[o + DH_SIGMA0], p[o + DH_FC], p[o + DH_SIGMA2], p[o + DH_ALPHA])


@njit(cache=True)
def dahl_params(v, z, p, o, g, rz, rf):  # pragma: no cover - compiled
    s0, fc = p[o + DH_SIGMA0], p[o + DH_FC]
    clear_block(g, rz, rf, o, DAHL_SIZE)
    if fc <= 0.0:
        g[rf, o + DH_SIGMA2] = v
        return
    s, phi, dphi = _dahl_shape(v, z, s0, fc, p[o + DH_ALPHA])
    sv = sign(v)
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


class Dahl(CoulombBristleLaw):
    """Dahl friction (Dahl 1976): a rate-independent hysteresis with no Stribeck dip."""

    block = DAHL_BLOCK
    law = "dahl"
    cli_name = "dahl"
    #: α < ½ makes dz/dt's slope near |z| = Fc/σ0 so steep that a run takes millions of
    #: steps (a comparison's fit tried α = 0.1 on Coulomb-viscous records)
    comparison_ranges: ClassVar[dict[str, tuple[float, float]]] = {"dahl_alpha": (0.5, 4.0)}

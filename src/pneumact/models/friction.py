"""Friction models behind one interface: LuGre, Dahl, Bouc-Wen and static maps.

Every model is a compiled scalar function ``f(v, z, prm)`` of the sliding velocity ``v``
and one internal state ``z`` (bristle deflection; unused and constant for static maps),
returning ``(dz/dt, F, d(dz/dt)/dv, d(dz/dt)/dz, dF/dv, dF/dz)``. The partial derivatives
feed the analytic Jacobian of the implicit integrator. A small strategy object per model
names its kernel and the parameters it needs; the same object is passed to an
``Actuator`` or a ``FrictionRig``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from numba import njit

from .layout import (
    I_BW_BETA,
    I_BW_GAMMA,
    I_BW_N,
    I_DAHL_ALPHA,
    I_DELTA,
    I_FC,
    I_FS,
    I_SIGMA0,
    I_SIGMA1,
    I_SIGMA2,
    I_VREG,
    I_VS,
)


@njit(cache=True, inline="always")
def _sign(v):  # pragma: no cover - compiled
    return 1.0 if v > 0.0 else (-1.0 if v < 0.0 else 0.0)


@njit(cache=True, inline="always")
def stribeck_curve(v, prm):  # pragma: no cover - compiled
    """g(v) = Fc + (Fs − Fc)·exp(−(|v|/vs)^δ) and its derivative dg/dv."""
    fc = prm[I_FC]
    ds = prm[I_FS] - fc
    vs = prm[I_VS]
    delta = prm[I_DELTA]
    a = abs(v) / vs
    if a == 0.0:
        return fc + ds, 0.0
    ad = a**delta
    e = math.exp(-ad)
    dg = -ds * e * delta * ad / a * _sign(v) / vs
    return fc + ds * e, dg


@njit(cache=True, inline="always")
def _lugre_core(v, z, prm, s1, ds1):  # pragma: no cover - compiled
    s0 = prm[I_SIGMA0]
    g, dg = stribeck_curve(v, prm)
    av = abs(v)
    zdot = v - s0 * av * z / g
    dzdot_dv = 1.0 - s0 * z * (_sign(v) * g - av * dg) / (g * g)
    dzdot_dz = -s0 * av / g
    sigma2 = prm[I_SIGMA2]
    force = s0 * z + s1 * zdot + sigma2 * v
    df_dv = ds1 * zdot + s1 * dzdot_dv + sigma2
    df_dz = s0 + s1 * dzdot_dz
    return zdot, force, dzdot_dv, dzdot_dz, df_dv, df_dz


@njit(cache=True, inline="always")
def lugre(v, z, prm):  # pragma: no cover - compiled
    """LuGre (paper eqs. 6-8) with constant micro-damping σ1."""
    return _lugre_core(v, z, prm, prm[I_SIGMA1], 0.0)


@njit(cache=True, inline="always")
def lugre_decaying_damping(v, z, prm):  # pragma: no cover - compiled
    """LuGre with σ1(v) = σ1·exp(−(v/vs)²): micro-damping that fades once sliding."""
    vs = prm[I_VS]
    s1 = prm[I_SIGMA1] * math.exp(-((v / vs) ** 2))
    return _lugre_core(v, z, prm, s1, -2.0 * v / (vs * vs) * s1)


@njit(cache=True, inline="always")
def dahl(v, z, prm):  # pragma: no cover - compiled
    """Dahl: dz/dt = v·φ(1 − σ0·z·sgn(v)/Fc), φ(s) = |s|^α·sgn(s); F = σ0·z + σ2·v."""
    s0 = prm[I_SIGMA0]
    fc = prm[I_FC]
    alpha = prm[I_DAHL_ALPHA]
    sv = _sign(v)
    s = 1.0 - s0 * z * sv / fc
    a = max(abs(s), 1e-300)
    phi = a**alpha * _sign(s)
    dphi = alpha * a ** (alpha - 1.0)
    zdot = v * phi
    sigma2 = prm[I_SIGMA2]
    return zdot, s0 * z + sigma2 * v, phi, -s0 * abs(v) * dphi / fc, sigma2, s0


@njit(cache=True, inline="always")
def bouc_wen(v, z, prm):  # pragma: no cover - compiled
    """Bouc-Wen, normalised so that steady sliding gives F = ±Fc + σ2·v.

    dz/dt = v − (β·|v|·|s|^(n−1)·s + γ·v·|s|^n)/(β + γ), s = σ0·z/Fc; F = σ0·z + σ2·v.
    With β = 1, γ = 0, n = 1 it is the Dahl model.
    """
    s0 = prm[I_SIGMA0]
    fc = prm[I_FC]
    beta = prm[I_BW_BETA]
    gam = prm[I_BW_GAMMA]
    n = prm[I_BW_N]
    norm = beta + gam
    s = s0 * z / fc
    a = abs(s)
    an1 = max(a, 1e-300) ** (n - 1.0)
    an = a * an1
    av = abs(v)
    zdot = v - (beta * av * an1 * s + gam * v * an) / norm
    dzdot_dv = 1.0 - (beta * _sign(v) * an1 * s + gam * an) / norm
    dzdot_dz = -(s0 / fc) * n * an1 * (beta * av + gam * v * _sign(s)) / norm
    sigma2 = prm[I_SIGMA2]
    return zdot, s0 * z + sigma2 * v, dzdot_dv, dzdot_dz, sigma2, s0


@njit(cache=True, inline="always")
def coulomb_viscous(v, z, prm):  # pragma: no cover - compiled
    """Static map F = Fc·sgn(v) + σ2·v, sign regularised as tanh(v/v_reg)."""
    vr = prm[I_VREG]
    th = math.tanh(v / vr)
    fc = prm[I_FC]
    sigma2 = prm[I_SIGMA2]
    return 0.0, fc * th + sigma2 * v, 0.0, 0.0, fc * (1.0 - th * th) / vr + sigma2, 0.0


@njit(cache=True, inline="always")
def stribeck_map(v, z, prm):  # pragma: no cover - compiled
    """Static map F = g(v)·sgn(v) + σ2·v (the LuGre steady state), sign regularised."""
    vr = prm[I_VREG]
    th = math.tanh(v / vr)
    g, dg = stribeck_curve(v, prm)
    sigma2 = prm[I_SIGMA2]
    df_dv = dg * th + g * (1.0 - th * th) / vr + sigma2
    return 0.0, g * th + sigma2 * v, 0.0, 0.0, df_dv, 0.0


# --- parameter derivatives: d[k] = (∂(dz/dt)/∂θ_k, ∂F/∂θ_k), θ = FRICTION_SENS -------------
FRICTION_SENS = ("sigma0", "sigma1", "sigma2", "Fc", "Fs", "vs")
_SENS_SLOTS = (I_SIGMA0, I_SIGMA1, I_SIGMA2, I_FC, I_FS, I_VS)


@njit(cache=True)
def _lugre_dtheta_core(v, z, prm, s1, ds1_dsigma1, ds1_dvs, d):  # pragma: no cover
    s0 = prm[I_SIGMA0]
    fc = prm[I_FC]
    ds = prm[I_FS] - fc
    vs = prm[I_VS]
    delta = prm[I_DELTA]
    a = abs(v) / vs
    if a == 0.0:
        e = 1.0
        dg_dvs = 0.0
    else:
        ad = a**delta
        e = math.exp(-ad)
        dg_dvs = ds * e * delta * ad / vs
    g = fc + ds * e
    av = abs(v)
    zdot = v - s0 * av * z / g
    dzd_dg = s0 * av * z / (g * g)
    dzd_ds0 = -av * z / g
    d[0, 0] = dzd_ds0
    d[0, 1] = z + s1 * dzd_ds0
    d[1, 0] = 0.0
    d[1, 1] = ds1_dsigma1 * zdot
    d[2, 0] = 0.0
    d[2, 1] = v
    d[3, 0] = dzd_dg * (1.0 - e)
    d[3, 1] = s1 * d[3, 0]
    d[4, 0] = dzd_dg * e
    d[4, 1] = s1 * d[4, 0]
    d[5, 0] = dzd_dg * dg_dvs
    d[5, 1] = s1 * d[5, 0] + ds1_dvs * zdot


@njit(cache=True)
def lugre_dtheta(v, z, prm, d):  # pragma: no cover - compiled
    """Analytic ∂(dz/dt)/∂θ and ∂F/∂θ of ``lugre`` for θ = FRICTION_SENS."""
    _lugre_dtheta_core(v, z, prm, prm[I_SIGMA1], 1.0, 0.0, d)


@njit(cache=True)
def lugre_decaying_damping_dtheta(v, z, prm, d):  # pragma: no cover - compiled
    """Analytic parameter derivatives of ``lugre_decaying_damping``."""
    vs = prm[I_VS]
    w = math.exp(-((v / vs) ** 2))
    s1 = prm[I_SIGMA1] * w
    _lugre_dtheta_core(v, z, prm, s1, w, s1 * 2.0 * v * v / (vs * vs * vs), d)


@njit(cache=True, inline="always")
def _fd_slot(prm, k):  # pragma: no cover - compiled
    slot = _SENS_SLOTS[k]
    scale = abs(prm[slot])
    return slot, 1e-7 * (scale if scale > 0.0 else 1.0)


@njit(cache=True)
def dahl_dtheta(v, z, prm, d):  # pragma: no cover - compiled
    """Parameter derivatives of ``dahl`` by forward differences of the law alone."""
    base = dahl(v, z, prm)
    p = prm.copy()
    for k in range(6):
        slot, h = _fd_slot(prm, k)
        p[slot] = prm[slot] + h
        r = dahl(v, z, p)
        d[k, 0] = (r[0] - base[0]) / h
        d[k, 1] = (r[1] - base[1]) / h
        p[slot] = prm[slot]


@njit(cache=True)
def bouc_wen_dtheta(v, z, prm, d):  # pragma: no cover - compiled
    """Parameter derivatives of ``bouc_wen`` by forward differences of the law alone."""
    base = bouc_wen(v, z, prm)
    p = prm.copy()
    for k in range(6):
        slot, h = _fd_slot(prm, k)
        p[slot] = prm[slot] + h
        r = bouc_wen(v, z, p)
        d[k, 0] = (r[0] - base[0]) / h
        d[k, 1] = (r[1] - base[1]) / h
        p[slot] = prm[slot]


@njit(cache=True)
def coulomb_viscous_dtheta(v, z, prm, d):  # pragma: no cover - compiled
    """Parameter derivatives of ``coulomb_viscous`` (only Fc and σ2 enter)."""
    for k in range(6):
        d[k, 0] = 0.0
        d[k, 1] = 0.0
    d[2, 1] = v
    d[3, 1] = math.tanh(v / prm[I_VREG])


@njit(cache=True)
def stribeck_map_dtheta(v, z, prm, d):  # pragma: no cover - compiled
    """Parameter derivatives of ``stribeck_map`` by forward differences of the law alone."""
    base = stribeck_map(v, z, prm)
    p = prm.copy()
    for k in range(6):
        slot, h = _fd_slot(prm, k)
        p[slot] = prm[slot] + h
        r = stribeck_map(v, z, p)
        d[k, 0] = 0.0
        d[k, 1] = (r[1] - base[1]) / h
        p[slot] = prm[slot]


@njit(cache=True)
def _evaluate_many(fn_id, v, z, prm, out):  # pragma: no cover - compiled
    for i in range(v.shape[0]):
        if fn_id == 0:
            r = lugre(v[i], z[i], prm)
        elif fn_id == 1:
            r = lugre_decaying_damping(v[i], z[i], prm)
        elif fn_id == 2:
            r = dahl(v[i], z[i], prm)
        elif fn_id == 3:
            r = bouc_wen(v[i], z[i], prm)
        elif fn_id == 4:
            r = coulomb_viscous(v[i], z[i], prm)
        else:
            r = stribeck_map(v[i], z[i], prm)
        for j in range(6):
            out[i, j] = r[j]


_KERNEL_IDS = {
    "lugre": 0, "lugre_decaying_damping": 1, "dahl": 2, "bouc_wen": 3,
    "coulomb_viscous": 4, "stribeck_map": 5,
}


class FrictionModel:
    """Strategy object: which compiled friction law to use and what it needs."""

    kernel: ClassVar[str]
    required: ClassVar[tuple[str, ...]]
    has_state: ClassVar[bool] = True
    module: ClassVar[str] = "pneumact.models.friction"

    def evaluate(self, v, z, params) -> dict[str, np.ndarray]:
        """Evaluate the law at arrays ``v``, ``z`` (outside any simulation), for tests and
        plots: returns dz/dt, force and the partial derivatives."""
        v = np.atleast_1d(np.asarray(v, dtype=np.float64))
        z = np.broadcast_to(np.asarray(z, dtype=np.float64), v.shape).copy()
        out = np.empty((v.size, 6))
        _evaluate_many(_KERNEL_IDS[self.kernel], v, z, _vector(params), out)
        keys = ("zdot", "force", "dzdot_dv", "dzdot_dz", "dforce_dv", "dforce_dz")
        return {k: out[:, i] for i, k in enumerate(keys)}

    def steady_state(self, v, params) -> np.ndarray:
        """Friction force in steady sliding at velocity ``v`` (dz/dt = 0)."""
        v = np.atleast_1d(np.asarray(v, dtype=np.float64))
        p = _vector(params)
        if not self.has_state:
            return self.evaluate(v, 0.0, params)["force"]
        z = np.sign(v) * self._steady_z(np.abs(v), p)
        return self.evaluate(v, z, params)["force"]

    def _steady_z(self, speed, p):
        return p[I_FC] / p[I_SIGMA0] * np.ones_like(speed)

    @property
    def name(self) -> str:
        return type(self).__name__

    def __repr__(self) -> str:
        return f"{self.name}()"

    def __eq__(self, other: object) -> bool:
        return type(self) is type(other) and self.kernel == other.kernel

    def __hash__(self) -> int:
        return hash((type(self).__name__, self.kernel))


def _vector(params) -> np.ndarray:
    if isinstance(params, np.ndarray):
        return params
    return params.vector()


@dataclass(frozen=True, eq=False)
class LuGre(FrictionModel):
    """LuGre friction (Canudas de Wit et al. 1995; paper eqs. 6-8).

    ``decaying_damping=True`` uses σ1(v) = σ1·exp(−(v/vs)²) instead of a constant σ1.
    """

    decaying_damping: bool = False
    required: ClassVar[tuple[str, ...]] = ("sigma0", "sigma1", "sigma2", "Fc", "Fs", "vs",
                                           "delta")

    @property
    def kernel(self) -> str:  # type: ignore[override]
        return "lugre_decaying_damping" if self.decaying_damping else "lugre"

    def _steady_z(self, speed, p):
        g = p[I_FC] + (p[I_FS] - p[I_FC]) * np.exp(-((speed / p[I_VS]) ** p[I_DELTA]))
        return g / p[I_SIGMA0]

    def __repr__(self) -> str:
        return f"LuGre(decaying_damping={self.decaying_damping})"


class Dahl(FrictionModel):
    """Dahl friction (Dahl 1976): a rate-independent hysteresis with no Stribeck dip."""

    kernel = "dahl"
    required = ("sigma0", "Fc", "sigma2", "dahl_alpha")


class BoucWen(FrictionModel):
    """Bouc-Wen hysteresis used as a friction model (normalised to slide at ±Fc)."""

    kernel = "bouc_wen"
    required = ("sigma0", "Fc", "sigma2", "bw_beta", "bw_gamma", "bw_n")

    def _steady_z(self, speed, p):
        return p[I_FC] / p[I_SIGMA0] * np.ones_like(speed)


class CoulombViscous(FrictionModel):
    """Static Coulomb + viscous map, sign regularised over ``v_reg``."""

    kernel = "coulomb_viscous"
    required = ("Fc", "sigma2", "v_reg")
    has_state = False


class StribeckMap(FrictionModel):
    """Static Stribeck map g(v)·sgn(v) + σ2·v, sign regularised over ``v_reg``."""

    kernel = "stribeck_map"
    required = ("Fc", "Fs", "vs", "delta", "sigma2", "v_reg")
    has_state = False

"""Compressible flow through orifices and the chamber law (paper eqs. 2-5).

``flow_function`` is Φ(r) of the pressure ratio r = p_d/p_u: choked below the critical
ratio, subsonic above it, and a short linear (laminar) branch on [r_lin, 1] so that the
right-hand side is Lipschitz and its Jacobian finite at r → 1. ``orifice`` gives the mass
flow from side 1 to side 2 and reverses it when p2 > p1.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from .layout import (
    I_FLOW_COEF,
    I_FLOW_LINSLOPE,
    I_FLOW_PHICHOKED,
    I_FLOW_RCRIT,
    I_GAMMA,
    I_R,
    I_RLIN,
    I_T,
)


@njit(cache=True, inline="always")
def critical_ratio(gamma):  # pragma: no cover - compiled
    """r_c = (2/(γ+1))^(γ/(γ−1)), ≈ 0.528 for air."""
    return (2.0 / (gamma + 1.0)) ** (gamma / (gamma - 1.0))


@njit(cache=True, inline="always")
def _phi_subsonic(r, gamma):  # pragma: no cover - compiled
    """Subsonic Φ and dΦ/dr; every power of r is a product of a = r^(1/γ) and r."""
    a = r ** (1.0 / gamma)
    a2 = a * a
    q = 2.0 / (gamma - 1.0) * (a2 - r * a)
    phi = math.sqrt(max(q, 0.0))
    dq = 2.0 / (gamma - 1.0) * (2.0 / gamma * a2 / r - (gamma + 1.0) / gamma * a)
    return phi, dq / (2.0 * phi) if phi > 0.0 else 0.0


@njit(cache=True, inline="always")
def _flow_constants(gamma, r_lin):  # pragma: no cover - compiled
    """(r_c, choked Φ, slope of the laminar branch) for γ and r_lin."""
    rc = critical_ratio(gamma)
    phi_choked = (2.0 / (gamma + 1.0)) ** ((gamma + 1.0) / (2.0 * (gamma - 1.0)))
    return rc, phi_choked, _phi_subsonic(r_lin, gamma)[0] / (1.0 - r_lin)


@njit(cache=True, inline="always")
def _phi_law(r, gamma, r_lin, rc, phi_choked, lin_slope):  # pragma: no cover - compiled
    """Φ(r), dΦ/dr: choked below r_c, subsonic up to r_lin, linear (laminar) up to 1."""
    if r <= rc:
        return phi_choked, 0.0
    if r < r_lin:
        return _phi_subsonic(r, gamma)
    return lin_slope * (1.0 - r), -lin_slope


@njit(cache=True)
def flow_function(r, gamma, r_lin):  # pragma: no cover - compiled
    """Φ(r) and dΦ/dr for 0 ≤ r ≤ 1 (choked, subsonic, laminar near r = 1)."""
    rc, phi_choked, lin_slope = _flow_constants(gamma, r_lin)
    return _phi_law(r, gamma, r_lin, rc, phi_choked, lin_slope)


@njit(cache=True)
def derive_flow_constants(prm):  # pragma: no cover - compiled
    """Fill the derived slots of ``prm`` (r_c, choked Φ, √(γ/(R·T)), laminar slope) from
    γ, R, T and r_lin; the kernels call it once per run, not once per orifice."""
    gamma = prm[I_GAMMA]
    rc, phi_choked, lin_slope = _flow_constants(gamma, prm[I_RLIN])
    prm[I_FLOW_RCRIT] = rc
    prm[I_FLOW_PHICHOKED] = phi_choked
    prm[I_FLOW_COEF] = math.sqrt(gamma / (prm[I_R] * prm[I_T]))
    prm[I_FLOW_LINSLOPE] = lin_slope


@njit(cache=True, inline="always")
def _phi_fast(r, prm):  # pragma: no cover - compiled
    """Φ(r), dΦ/dr with the derived constants of ``prm``."""
    return _phi_law(r, prm[I_GAMMA], prm[I_RLIN], prm[I_FLOW_RCRIT], prm[I_FLOW_PHICHOKED],
                    prm[I_FLOW_LINSLOPE])


@njit(cache=True, inline="always")
def orifice(p1, p2, area, prm):  # pragma: no cover - compiled
    """Mass flow [kg/s] from side 1 to side 2 through effective area ``area``.

    Returns (ṁ, ∂ṁ/∂p1, ∂ṁ/∂p2); negative when the flow goes from 2 to 1. Needs the
    derived slots of ``prm`` (``derive_flow_constants``).
    """
    c = area * prm[I_FLOW_COEF]
    if p1 >= p2:
        if p1 <= 0.0:
            return 0.0, 0.0, 0.0
        r = p2 / p1
        phi, dphi = _phi_fast(r, prm)
        return c * p1 * phi, c * (phi - r * dphi), c * dphi
    if p2 <= 0.0:
        return 0.0, 0.0, 0.0
    r = p1 / p2
    phi, dphi = _phi_fast(r, prm)
    return -c * p2 * phi, -c * dphi, -c * (phi - r * dphi)


@njit(cache=True)
def _orifice_many(p1, p2, area, prm, out):  # pragma: no cover - compiled
    for i in range(p1.shape[0]):
        out[i, 0], out[i, 1], out[i, 2] = orifice(p1[i], p2[i], area, prm)


@njit(cache=True)
def _phi_many(r, gamma, r_lin, out):  # pragma: no cover - compiled
    for i in range(r.shape[0]):
        out[i, 0], out[i, 1] = flow_function(r[i], gamma, r_lin)


def flow_function_values(r, gamma: float = 1.4, r_lin: float = 0.999) -> np.ndarray:
    """Φ(r) evaluated at an array of pressure ratios (for tests and plots)."""
    r = np.atleast_1d(np.asarray(r, dtype=np.float64))
    out = np.empty((r.size, 2))
    _phi_many(r, gamma, r_lin, out)
    return out[:, 0]


def orifice_mass_flow(p_upstream, p_downstream, area: float, params) -> np.ndarray:
    """Mass flow [kg/s] through an orifice for arrays of pressures [Pa] (SI)."""
    p1, p2 = np.broadcast_arrays(np.atleast_1d(np.asarray(p_upstream, dtype=np.float64)),
                                 np.asarray(p_downstream, dtype=np.float64))
    p1, p2 = p1.ravel().copy(), p2.ravel().copy()
    out = np.empty((p1.size, 3))
    prm = (params if isinstance(params, np.ndarray) else params.vector()).copy()
    derive_flow_constants(prm)
    _orifice_many(p1, p2, float(area), prm, out)
    return out[:, 0]


# --- chamber laws: strategy objects that set the polytropic index n ------------------


class ChamberLaw:
    """How the chamber gas exchanges heat: dp/dt = n/V·(R·T·ṁ + p·A_d·v)."""

    def polytropic_index(self, params) -> float:
        raise NotImplementedError


@dataclass(frozen=True)
class Isothermal(ChamberLaw):
    """n = 1: slow processes, the chamber stays at the wall temperature (default)."""

    def polytropic_index(self, params) -> float:
        return 1.0


@dataclass(frozen=True)
class Adiabatic(ChamberLaw):
    """n = γ: fast processes with no heat exchange."""

    def polytropic_index(self, params) -> float:
        return float(params["gamma"])


@dataclass(frozen=True)
class Polytropic(ChamberLaw):
    """Any n between 1 (isothermal) and γ (adiabatic)."""

    n: float = 1.2

    def __post_init__(self):
        from ..errors import ParameterError

        if not (np.isfinite(self.n) and self.n >= 1.0):
            raise ParameterError(f"Polytropic: n = {self.n}, must be >= 1")

    def polytropic_index(self, params) -> float:
        return float(self.n)

"""Compressible flow through orifices and the chamber law (paper eqs. 2-5).

``phi`` is Φ(r) of the pressure ratio r = p_d/p_u: choked below the critical ratio,
subsonic above it, and a short linear (laminar) branch on [r_lin, 1] so that the
right-hand side is Lipschitz and its Jacobian finite at r → 1. ``orifice`` gives the
mass flow per unit effective area from side 1 to side 2 and reverses it when p2 > p1.
Like every component function it reads its block at offset ``o`` of the vector ``p``.

The chamber block ``CHAMBER_BLOCK`` (diaphragm area and volume, pressures, orifice
areas, gas) is the first part of every valve's block (``models.valves``); its derived
entries, the orifice-flow constants and the polytropic index, are computed by
``derive_chamber`` whenever a value changes. The chamber law (isothermal, adiabatic,
polytropic) is a strategy object that fixes two settings of the block: n = a + b·γ.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..core.component import Block
from ..core.jit import njit
from ..errors import ParameterError
from ..parameters.catalogue import ParameterSpec, declare, declare_relation

P = ParameterSpec
declare(
    P("A_d", "m^2", "effective diaphragm area", None, 0.0, True, 10.0, group="pneumatics",
      plausible=(1e-6, 1.0)),
    P("p_atm", "Pa", "atmospheric pressure (absolute)", None, 1e3, False, 1e7,
      group="pneumatics", plausible=(50e3, 110e3)),
    P("V0", "m^3", "chamber volume at the rest stop (x = 0)", None, 0.0, True, 10.0,
      group="pneumatics", plausible=(1e-8, 0.1)),
    P("p_res", "Pa", "vacuum reservoir pressure (absolute), below p_atm", None, 0.0, False,
      1e7, group="pneumatics", plausible=(1e3, 2e6)),
    P("gamma", "", "ratio of specific heats of the gas (ideal gases: 1 < gamma <= 5/3)", 1.4,
      1.0, True, 5.0 / 3.0, group="pneumatics"),
    P("R", "J/(kg*K)", "specific gas constant of air", 287.0, 0.0, True, 1e5,
      group="pneumatics", plausible=(50.0, 5000.0)),
    P("T", "K", "gas temperature (upstream and chamber)", 293.15, 0.0, True, 5000.0,
      group="pneumatics", plausible=(150.0, 600.0)),
    P("r_lin", "", "pressure ratio where the orifice flow turns linear (laminar branch)",
      0.999, 0.53, True, 1.0, group="pneumatics"),
    P("A_res", "m^2", "max effective area chamber -> vacuum reservoir", None, 0.0, False,
      1.0, group="valve", plausible=(0.0, 1e-2)),
    P("A_atm", "m^2", "max effective area atmosphere -> chamber", None, 0.0, False, 1.0,
      group="valve", plausible=(0.0, 1e-2)),
)
declare(
    P("iso_C_res", "m^3/(s*Pa)", "ISO 6358 sonic conductance chamber -> vacuum reservoir, "
      "valve fully open", 2.99e-9, 0.0, False, 1e-3, group="valve", plausible=(0.0, 1e-6)),
    P("iso_C_atm", "m^3/(s*Pa)", "ISO 6358 sonic conductance atmosphere -> chamber, valve "
      "fully open", 2.99e-9, 0.0, False, 1e-3, group="valve", plausible=(0.0, 1e-6)),
    P("iso_b", "", "ISO 6358 critical back-pressure ratio b (choked for p_down/p_up <= b)",
      0.528, 0.0, False, 1.0, group="valve", plausible=(0.05, 0.7)),
    P("iso_m", "", "ISO 6358 subsonic index m (0.5: the ellipse of ISO 6358:1989)", 0.5, 0.0,
      True, 1.0, group="valve", plausible=(0.2, 1.0)),
)
declare_relation(("r_lin",), lambda r_lin: r_lin < 1.0,
                 lambda r_lin: "must be < 1 (the laminar branch spans r_lin <= r <= 1)")
declare_relation(("iso_b", "r_lin"), lambda b, r_lin: b < r_lin,
                 lambda b, r_lin: f"must be < r_lin = {r_lin:g} (the ISO 6358 flow turns "
                                  "laminar at r_lin, above the choked range r <= b)")
declare_relation(("p_res", "p_atm"), lambda p_res, p_atm: p_res < p_atm,
                 lambda p_res, p_atm: f"must be < p_atm = {p_atm:g} Pa (the vacuum reservoir "
                                      "is below atmospheric pressure)")
declare_relation(("V0", "A_d", "x_max"), lambda v0, a, x: v0 > a * x,
                 lambda v0, a, x: f"must be > A_d*x_max = {a * x:g} m^3 (the chamber volume "
                                  "V0 - A_d*x must stay positive over the stroke)")

CHAMBER_BLOCK = Block.of(
    "A_d", "V0", "p_atm", "p_res", "A_res", "A_atm", "gamma", "R", "T", "r_lin",
    settings=("chamber_n_offset", "chamber_n_gamma"),
    derived=("n_poly", "flow_rc", "flow_phi_choked", "flow_coef", "flow_lin_slope"),
)
PN_AD = CHAMBER_BLOCK.index("A_d")
PN_V0 = CHAMBER_BLOCK.index("V0")
PN_PATM = CHAMBER_BLOCK.index("p_atm")
PN_PRES = CHAMBER_BLOCK.index("p_res")
PN_ARES = CHAMBER_BLOCK.index("A_res")
PN_AATM = CHAMBER_BLOCK.index("A_atm")
PN_GAMMA = CHAMBER_BLOCK.index("gamma")
PN_R = CHAMBER_BLOCK.index("R")
PN_T = CHAMBER_BLOCK.index("T")
PN_RLIN = CHAMBER_BLOCK.index("r_lin")
PN_N_OFFSET = CHAMBER_BLOCK.index("chamber_n_offset")
PN_N_GAMMA = CHAMBER_BLOCK.index("chamber_n_gamma")
PN_N = CHAMBER_BLOCK.index("n_poly")
PN_RC = CHAMBER_BLOCK.index("flow_rc")
PN_PHI_CHOKED = CHAMBER_BLOCK.index("flow_phi_choked")
PN_COEF = CHAMBER_BLOCK.index("flow_coef")
PN_LIN_SLOPE = CHAMBER_BLOCK.index("flow_lin_slope")


# --------------------------------------------------------------------------- Φ(r)
@njit(cache=True)
def critical_ratio(gamma):  # pragma: no cover - compiled
    """r_c = (2/(γ+1))^(γ/(γ−1)), ≈ 0.528 for air."""
    return (2.0 / (gamma + 1.0)) ** (gamma / (gamma - 1.0))


@njit(cache=True)
def _phi_subsonic(r, gamma):  # pragma: no cover - compiled
    """Subsonic Φ and dΦ/dr; every power of r is a product of a = r^(1/γ) and r."""
    a = r ** (1.0 / gamma)
    a2 = a * a
    q = 2.0 / (gamma - 1.0) * (a2 - r * a)
    phi = math.sqrt(max(q, 0.0))
    dq = 2.0 / (gamma - 1.0) * (2.0 / gamma * a2 / r - (gamma + 1.0) / gamma * a)
    return phi, dq / (2.0 * phi) if phi > 0.0 else 0.0


@njit(cache=True)
def _phi_subsonic_dgamma(r, gamma):  # pragma: no cover - compiled
    """∂Φ/∂γ of the subsonic branch at fixed r."""
    a = r ** (1.0 / gamma)
    a2 = a * a
    lr = math.log(r)
    q = 2.0 / (gamma - 1.0) * (a2 - r * a)
    if q <= 0.0:
        return 0.0
    g2 = gamma * gamma
    dq = (-2.0 / (gamma - 1.0) ** 2 * (a2 - r * a)
          + 2.0 / (gamma - 1.0) * (-2.0 * lr / g2 * a2 + lr / g2 * r * a))
    return dq / (2.0 * math.sqrt(q))


@njit(cache=True)
def flow_constants(gamma, r_lin):  # pragma: no cover - compiled
    """(r_c, choked Φ, slope of the laminar branch) for γ and r_lin."""
    rc = critical_ratio(gamma)
    phi_choked = (2.0 / (gamma + 1.0)) ** ((gamma + 1.0) / (2.0 * (gamma - 1.0)))
    return rc, phi_choked, _phi_subsonic(r_lin, gamma)[0] / (1.0 - r_lin)


@njit(cache=True)
def phi_law(r, gamma, r_lin, rc, phi_choked, lin_slope):  # pragma: no cover - compiled
    """Φ(r), dΦ/dr: choked below r_c, subsonic up to r_lin, linear (laminar) up to 1."""
    if r <= rc:
        return phi_choked, 0.0
    if r < r_lin:
        return _phi_subsonic(r, gamma)
    return lin_slope * (1.0 - r), -lin_slope


@njit(cache=True)
def derive_chamber(p, o):  # pragma: no cover - compiled
    """Fill the derived entries of the chamber block (at offset ``o`` of ``p``) from its
    parameters and settings."""
    gamma = p[o + PN_GAMMA]
    rc, phi_choked, lin_slope = flow_constants(gamma, p[o + PN_RLIN])
    p[o + PN_N] = p[o + PN_N_OFFSET] + p[o + PN_N_GAMMA] * gamma
    p[o + PN_RC] = rc
    p[o + PN_PHI_CHOKED] = phi_choked
    p[o + PN_COEF] = math.sqrt(gamma / (p[o + PN_R] * p[o + PN_T]))
    p[o + PN_LIN_SLOPE] = lin_slope


# --------------------------------------------------------------------------- orifices
@njit(cache=True)
def _forward(p1, p2, coef, gamma, r_lin, rc, phi_choked, lin_slope):  # pragma: no cover
    """Flow per unit area from p1 to p2 <= p1: (q, ∂q/∂p1, ∂q/∂p2, r)."""
    r = p2 / p1
    phi, dphi = phi_law(r, gamma, r_lin, rc, phi_choked, lin_slope)
    return coef * p1 * phi, coef * (phi - r * dphi), coef * dphi, r


@njit(cache=True)
def orifice(p1, p2, coef, gamma, r_lin, rc, phi_choked, lin_slope):  # pragma: no cover
    """Mass flow [kg/s] per m² of effective area from side 1 to side 2, and its partials
    (∂/∂p1, ∂/∂p2); negative when the flow goes from 2 to 1."""
    if p1 >= p2:
        if p1 <= 0.0:
            return 0.0, 0.0, 0.0
        q, d1, d2, _ = _forward(p1, p2, coef, gamma, r_lin, rc, phi_choked, lin_slope)
        return q, d1, d2
    if p2 <= 0.0:
        return 0.0, 0.0, 0.0
    q, d2, d1, _ = _forward(p2, p1, coef, gamma, r_lin, rc, phi_choked, lin_slope)
    return -q, -d1, -d2


@njit(cache=True)
def orifice_params(p1, p2, coef, gamma, r_lin, rc, phi_choked, lin_slope):  # pragma: no cover
    """Partials of ``orifice`` with respect to the block entries it reads directly:
    (∂/∂flow_coef, ∂/∂flow_phi_choked, ∂/∂flow_lin_slope, ∂/∂gamma at fixed constants)."""
    sign = 1.0
    if p1 < p2:
        p1, p2 = p2, p1
        sign = -1.0
    if p1 <= 0.0:
        return 0.0, 0.0, 0.0, 0.0
    q, _, _, r = _forward(p1, p2, coef, gamma, r_lin, rc, phi_choked, lin_slope)
    if r <= rc:
        return sign * q / coef, sign * coef * p1, 0.0, 0.0
    if r < r_lin:
        return sign * q / coef, 0.0, 0.0, sign * coef * p1 * _phi_subsonic_dgamma(r, gamma)
    return sign * q / coef, 0.0, sign * coef * p1 * (1.0 - r), 0.0


@njit(cache=True, inline="always")
def orifice_of(p1, p2, p, o):  # pragma: no cover - compiled
    """``orifice`` with the gas and flow constants of the chamber block at ``o``."""
    return orifice(p1, p2, p[o + PN_COEF], p[o + PN_GAMMA], p[o + PN_RLIN], p[o + PN_RC],
                   p[o + PN_PHI_CHOKED], p[o + PN_LIN_SLOPE])


@njit(cache=True, inline="always")
def orifice_params_of(p1, p2, p, o):  # pragma: no cover - compiled
    return orifice_params(p1, p2, p[o + PN_COEF], p[o + PN_GAMMA], p[o + PN_RLIN],
                          p[o + PN_RC], p[o + PN_PHI_CHOKED], p[o + PN_LIN_SLOPE])


@njit(cache=True)
def _phi_many(r, gamma, r_lin, out):  # pragma: no cover - compiled
    rc, phi_choked, lin_slope = flow_constants(gamma, r_lin)
    for i in range(r.shape[0]):
        out[i] = phi_law(r[i], gamma, r_lin, rc, phi_choked, lin_slope)[0]


@njit(cache=True)
def _orifice_many(p1, p2, area, pv, out):  # pragma: no cover - compiled
    derive_chamber(pv, 0)
    for i in range(p1.shape[0]):
        out[i] = area * orifice_of(p1[i], p2[i], pv, 0)[0]


def flow_function_values(r, gamma: float = 1.4, r_lin: float = 0.999) -> np.ndarray:
    """Φ(r) evaluated at an array of pressure ratios (for tests and plots)."""
    r = np.atleast_1d(np.asarray(r, dtype=np.float64))
    out = np.empty(r.size)
    _phi_many(r, float(gamma), float(r_lin), out)
    return out


def orifice_mass_flow(p_upstream, p_downstream, area: float, params) -> np.ndarray:
    """Mass flow [kg/s] through an orifice of effective area ``area`` [m²] for arrays of
    pressures [Pa]; gas properties (gamma, R, T, r_lin) from ``params``."""
    p1, p2 = np.broadcast_arrays(np.atleast_1d(np.asarray(p_upstream, dtype=np.float64)),
                                 np.asarray(p_downstream, dtype=np.float64))
    p1, p2 = p1.ravel().copy(), p2.ravel().copy()
    pv = np.zeros(len(CHAMBER_BLOCK))
    for name in ("gamma", "R", "T", "r_lin"):
        pv[CHAMBER_BLOCK.index(name)] = params[name]
    out = np.empty(p1.size)
    _orifice_many(p1, p2, float(area), pv, out)
    return out


# --------------------------------------------------------------------------- ISO 6358
#: ISO 6358 reference conditions (ISO 8778, ANR): the density and temperature that the
#: sonic conductance C of a datasheet refers to.
ISO_RHO0 = 1.185  # kg/m³
ISO_T0 = 293.15  # K


@njit(cache=True)
def iso_subsonic(r, b, m):  # pragma: no cover - compiled
    """φ = (1 − x²)^m with x = (r − b)/(1 − b), and dφ/dr, dφ/db, dφ/dm (b < r < 1)."""
    span = 1.0 - b
    x = (r - b) / span
    base = 1.0 - x * x
    phi = base ** m
    dphi_dx = -2.0 * m * x * phi / base
    return (phi, dphi_dx / span, dphi_dx * (r - 1.0) / (span * span),
            phi * math.log(base))


@njit(cache=True)
def iso_phi(r, b, m, r_lam):  # pragma: no cover - compiled
    """ISO 6358 φ(r) and its partials (∂/∂r, ∂/∂b, ∂/∂m, ∂/∂r_lam): 1 when choked (r ≤ b),
    the subsonic ellipse up to r_lam, then linear in 1 − r, equal to the ellipse at r_lam
    (the laminar correction: a finite slope at r = 1)."""
    if r <= b:
        return 1.0, 0.0, 0.0, 0.0, 0.0
    if r < r_lam:
        phi, d_r, d_b, d_m = iso_subsonic(r, b, m)
        return phi, d_r, d_b, d_m, 0.0
    phi_lam, slope_lam, db_lam, dm_lam = iso_subsonic(r_lam, b, m)
    width = 1.0 - r_lam
    gap = (1.0 - r) / width
    return (phi_lam * gap, -phi_lam / width, db_lam * gap, dm_lam * gap,
            gap * (slope_lam + phi_lam / width))


@njit(cache=True)
def iso_flow(p1, p2, b, m, r_lam, temperature):  # pragma: no cover - compiled
    """ISO 6358 mass flow [kg/s] per unit sonic conductance [m³/(s·Pa)] from side 1 to
    side 2, and its partials (∂/∂p1, ∂/∂p2); negative when the flow goes from 2 to 1."""
    sign = 1.0
    if p1 < p2:
        p1, p2 = p2, p1
        sign = -1.0
    if p1 <= 0.0:
        return 0.0, 0.0, 0.0
    scale = ISO_RHO0 * math.sqrt(ISO_T0 / temperature)
    r = p2 / p1
    phi, d_r, _, _, _ = iso_phi(r, b, m, r_lam)
    q, d_up, d_down = scale * p1 * phi, scale * (phi - r * d_r), scale * d_r
    if sign > 0.0:
        return q, d_up, d_down
    return -q, -d_down, -d_up


@njit(cache=True)
def iso_flow_params(p1, p2, b, m, r_lam, temperature):  # pragma: no cover - compiled
    """Partials of ``iso_flow`` (per unit conductance) with respect to b, m, r_lam and the
    upstream temperature."""
    sign = 1.0
    if p1 < p2:
        p1, p2 = p2, p1
        sign = -1.0
    if p1 <= 0.0:
        return 0.0, 0.0, 0.0, 0.0
    scale = sign * ISO_RHO0 * math.sqrt(ISO_T0 / temperature) * p1
    phi, _, d_b, d_m, d_lam = iso_phi(p2 / p1, b, m, r_lam)
    return scale * d_b, scale * d_m, scale * d_lam, -0.5 * scale * phi / temperature


@njit(cache=True)
def _iso_many(p1, p2, conductance, b, m, r_lam, temperature, out):  # pragma: no cover
    for i in range(p1.shape[0]):
        out[i] = conductance * iso_flow(p1[i], p2[i], b, m, r_lam, temperature)[0]


def iso6358_mass_flow(p_upstream, p_downstream, conductance: float, params) -> np.ndarray:
    """ISO 6358 mass flow [kg/s] through a component of sonic conductance ``conductance``
    [m³/(s·Pa)] for arrays of pressures [Pa]; b, m, the laminar ratio r_lin and the
    upstream temperature T from ``params`` (``iso_b``, ``iso_m``, ``r_lin``, ``T``)."""
    p1, p2 = np.broadcast_arrays(np.atleast_1d(np.asarray(p_upstream, dtype=np.float64)),
                                 np.asarray(p_downstream, dtype=np.float64))
    p1, p2 = p1.ravel().copy(), p2.ravel().copy()
    out = np.empty(p1.size)
    _iso_many(p1, p2, float(conductance), float(params["iso_b"]), float(params["iso_m"]),
              float(params["r_lin"]), float(params["T"]), out)
    return out


def conductance_of_area(area: float, params) -> float:
    """The sonic conductance C [m³/(s·Pa)] whose choked ISO 6358 flow equals the orifice
    law's through effective area ``area`` [m²] at the gas temperature:
    C·ρ0·sqrt(T0/T) = A·sqrt(γ/(R·T))·Φ*, i.e. C = A·Φ*·sqrt(γ/R)/(ρ0·sqrt(T0))."""
    gamma = float(params["gamma"])
    phi_choked = (2.0 / (gamma + 1.0)) ** ((gamma + 1.0) / (2.0 * (gamma - 1.0)))
    return area * phi_choked * math.sqrt(gamma / float(params["R"])) / (
        ISO_RHO0 * math.sqrt(ISO_T0))


# --------------------------------------------------------------------------- chamber laws
class ChamberLaw:
    """How the chamber gas exchanges heat: dp/dt = n/V·(R·T·ṁ + p·A_d·v), n = a + b·γ."""

    #: whether the law carries the gas temperature as a state (only the cylinder has one)
    temperature_state: bool = False

    def settings(self) -> dict[str, float]:
        """Values of the chamber block's settings (a, b)."""
        raise NotImplementedError

    def polytropic_index(self, params) -> float:
        """n for a parameter set (the kernel derives the same from the block)."""
        settings = self.settings()
        return settings["chamber_n_offset"] + settings["chamber_n_gamma"] * params["gamma"]


@dataclass(frozen=True)
class Isothermal(ChamberLaw):
    """n = 1: slow processes, the chamber stays at the wall temperature (default)."""

    def settings(self) -> dict[str, float]:
        return {"chamber_n_offset": 1.0, "chamber_n_gamma": 0.0}


@dataclass(frozen=True)
class Adiabatic(ChamberLaw):
    """n = γ: fast processes with no heat exchange (γ may vary from run to run)."""

    def settings(self) -> dict[str, float]:
        return {"chamber_n_offset": 0.0, "chamber_n_gamma": 1.0}


@dataclass(frozen=True)
class Polytropic(ChamberLaw):
    """Any fixed polytropic ``exponent`` n between 1 (isothermal) and γ (adiabatic)."""

    exponent: float = 1.2

    def __post_init__(self):
        from ..checks import check_range

        check_range("exponent", self.exponent, 1.0, 5.0 / 3.0, where="Polytropic",
                    error=ParameterError,
                    hint="1 isothermal, γ adiabatic; γ <= 5/3 for any ideal gas")

    def settings(self) -> dict[str, float]:
        return {"chamber_n_offset": float(self.exponent), "chamber_n_gamma": 0.0}


@dataclass(frozen=True)
class HeatTransfer(ChamberLaw):
    """The energy equation with the gas temperature as a state and Newton's heat transfer
    h·A_w·(T_wall − T) to walls at the gas temperature T of the set (``Cylinder`` only;
    h = ``heat_transfer_coefficient``): h = 0 is adiabatic, a large h isothermal."""

    temperature_state: bool = True

    def settings(self) -> dict[str, float]:
        return {"chamber_n_offset": 0.0, "chamber_n_gamma": 1.0}

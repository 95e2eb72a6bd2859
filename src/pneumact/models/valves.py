"""What feeds the chamber: an ideal pressure source, a command valve, a pressure regulator.

Every valve exposes the same compiled functions, with the prefix of its kind
(``source_``, ``command_``, ``regulator_``); the kernel generator binds them under the
names ``valve_*``. A valve owns its states (none, the chamber pressure, or pressure +
valve opening + the regulator's integral), which start at offset ``s`` of the state
vector ``y``, and reads its parameter block at offset ``o`` of the vector ``p``:

- ``pressure(t, ts, y, s, p, o, sig, ptr)``: the chamber pressure;
- ``rates(t, ts, x, v, y, s, p, o, sig, ptr, dydt)``: its states' derivatives;
- ``partials(..., jac, cx, cv)``: their rows of the Jacobian (own states, and the
  columns cx, cv of position and velocity);
- ``params(..., g)``: their rows of ∂f/∂p over the block's columns;
- ``flows(...)``: (opening u, ṁ_in, ṁ_out) for the outputs;
- ``derive(p, o)``, ``equilibrium(t, ts, p, o, sig, ptr, y0, s)`` (the rest state of
  the chamber under the initial input), ``scales(p, o, out, s)`` (typical magnitudes),
  ``project(y, s)`` (back onto the bounds the exact dynamics keep, after each step).

The functions of the hot loop are thin wrappers inlined by numba around scalar-only
functions (``chamber_rate``, ``orifice``): see ``models.friction`` on why.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, replace
from typing import ClassVar

from ..checks import ABSOLUTE_PRESSURE_PLAUSIBLE, check_absolute_pressure
from ..core.channels import CH_DRIVE, CH_MAP_ATM, CH_MAP_RES, InputChannel
from ..core.component import Block, Part, StateSpec
from ..core.jit import njit
from ..core.signals import Signal, channel_eval, map_eval
from ..parameters.catalogue import ParameterSpec, declare
from .pneumatics import (
    CHAMBER_BLOCK,
    PN_AATM,
    PN_AD,
    PN_ARES,
    PN_COEF,
    PN_GAMMA,
    PN_LIN_SLOPE,
    PN_N,
    PN_PATM,
    PN_PHI_CHOKED,
    PN_PRES,
    PN_R,
    PN_RLIN,
    PN_T,
    PN_V0,
    ChamberLaw,
    Isothermal,
    iso_flow,
    iso_flow_params,
    orifice_of,
    orifice_params_of,
)

P = ParameterSpec
declare(
    P("reg_kp", "", "regulator gain: valve opening per unit of (p - p_set)/p_atm", 20.0, 0.0,
      False, 1e6, group="valve", plausible=(0.0, 1e4)),
    P("reg_ti", "s", "regulator integral time", 0.05, 0.0, True, 1e4, group="valve",
      plausible=(1e-6, 100.0)),
    P("reg_tau", "s", "valve (spool) time constant", 0.01, 0.0, True, 1e4, group="valve",
      plausible=(1e-7, 10.0)),
)

SOURCE_BLOCK = Block()
COMMAND_BLOCK = CHAMBER_BLOCK
REGULATOR_BLOCK = CHAMBER_BLOCK + Block.of("reg_kp", "reg_ti", "reg_tau")
ISO_BLOCK = CHAMBER_BLOCK + Block.of("iso_C_res", "iso_C_atm", "iso_b", "iso_m")
IS_CRES = ISO_BLOCK.index("iso_C_res")
IS_CATM = ISO_BLOCK.index("iso_C_atm")
IS_B = ISO_BLOCK.index("iso_b")
IS_M = ISO_BLOCK.index("iso_m")
ISO_SIZE = len(ISO_BLOCK)
RG_KP = REGULATOR_BLOCK.index("reg_kp")
RG_TI = REGULATOR_BLOCK.index("reg_ti")
RG_TAU = REGULATOR_BLOCK.index("reg_tau")
CHAMBER_SIZE = len(CHAMBER_BLOCK)
REGULATOR_SIZE = len(REGULATOR_BLOCK)

# local state indices (the valve's slice of the state vector)
ST_PRESSURE = 0
ST_OPENING = 1
ST_INTEGRAL = 2
SOURCE_PRESSURE_STATE = -1
COMMAND_PRESSURE_STATE = ST_PRESSURE
REGULATOR_PRESSURE_STATE = ST_PRESSURE
ISO_PRESSURE_STATE = ST_PRESSURE

#: Bisection steps of the equilibrium searches (interval shrinks by 2^-60).
EQUILIBRIUM_ITERATIONS = 60


# ------------------------------------------------------------------ ideal pressure source
@njit(cache=True, inline="always")
def source_pressure(t, ts, y, s, p, o, sig, ptr):  # pragma: no cover - compiled
    """Chamber pressure prescribed by the drive signal."""
    return channel_eval(sig, ptr, CH_DRIVE, t, ts)[0]


@njit(cache=True, inline="always")
def source_rates(t, ts, x, v, y, s, p, o, sig, ptr, dydt):  # pragma: no cover - compiled
    pass


@njit(cache=True, inline="always")
def source_partials(t, ts, x, v, y, s, p, o, sig, ptr, jac, cx, cv):  # pragma: no cover
    pass


@njit(cache=True)
def source_params(t, ts, x, v, y, s, p, o, sig, ptr, g):  # pragma: no cover - compiled
    pass


@njit(cache=True, inline="always")
def source_flows(t, ts, x, v, y, s, p, o, sig, ptr):  # pragma: no cover - compiled
    """(opening u, ṁ_in, ṁ_out): not modelled for a prescribed pressure."""
    return 0.0, 0.0, 0.0


@njit(cache=True)
def source_derive(p, o):  # pragma: no cover - compiled
    pass


@njit(cache=True)
def source_equilibrium(t, ts, p, o, sig, ptr, y0, s):  # pragma: no cover - compiled
    return channel_eval(sig, ptr, CH_DRIVE, t, ts)[0]


@njit(cache=True)
def source_scales(p, o, out, s):  # pragma: no cover - compiled
    pass


@njit(cache=True)
def no_projection(y, s):  # pragma: no cover - compiled
    """A valve whose states have no invariant bounds."""


# ------------------------------------------------------------ the chamber behind a valve
@njit(cache=True, inline="always")
def _valve_flows(pressure, u, p, o, sig, ptr):  # pragma: no cover - compiled
    """Flows at opening u: (ṁ_in, ṁ_out, ∂ṁ/∂p, ∂ṁ/∂u); ṁ = ṁ_in − ṁ_out.

    Orifice flow is linear in the area, so each orifice is evaluated once per unit area
    and scaled by the mapped opening.
    """
    m_res, dm_res = map_eval(sig, ptr, CH_MAP_RES, u)
    m_atm, dm_atm = map_eval(sig, ptr, CH_MAP_ATM, u)
    a_res = p[o + PN_ARES] * m_res
    a_atm = p[o + PN_AATM] * m_atm
    q_in, _, dqin_dp = orifice_of(p[o + PN_PATM], pressure, p, o)
    q_out, dqout_dp, _ = orifice_of(pressure, p[o + PN_PRES], p, o)
    dq_dp = a_atm * dqin_dp - a_res * dqout_dp
    dq_du = p[o + PN_AATM] * dm_atm * q_in - p[o + PN_ARES] * dm_res * q_out
    return a_atm * q_in, a_res * q_out, dq_dp, dq_du


@njit(cache=True, inline="always")
def _chamber(p, o):  # pragma: no cover - compiled
    """(A_d, V0, n, R·T) of the chamber block."""
    return p[o + PN_AD], p[o + PN_V0], p[o + PN_N], p[o + PN_R] * p[o + PN_T]


@njit(cache=True)
def chamber_rate(x, v, pressure, mdot, ad, v0, n, rt):  # pragma: no cover - compiled
    """dp/dt = n/V·(R·T·ṁ + p·A_d·v), with the chamber volume V = V0 − A_d·x."""
    return n / (v0 - ad * x) * (rt * mdot + pressure * ad * v)


@njit(cache=True)
def chamber_jac(x, v, pressure, mdot, dmdot_dp, ad, v0, n, rt):  # pragma: no cover
    """(∂ṗ/∂x, ∂ṗ/∂v, ∂ṗ/∂p, ∂ṗ/∂ṁ) of the chamber law."""
    vol = v0 - ad * x
    rate = n / vol * (rt * mdot + pressure * ad * v)
    return (rate * ad / vol, n * pressure * ad / vol, n / vol * (rt * dmdot_dp + ad * v),
            n / vol * rt)


@njit(cache=True)
def _chamber_params(x, v, pressure, u, p, o, sig, ptr, g, row):  # pragma: no cover
    """g[row, o + k] = ∂ṗ/∂p_k for the chamber block entries k."""
    m_res = map_eval(sig, ptr, CH_MAP_RES, u)[0]
    m_atm = map_eval(sig, ptr, CH_MAP_ATM, u)[0]
    p_atm, p_res = p[o + PN_PATM], p[o + PN_PRES]
    q_in, dqin_dpatm, _ = orifice_of(p_atm, pressure, p, o)
    q_out, _, dqout_dpres = orifice_of(pressure, p_res, p, o)
    in_coef, in_phich, in_lin, in_gamma = orifice_params_of(p_atm, pressure, p, o)
    out_coef, out_phich, out_lin, out_gamma = orifice_params_of(pressure, p_res, p, o)
    a_res = p[o + PN_ARES] * m_res
    a_atm = p[o + PN_AATM] * m_atm
    mdot = a_atm * q_in - a_res * q_out
    ad = p[o + PN_AD]
    vol = p[o + PN_V0] - ad * x
    n = p[o + PN_N]
    inner = p[o + PN_R] * p[o + PN_T] * mdot + pressure * ad * v
    k = n / vol * p[o + PN_R] * p[o + PN_T]  # ∂ṗ/∂ṁ
    for i in range(CHAMBER_SIZE):
        g[row, o + i] = 0.0
    g[row, o + PN_AD] = n * x / (vol * vol) * inner + n / vol * pressure * v
    g[row, o + PN_V0] = -n / (vol * vol) * inner
    g[row, o + PN_PATM] = k * a_atm * dqin_dpatm
    g[row, o + PN_PRES] = -k * a_res * dqout_dpres
    g[row, o + PN_ARES] = -k * m_res * q_out
    g[row, o + PN_AATM] = k * m_atm * q_in
    g[row, o + PN_GAMMA] = k * (a_atm * in_gamma - a_res * out_gamma)
    g[row, o + PN_R] = n / vol * p[o + PN_T] * mdot
    g[row, o + PN_T] = n / vol * p[o + PN_R] * mdot
    g[row, o + PN_N] = inner / vol
    g[row, o + PN_PHI_CHOKED] = k * (a_atm * in_phich - a_res * out_phich)
    g[row, o + PN_COEF] = k * (a_atm * in_coef - a_res * out_coef)
    g[row, o + PN_LIN_SLOPE] = k * (a_atm * in_lin - a_res * out_lin)


@njit(cache=True)
def _net_flow(pressure, u, p, o, sig, ptr, iso):  # pragma: no cover - compiled
    """ṁ_in − ṁ_out at opening u: orifice law, or ISO 6358 if ``iso``."""
    if iso:
        q_in, q_out, _, _ = _iso_valve_flows(pressure, u, p, o, sig, ptr)
    else:
        q_in, q_out, _, _ = _valve_flows(pressure, u, p, o, sig, ptr)
    return q_in - q_out


@njit(cache=True)
def _bisect_pressure(u, p, o, sig, ptr, iso):  # pragma: no cover - compiled
    """Chamber pressure in [p_res, p_atm] where the net flow vanishes at opening u (the net
    flow falls as the pressure rises); an end of the interval if it has one sign there."""
    lo, hi = p[o + PN_PRES], p[o + PN_PATM]
    if _net_flow(lo, u, p, o, sig, ptr, iso) <= 0.0:
        return lo
    if _net_flow(hi, u, p, o, sig, ptr, iso) >= 0.0:
        return hi
    for _ in range(EQUILIBRIUM_ITERATIONS):
        mid = 0.5 * (lo + hi)
        if _net_flow(mid, u, p, o, sig, ptr, iso) > 0.0:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


@njit(cache=True)
def _bisect_opening(pressure, p, o, sig, ptr, iso):  # pragma: no cover - compiled
    """Opening u in [0, 1] that holds ``pressure`` (the net flow falls as u rises)."""
    lo, hi = 0.0, 1.0
    if _net_flow(pressure, lo, p, o, sig, ptr, iso) <= 0.0:
        return lo
    if _net_flow(pressure, hi, p, o, sig, ptr, iso) >= 0.0:
        return hi
    for _ in range(EQUILIBRIUM_ITERATIONS):
        mid = 0.5 * (lo + hi)
        if _net_flow(pressure, mid, p, o, sig, ptr, iso) > 0.0:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


# ------------------------------------------------------------------------ command valve
@njit(cache=True, inline="always")
def command_pressure(t, ts, y, s, p, o, sig, ptr):  # pragma: no cover - compiled
    return y[s + ST_PRESSURE]


@njit(cache=True, inline="always")
def command_rates(t, ts, x, v, y, s, p, o, sig, ptr, dydt):  # pragma: no cover - compiled
    u = channel_eval(sig, ptr, CH_DRIVE, t, ts)[0]
    pressure = y[s + ST_PRESSURE]
    q_in, q_out, _, _ = _valve_flows(pressure, u, p, o, sig, ptr)
    ad, v0, n, rt = _chamber(p, o)
    dydt[s + ST_PRESSURE] = chamber_rate(x, v, pressure, q_in - q_out, ad, v0, n, rt)


@njit(cache=True, inline="always")
def command_partials(t, ts, x, v, y, s, p, o, sig, ptr, jac, cx, cv):  # pragma: no cover
    u = channel_eval(sig, ptr, CH_DRIVE, t, ts)[0]
    pressure = y[s + ST_PRESSURE]
    q_in, q_out, dq_dp, _ = _valve_flows(pressure, u, p, o, sig, ptr)
    ad, v0, n, rt = _chamber(p, o)
    d_x, d_v, d_p, _ = chamber_jac(x, v, pressure, q_in - q_out, dq_dp, ad, v0, n, rt)
    row = s + ST_PRESSURE
    jac[row, cx] = d_x
    jac[row, cv] = d_v
    jac[row, row] = d_p


@njit(cache=True)
def command_params(t, ts, x, v, y, s, p, o, sig, ptr, g):  # pragma: no cover - compiled
    u = channel_eval(sig, ptr, CH_DRIVE, t, ts)[0]
    _chamber_params(x, v, y[s + ST_PRESSURE], u, p, o, sig, ptr, g, s + ST_PRESSURE)


@njit(cache=True, inline="always")
def command_flows(t, ts, x, v, y, s, p, o, sig, ptr):  # pragma: no cover - compiled
    u = channel_eval(sig, ptr, CH_DRIVE, t, ts)[0]
    q_in, q_out, _, _ = _valve_flows(y[s + ST_PRESSURE], u, p, o, sig, ptr)
    return u, q_in, q_out


@njit(cache=True)
def command_equilibrium(t, ts, p, o, sig, ptr, y0, s):  # pragma: no cover - compiled
    """Rest pressure of the chamber at the initial command (net flow zero)."""
    u = min(max(channel_eval(sig, ptr, CH_DRIVE, t, ts)[0], 0.0), 1.0)
    p0 = _bisect_pressure(u, p, o, sig, ptr, False)
    y0[s + ST_PRESSURE] = p0
    return p0


@njit(cache=True)
def command_scales(p, o, out, s):  # pragma: no cover - compiled
    out[s + ST_PRESSURE] = p[o + PN_PATM]


# ------------------------------------------------------------------ ISO 6358 valve
@njit(cache=True, inline="always")
def _iso_gas(p, o):  # pragma: no cover - compiled
    """(b, m, r_lam, T) of the ISO 6358 block."""
    return p[o + IS_B], p[o + IS_M], p[o + PN_RLIN], p[o + PN_T]


@njit(cache=True, inline="always")
def _iso_valve_flows(pressure, u, p, o, sig, ptr):  # pragma: no cover - compiled
    """Flows at opening u through two ISO 6358 paths whose conductances follow the area
    maps: (ṁ_in, ṁ_out, ∂ṁ/∂p, ∂ṁ/∂u); ṁ = ṁ_in − ṁ_out."""
    m_res, dm_res = map_eval(sig, ptr, CH_MAP_RES, u)
    m_atm, dm_atm = map_eval(sig, ptr, CH_MAP_ATM, u)
    c_res = p[o + IS_CRES] * m_res
    c_atm = p[o + IS_CATM] * m_atm
    b, m, r_lam, temperature = _iso_gas(p, o)
    q_in, _, dqin_dp = iso_flow(p[o + PN_PATM], pressure, b, m, r_lam, temperature)
    q_out, dqout_dp, _ = iso_flow(pressure, p[o + PN_PRES], b, m, r_lam, temperature)
    dq_dp = c_atm * dqin_dp - c_res * dqout_dp
    dq_du = p[o + IS_CATM] * dm_atm * q_in - p[o + IS_CRES] * dm_res * q_out
    return c_atm * q_in, c_res * q_out, dq_dp, dq_du


@njit(cache=True)
def _iso_chamber_params(x, v, pressure, u, p, o, sig, ptr, g, row):  # pragma: no cover
    """g[row, o + k] = ∂ṗ/∂p_k for the ISO valve's block entries k (the orifice entries
    of the chamber block, A_res, A_atm and the flow constants, do not enter)."""
    m_res = map_eval(sig, ptr, CH_MAP_RES, u)[0]
    m_atm = map_eval(sig, ptr, CH_MAP_ATM, u)[0]
    p_atm, p_res = p[o + PN_PATM], p[o + PN_PRES]
    b, m, r_lam, temperature = _iso_gas(p, o)
    q_in, dqin_dpatm, _ = iso_flow(p_atm, pressure, b, m, r_lam, temperature)
    q_out, _, dqout_dpres = iso_flow(pressure, p_res, b, m, r_lam, temperature)
    in_b, in_m, in_lam, in_t = iso_flow_params(p_atm, pressure, b, m, r_lam, temperature)
    out_b, out_m, out_lam, out_t = iso_flow_params(pressure, p_res, b, m, r_lam,
                                                   temperature)
    c_res = p[o + IS_CRES] * m_res
    c_atm = p[o + IS_CATM] * m_atm
    mdot = c_atm * q_in - c_res * q_out
    ad, v0, n, rt = _chamber(p, o)
    vol = v0 - ad * x
    inner = rt * mdot + pressure * ad * v
    k = n / vol * rt  # ∂ṗ/∂ṁ
    for i in range(ISO_SIZE):
        g[row, o + i] = 0.0
    g[row, o + PN_AD] = n * x / (vol * vol) * inner + n / vol * pressure * v
    g[row, o + PN_V0] = -n / (vol * vol) * inner
    g[row, o + PN_PATM] = k * c_atm * dqin_dpatm
    g[row, o + PN_PRES] = -k * c_res * dqout_dpres
    g[row, o + PN_R] = n / vol * temperature * mdot
    g[row, o + PN_T] = n / vol * p[o + PN_R] * mdot + k * (c_atm * in_t - c_res * out_t)
    g[row, o + PN_N] = inner / vol
    g[row, o + PN_RLIN] = k * (c_atm * in_lam - c_res * out_lam)
    g[row, o + IS_CRES] = -k * m_res * q_out
    g[row, o + IS_CATM] = k * m_atm * q_in
    g[row, o + IS_B] = k * (c_atm * in_b - c_res * out_b)
    g[row, o + IS_M] = k * (c_atm * in_m - c_res * out_m)


iso_pressure = command_pressure
iso_scales = command_scales


@njit(cache=True, inline="always")
def iso_rates(t, ts, x, v, y, s, p, o, sig, ptr, dydt):  # pragma: no cover - compiled
    u = channel_eval(sig, ptr, CH_DRIVE, t, ts)[0]
    pressure = y[s + ST_PRESSURE]
    q_in, q_out, _, _ = _iso_valve_flows(pressure, u, p, o, sig, ptr)
    ad, v0, n, rt = _chamber(p, o)
    dydt[s + ST_PRESSURE] = chamber_rate(x, v, pressure, q_in - q_out, ad, v0, n, rt)


@njit(cache=True, inline="always")
def iso_partials(t, ts, x, v, y, s, p, o, sig, ptr, jac, cx, cv):  # pragma: no cover
    u = channel_eval(sig, ptr, CH_DRIVE, t, ts)[0]
    pressure = y[s + ST_PRESSURE]
    q_in, q_out, dq_dp, _ = _iso_valve_flows(pressure, u, p, o, sig, ptr)
    ad, v0, n, rt = _chamber(p, o)
    d_x, d_v, d_p, _ = chamber_jac(x, v, pressure, q_in - q_out, dq_dp, ad, v0, n, rt)
    row = s + ST_PRESSURE
    jac[row, cx] = d_x
    jac[row, cv] = d_v
    jac[row, row] = d_p


@njit(cache=True)
def iso_params(t, ts, x, v, y, s, p, o, sig, ptr, g):  # pragma: no cover - compiled
    u = channel_eval(sig, ptr, CH_DRIVE, t, ts)[0]
    _iso_chamber_params(x, v, y[s + ST_PRESSURE], u, p, o, sig, ptr, g, s + ST_PRESSURE)


@njit(cache=True, inline="always")
def iso_flows(t, ts, x, v, y, s, p, o, sig, ptr):  # pragma: no cover - compiled
    u = channel_eval(sig, ptr, CH_DRIVE, t, ts)[0]
    q_in, q_out, _, _ = _iso_valve_flows(y[s + ST_PRESSURE], u, p, o, sig, ptr)
    return u, q_in, q_out


@njit(cache=True)
def iso_equilibrium(t, ts, p, o, sig, ptr, y0, s):  # pragma: no cover - compiled
    """Rest pressure of the chamber at the initial command (net ISO flow zero)."""
    u = min(max(channel_eval(sig, ptr, CH_DRIVE, t, ts)[0], 0.0), 1.0)
    p0 = _bisect_pressure(u, p, o, sig, ptr, True)
    y0[s + ST_PRESSURE] = p0
    return p0


# ------------------------------------------------------------------ pressure regulator
@njit(cache=True, inline="always")
def _regulator_law(t, ts, pressure, integral, p, o, sig, ptr):  # pragma: no cover
    """PI law on the normalised pressure error with back-calculation anti-windup.

    e = (p − p_set)/p_atm (more vacuum needed → open towards the reservoir), raw opening
    u_raw = kp·e + i, commanded opening u_cmd = clip(u_raw, 0, 1).
    Returns (u_cmd, ∂u_cmd/∂p, ∂u_cmd/∂i, e, saturated).
    """
    p_set = channel_eval(sig, ptr, CH_DRIVE, t, ts)[0]
    patm = p[o + PN_PATM]
    kp = p[o + RG_KP]
    e = (pressure - p_set) / patm
    u_raw = kp * e + integral
    if u_raw > 1.0:
        return 1.0, 0.0, 0.0, e, True
    if u_raw < 0.0:
        return 0.0, 0.0, 0.0, e, True
    return u_raw, kp / patm, 1.0, e, False


@njit(cache=True, inline="always")
def regulator_pressure(t, ts, y, s, p, o, sig, ptr):  # pragma: no cover - compiled
    return y[s + ST_PRESSURE]


@njit(cache=True, inline="always")
def regulator_rates(t, ts, x, v, y, s, p, o, sig, ptr, dydt):  # pragma: no cover
    pressure, u, integral = y[s + ST_PRESSURE], y[s + ST_OPENING], y[s + ST_INTEGRAL]
    q_in, q_out, _, _ = _valve_flows(pressure, u, p, o, sig, ptr)
    ad, v0, n, rt = _chamber(p, o)
    dydt[s + ST_PRESSURE] = chamber_rate(x, v, pressure, q_in - q_out, ad, v0, n, rt)
    u_cmd = _regulator_law(t, ts, pressure, integral, p, o, sig, ptr)[0]
    dydt[s + ST_OPENING] = (u_cmd - u) / p[o + RG_TAU]
    # back-calculation anti-windup with tracking time Ti: di/dt = (u_cmd − i)/Ti
    dydt[s + ST_INTEGRAL] = (u_cmd - integral) / p[o + RG_TI]


@njit(cache=True, inline="always")
def regulator_partials(t, ts, x, v, y, s, p, o, sig, ptr, jac, cx, cv):  # pragma: no cover
    pressure, u, integral = y[s + ST_PRESSURE], y[s + ST_OPENING], y[s + ST_INTEGRAL]
    q_in, q_out, dq_dp, dq_du = _valve_flows(pressure, u, p, o, sig, ptr)
    ad, v0, n, rt = _chamber(p, o)
    d_x, d_v, d_p, d_mdot = chamber_jac(x, v, pressure, q_in - q_out, dq_dp, ad, v0, n, rt)
    rp, ru, ri = s + ST_PRESSURE, s + ST_OPENING, s + ST_INTEGRAL
    jac[rp, cx] = d_x
    jac[rp, cv] = d_v
    jac[rp, rp] = d_p
    jac[rp, ru] = d_mdot * dq_du
    _, du_dp, du_di, _, _ = _regulator_law(t, ts, pressure, integral, p, o, sig, ptr)
    tau, ti = p[o + RG_TAU], p[o + RG_TI]
    jac[ru, rp] = du_dp / tau
    jac[ru, ru] = -1.0 / tau
    jac[ru, ri] = du_di / tau
    jac[ri, rp] = du_dp / ti
    jac[ri, ri] = (du_di - 1.0) / ti


@njit(cache=True)
def regulator_params(t, ts, x, v, y, s, p, o, sig, ptr, g):  # pragma: no cover - compiled
    pressure, u, integral = y[s + ST_PRESSURE], y[s + ST_OPENING], y[s + ST_INTEGRAL]
    rp, ru, ri = s + ST_PRESSURE, s + ST_OPENING, s + ST_INTEGRAL
    _chamber_params(x, v, pressure, u, p, o, sig, ptr, g, rp)
    for k in range(CHAMBER_SIZE, REGULATOR_SIZE):
        g[rp, o + k] = 0.0
    u_cmd, _, _, e, saturated = _regulator_law(t, ts, pressure, integral, p, o, sig, ptr)
    tau, ti = p[o + RG_TAU], p[o + RG_TI]
    for k in range(REGULATOR_SIZE):
        g[ru, o + k] = 0.0
        g[ri, o + k] = 0.0
    du_dkp = 0.0 if saturated else e
    du_dpatm = 0.0 if saturated else -p[o + RG_KP] * e / p[o + PN_PATM]
    g[ru, o + RG_KP] = du_dkp / tau
    g[ru, o + PN_PATM] = du_dpatm / tau
    g[ru, o + RG_TAU] = -(u_cmd - u) / (tau * tau)
    g[ri, o + RG_KP] = du_dkp / ti
    g[ri, o + PN_PATM] = du_dpatm / ti
    g[ri, o + RG_TI] = -(u_cmd - integral) / (ti * ti)


@njit(cache=True, inline="always")
def regulator_flows(t, ts, x, v, y, s, p, o, sig, ptr):  # pragma: no cover - compiled
    u = y[s + ST_OPENING]
    q_in, q_out, _, _ = _valve_flows(y[s + ST_PRESSURE], u, p, o, sig, ptr)
    return u, q_in, q_out


@njit(cache=True)
def regulator_equilibrium(t, ts, p, o, sig, ptr, y0, s):  # pragma: no cover - compiled
    """Set-point pressure (within [p_res, p_atm]) held by the opening that balances the
    flows; the integral state equals that opening (zero error)."""
    p_set = channel_eval(sig, ptr, CH_DRIVE, t, ts)[0]
    p0 = min(max(p_set, p[o + PN_PRES]), p[o + PN_PATM])
    u0 = _bisect_opening(p0, p, o, sig, ptr, False)
    y0[s + ST_PRESSURE] = p0
    y0[s + ST_OPENING] = u0
    y0[s + ST_INTEGRAL] = u0
    return p0


@njit(cache=True)
def regulator_project(y, s):  # pragma: no cover - compiled
    """The opening follows a command clipped to [0, 1]: [0, 1] is invariant."""
    y[s + ST_OPENING] = min(max(y[s + ST_OPENING], 0.0), 1.0)


@njit(cache=True)
def regulator_scales(p, o, out, s):  # pragma: no cover - compiled
    out[s + ST_PRESSURE] = p[o + PN_PATM]
    out[s + ST_OPENING] = 1.0
    out[s + ST_INTEGRAL] = 1.0


# -------------------------------------------------------------------- strategy objects
_FUNCTIONS = ("pressure", "rates", "partials", "params", "flows", "derive", "equilibrium",
              "scales")


class Valve:
    """Strategy object: which compiled valve functions feed the chamber.

    ``declared`` is the input it owns (``core.channels.InputChannel``): its name, what the
    experiment's signal means for this valve (a pressure, or the command u), its unit and
    range, and the record signal that drives it (a record made through the regulator logs
    its set-point); ``drive`` and ``input_signal`` are read from it. ``cli_name`` is its
    ``--valve`` choice on the command line.
    """

    prefix: ClassVar[str]
    block: ClassVar[Block]
    states: ClassVar[tuple[StateSpec, ...]]
    declared: ClassVar[InputChannel]
    drive: ClassVar[str]
    input_signal: ClassVar[str]
    cli_name: ClassVar[str]

    def __init_subclass__(cls, **kwargs) -> None:
        """``drive`` and ``input_signal`` from the input the class declares."""
        super().__init_subclass__(**kwargs)
        if "declared" in vars(cls):
            cls.drive = cls.declared.name
            cls.input_signal = cls.declared.record_signal

    def maps(self) -> tuple[Signal | None, Signal | None]:
        """Area maps against the command (reservoir, atmosphere); None when unused."""
        return None, None

    def declared_input(self, params) -> InputChannel:
        """Its input with the parameters' values where they set its range."""
        return self.declared

    def input_range(self, params) -> tuple[float, float]:
        """The values its input acts over (``InputChannel.span``)."""
        return self.declared_input(params).span

    def check_drive_values(self, params, low: float, high: float, where: str) -> None:
        """Refuse an experiment whose signal spans ``low`` to ``high`` outside its declared
        input (``where`` names the experiment)."""
        self.declared_input(params).check(low, high, where)

    @property
    def required(self) -> tuple[str, ...]:
        return self.block.parameters

    def part(self, chamber: ChamberLaw | None = None) -> Part:
        module = __name__
        functions = {f"valve_{name}": f"{module}:{self.prefix}_{name}" for name in _FUNCTIONS}
        if len(self.block):
            functions["valve_derive"] = "pneumact.models.pneumatics:derive_chamber"
        projection = "regulator_project" if self.prefix == "regulator" else "no_projection"
        functions["valve_project"] = f"{module}:{projection}"
        settings = (chamber or Isothermal()).settings() if len(self.block) else {}
        return Part(role="valve", block=self.block, states=self.states, functions=functions,
                    constants={"VALVE_PRESSURE_STATE":
                               f"{module}:{self.prefix.upper()}_PRESSURE_STATE"},
                    settings=settings, label=self.name, key=self.prefix)

    @property
    def name(self) -> str:
        return type(self).__name__


#: an imposed absolute pressure (refused below 1 kPa: a unit mistake; the hint says so)
PRESSURE_INPUT = InputChannel(
    "pressure", "Pa", *ABSOLUTE_PRESSURE_PLAUSIBLE, record_signals=("pressure",),
    description="chamber pressure imposed by the source", label="pressure",
    check_value=check_absolute_pressure)
#: the regulator's set-point: an absolute pressure, clipped to [p_res, p_atm]
SETPOINT_INPUT = replace(PRESSURE_INPUT, record_signals=("setpoint",),
                         description="set-point of the pressure regulator")
#: the command u of a valve between the chamber, the reservoir and the atmosphere
COMMAND_INPUT = InputChannel(
    "command", "1", 0.0, 1.0, record_signals=("command",),
    description="valve command (0 closed to atmosphere, 1 open to the vacuum reservoir)",
    label="command", rule="a valve command must stay within [{low:g}, {high:g}] (0 vents "
                          "the chamber, 1 opens it to the reservoir)")


@dataclass(frozen=True)
class PressureSource(Valve):
    """Ideal source: the chamber pressure is the experiment's pressure signal (paper
    Figs. 5-6, where the measured pressure is applied)."""

    prefix: ClassVar[str] = "source"
    block: ClassVar[Block] = SOURCE_BLOCK
    states: ClassVar[tuple[StateSpec, ...]] = ()
    declared: ClassVar[InputChannel] = PRESSURE_INPUT
    cli_name: ClassVar[str] = "source"


@functools.cache
def _linear_map(rising: bool) -> Signal:
    """The default area map: linear from closed to fully open over u ∈ [0, 1]."""
    from ..core.signals import PiecewiseLinear

    return PiecewiseLinear([0.0, 1.0], [0.0, 1.0] if rising else [1.0, 0.0])


@dataclass(frozen=True)
class CommandValve(Valve):
    """Three-way valve driven by a command u ∈ [0, 1].

    Two area maps give the opening, as a fraction of ``A_res`` and ``A_atm``, against u:
    by default u = 0 vents the chamber to the atmosphere, u = 1 connects it to the
    vacuum reservoir, linearly in between. Any ``Signal`` of u (e.g. a
    ``PiecewiseLinear`` table measured on a valve) can replace them.
    """

    reservoir_map: Signal | None = None
    atmosphere_map: Signal | None = None
    prefix: ClassVar[str] = "command"
    block: ClassVar[Block] = COMMAND_BLOCK
    states: ClassVar[tuple[StateSpec, ...]] = (StateSpec("pressure", "Pa"),)
    declared: ClassVar[InputChannel] = COMMAND_INPUT
    cli_name: ClassVar[str] = "command"

    def maps(self) -> tuple[Signal, Signal]:
        return (self.reservoir_map or _linear_map(True),
                self.atmosphere_map or _linear_map(False))


@dataclass(frozen=True)
class PressureRegulator(CommandValve):
    """Electro-pneumatic pressure regulator (the paper's EPC): a PI law on the pressure
    error moves the valve, which has its own first-order lag ``reg_tau``; the experiment's
    signal is the pressure set-point."""

    prefix: ClassVar[str] = "regulator"
    block: ClassVar[Block] = REGULATOR_BLOCK
    states: ClassVar[tuple[StateSpec, ...]] = (
        StateSpec("pressure", "Pa"), StateSpec("opening", "1", monotone=True),
        StateSpec("integral", "1"))
    declared: ClassVar[InputChannel] = SETPOINT_INPUT
    cli_name: ClassVar[str] = "regulator"

    def declared_input(self, params) -> InputChannel:
        """An absolute pressure, acting within [p_res, p_atm] (it is clipped there)."""
        return replace(self.declared,
                       acts_within=(float(params["p_res"]), float(params["p_atm"])))


@dataclass(frozen=True)
class Iso6358Valve(CommandValve):
    """The command valve with each path's flow as ISO 6358 gives it from a datasheet's
    sonic conductance C (``iso_C_res``, ``iso_C_atm``, fully open) and critical
    back-pressure ratio b (``iso_b``), with the ISO 6358-3 subsonic index m (``iso_m``)
    and the laminar branch above r_lin; the area maps scale the conductances against u."""

    prefix: ClassVar[str] = "iso"
    block: ClassVar[Block] = ISO_BLOCK
    cli_name: ClassVar[str] = "iso6358"


#: ``--valve`` choices of the command line.
VALVES: dict[str, type[Valve]] = {cls.cli_name: cls for cls in (
    PressureSource, CommandValve, PressureRegulator, Iso6358Valve)}

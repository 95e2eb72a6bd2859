"""What feeds the chamber: an ideal pressure source, a command valve, a pressure regulator.

Each valve is a set of compiled functions with a common prefix (``source_``,
``command_``, ``regulator_``) and a state count; the kernel generator imports them under
the names ``valve_*``. States are laid out after the mechanics and friction:
``[x, v, z | p | u, i]``: chamber pressure p, valve opening u and the regulator's
integral state i.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import ClassVar

from numba import njit

from ..experiments.signals import Signal, channel_eval
from .layout import (
    CH_DRIVE,
    CH_MAP_ATM,
    CH_MAP_RES,
    I_AATM,
    I_AD,
    I_ARES,
    I_NPOLY,
    I_PATM,
    I_PRES,
    I_R,
    I_REG_KP,
    I_REG_TAU,
    I_REG_TI,
    I_T,
    I_V0,
)
from .pneumatics import orifice

# ------------------------------------------------------------------ ideal pressure source
SOURCE_NSTATE = 3


@njit(cache=True, inline="always")
def source_pressure(t, ts, y, prm, sig, ptr):  # pragma: no cover - compiled
    """Chamber pressure prescribed by the drive signal."""
    return channel_eval(sig, ptr, CH_DRIVE, t, ts)[0]


@njit(cache=True, inline="always")
def source_rhs(t, ts, y, prm, sig, ptr, dydt):  # pragma: no cover - compiled
    pass


@njit(cache=True, inline="always")
def source_jac(t, ts, y, prm, sig, ptr, jac):  # pragma: no cover - compiled
    pass


@njit(cache=True, inline="always")
def source_flows(t, ts, y, prm, sig, ptr):  # pragma: no cover - compiled
    """(opening u, ṁ_in, ṁ_out): not modelled for a prescribed pressure."""
    return 0.0, 0.0, 0.0


# ------------------------------------------------------- chamber shared by the valves
@njit(cache=True, inline="always")
def _chamber_rate(y, prm, mdot):  # pragma: no cover - compiled
    """dp/dt = n/V·(R·T·ṁ + p·A_d·v), with the chamber volume V = V0 − A_d·x."""
    ad = prm[I_AD]
    vol = prm[I_V0] - ad * y[0]
    return prm[I_NPOLY] / vol * (prm[I_R] * prm[I_T] * mdot + y[3] * ad * y[1])


@njit(cache=True, inline="always")
def _chamber_jac(y, prm, mdot, dmdot_dp, jac):  # pragma: no cover - compiled
    """Row of the pressure state in the Jacobian (∂/∂x, ∂/∂v, ∂/∂p)."""
    ad = prm[I_AD]
    vol = prm[I_V0] - ad * y[0]
    n = prm[I_NPOLY]
    rt = prm[I_R] * prm[I_T]
    jac[3, 0] = n / vol * (rt * mdot + y[3] * ad * y[1]) * ad / vol
    jac[3, 1] = n * y[3] * ad / vol
    jac[3, 3] = n / vol * (rt * dmdot_dp + ad * y[1])


@njit(cache=True, inline="always")
def _valve_flows(p, u, prm, sig, ptr):  # pragma: no cover - compiled
    """Flows in (atmosphere -> chamber) and out (chamber -> reservoir) at opening u.

    Orifice flow is linear in the area, so each orifice is evaluated once per unit area
    and scaled by the mapped opening. Returns (ṁ_in, ṁ_out, ∂ṁ/∂p, ∂ṁ/∂u), ṁ = ṁ_in − ṁ_out.
    """
    m_res, dm_res = channel_eval(sig, ptr, CH_MAP_RES, u, u)
    m_atm, dm_atm = channel_eval(sig, ptr, CH_MAP_ATM, u, u)
    a_res = prm[I_ARES] * m_res
    a_atm = prm[I_AATM] * m_atm
    q_in_unit, _, dqin_dp_unit = orifice(prm[I_PATM], p, 1.0, prm)
    q_out_unit, dqout_dp_unit, _ = orifice(p, prm[I_PRES], 1.0, prm)
    dq_dp = a_atm * dqin_dp_unit - a_res * dqout_dp_unit
    dq_du = prm[I_AATM] * dm_atm * q_in_unit - prm[I_ARES] * dm_res * q_out_unit
    return a_atm * q_in_unit, a_res * q_out_unit, dq_dp, dq_du


# ------------------------------------------------------------------------ command valve
COMMAND_NSTATE = 4


@njit(cache=True, inline="always")
def command_pressure(t, ts, y, prm, sig, ptr):  # pragma: no cover - compiled
    return y[3]


@njit(cache=True, inline="always")
def command_rhs(t, ts, y, prm, sig, ptr, dydt):  # pragma: no cover - compiled
    u = channel_eval(sig, ptr, CH_DRIVE, t, ts)[0]
    q_in, q_out, _, _ = _valve_flows(y[3], u, prm, sig, ptr)
    dydt[3] = _chamber_rate(y, prm, q_in - q_out)


@njit(cache=True, inline="always")
def command_jac(t, ts, y, prm, sig, ptr, jac):  # pragma: no cover - compiled
    u = channel_eval(sig, ptr, CH_DRIVE, t, ts)[0]
    q_in, q_out, dq_dp, _ = _valve_flows(y[3], u, prm, sig, ptr)
    _chamber_jac(y, prm, q_in - q_out, dq_dp, jac)


@njit(cache=True, inline="always")
def command_flows(t, ts, y, prm, sig, ptr):  # pragma: no cover - compiled
    u = channel_eval(sig, ptr, CH_DRIVE, t, ts)[0]
    q_in, q_out, _, _ = _valve_flows(y[3], u, prm, sig, ptr)
    return u, q_in, q_out


# ------------------------------------------------------------------ pressure regulator
REGULATOR_NSTATE = 6


@njit(cache=True, inline="always")
def _regulator_law(t, ts, y, prm, sig, ptr):  # pragma: no cover - compiled
    """PI law on the normalised pressure error with back-calculation anti-windup.

    e = (p − p_set)/p_atm (more vacuum needed → open towards the reservoir), raw opening
    u_raw = kp·e + i, commanded opening u_cmd = clip(u_raw, 0, 1).
    Returns (u_cmd, du_cmd/dp, du_cmd/di, e, saturated).
    """
    p_set = channel_eval(sig, ptr, CH_DRIVE, t, ts)[0]
    patm = prm[I_PATM]
    kp = prm[I_REG_KP]
    e = (y[3] - p_set) / patm
    u_raw = kp * e + y[5]
    if u_raw > 1.0:
        return 1.0, 0.0, 0.0, e, True
    if u_raw < 0.0:
        return 0.0, 0.0, 0.0, e, True
    return u_raw, kp / patm, 1.0, e, False


@njit(cache=True, inline="always")
def regulator_pressure(t, ts, y, prm, sig, ptr):  # pragma: no cover - compiled
    return y[3]


@njit(cache=True, inline="always")
def regulator_rhs(t, ts, y, prm, sig, ptr, dydt):  # pragma: no cover - compiled
    u = y[4]
    q_in, q_out, _, _ = _valve_flows(y[3], u, prm, sig, ptr)
    dydt[3] = _chamber_rate(y, prm, q_in - q_out)
    u_cmd = _regulator_law(t, ts, y, prm, sig, ptr)[0]
    dydt[4] = (u_cmd - u) / prm[I_REG_TAU]
    # back-calculation anti-windup with tracking time Ti: di/dt = kp·e/Ti + (u_cmd − u_raw)/Ti
    dydt[5] = (u_cmd - y[5]) / prm[I_REG_TI]


@njit(cache=True, inline="always")
def regulator_jac(t, ts, y, prm, sig, ptr, jac):  # pragma: no cover - compiled
    u = y[4]
    q_in, q_out, dq_dp, dq_du = _valve_flows(y[3], u, prm, sig, ptr)
    _chamber_jac(y, prm, q_in - q_out, dq_dp, jac)
    n = prm[I_NPOLY]
    vol = prm[I_V0] - prm[I_AD] * y[0]
    jac[3, 4] = n / vol * prm[I_R] * prm[I_T] * dq_du
    _, du_dp, du_di, _, _ = _regulator_law(t, ts, y, prm, sig, ptr)
    tau = prm[I_REG_TAU]
    jac[4, 3] = du_dp / tau
    jac[4, 4] = -1.0 / tau
    jac[4, 5] = du_di / tau
    ti = prm[I_REG_TI]
    jac[5, 3] = du_dp / ti
    jac[5, 5] = (du_di - 1.0) / ti


@njit(cache=True, inline="always")
def regulator_flows(t, ts, y, prm, sig, ptr):  # pragma: no cover - compiled
    q_in, q_out, _, _ = _valve_flows(y[3], y[4], prm, sig, ptr)
    return y[4], q_in, q_out


# -------------------------------------------------------------------- strategy objects
class Valve:
    """Strategy object: which compiled valve functions feed the chamber."""

    prefix: ClassVar[str]
    nstate: ClassVar[int]
    drive: ClassVar[str]  # what the experiment's signal means for this valve
    required: ClassVar[tuple[str, ...]]
    module: ClassVar[str] = "pneumact.models.valves"

    def maps(self) -> tuple[Signal | None, Signal | None]:
        return None, None

    @property
    def name(self) -> str:
        return type(self).__name__


@dataclass(frozen=True)
class PressureSource(Valve):
    """Ideal source: the chamber pressure is the experiment's pressure signal (paper
    Figs. 5-6, where the measured pressure is applied)."""

    prefix: ClassVar[str] = "source"
    nstate: ClassVar[int] = SOURCE_NSTATE
    drive: ClassVar[str] = "pressure"
    required: ClassVar[tuple[str, ...]] = ()


@functools.cache
def _linear_map(rising: bool) -> Signal:
    """The default area map: linear from closed to fully open over u ∈ [0, 1]."""
    from ..experiments.signals import PiecewiseLinear

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
    nstate: ClassVar[int] = COMMAND_NSTATE
    drive: ClassVar[str] = "command"
    required: ClassVar[tuple[str, ...]] = ("A_res", "A_atm", "p_res", "V0", "R", "T", "gamma",
                                           "r_lin")

    def maps(self) -> tuple[Signal, Signal]:
        return (self.reservoir_map or _linear_map(True),
                self.atmosphere_map or _linear_map(False))


@dataclass(frozen=True)
class PressureRegulator(CommandValve):
    """Electro-pneumatic pressure regulator (the paper's EPC): a PI law on the pressure
    error moves the valve, which has its own first-order lag ``reg_tau``; the experiment's
    signal is the pressure set-point."""

    prefix: ClassVar[str] = "regulator"
    nstate: ClassVar[int] = REGULATOR_NSTATE
    drive: ClassVar[str] = "pressure"
    required: ClassVar[tuple[str, ...]] = (*CommandValve.required, "reg_kp", "reg_ti",
                                           "reg_tau")

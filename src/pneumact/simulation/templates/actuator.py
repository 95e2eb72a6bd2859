"""Kernel template: the diaphragm actuator (paper eq. 1 with the chamber of eqs. 2-5).

The generator replaces the block between the ``components`` markers with the chosen
friction law and valve and compiles the result as one module, cached on disk. As shipped,
the block names LuGre + an ideal pressure source, so this file is itself a valid kernel.

State: [x, v, z | p | u, i] (see ``pneumact.models.valves``).
"""

from numba import njit

from pneumact.experiments.signals import channel_eval
from pneumact.models.layout import (
    CH_LOAD_T,
    CH_LOAD_X,
    I_AD,
    I_CSTOP,
    I_F0,
    I_K,
    I_KSTOP,
    I_M,
    I_PATM,
    I_XMAX,
)

# isort: off
# --- components ---
from pneumact.models.friction import lugre as friction_eval
from pneumact.models.friction import lugre_dtheta as friction_dtheta
from pneumact.models.valves import SOURCE_NSTATE as NSTATE
from pneumact.models.valves import source_flows as valve_flows
from pneumact.models.valves import source_jac as valve_jac
from pneumact.models.valves import source_pressure as valve_pressure
from pneumact.models.valves import source_rhs as valve_rhs

# --- end components ---
# isort: on

OUTPUT_NAMES = (
    "pressure", "friction", "spring_force", "pressure_force", "stop_force", "load",
    "opening", "mass_flow_in", "mass_flow_out", "bristle_rate",
)
OUTPUT_UNITS = ("Pa", "N", "N", "N", "N", "N", "1", "kg/s", "kg/s", "m/s")
NOUT = len(OUTPUT_NAMES)
STATE_NAMES = ("position", "velocity", "bristle", "pressure", "opening", "integral")[:NSTATE]
STATE_UNITS = ("m", "m/s", "m", "Pa", "1", "1")[:NSTATE]


@njit(cache=True, inline="always")
def stop_force(x, v, prm):  # pragma: no cover - compiled
    """End stops as compression-only spring-dampers: they push, never pull (no sticking),
    and their damping only dissipates (no energy injected).

    Returns (F, ∂F/∂x, ∂F/∂v), positive pushing towards larger x.
    """
    ks = prm[I_KSTOP]
    cs = prm[I_CSTOP]
    if x < 0.0:
        f = -ks * x - cs * v
        if f > 0.0:
            return f, -ks, -cs
    else:
        pen = x - prm[I_XMAX]
        if pen > 0.0:
            f = ks * pen + cs * v
            if f > 0.0:
                return -f, -ks, -cs
    return 0.0, 0.0, 0.0


@njit(cache=True, inline="always")
def external_load(t, ts, x, sig, ptr):  # pragma: no cover - compiled
    """F_ext(t, x) = load(t) + load_map(x), opposing motion towards larger x."""
    f_t = channel_eval(sig, ptr, CH_LOAD_T, t, ts)[0]
    f_x, df_dx = channel_eval(sig, ptr, CH_LOAD_X, x, x)
    return f_t + f_x, df_dx


@njit(cache=True)
def rhs(t, ts, y, prm, sig, ptr, dydt):  # pragma: no cover - compiled
    x = y[0]
    v = y[1]
    p = valve_pressure(t, ts, y, prm, sig, ptr)
    zdot, f_fric, _, _, _, _ = friction_eval(v, y[2], prm)
    f_stop, _, _ = stop_force(x, v, prm)
    f_ext, _ = external_load(t, ts, x, sig, ptr)
    net = (prm[I_PATM] - p) * prm[I_AD] - (prm[I_F0] + prm[I_K] * x) - f_fric - f_ext + f_stop
    dydt[0] = v
    dydt[1] = net / prm[I_M]
    dydt[2] = zdot
    valve_rhs(t, ts, y, prm, sig, ptr, dydt)


@njit(cache=True)
def jac(t, ts, y, prm, sig, ptr, out):  # pragma: no cover - compiled
    """Analytic Jacobian ∂f/∂y (``out`` is zeroed by the caller)."""
    x = y[0]
    v = y[1]
    _, _, dzd_dv, dzd_dz, df_dv, df_dz = friction_eval(v, y[2], prm)
    _, dstop_dx, dstop_dv = stop_force(x, v, prm)
    _, dext_dx = external_load(t, ts, x, sig, ptr)
    m = prm[I_M]
    out[0, 1] = 1.0
    out[1, 0] = (-prm[I_K] - dext_dx + dstop_dx) / m
    out[1, 1] = (-df_dv + dstop_dv) / m
    out[1, 2] = -df_dz / m
    out[2, 1] = dzd_dv
    out[2, 2] = dzd_dz
    if NSTATE > 3:
        out[1, 3] = -prm[I_AD] / m
    valve_jac(t, ts, y, prm, sig, ptr, out)


@njit(cache=True)
def friction_param_rhs(t, ts, y, prm, sig, ptr, d, g):  # pragma: no cover - compiled
    """g[k] = ∂f/∂θ_k for the friction parameters θ = FRICTION_SENS (d: work array)."""
    friction_dtheta(y[1], y[2], prm, d)
    m = prm[I_M]
    for k in range(d.shape[0]):
        for a in range(NSTATE):
            g[k, a] = 0.0
        g[k, 1] = -d[k, 1] / m
        g[k, 2] = d[k, 0]


@njit(cache=True)
def outputs(t, ts, y, prm, sig, ptr, out):  # pragma: no cover - compiled
    """Derived signals at one instant, in the order of OUTPUT_NAMES."""
    x = y[0]
    v = y[1]
    p = valve_pressure(t, ts, y, prm, sig, ptr)
    zdot, f_fric, _, _, _, _ = friction_eval(v, y[2], prm)
    u, q_in, q_out = valve_flows(t, ts, y, prm, sig, ptr)
    out[0] = p
    out[1] = f_fric
    out[2] = prm[I_F0] + prm[I_K] * x
    out[3] = (prm[I_PATM] - p) * prm[I_AD]
    out[4] = stop_force(x, v, prm)[0]
    out[5] = external_load(t, ts, x, sig, ptr)[0]
    out[6] = u
    out[7] = q_in
    out[8] = q_out
    out[9] = zdot

"""Kernel template: the friction test rig of Canudas de Wit et al. (1995).

A mass on a surface with friction, driven by a prescribed force, velocity or position,
or pulled through a spring whose free end follows the drive signal (stick-slip). The
generator substitutes the friction law and the drive in the ``components`` block.

State: [x, v, z].
"""

from numba import njit

from pneumact.models.layout import I_M

# isort: off
# --- components ---
from pneumact.models.friction import lugre as friction_eval
from pneumact.models.friction import lugre_dtheta as friction_dtheta
from pneumact.models.rig import force_drive as drive_eval

# --- end components ---
# isort: on

NSTATE = 3
OUTPUT_NAMES = ("friction", "drive", "drive_force", "bristle_rate")
OUTPUT_UNITS = ("N", "1", "N", "m/s")
NOUT = len(OUTPUT_NAMES)
STATE_NAMES = ("position", "velocity", "bristle")
STATE_UNITS = ("m", "m/s", "m")


@njit(cache=True)
def rhs(t, ts, y, prm, sig, ptr, dydt):  # pragma: no cover - compiled
    kin, v_kin, a_kin, f_drive, _, _, _, _ = drive_eval(t, ts, y, prm, sig, ptr)
    v = v_kin if kin else y[1]
    zdot, f_fric, _, _, _, _ = friction_eval(v, y[2], prm)
    dydt[0] = v
    dydt[1] = a_kin if kin else (f_drive - f_fric) / drive_mass(prm)
    dydt[2] = zdot


@njit(cache=True)
def jac(t, ts, y, prm, sig, ptr, out):  # pragma: no cover - compiled
    kin, v_kin, _, _, dfd_dx, dfd_dv, _, _ = drive_eval(t, ts, y, prm, sig, ptr)
    v = v_kin if kin else y[1]
    _, _, dzd_dv, dzd_dz, df_dv, df_dz = friction_eval(v, y[2], prm)
    out[2, 2] = dzd_dz
    if kin:
        return
    m = drive_mass(prm)
    out[0, 1] = 1.0
    out[1, 0] = dfd_dx / m
    out[1, 1] = (dfd_dv - df_dv) / m
    out[1, 2] = -df_dz / m
    out[2, 1] = dzd_dv


@njit(cache=True)
def friction_param_rhs(t, ts, y, prm, sig, ptr, d, g):  # pragma: no cover - compiled
    """g[k] = ∂f/∂θ_k for the friction parameters θ = FRICTION_SENS (d: work array)."""
    kin, v_kin, _, _, _, _, _, _ = drive_eval(t, ts, y, prm, sig, ptr)
    v = v_kin if kin else y[1]
    friction_dtheta(v, y[2], prm, d)
    m = drive_mass(prm)
    for k in range(d.shape[0]):
        g[k, 0] = 0.0
        g[k, 1] = 0.0 if kin else -d[k, 1] / m
        g[k, 2] = d[k, 0]


@njit(cache=True)
def outputs(t, ts, y, prm, sig, ptr, out):  # pragma: no cover - compiled
    kin, v_kin, _, f_drive, _, _, drive, _ = drive_eval(t, ts, y, prm, sig, ptr)
    v = v_kin if kin else y[1]
    zdot, f_fric, _, _, _, _ = friction_eval(v, y[2], prm)
    out[0] = f_fric
    out[1] = drive
    out[2] = f_fric if kin else f_drive
    out[3] = zdot


@njit(cache=True, inline="always")
def drive_mass(prm):  # pragma: no cover - compiled
    return prm[I_M]

"""Model template: the friction test rig of Canudas de Wit et al. (1995).

A mass on a surface with friction, driven by a prescribed force, velocity or position,
or pulled through a spring whose free end follows the drive signal (stick-slip). The
generator binds the friction law and the drive; states are [position, velocity |
friction states], the parameter vector is [rig block | friction block].
"""

from pneumact.core import kernel
from pneumact.models.rig import RG_M

# --- bound by the generator --------------------------------------------------------------
friction_rates = friction_force = friction_partials = friction_param_partials = None
friction_project = friction_scales = friction_store = friction_store_partials = None
drive_eval = drive_params = drive_start = None
NSTATE = 3
RIG_LO = RIG_HI = FRICTION_LO = FRICTION_HI = 0
S_POSITION = 0
S_VELOCITY = 1
S_FRICTION = 2
# ------------------------------------------------------------------------------------------

OUTPUT_NAMES = ("friction", "drive", "drive_force")
OUTPUT_UNITS = ("N", "1", "N")
#: generated from OUTPUT_NAMES (the assembly's layout): NOUT and OUT_<NAME>
NOUT = OUT_FRICTION = OUT_DRIVE = OUT_DRIVE_FORCE = None


@kernel()
def derive(prm):
    """No derived quantities on the rig."""


@kernel()
def _drive(t, ts, y, prm, sig, ptr):
    return drive_eval(t, ts, y[S_POSITION], y[S_VELOCITY], prm, RIG_LO, sig, ptr)


@kernel()
def model_velocity(t, ts, y, prm, sig, ptr):
    """The mass's velocity: a kinematic drive's, else the state (what a friction law's
    events read)."""
    kin, v_kin, _, _, _, _, _ = _drive(t, ts, y, prm, sig, ptr)
    return v_kin if kin else y[S_VELOCITY]


@kernel()
def rhs(t, ts, y, prm, sig, ptr, dydt):
    kin, v_kin, a_kin, f_drive, _, _, _ = _drive(t, ts, y, prm, sig, ptr)
    v = v_kin if kin else y[S_VELOCITY]
    f_fric, z_rates = friction_rates(v, y, S_FRICTION, prm, FRICTION_LO)
    dydt[S_POSITION] = v
    dydt[S_VELOCITY] = a_kin if kin else (f_drive - f_fric) / prm[RIG_LO + RG_M]
    friction_store(z_rates, dydt, S_FRICTION)


@kernel()
def jac(t, ts, y, prm, sig, ptr, out):
    """Analytic Jacobian ∂f/∂y (``out`` is zeroed by the caller)."""
    kin, v_kin, _, _, dfd_dx, dfd_dv, _ = _drive(t, ts, y, prm, sig, ptr)
    v = v_kin if kin else y[S_VELOCITY]
    m = prm[RIG_LO + RG_M]
    moved = -1 if kin else S_VELOCITY  # a prescribed velocity has no column, no row
    _, df_dv, z_partials = friction_partials(v, y, S_FRICTION, prm, FRICTION_LO)
    friction_store_partials(z_partials, out, S_FRICTION, moved, moved, m)
    if kin:
        return
    out[S_POSITION, S_VELOCITY] = 1.0
    out[S_VELOCITY, S_POSITION] = dfd_dx / m
    out[S_VELOCITY, S_VELOCITY] = (dfd_dv - df_dv) / m


@kernel()
def param_jac(t, ts, y, prm, sig, ptr, g, needed):
    """g[a, k] = ∂f_a/∂prm[k] (NSTATE × vector size)."""
    for a in range(NSTATE):
        for k in range(g.shape[1]):
            g[a, k] = 0.0
    kin, v_kin, _, f_drive, _, _, _ = _drive(t, ts, y, prm, sig, ptr)
    v = v_kin if kin else y[S_VELOCITY]
    friction_param_partials(v, y, S_FRICTION, prm, FRICTION_LO, g, S_VELOCITY)
    if kin:  # the velocity is prescribed: nothing acts on its row
        for k in range(g.shape[1]):
            g[S_VELOCITY, k] = 0.0
        return
    m = prm[RIG_LO + RG_M]
    for k in range(FRICTION_LO, FRICTION_HI):
        g[S_VELOCITY, k] = -g[S_VELOCITY, k] / m
    drive_params(t, ts, y[S_POSITION], y[S_VELOCITY], prm, RIG_LO, sig, ptr, g, S_VELOCITY)
    for k in range(RIG_LO, RIG_HI):
        g[S_VELOCITY, k] = g[S_VELOCITY, k] / m
    f_fric = friction_force(v, y, S_FRICTION, prm, FRICTION_LO)
    g[S_VELOCITY, RIG_LO + RG_M] = -(f_drive - f_fric) / (m * m)


@kernel()
def outputs(t, ts, y, prm, sig, ptr, out):
    """Derived signals at one instant, in the order of OUTPUT_NAMES."""
    kin, v_kin, _, f_drive, _, _, drive = _drive(t, ts, y, prm, sig, ptr)
    v = v_kin if kin else y[S_VELOCITY]
    f_fric = friction_force(v, y, S_FRICTION, prm, FRICTION_LO)
    out[OUT_FRICTION] = f_fric
    out[OUT_DRIVE] = drive
    out[OUT_DRIVE_FORCE] = f_fric if kin else f_drive


@kernel()
def initial_state(t, ts, prm, sig, ptr, y0):
    """At rest at the origin, or moving with a kinematic drive's initial value."""
    for i in range(NSTATE):
        y0[i] = 0.0
    y0[S_POSITION], y0[S_VELOCITY] = drive_start(t, ts, prm, RIG_LO, sig, ptr)


@kernel()
def project(prm, y):
    """Back onto the friction law's bounds the exact dynamics never leave (see the
    actuator)."""
    friction_project(prm, FRICTION_LO, y, S_FRICTION)


@kernel()
def state_scales(prm, out):
    """Typical magnitude of x, v and the friction states: the presliding range Fs/σ0 and
    its velocity Fs/√(σ0·m) (static maps: the regularisation velocity), for default atol."""
    z_scale, stiffness, v_reg = friction_scales(prm, FRICTION_LO, out, S_FRICTION)
    if stiffness > 0.0:
        out[S_POSITION] = z_scale
        out[S_VELOCITY] = z_scale * (stiffness / prm[RIG_LO + RG_M]) ** 0.5
    else:
        out[S_VELOCITY] = v_reg
        out[S_POSITION] = 1e-2 * v_reg

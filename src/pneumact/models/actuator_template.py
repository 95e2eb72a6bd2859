"""Model template: the diaphragm actuator (paper eq. 1) with a friction law and a valve.

The generator (``core.codegen``) binds these functions into one module per
friction × valve combination, where the names below marked "bound by the generator"
are the chosen component functions and the layout constants of the assembly
(``core.assembly``): states are [position, velocity | friction states | valve
states], the parameter vector is [mechanics block | friction block | valve block]. The
friction law is called through its slice-level functions (``models.friction.base``).
"""

from pneumact.core import kernel
from pneumact.models.mechanics import (
    MC_AD,
    MC_F0,
    MC_K,
    MC_KSTOP,
    MC_M,
    MC_PATM,
    MC_XMAX,
    acceleration_params,
    load_against_position,
    load_against_time,
    mechanics_scales,
    net_force,
    rest_position,
    stop_force_of,
    stop_guards,
)

# --- bound by the generator --------------------------------------------------------------
friction_rates = friction_force = friction_partials = friction_param_partials = None
friction_project = friction_scales = friction_store = friction_store_partials = None
valve_pressure = valve_rates = valve_partials = valve_params = valve_flows = None
valve_derive = valve_equilibrium = valve_scales = valve_project = None
VALVE_PRESSURE_STATE = -1
HAS_LOAD = True
NSTATE = 3
MECHANICS_LO = MECHANICS_HI = FRICTION_LO = FRICTION_HI = VALVE_LO = VALVE_HI = 0
S_POSITION = 0
S_VELOCITY = 1
S_FRICTION = 2
S_VALVE = 3
# ------------------------------------------------------------------------------------------

OUTPUT_NAMES = ("pressure", "friction", "spring_force", "pressure_force", "stop_force",
                "load", "opening", "mass_flow_in", "mass_flow_out")
OUTPUT_UNITS = ("Pa", "N", "N", "N", "N", "N", "1", "kg/s", "kg/s")
#: generated from OUTPUT_NAMES (the assembly's layout): NOUT and OUT_<NAME>
NOUT = OUT_PRESSURE = OUT_FRICTION = OUT_SPRING_FORCE = OUT_PRESSURE_FORCE = None
OUT_STOP_FORCE = OUT_LOAD = OUT_OPENING = OUT_MASS_FLOW_IN = OUT_MASS_FLOW_OUT = None
#: Fixed-point steps of the rest position under a load that depends on position.
LOAD_ITERATIONS = 20


@kernel()
def external_load(t, ts, x, sig, ptr):
    """F_ext(t, x) = load(t) + load_map(x) and its slope; no code without a load (with
    one of the two, the other is a zero signal: one kernel for any load)."""
    f_ext = 0.0
    slope = 0.0
    if HAS_LOAD:
        f_x, slope = load_against_position(x, sig, ptr)
        f_ext = load_against_time(t, ts, sig, ptr) + f_x
    return f_ext, slope


@kernel()
def model_velocity(t, ts, y, prm, sig, ptr):
    """The diaphragm's velocity (what a friction law's events read)."""
    return y[S_VELOCITY]


@kernel()
def derive(prm):
    """Recompute the derived entries of every block (after any change of a value)."""
    valve_derive(prm, VALVE_LO)


@kernel()
def rhs(t, ts, y, prm, sig, ptr, dydt):
    x = y[S_POSITION]
    v = y[S_VELOCITY]
    p = valve_pressure(t, ts, y, S_VALVE, prm, VALVE_LO, sig, ptr)
    f_fric, z_rates = friction_rates(v, y, S_FRICTION, prm, FRICTION_LO)
    f_ext = external_load(t, ts, x, sig, ptr)[0]
    net = net_force(x, v, p, f_fric, f_ext, prm, MECHANICS_LO)[0]
    dydt[S_POSITION] = v
    dydt[S_VELOCITY] = net / prm[MECHANICS_LO + MC_M]
    friction_store(z_rates, dydt, S_FRICTION)
    valve_rates(t, ts, x, v, y, S_VALVE, prm, VALVE_LO, sig, ptr, dydt)


@kernel()
def jac(t, ts, y, prm, sig, ptr, out):
    """Analytic Jacobian ∂f/∂y (``out`` is zeroed by the caller)."""
    x = y[S_POSITION]
    v = y[S_VELOCITY]
    p = valve_pressure(t, ts, y, S_VALVE, prm, VALVE_LO, sig, ptr)
    m = prm[MECHANICS_LO + MC_M]
    f_fric, df_dv, z_partials = friction_partials(v, y, S_FRICTION, prm, FRICTION_LO)
    f_ext, dext_dx = external_load(t, ts, x, sig, ptr)
    _, dnet_dx, dnet_dv, dnet_dp = net_force(x, v, p, f_fric, f_ext, prm, MECHANICS_LO)
    out[S_POSITION, S_VELOCITY] = 1.0
    out[S_VELOCITY, S_POSITION] = (dnet_dx - dext_dx) / m
    out[S_VELOCITY, S_VELOCITY] = (dnet_dv - df_dv) / m
    friction_store_partials(z_partials, out, S_FRICTION, S_VELOCITY, S_VELOCITY, m)
    if VALVE_PRESSURE_STATE >= 0:
        out[S_VELOCITY, S_VALVE + VALVE_PRESSURE_STATE] = dnet_dp / m
    valve_partials(t, ts, x, v, y, S_VALVE, prm, VALVE_LO, sig, ptr, out, S_POSITION,
                   S_VELOCITY)


@kernel()
def param_jac(t, ts, y, prm, sig, ptr, g, needed):
    """g[a, k] = ∂f_a/∂prm[k] (NSTATE × vector size); blocks with no ``needed`` slot skipped."""
    for a in range(NSTATE):
        for k in range(g.shape[1]):
            g[a, k] = 0.0
    x = y[S_POSITION]
    v = y[S_VELOCITY]
    if _any(needed, MECHANICS_LO, MECHANICS_HI):
        p = valve_pressure(t, ts, y, S_VALVE, prm, VALVE_LO, sig, ptr)
        f_fric = friction_force(v, y, S_FRICTION, prm, FRICTION_LO)
        f_ext = external_load(t, ts, x, sig, ptr)[0]
        net = net_force(x, v, p, f_fric, f_ext, prm, MECHANICS_LO)[0]
        acceleration_params(x, v, p, net, prm, MECHANICS_LO, g, S_VELOCITY)
    if _any(needed, FRICTION_LO, FRICTION_HI):
        # the friction force enters the acceleration as −F/m
        friction_param_partials(v, y, S_FRICTION, prm, FRICTION_LO, g, S_VELOCITY)
        m = prm[MECHANICS_LO + MC_M]
        for k in range(FRICTION_LO, FRICTION_HI):
            g[S_VELOCITY, k] = -g[S_VELOCITY, k] / m
    if _any(needed, VALVE_LO, VALVE_HI):
        valve_params(t, ts, x, v, y, S_VALVE, prm, VALVE_LO, sig, ptr, g)


@kernel()
def _any(flags, lo, hi):
    for k in range(lo, hi):
        if flags[k]:
            return True
    return False


@kernel()
def outputs(t, ts, y, prm, sig, ptr, out):
    """Derived signals at one instant, in the order of OUTPUT_NAMES."""
    x = y[S_POSITION]
    v = y[S_VELOCITY]
    p = valve_pressure(t, ts, y, S_VALVE, prm, VALVE_LO, sig, ptr)
    f_fric = friction_force(v, y, S_FRICTION, prm, FRICTION_LO)
    u, q_in, q_out = valve_flows(t, ts, x, v, y, S_VALVE, prm, VALVE_LO, sig, ptr)
    out[OUT_PRESSURE] = p
    out[OUT_FRICTION] = f_fric
    out[OUT_SPRING_FORCE] = prm[MECHANICS_LO + MC_F0] + prm[MECHANICS_LO + MC_K] * x
    out[OUT_PRESSURE_FORCE] = (prm[MECHANICS_LO + MC_PATM] - p) * prm[MECHANICS_LO + MC_AD]
    out[OUT_STOP_FORCE] = stop_force_of(x, v, prm, MECHANICS_LO)[0]
    out[OUT_LOAD] = external_load(t, ts, x, sig, ptr)[0]
    out[OUT_OPENING] = u
    out[OUT_MASS_FLOW_IN] = q_in
    out[OUT_MASS_FLOW_OUT] = q_out


@kernel()
def switch_guards(t, ts, y, prm, sig, ptr, out):
    """Guards of the right-hand side's kinks, > 0 away from them: the end stops. Where an
    importer's solver must stop and restart (an FMU's event indicators, with a friction
    law's own events); the pneumact integrator's error control handles them itself.
    Returns how many."""
    out[0], out[1] = stop_guards(y[S_POSITION], prm, MECHANICS_LO)
    return 2


@kernel()
def initial_state(t, ts, prm, sig, ptr, y0):
    """Rest at the static equilibrium of the initial input (friction unloaded): the
    valve's rest pressure, then the position where spring, stops and loads balance it."""
    for i in range(NSTATE):
        y0[i] = 0.0
    p0 = valve_equilibrium(t, ts, prm, VALVE_LO, sig, ptr, y0, S_VALVE)
    net0 = ((prm[MECHANICS_LO + MC_PATM] - p0) * prm[MECHANICS_LO + MC_AD]
            - prm[MECHANICS_LO + MC_F0])
    k = prm[MECHANICS_LO + MC_K]
    ks = prm[MECHANICS_LO + MC_KSTOP]
    x_max = prm[MECHANICS_LO + MC_XMAX]
    x0 = rest_position(net0 - external_load(t, ts, 0.0, sig, ptr)[0], k, ks, x_max)
    if HAS_LOAD:
        for _ in range(LOAD_ITERATIONS):  # a load against position: fixed-point steps
            x0 = rest_position(net0 - external_load(t, ts, x0, sig, ptr)[0], k, ks, x_max)
    y0[S_POSITION] = x0


@kernel()
def project(prm, y):
    """Back onto the bounds the exact dynamics never leave (the friction law's states,
    the regulator's opening) after a step: a loose tolerance may overshoot them slightly,
    and the projection onto such a convex set can only bring y closer to the solution."""
    friction_project(prm, FRICTION_LO, y, S_FRICTION)
    valve_project(y, S_VALVE)


@kernel()
def state_scales(prm, out):
    """Typical magnitude of each state (for the default absolute tolerances)."""
    out[S_POSITION], out[S_VELOCITY] = mechanics_scales(prm, MECHANICS_LO)
    friction_scales(prm, FRICTION_LO, out, S_FRICTION)
    valve_scales(prm, VALVE_LO, out, S_VALVE)

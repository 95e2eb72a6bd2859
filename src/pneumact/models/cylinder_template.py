"""Model template: the double-acting cylinder, each chamber fed through its own valve
paths (supply → chamber, chamber → exhaust), by a 5/3 proportional valve or by a
proportional 3/2 valve per chamber (``TWO_VALVES``, bound by the model).

Each chamber has its own command (``_commands``: the 5/3 valve's spool position u for A
and −u for B, its ports mirrored; or each 3/2 valve's command on its channel
``CH_COMMAND_A``, ``CH_COMMAND_B``, B's times ``COMMAND_B_SIGN``, −1 where the valves are
mirrored and both read the drive) and its own paths, whose C, leak and overlap stand at
an offset (``_paths``: the 5/3 valve's entries of the cylinder block for both chambers,
or each 3/2 valve's own block, ``VALVE_A_LO``, ``VALVE_B_LO``); their conductances at the
command (``_conductances``: the 5/3 valve's B paths are A's swapped, evaluated once) feed
one set of equations for both (``models.cylinder``: ``chamber_flows``, ``cylinder_rates``,
``rest_pressures``, ``cylinder_params``).

States are [position, velocity, pressure_a, pressure_b | friction states | the spool's
position (and velocity) when it lags | the chambers' temperatures with heat transfer],
the parameter vector is [cylinder block | chamber_a's block | chamber_b's block |
friction block | spool block or valve_a's and valve_b's blocks | heat transfer block];
the generator binds the friction law, the spool (``spool_*``: direct, lagged or
second-order; the 3/2 valves' is the direct one, whose functions do nothing beyond its
position, which they do not read) and the chambers (``thermal_*``: polytropic, whose
functions do nothing, or with heat transfer, whose energy equations replace the pressure
rates, rows and columns the polytropic code wrote, reading the 5/3 valve's spool). The
supply pressure is the input ``supply`` on the cylinder's own channel (``CH_SUPPLY``,
generated) where an experiment drives it, else the parameter p_supply (``_supply``); only
then do the parameters' partials include p_supply's column.
"""

from pneumact.core import kernel
from pneumact.models.cylinder import (
    CY_AA,
    CY_AB,
    CY_KSTOP,
    CY_M,
    CY_N,
    CY_PATHS,
    CY_PATM,
    CY_PSUP,
    CY_R,
    CY_T,
    CY_XMAX,
    SPOOL_OUTPUT_NAMES,
    SPOOL_OUTPUT_UNITS,
    chamber_flow_slopes,
    chamber_flows,
    chamber_row,
    chamber_volumes,
    cylinder_params,
    cylinder_rates,
    derive_cylinder,
    end_stop_guards,
    path_conductances,
    piston_force,
    rest_pressures,
    spool_conductances,
    supply_held,
    supply_pressure,
    valve_command,
)
from pneumact.models.mechanics import load_against_time, rest_position

# --- bound by the generator --------------------------------------------------------------
friction_rates = friction_force = friction_partials = friction_param_partials = None
friction_project = friction_scales = friction_store = friction_store_partials = None
spool_position = spool_rates = spool_partials = spool_params = spool_start = None
spool_project = spool_scales = None
thermal_rates = thermal_flows = thermal_partials = thermal_params = None
thermal_start = thermal_scales = None
SPOOL_STATE = -1
THERMAL_STATE = -1
NSTATE = 5
CYLINDER_LO = CYLINDER_HI = FRICTION_LO = FRICTION_HI = VALVE_LO = VALVE_HI = 0
THERMAL_LO = THERMAL_HI = 0
CHAMBER_A_LO = CHAMBER_A_HI = CHAMBER_B_LO = CHAMBER_B_HI = 0
VALVE_A_LO = VALVE_A_HI = VALVE_B_LO = VALVE_B_HI = 0  # generated with two 3/2 valves
S_POSITION = 0
S_VELOCITY = 1
S_PRESSURE_A = 2
S_PRESSURE_B = 3
S_FRICTION = 4
S_VALVE = 5
S_THERMAL = 6
CH_SUPPLY = None  # generated: the supply channel's index (``core.channels``)
#: bound by the model (``Cylinder.kernel_constants``): whether a 3/2 valve feeds each
#: chamber; then valve A's and B's command channels (generated, or both the drive's where
#: the valves are mirrored) and the sign of B's command (-1.0 mirrored: u_b = -u)
TWO_VALVES = False
CH_COMMAND_A = CH_COMMAND_B = -1
COMMAND_B_SIGN = 1.0
# ------------------------------------------------------------------------------------------

#: the 5/3 valve's outputs; two 3/2 valves have command_a and command_b for spool
#: (``Cylinder.output_names``)
OUTPUT_NAMES, OUTPUT_UNITS = SPOOL_OUTPUT_NAMES, SPOOL_OUTPUT_UNITS
#: generated from the model's output names (the assembly's layout): NOUT and OUT_<NAME>
NOUT = OUT_FRICTION = OUT_PRESSURE_FORCE = OUT_STOP_FORCE = OUT_LOAD = None
OUT_MASS_FLOW_A = OUT_MASS_FLOW_B = None
OUT_SPOOL = OUT_COMMAND_A = OUT_COMMAND_B = -1  # generated where the model has them


@kernel(inline="always")
def _commands(t, ts, y, prm, sig, ptr):
    """Each chamber's valve command (u_a, u_b): the 5/3 valve's spool position u (its
    command, or its lagged state) and −u, or each 3/2 valve's on its channel."""
    if TWO_VALVES:
        return (valve_command(t, ts, sig, ptr, CH_COMMAND_A),
                COMMAND_B_SIGN * valve_command(t, ts, sig, ptr, CH_COMMAND_B))
    u = spool_position(t, ts, y, S_VALVE, prm, VALVE_LO, sig, ptr)
    return u, -u


@kernel(inline="always")
def _paths():
    """Where chamber A's and chamber B's paths' C, leak and overlap stand: each 3/2
    valve's block, or both the 5/3 valve's entries of the cylinder block."""
    if TWO_VALVES:
        return VALVE_A_LO, VALVE_B_LO
    return CYLINDER_LO + CY_PATHS, CYLINDER_LO + CY_PATHS


@kernel(inline="always")
def _conductances(ua, ub, prm):
    """Each chamber's supply and exhaust paths' conductances at its command (c_fill_a,
    c_vent_a, c_fill_b, c_vent_b): each 3/2 valve's, or the 5/3 valve's (B's A's swapped:
    one opening of each path, as the spool has)."""
    if TWO_VALVES:
        fill_a, vent_a = path_conductances(ua, prm, VALVE_A_LO)
        fill_b, vent_b = path_conductances(ub, prm, VALVE_B_LO)
        return fill_a, vent_a, fill_b, vent_b
    return spool_conductances(ua, prm, CYLINDER_LO)


@kernel(inline="always")
def _supply(t, ts, prm, sig, ptr):
    """The supply pressure: its input where driven, else p_supply."""
    return supply_pressure(t, ts, prm, CYLINDER_LO, sig, ptr, CH_SUPPLY)


@kernel()
def derive(prm):
    """The piston areas, the polytropic index and the chambers' dead volumes (after any
    change of a value)."""
    derive_cylinder(prm, CYLINDER_LO, CHAMBER_A_LO, CHAMBER_B_LO)


@kernel()
def model_velocity(t, ts, y, prm, sig, ptr):
    """The piston's velocity (what a friction law's events read)."""
    return y[S_VELOCITY]


@kernel()
def rhs(t, ts, y, prm, sig, ptr, dydt):
    x = y[S_POSITION]
    v = y[S_VELOCITY]
    pa = y[S_PRESSURE_A]
    pb = y[S_PRESSURE_B]
    f_fric, z_rates = friction_rates(v, y, S_FRICTION, prm, FRICTION_LO)
    ua, ub = _commands(t, ts, y, prm, sig, ptr)
    fill_a, vent_a, fill_b, vent_b = _conductances(ua, ub, prm)
    p_sup = _supply(t, ts, prm, sig, ptr)
    accel, rate_a, rate_b = cylinder_rates(
        x, v, pa, pb, fill_a, vent_a, fill_b, vent_b, p_sup, f_fric,
        load_against_time(t, ts, sig, ptr), prm, CYLINDER_LO)
    dydt[S_POSITION] = v
    dydt[S_VELOCITY] = accel
    dydt[S_PRESSURE_A] = rate_a
    dydt[S_PRESSURE_B] = rate_b
    thermal_rates(x, v, pa, pb, y, S_THERMAL, ua, p_sup, prm, CYLINDER_LO, THERMAL_LO, dydt,
                  S_PRESSURE_A, S_PRESSURE_B)
    friction_store(z_rates, dydt, S_FRICTION)
    spool_rates(t, ts, y, S_VALVE, prm, VALVE_LO, sig, ptr, dydt)


@kernel()
def jac(t, ts, y, prm, sig, ptr, out):
    """Analytic Jacobian ∂f/∂y (``out`` is zeroed by the caller)."""
    x = y[S_POSITION]
    v = y[S_VELOCITY]
    pa = y[S_PRESSURE_A]
    pb = y[S_PRESSURE_B]
    o = CYLINDER_LO
    m = prm[o + CY_M]
    area_a, area_b = prm[o + CY_AA], prm[o + CY_AB]
    n, rt = prm[o + CY_N], prm[o + CY_R] * prm[o + CY_T]
    _, df_dv, z_partials = friction_partials(v, y, S_FRICTION, prm, FRICTION_LO)
    _, _, ds_dx, ds_dv = piston_force(x, v, pa, pb, prm, o)
    ua, ub = _commands(t, ts, y, prm, sig, ptr)
    fill_a, vent_a, fill_b, vent_b = _conductances(ua, ub, prm)
    p_sup = _supply(t, ts, prm, sig, ptr)
    mdot_a, dma_dpa, mdot_b, dmb_dpb = chamber_flows(fill_a, vent_a, fill_b, vent_b, p_sup,
                                                     pa, pb, prm, o)
    vol_a, vol_b = chamber_volumes(x, prm, o)
    out[S_POSITION, S_VELOCITY] = 1.0
    out[S_VELOCITY, S_POSITION] = ds_dx / m
    out[S_VELOCITY, S_VELOCITY] = (ds_dv - df_dv) / m
    out[S_VELOCITY, S_PRESSURE_A] = area_a / m
    out[S_VELOCITY, S_PRESSURE_B] = -area_b / m
    friction_store_partials(z_partials, out, S_FRICTION, S_VELOCITY, S_VELOCITY, m)
    d_x, d_v, d_p = chamber_row(pa, vol_a, area_a, area_a, v, mdot_a, dma_dpa, n, rt)
    out[S_PRESSURE_A, S_POSITION] = d_x
    out[S_PRESSURE_A, S_VELOCITY] = d_v
    out[S_PRESSURE_A, S_PRESSURE_A] = d_p
    d_x, d_v, d_p = chamber_row(pb, vol_b, -area_b, -area_b, v, mdot_b, dmb_dpb, n, rt)
    out[S_PRESSURE_B, S_POSITION] = d_x
    out[S_PRESSURE_B, S_VELOCITY] = d_v
    out[S_PRESSURE_B, S_PRESSURE_B] = d_p
    if SPOOL_STATE >= 0:  # the flows follow the 5/3 valve's lagged spool u = u_a
        dma_du, dmb_du = chamber_flow_slopes(ua, p_sup, pa, pb, prm, o)
        out[S_PRESSURE_A, S_VALVE + SPOOL_STATE] = n / vol_a * rt * dma_du
        out[S_PRESSURE_B, S_VALVE + SPOOL_STATE] = n / vol_b * rt * dmb_du
    thermal_partials(x, v, pa, pb, y, S_THERMAL, ua, p_sup, prm, o, THERMAL_LO, out,
                     S_PRESSURE_A, S_PRESSURE_B,
                     S_VALVE + SPOOL_STATE if SPOOL_STATE >= 0 else -1)
    spool_partials(prm, VALVE_LO, out, S_VALVE)


@kernel()
def param_jac(t, ts, y, prm, sig, ptr, g, needed):
    """g[a, k] = ∂f_a/∂prm[k] (NSTATE × vector size)."""
    for a in range(NSTATE):
        for k in range(g.shape[1]):
            g[a, k] = 0.0
    x = y[S_POSITION]
    v = y[S_VELOCITY]
    pa = y[S_PRESSURE_A]
    pb = y[S_PRESSURE_B]
    f_fric = friction_force(v, y, S_FRICTION, prm, FRICTION_LO)
    f_press, f_stop, _, _ = piston_force(x, v, pa, pb, prm, CYLINDER_LO)
    net = f_press - f_fric - load_against_time(t, ts, sig, ptr) + f_stop
    ua, ub = _commands(t, ts, y, prm, sig, ptr)
    oa, ob = _paths()
    p_sup = _supply(t, ts, prm, sig, ptr)
    held = supply_held(sig, ptr, CH_SUPPLY)
    cylinder_params(x, v, pa, pb, ua, ub, p_sup, held, net, prm, CYLINDER_LO, oa, ob, g,
                    S_VELOCITY, S_PRESSURE_A, S_PRESSURE_B)
    thermal_params(x, v, pa, pb, y, S_THERMAL, ua, p_sup, held, prm, CYLINDER_LO, THERMAL_LO,
                   g, S_PRESSURE_A, S_PRESSURE_B)
    spool_params(t, ts, y, S_VALVE, prm, VALVE_LO, sig, ptr, g)
    friction_param_partials(v, y, S_FRICTION, prm, FRICTION_LO, g, S_VELOCITY)
    m = prm[CYLINDER_LO + CY_M]
    for k in range(FRICTION_LO, FRICTION_HI):  # the friction force enters as −F/m
        g[S_VELOCITY, k] = -g[S_VELOCITY, k] / m


@kernel()
def outputs(t, ts, y, prm, sig, ptr, out):
    """Derived signals at one instant, in the order of OUTPUT_NAMES."""
    x = y[S_POSITION]
    v = y[S_VELOCITY]
    ua, ub = _commands(t, ts, y, prm, sig, ptr)
    fill_a, vent_a, fill_b, vent_b = _conductances(ua, ub, prm)
    f_press, f_stop, _, _ = piston_force(x, v, y[S_PRESSURE_A], y[S_PRESSURE_B], prm,
                                         CYLINDER_LO)
    p_sup = _supply(t, ts, prm, sig, ptr)
    mdot_a, _, mdot_b, _ = chamber_flows(fill_a, vent_a, fill_b, vent_b, p_sup,
                                         y[S_PRESSURE_A], y[S_PRESSURE_B], prm, CYLINDER_LO)
    out[OUT_FRICTION] = friction_force(v, y, S_FRICTION, prm, FRICTION_LO)
    out[OUT_PRESSURE_FORCE] = f_press
    out[OUT_STOP_FORCE] = f_stop
    out[OUT_LOAD] = load_against_time(t, ts, sig, ptr)
    if TWO_VALVES:
        out[OUT_COMMAND_A] = ua
        out[OUT_COMMAND_B] = ub
    else:
        out[OUT_SPOOL] = ua
    out[OUT_MASS_FLOW_A] = mdot_a
    out[OUT_MASS_FLOW_B] = mdot_b
    thermal_flows(x, y[S_PRESSURE_A], y[S_PRESSURE_B], y, S_THERMAL, ua, p_sup, prm,
                  CYLINDER_LO, THERMAL_LO, out, OUT_MASS_FLOW_A, OUT_MASS_FLOW_B)


@kernel()
def pressure_feedback(y, prm):
    """The pressure difference the piston feels, its pressure force per cap area:
    (p_a − p_atm) − (p_b − p_atm)·A_b/A_a [Pa] (zero where the chambers balance with
    no load), what the servo-pneumatic state feedback reads (a closed loop calls it)."""
    o = CYLINDER_LO
    p_atm = prm[o + CY_PATM]
    return (y[S_PRESSURE_A] - p_atm) - (y[S_PRESSURE_B] - p_atm) * prm[o + CY_AB] / prm[o + CY_AA]


@kernel()
def switch_guards(t, ts, y, prm, sig, ptr, out):
    """Guards of the right-hand side's kinks, > 0 away from them: the end stops. Returns
    how many."""
    out[0], out[1] = end_stop_guards(y[S_POSITION], prm, CYLINDER_LO)
    return 2


@kernel()
def initial_state(t, ts, prm, sig, ptr, y0):
    """At rest, each chamber at the pressure where the flows through its paths balance at
    its initial command (the exhaust's when no path is open), the piston on the stop that
    the resulting force presses it against (the cap end when it is zero)."""
    for i in range(NSTATE):
        y0[i] = 0.0
    o = CYLINDER_LO
    spool_start(t, ts, prm, VALVE_LO, sig, ptr, y0, S_VALVE)
    ua, ub = _commands(t, ts, y0, prm, sig, ptr)
    fill_a, vent_a, fill_b, vent_b = _conductances(ua, ub, prm)
    pa, pb = rest_pressures(fill_a, vent_a, fill_b, vent_b, _supply(t, ts, prm, sig, ptr),
                            prm, o)
    f_press = piston_force(0.0, 0.0, pa, pb, prm, o)[0]
    net0 = f_press - load_against_time(t, ts, sig, ptr)
    y0[S_POSITION] = rest_position(net0, 0.0, prm[o + CY_KSTOP], prm[o + CY_XMAX])
    y0[S_PRESSURE_A] = pa
    y0[S_PRESSURE_B] = pb
    thermal_start(prm, o, y0, S_THERMAL)


@kernel()
def project(prm, y):
    """Back onto the bounds the exact dynamics never leave: the friction law's, the
    spool's travel."""
    friction_project(prm, FRICTION_LO, y, S_FRICTION)
    spool_project(y, S_VALVE)


@kernel()
def state_scales(prm, out):
    """Typical magnitudes: the stroke, 10 strokes per second, the supply pressure, the
    friction law's own and the spool's travel."""
    x_max = prm[CYLINDER_LO + CY_XMAX]
    out[S_POSITION] = x_max
    out[S_VELOCITY] = 10.0 * x_max
    out[S_PRESSURE_A] = prm[CYLINDER_LO + CY_PSUP]
    out[S_PRESSURE_B] = prm[CYLINDER_LO + CY_PSUP]
    friction_scales(prm, FRICTION_LO, out, S_FRICTION)
    spool_scales(out, S_VALVE)
    thermal_scales(prm, CYLINDER_LO, out, S_THERMAL)

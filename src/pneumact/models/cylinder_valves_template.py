"""Model template: the double-acting cylinder fed by two proportional 3/2 valves.

Each chamber has its own 3/2 valve (``valve_a``, ``valve_b``: instances of one valve
kind, their blocks at ``VALVE_A_LO``, ``VALVE_B_LO``), driven by its own command on its
own channel (``CH_COMMAND_A``, ``CH_COMMAND_B``, generated): u > 0 connects the chamber
to the supply, u < 0 to the exhaust, 0 closes it (leakage aside). States are [position,
velocity, pressure_a, pressure_b | friction states], the parameter vector [cylinder block
| chamber_a's block | chamber_b's block | friction block | valve_a's block | valve_b's
block]. The equations are ``models.cylinder``'s (``valves_*``); the supply pressure is
the input ``supply`` as in the 5/3 cylinder's template.
"""

from pneumact.core import kernel
from pneumact.models.cylinder import (
    CY_AA,
    CY_AB,
    CY_KSTOP,
    CY_M,
    CY_N,
    CY_PATM,
    CY_PSUP,
    CY_R,
    CY_T,
    CY_XMAX,
    chamber_row,
    chamber_volumes,
    derive_cylinder,
    end_stop_guards,
    piston_force,
    supply_held,
    supply_pressure,
    valve_command,
    valves_flows,
    valves_params,
    valves_rates,
    valves_rest_pressures,
)
from pneumact.models.mechanics import load_against_time, rest_position

# --- bound by the generator --------------------------------------------------------------
friction_rates = friction_force = friction_partials = friction_param_partials = None
friction_project = friction_scales = friction_store = friction_store_partials = None
NSTATE = 4
CYLINDER_LO = CYLINDER_HI = FRICTION_LO = FRICTION_HI = 0
CHAMBER_A_LO = CHAMBER_A_HI = CHAMBER_B_LO = CHAMBER_B_HI = 0
VALVE_A_LO = VALVE_A_HI = VALVE_B_LO = VALVE_B_HI = 0
S_POSITION = 0
S_VELOCITY = 1
S_PRESSURE_A = 2
S_PRESSURE_B = 3
S_FRICTION = 4
CH_SUPPLY = None  # generated: the supply channel's index (``core.channels``)
CH_COMMAND_A = None  # generated: valve A's command channel
CH_COMMAND_B = None  # generated: valve B's command channel
#: bound by the model: 1.0, or -1.0 where the valves are mirrored (``mirrored=True``: both
#: read the drive channel, u_a = u and u_b = -u; ``Cylinder.kernel_constants``)
COMMAND_B_SIGN = 1.0
# ------------------------------------------------------------------------------------------

OUTPUT_NAMES = ("friction", "pressure_force", "stop_force", "load", "command_a", "command_b",
                "mass_flow_a", "mass_flow_b")
OUTPUT_UNITS = ("N", "N", "N", "N", "1", "1", "kg/s", "kg/s")
#: generated from OUTPUT_NAMES (the assembly's layout): NOUT and OUT_<NAME>
NOUT = OUT_FRICTION = OUT_PRESSURE_FORCE = OUT_STOP_FORCE = OUT_LOAD = None
OUT_COMMAND_A = OUT_COMMAND_B = OUT_MASS_FLOW_A = OUT_MASS_FLOW_B = None


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
    ua = valve_command(t, ts, sig, ptr, CH_COMMAND_A)
    ub = COMMAND_B_SIGN * valve_command(t, ts, sig, ptr, CH_COMMAND_B)
    p_sup = _supply(t, ts, prm, sig, ptr)
    accel, rate_a, rate_b = valves_rates(
        x, v, pa, pb, ua, ub, p_sup, f_fric, load_against_time(t, ts, sig, ptr), prm,
        CYLINDER_LO, VALVE_A_LO, VALVE_B_LO)
    dydt[S_POSITION] = v
    dydt[S_VELOCITY] = accel
    dydt[S_PRESSURE_A] = rate_a
    dydt[S_PRESSURE_B] = rate_b
    friction_store(z_rates, dydt, S_FRICTION)


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
    ua = valve_command(t, ts, sig, ptr, CH_COMMAND_A)
    ub = COMMAND_B_SIGN * valve_command(t, ts, sig, ptr, CH_COMMAND_B)
    p_sup = _supply(t, ts, prm, sig, ptr)
    mdot_a, dma_dpa, mdot_b, dmb_dpb = valves_flows(ua, ub, p_sup, pa, pb, prm, o,
                                                    VALVE_A_LO, VALVE_B_LO)
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
    ua = valve_command(t, ts, sig, ptr, CH_COMMAND_A)
    ub = COMMAND_B_SIGN * valve_command(t, ts, sig, ptr, CH_COMMAND_B)
    p_sup = _supply(t, ts, prm, sig, ptr)
    held = supply_held(sig, ptr, CH_SUPPLY)
    valves_params(x, v, pa, pb, ua, ub, p_sup, held, net, prm, CYLINDER_LO, VALVE_A_LO,
                  VALVE_B_LO, g, S_VELOCITY, S_PRESSURE_A, S_PRESSURE_B)
    friction_param_partials(v, y, S_FRICTION, prm, FRICTION_LO, g, S_VELOCITY)
    m = prm[CYLINDER_LO + CY_M]
    for k in range(FRICTION_LO, FRICTION_HI):  # the friction force enters as −F/m
        g[S_VELOCITY, k] = -g[S_VELOCITY, k] / m


@kernel()
def outputs(t, ts, y, prm, sig, ptr, out):
    """Derived signals at one instant, in the order of OUTPUT_NAMES."""
    x = y[S_POSITION]
    v = y[S_VELOCITY]
    ua = valve_command(t, ts, sig, ptr, CH_COMMAND_A)
    ub = COMMAND_B_SIGN * valve_command(t, ts, sig, ptr, CH_COMMAND_B)
    f_press, f_stop, _, _ = piston_force(x, v, y[S_PRESSURE_A], y[S_PRESSURE_B], prm,
                                         CYLINDER_LO)
    p_sup = _supply(t, ts, prm, sig, ptr)
    mdot_a, _, mdot_b, _ = valves_flows(ua, ub, p_sup, y[S_PRESSURE_A], y[S_PRESSURE_B],
                                        prm, CYLINDER_LO, VALVE_A_LO, VALVE_B_LO)
    out[OUT_FRICTION] = friction_force(v, y, S_FRICTION, prm, FRICTION_LO)
    out[OUT_PRESSURE_FORCE] = f_press
    out[OUT_STOP_FORCE] = f_stop
    out[OUT_LOAD] = load_against_time(t, ts, sig, ptr)
    out[OUT_COMMAND_A] = ua
    out[OUT_COMMAND_B] = ub
    out[OUT_MASS_FLOW_A] = mdot_a
    out[OUT_MASS_FLOW_B] = mdot_b


@kernel()
def pressure_feedback(y, prm):
    """The pressure difference the piston feels, its pressure force per cap area:
    (p_a − p_atm) − (p_b − p_atm)·A_b/A_a [Pa]."""
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
    """At rest, each chamber at the pressure where the flows through its valve balance at
    its initial command (the exhaust's when no path is open), the piston on the stop that
    the resulting force presses it against (the cap end when it is zero)."""
    for i in range(NSTATE):
        y0[i] = 0.0
    o = CYLINDER_LO
    pa, pb = valves_rest_pressures(valve_command(t, ts, sig, ptr, CH_COMMAND_A),
                                   COMMAND_B_SIGN * valve_command(t, ts, sig, ptr,
                                                                  CH_COMMAND_B),
                                   _supply(t, ts, prm, sig, ptr), prm, o, VALVE_A_LO,
                                   VALVE_B_LO)
    f_press = piston_force(0.0, 0.0, pa, pb, prm, o)[0]
    net0 = f_press - load_against_time(t, ts, sig, ptr)
    y0[S_POSITION] = rest_position(net0, 0.0, prm[o + CY_KSTOP], prm[o + CY_XMAX])
    y0[S_PRESSURE_A] = pa
    y0[S_PRESSURE_B] = pb


@kernel()
def project(prm, y):
    """Back onto the bounds the exact dynamics never leave: the friction law's."""
    friction_project(prm, FRICTION_LO, y, S_FRICTION)


@kernel()
def state_scales(prm, out):
    """Typical magnitudes: the stroke, 10 strokes per second, the supply pressure and the
    friction law's own."""
    x_max = prm[CYLINDER_LO + CY_XMAX]
    out[S_POSITION] = x_max
    out[S_VELOCITY] = 10.0 * x_max
    out[S_PRESSURE_A] = prm[CYLINDER_LO + CY_PSUP]
    out[S_PRESSURE_B] = prm[CYLINDER_LO + CY_PSUP]
    friction_scales(prm, FRICTION_LO, out, S_FRICTION)

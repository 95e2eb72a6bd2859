"""A double-acting pneumatic cylinder fed by a 5/3 proportional valve (issue 41, item 4),
or by a proportional 3/2 valve per chamber (``valves="two-3/2"``, issue 41 items 1-2).

    m·dv/dt = (p_a − p_atm)·A_a − (p_b − p_atm)·A_b − F_f − F_load(t) + F_stop(x, v)
    dp_a/dt = n/V_a·(R·T·ṁ_a − p_a·A_a·v),   V_a = chamber_a.V_dead + A_a·x
    dp_b/dt = n/V_b·(R·T·ṁ_b + p_b·A_b·v),   V_b = chamber_b.V_dead + A_b·(x_max − x)

x ∈ [0, x_max] is the rod's extension from the cap-end stop; chamber A is the cap side
(A_a = π·D²/4), chamber B the rod side (A_b = π·(D² − d²)/4); the atmosphere acts on
the rod's cross-section A_a − A_b. The end stops are the Hunt–Crossley contacts of
``models.mechanics``. The spool command u ∈ [−1, 1] of the closed-centre 5/3 valve opens
supply → A and B → exhaust for u > 0, supply → B and A → exhaust for u < 0; each path
is an ISO 6358 flow (``pneumatics.iso_flow``) of conductance valve_C·(a(±u) + valve_leak),
a(w) = max(w − e, 0)/(1 − e) the opening of a path the spool travels w towards, e the
spool's overlap (e < 0: an underlap, both paths of a chamber open around the centre); the
mid-position leakage keeps a chamber's pressure defined at u = 0. The chamber law
(isothermal, adiabatic, polytropic) is the actuator's ``ChamberLaw``: n = a + b·γ; with
``HeatTransfer()`` each chamber's energy equation replaces it, its temperature a state
(``thermal_part``, docs/model.md).

The two chambers are two instances of one chamber component (``chamber_part``:
``chamber_a``, ``chamber_b``), each with its block ``CHAMBER_BLOCK`` (its dead volume,
``chamber_a.V_dead``), read by ``chamber_dead_volume`` at the instance's offset; the
cylinder's ``derive`` copies them into derived entries of its own block, which its
equations read (the assembly carries a parameter's sensitivity through such entries).
The compiled functions read the block ``CYLINDER_BLOCK`` at offset ``o`` of ``p``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, ClassVar

from ..checks import MAX_ABSOLUTE_PRESSURE
from ..core.channels import CH_DRIVE, DeclaredInputs, InputChannel, in_order
from ..core.component import SETTING, Block, Part, StateSpec, required_parameters
from ..core.jit import njit
from ..core.signals import Constant, Signal, channel_driven, channel_eval
from ..parameters.catalogue import (
    ParameterSpec,
    declare,
    declare_instances,
    declare_kind,
    declare_relation,
    declare_renamed,
    instances_of,
)
from .fmu_interface import (
    FmuInput,
    FmuInterface,
    declared_fmu_input,
    drive_input,
    force_input,
    refuse_load_against_time,
)
from .friction import FrictionModel, LuGre
from .mechanics import explicit_step, stop_force, stop_force_params
from .pneumatics import ChamberLaw, Isothermal, iso_flow, iso_flow_params
from .sensors import SensorNames, declare_sensors

if TYPE_CHECKING:
    import numpy as np

    from ..parameters.files import ParameterSetLike
    from ..parameters.parameter_set import ParameterSet

P = ParameterSpec
declare(
    P("D_bore", "m", "cylinder bore (piston diameter)", None, 0.0, True, 2.0,
      group="cylinder", plausible=(2e-3, 0.5)),
    P("d_rod", "m", "piston rod diameter (0: a rodless, equal-area piston)", None, 0.0,
      False, 2.0, group="cylinder", plausible=(0.0, 0.2)),
    P("p_supply", "Pa", "supply pressure of the 5/3 valve (absolute)", None, 0.0, True, 1e8,
      group="cylinder", plausible=(1.5e5, 1.6e6)),
    P("valve_C", "m^3/(s*Pa)", "ISO 6358 sonic conductance of each path of the 5/3 valve, "
      "spool fully open (|u| = 1)", None, 0.0, False, 1e-3, group="cylinder",
      plausible=(1e-10, 1e-6)),
    P("valve_leak", "", "mid-position leakage of each path of the 5/3 valve, as a fraction "
      "of valve_C", 0.0, 0.0, False, 1.0, group="cylinder", plausible=(0.0, 0.1)),
    P("spool_overlap", "", "overlap of the 5/3 valve's spool lands over its ports, as a "
      "fraction of the spool's travel: no path opens until |u| exceeds it; negative: an "
      "underlap, both paths of a chamber open around the centre (0: critical centre)", 0.0,
      -0.5, False, 0.5, group="cylinder", plausible=(-0.2, 0.3)),
    P("spool_omega", "rad/s", "natural frequency of the 5/3 valve's spool as a second-order "
      "system (Cylinder(spool_lag=2))", None, 0.0, True, 1e6, group="cylinder",
      plausible=(10.0, 1e5)),
    P("spool_zeta", "", "damping ratio of the 5/3 valve's spool as a second-order system "
      "(Cylinder(spool_lag=2))", None, 0.0, True, 10.0, group="cylinder",
      plausible=(0.1, 3.0)),
    P("heat_transfer_coefficient", "W/(m^2*K)", "heat transfer coefficient between each "
      "chamber's gas and its walls (Cylinder(chamber=HeatTransfer())): 0 adiabatic, large "
      "isothermal", None, 0.0, False, None, group="cylinder", plausible=(0.0, 2000.0)),
    P("spool_tau", "s", "time constant of the 5/3 valve's spool: a first-order lag of the "
      "command (Cylinder(spool_lag=True))", None, 0.0, True, 10.0, group="cylinder",
      plausible=(1e-5, 1.0)),
)
#: a cylinder chamber, placed as chamber_a and chamber_b: its parameters, declared once
declare_kind("chamber", P("V_dead", "m^3", "dead volume of a cylinder chamber when the "
                          "piston is on its end stop (end cap, port, tubing to the valve)",
                          None, 0.0, True, 10.0, group="cylinder", plausible=(1e-8, 1e-2)))
declare_instances("chamber", chamber_a="chamber A, the cap side, empty at x = 0",
                  chamber_b="chamber B, the rod side, empty at x = x_max")
declare_renamed(V_dead_a="chamber_a.V_dead", V_dead_b="chamber_b.V_dead")
#: a proportional 3/2 valve feeding one chamber (Cylinder(valves="two-3/2")), placed as
#: valve_a and valve_b: its parameters, declared once (those of one chamber's two paths
#: of the 5/3 valve: valve_C, valve_leak, spool_overlap)
declare_kind(
    "valve_3_2",
    P("C", "m^3/(s*Pa)", "ISO 6358 sonic conductance of each path of a 3/2 valve (supply "
      "to its chamber, its chamber to the exhaust), fully open (|u| = 1)", None, 0.0,
      False, 1e-3, group="cylinder", plausible=(1e-10, 1e-6)),
    P("leak", "", "closed-position leakage of each path of a 3/2 valve, as a fraction of "
      "its C", 0.0, 0.0, False, 1.0, group="cylinder", plausible=(0.0, 0.1)),
    P("overlap", "", "overlap of a 3/2 valve's spool over its ports, as a fraction of its "
      "travel: no path opens until |u| exceeds it; negative: an underlap, both paths open "
      "around the centre (0: critical centre)", 0.0, -0.5, False, 0.5, group="cylinder",
      plausible=(-0.2, 0.3)))
declare_instances("valve_3_2", valve_a="the 3/2 valve of chamber A (command_a)",
                  valve_b="the 3/2 valve of chamber B (command_b)")
#: the places of a friction law on the cylinder where two share it (Cylinder(friction=
#: {"piston": ..., "rod": ...})): the kind "friction" (every law's parameters) placed as
#: friction_piston and friction_rod, parameters ``friction_rod.Fc`` ...
declare_instances("friction", friction_piston="the friction law of the piston's seal",
                  friction_rod="the friction law of the rod's seal")
#: the kernel template of two laws placed on one body (``models.friction.placed_laws``)
PLACED_LAWS = "pneumact.models.friction.placed_laws"
#: the bench's sensors, one per measured signal (``models.sensors``): sensor_position,
#: sensor_pressure_a and sensor_pressure_b, parameters ``sensor_pressure_a.lag`` ...
CYLINDER_SENSORS = declare_sensors(position="m", pressure_a="Pa", pressure_b="Pa")
declare_relation(("d_rod", "D_bore"), lambda rod, bore: rod < bore,
                 lambda rod, bore: f"must be < D_bore = {bore:g} m (the rod passes "
                                   "through the piston)")
declare_relation(("p_supply", "p_atm"), lambda supply, atm: supply > atm,
                 lambda supply, atm: f"must be > p_atm = {atm:g} Pa (the supply drives "
                                     "air into the chambers)")

CYLINDER_BLOCK = Block.of(
    "m", "D_bore", "d_rod", "x_max", "p_atm", "p_supply",
    "valve_C", "valve_leak", "spool_overlap", "iso_b", "iso_m", "r_lin", "gamma", "R", "T",
    "k_stop", "c_stop",
    settings=("chamber_n_offset", "chamber_n_gamma"),
    derived=("n_poly", "area_a", "area_b", "dead_volume_a", "dead_volume_b"),
)
#: the cylinder's block where two 3/2 valves feed it: the same entries at the same
#: indices, the 5/3 valve's three settings there (its functions never read them)
FIVE_THREE_ENTRIES = ("valve_C", "valve_leak", "spool_overlap")
VALVES_CYLINDER_BLOCK = Block(tuple((name, SETTING if name in FIVE_THREE_ENTRIES else kind)
                                    for name, kind in CYLINDER_BLOCK.entries))
CY_M = CYLINDER_BLOCK.index("m")
CY_BORE = CYLINDER_BLOCK.index("D_bore")
CY_ROD = CYLINDER_BLOCK.index("d_rod")
CY_XMAX = CYLINDER_BLOCK.index("x_max")
CY_VDA = CYLINDER_BLOCK.index("dead_volume_a")
CY_VDB = CYLINDER_BLOCK.index("dead_volume_b")
CY_PATM = CYLINDER_BLOCK.index("p_atm")
CY_PSUP = CYLINDER_BLOCK.index("p_supply")
CY_C = CYLINDER_BLOCK.index("valve_C")
CY_LEAK = CYLINDER_BLOCK.index("valve_leak")
CY_OVERLAP = CYLINDER_BLOCK.index("spool_overlap")
CY_B = CYLINDER_BLOCK.index("iso_b")
CY_MEXP = CYLINDER_BLOCK.index("iso_m")
CY_RLIN = CYLINDER_BLOCK.index("r_lin")
CY_GAMMA = CYLINDER_BLOCK.index("gamma")
CY_R = CYLINDER_BLOCK.index("R")
CY_T = CYLINDER_BLOCK.index("T")
CY_KSTOP = CYLINDER_BLOCK.index("k_stop")
CY_CSTOP = CYLINDER_BLOCK.index("c_stop")
CY_N_OFFSET = CYLINDER_BLOCK.index("chamber_n_offset")
CY_N_GAMMA = CYLINDER_BLOCK.index("chamber_n_gamma")
CY_N = CYLINDER_BLOCK.index("n_poly")
CY_AA = CYLINDER_BLOCK.index("area_a")
CY_AB = CYLINDER_BLOCK.index("area_b")
CYLINDER_SIZE = len(CYLINDER_BLOCK)
QUARTER_PI = 0.25 * math.pi
#: Bisection steps of a chamber's rest pressure (the interval shrinks by 2^-60).
REST_ITERATIONS = 60


#: a chamber instance's block: its dead volume
CHAMBER_BLOCK = Block.of("V_dead")
CH_V_DEAD = CHAMBER_BLOCK.index("V_dead")


@njit(cache=True)
def chamber_dead_volume(p, o):  # pragma: no cover - compiled
    """The dead volume of the chamber whose block is at offset ``o``."""
    return p[o + CH_V_DEAD]


def chamber_part(instance: str, label: str) -> Part:
    """One chamber of the cylinder, placed under ``instance`` (chamber_a, chamber_b)."""
    return Part(role="chamber", instance=instance, block=CHAMBER_BLOCK, label=label)


def friction_place_parts(placed: Mapping[str, FrictionModel]) -> tuple[Part, ...]:
    """Friction laws placed on the cylinder by place (piston, rod): each law's block and
    states under its instance (``friction_rod.Fc``, state ``friction_rod_bristle``), its
    functions a child kernel (``Cylinder.kernel_children``), and the template that sums
    them (``placed_laws``), which the cylinder's template calls as its one law."""
    parts = tuple(Part(role="friction", instance=f"friction_{place}", block=law.block,
                       states=tuple(replace(state, name=f"friction_{place}_{state.name}")
                                    for state in law.states),
                       label=f"{law!r} on the {place}", key=f"{place}_{law.law}")
                  for place, law in placed.items())
    places = " and ".join(placed)
    return (*parts, Part(role="friction_laws", block=Block(), templates=(PLACED_LAWS,),
                         label=f"the friction laws of the {places}"))


def friction_places() -> tuple[str, ...]:
    """The places a friction law may take where laws share the cylinder (the declared
    instances of the kind friction, friction_piston ..., less their prefix)."""
    return tuple(i.removeprefix("friction_") for i in instances_of("friction"))


def placed_friction(given: Mapping, examples: str) -> dict[str, FrictionModel]:
    """``{"piston": law, "rod": law}`` checked: every place named once, in the declared
    order, each a law that can share the body (refused naming the places otherwise)."""
    from ..checks import as_instance
    from ..errors import ArgumentError

    places = friction_places()
    listed = ", ".join(repr(p) for p in places)
    unknown = [key for key in given if key not in places]
    if unknown:
        raise ArgumentError(
            f"Cylinder: friction = {dict(given)!r}: {unknown[0]!r} is no place of a friction "
            f"law; places: {listed} (instances "
            f"{', '.join(f'friction_{p}' for p in places)})")
    if set(given) != set(places):
        raise ArgumentError(
            f"Cylinder: friction = {dict(given)!r}: a mapping places a law on each of "
            f"{listed}; one law on the piston alone: friction=pa.LuGre() (say)")
    placed = {}
    for place in places:
        law = as_instance(f"friction[{place!r}]", given[place], FrictionModel,
                          where="Cylinder", examples=examples)
        if law.placed_alone is not None:
            raise ArgumentError(f"Cylinder: friction[{place!r}] = {law!r}: placed alone, not "
                                f"beside another law: {law.placed_alone}")
        placed[place] = law
    return placed


@njit(cache=True)
def derive_cylinder(p, o, o_a, o_b):  # pragma: no cover - compiled
    """The piston areas and the polytropic index from the block's values and settings,
    and the dead volumes of the chambers whose blocks are at ``o_a`` and ``o_b``."""
    p[o + CY_VDA] = chamber_dead_volume(p, o_a)
    p[o + CY_VDB] = chamber_dead_volume(p, o_b)
    bore = p[o + CY_BORE]
    rod = p[o + CY_ROD]
    p[o + CY_AA] = QUARTER_PI * bore * bore
    p[o + CY_AB] = QUARTER_PI * (bore * bore - rod * rod)
    p[o + CY_N] = p[o + CY_N_OFFSET] + p[o + CY_N_GAMMA] * p[o + CY_GAMMA]


@njit(cache=True)
def path_opening(travel, overlap):  # pragma: no cover - compiled
    """Opening of one path as a fraction of valve_C, the spool ``travel`` towards it
    (±u): zero until the travel passes the overlap, then linear, full at travel 1."""
    return max(travel - overlap, 0.0) / (1.0 - overlap)


@njit(cache=True)
def path_opening_slopes(travel, overlap):  # pragma: no cover - compiled
    """(∂opening/∂travel, ∂opening/∂overlap) of ``path_opening``; at the edge of the
    band the travel's slope from above, the overlap's from above (none)."""
    span = 1.0 - overlap
    if travel > overlap:
        return 1.0 / span, (travel - 1.0) / (span * span)
    if travel == overlap:
        return 1.0 / span, 0.0
    return 0.0, 0.0


@njit(cache=True)
def spool_fractions(u, leak, overlap):  # pragma: no cover - compiled
    """Openings of the four paths as fractions of valve_C at spool position u (clipped to
    [−1, 1]), each with the leakage: (supply → A, A → exhaust, supply → B, B → exhaust):
    chamber A's paths at command u, B's the same two swapped (``path_fractions``)."""
    extend, retract = path_fractions(u, leak, overlap)
    return extend, retract, retract, extend


@njit(cache=True)
def spool_fraction_slopes(u, overlap):  # pragma: no cover - compiled
    """∂/∂u and ∂/∂overlap of the paths that open as u rises (supply → A, B → exhaust)
    and of those that open as it falls (A → exhaust, supply → B): (d_extend_du,
    d_retract_du, d_extend_de, d_retract_de), slopes in u from above; none in u beyond
    ±1, where the spool is on its stop."""
    spool = min(max(u, -1.0), 1.0)
    du_ext, de_ext = path_opening_slopes(spool, overlap)
    du_ret, de_ret = path_opening_slopes(-spool, overlap)
    if -spool == overlap:  # the retracting edge closes as u rises: from above, shut
        du_ret = 0.0
    if u > 1.0 or u < -1.0:
        du_ext = du_ret = 0.0
    return du_ext, -du_ret, de_ext, de_ret


@njit(cache=True)
def chamber_inflow(pressure, p_supply, p_exhaust, c_fill, c_vent, b, m, r_lam,
                   temperature):  # pragma: no cover - compiled
    """Net mass flow [kg/s] into a chamber at ``pressure``, filled from the supply through
    conductance ``c_fill`` and vented to the exhaust through ``c_vent``: (ṁ, ∂ṁ/∂p,
    ∂ṁ/∂p_supply, ∂ṁ/∂p_exhaust, flow per unit c_fill, flow per unit c_vent)."""
    q_in, dqin_dsup, dqin_dp = iso_flow(p_supply, pressure, b, m, r_lam, temperature)
    q_out, dqout_dp, dqout_dexh = iso_flow(pressure, p_exhaust, b, m, r_lam, temperature)
    return (c_fill * q_in - c_vent * q_out, c_fill * dqin_dp - c_vent * dqout_dp,
            c_fill * dqin_dsup, -c_vent * dqout_dexh, q_in, q_out)


@njit(cache=True)
def chamber_inflow_params(pressure, p_supply, p_exhaust, c_fill, c_vent, b, m, r_lam,
                          temperature):  # pragma: no cover - compiled
    """(∂ṁ/∂b, ∂ṁ/∂m, ∂ṁ/∂r_lam, ∂ṁ/∂T) of ``chamber_inflow`` at fixed conductances."""
    in_b, in_m, in_lam, in_t = iso_flow_params(p_supply, pressure, b, m, r_lam, temperature)
    out_b, out_m, out_lam, out_t = iso_flow_params(pressure, p_exhaust, b, m, r_lam,
                                                   temperature)
    return (c_fill * in_b - c_vent * out_b, c_fill * in_m - c_vent * out_m,
            c_fill * in_lam - c_vent * out_lam, c_fill * in_t - c_vent * out_t)


@njit(cache=True)
def chamber_pressure_rate(pressure, volume, volume_rate, mdot, n, rt):  # pragma: no cover
    """dp/dt = n/V·(R·T·ṁ − p·dV/dt) of a chamber of volume V changing at dV/dt."""
    return n / volume * (rt * mdot - pressure * volume_rate)


@njit(cache=True)
def rest_pressure(p_supply, p_exhaust, c_fill, c_vent, b, m, r_lam,
                  temperature):  # pragma: no cover - compiled
    """The pressure in [p_exhaust, p_supply] at which a closed chamber's net inflow
    vanishes (it falls as the pressure rises); the exhaust pressure if no path is open."""
    lo, hi = p_exhaust, p_supply
    if chamber_inflow(lo, p_supply, p_exhaust, c_fill, c_vent, b, m, r_lam,
                      temperature)[0] <= 0.0:
        return lo
    if chamber_inflow(hi, p_supply, p_exhaust, c_fill, c_vent, b, m, r_lam,
                      temperature)[0] >= 0.0:
        return hi
    for _ in range(REST_ITERATIONS):
        mid = 0.5 * (lo + hi)
        if chamber_inflow(mid, p_supply, p_exhaust, c_fill, c_vent, b, m, r_lam,
                          temperature)[0] > 0.0:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


@njit(cache=True)
def end_stop_guards(x, p, o):  # pragma: no cover - compiled
    """x and x_max − x: where the end-stop force switches on (> 0 off the stops)."""
    return x, p[o + CY_XMAX] - x


@njit(cache=True, inline="always")
def spool_command(t, ts, sig, ptr):  # pragma: no cover - compiled
    """The experiment's spool command u (the drive channel)."""
    return channel_eval(sig, ptr, CH_DRIVE, t, ts)[0]


@njit(cache=True)
def driven_supply(t, ts, sig, ptr, ch):  # pragma: no cover - compiled
    """The input ``supply`` on channel ``ch`` (a call of its own: the evaluation of a
    signal stays out of the equations that read the parameter where it is not driven)."""
    return channel_eval(sig, ptr, ch, t, ts)[0]


@njit(cache=True, inline="always")
def supply_pressure(t, ts, p, o, sig, ptr, ch):  # pragma: no cover - compiled
    """The supply pressure p_sup [Pa absolute]: the input ``supply`` on channel ``ch``
    where an experiment drives it, else the parameter p_supply."""
    if channel_driven(sig, ptr, ch):
        return driven_supply(t, ts, sig, ptr, ch)
    return p[o + CY_PSUP]


@njit(cache=True, inline="always")
def supply_held(sig, ptr, ch):  # pragma: no cover - compiled
    """Whether the supply pressure is the parameter p_supply (no experiment drives the
    input ``supply`` on channel ``ch``): only then does p_supply act on the run."""
    return not channel_driven(sig, ptr, ch)


@njit(cache=True)
def chamber_flow_slopes(u, p_sup, pa, pb, p, o):  # pragma: no cover - compiled
    """(∂ṁ_a/∂u, ∂ṁ_b/∂u) at spool position u and supply pressure p_sup (slopes from
    above at the edges of the band; none beyond ±1, where the spool is on its stop)."""
    d_extend, d_retract, _, _ = spool_fraction_slopes(u, p[o + CY_OVERLAP])
    c = p[o + CY_C]
    b, m, r_lam, temperature = p[o + CY_B], p[o + CY_MEXP], p[o + CY_RLIN], p[o + CY_T]
    p_exh = p[o + CY_PATM]
    fill_a = iso_flow(p_sup, pa, b, m, r_lam, temperature)[0]
    vent_a = iso_flow(pa, p_exh, b, m, r_lam, temperature)[0]
    fill_b = iso_flow(p_sup, pb, b, m, r_lam, temperature)[0]
    vent_b = iso_flow(pb, p_exh, b, m, r_lam, temperature)[0]
    return (c * (d_extend * fill_a - d_retract * vent_a),
            c * (d_retract * fill_b - d_extend * vent_b))


@njit(cache=True)
def chamber_volumes(x, p, o):  # pragma: no cover - compiled
    """(V_a, V_b) at piston position x."""
    return (p[o + CY_VDA] + p[o + CY_AA] * x,
            p[o + CY_VDB] + p[o + CY_AB] * (p[o + CY_XMAX] - x))


@njit(cache=True)
def piston_force(x, v, pa, pb, p, o):  # pragma: no cover - compiled
    """Pressure force (p_a − p_atm)·A_a − (p_b − p_atm)·A_b and the end stops' force,
    with the stops' partials (∂x, ∂v)."""
    p_atm = p[o + CY_PATM]
    pressure = (pa - p_atm) * p[o + CY_AA] - (pb - p_atm) * p[o + CY_AB]
    f_stop, ds_dx, ds_dv = stop_force(x, v, p[o + CY_KSTOP], p[o + CY_CSTOP],
                                      p[o + CY_XMAX])
    return pressure, f_stop, ds_dx, ds_dv


@njit(cache=True)
def chamber_row(pressure, volume, dvol_dx, dvol_dv, v, mdot, dmdot_dp, n,
                rt):  # pragma: no cover - compiled
    """(∂ṗ/∂x, ∂ṗ/∂v, ∂ṗ/∂p) of a chamber whose volume changes with x at dvol_dx and
    whose volume rate is dvol_dv·v."""
    rate = chamber_pressure_rate(pressure, volume, dvol_dv * v, mdot, n, rt)
    return (-rate / volume * dvol_dx, -n / volume * pressure * dvol_dv,
            n / volume * (rt * dmdot_dp - dvol_dv * v))


@njit(cache=True)
def flow_params(row, pressure, volume, vol_rate, u_fill, u_vent, e_fill, e_vent, c, p_sup,
                held, p, o, g, col_c, col_leak, col_overlap):  # pragma: no cover - compiled
    """g[row, ·] = ∂ṗ/∂θ of one chamber for its flow's entries (the volume's are the
    caller's): its paths' C, leakage and overlap in the columns ``col_c``, ``col_leak``,
    ``col_overlap`` (the 5/3 valve's in the cylinder block, a 3/2 valve's in its own),
    p_supply (only where it is ``held``: a driven supply pressure p_sup does not read it),
    p_atm, iso_b, iso_m, r_lin, R, T and n_poly in the cylinder block at ``o``. ``u_fill``,
    ``u_vent`` are the paths' fractions, ``e_fill``, ``e_vent`` their slopes in the
    overlap."""
    b, m, r_lam, temperature = p[o + CY_B], p[o + CY_MEXP], p[o + CY_RLIN], p[o + CY_T]
    p_exh = p[o + CY_PATM]
    n, r_gas = p[o + CY_N], p[o + CY_R]
    rt = r_gas * temperature
    mdot, _, d_sup, d_exh, q_in, q_out = chamber_inflow(
        pressure, p_sup, p_exh, c * u_fill, c * u_vent, b, m, r_lam, temperature)
    d_b, d_m, d_lam, d_t = chamber_inflow_params(pressure, p_sup, p_exh, c * u_fill,
                                                 c * u_vent, b, m, r_lam, temperature)
    k = n / volume * rt  # ∂ṗ/∂ṁ
    g[row, col_c] = k * (u_fill * q_in - u_vent * q_out)
    g[row, col_leak] = k * c * (q_in - q_out)
    g[row, col_overlap] = k * c * (e_fill * q_in - e_vent * q_out)
    g[row, o + CY_PSUP] = k * d_sup if held else 0.0
    g[row, o + CY_PATM] = k * d_exh
    g[row, o + CY_B] = k * d_b
    g[row, o + CY_MEXP] = k * d_m
    g[row, o + CY_RLIN] = k * d_lam
    g[row, o + CY_R] = n / volume * temperature * mdot
    g[row, o + CY_T] = n / volume * r_gas * mdot + k * d_t
    g[row, o + CY_N] = (rt * mdot - pressure * vol_rate) / volume


# ---------------------------------------------------- each chamber's own valve paths
#: a 3/2 valve's block (the kind ``valve_3_2``, placed as valve_a and valve_b): the
#: conductance of each of its paths fully open, its leakage and its spool's overlap
VALVE32_BLOCK = Block.of("C", "leak", "overlap")
V32_C = VALVE32_BLOCK.index("C")
V32_LEAK = VALVE32_BLOCK.index("leak")
V32_OVERLAP = VALVE32_BLOCK.index("overlap")
#: where the 5/3 valve's (valve_C, valve_leak, spool_overlap) start in the cylinder block:
#: in a 3/2 valve block's order, so that each chamber's flow reads the 5/3 valve's paths
#: at o + CY_PATHS as it reads a 3/2 valve's at that valve's block (one code for both)
CY_PATHS = CY_C
if (CY_LEAK - CY_PATHS, CY_OVERLAP - CY_PATHS) != (V32_LEAK, V32_OVERLAP):
    raise RuntimeError("the cylinder block's 5/3 valve entries must follow VALVE32_BLOCK")


@njit(cache=True)
def path_fractions(u, leak, overlap):  # pragma: no cover - compiled
    """Openings of one chamber's two paths as fractions of their C at its valve's command
    u (clipped to [−1, 1]), each with the leakage: (supply → chamber, chamber →
    exhaust). The 5/3 valve drives A's paths by its spool u and B's by −u."""
    spool = min(max(u, -1.0), 1.0)
    return path_opening(spool, overlap) + leak, path_opening(-spool, overlap) + leak


@njit(cache=True)
def path_conductances(u, p, ov):  # pragma: no cover - compiled
    """(c_fill, c_vent) at command u of the paths whose C, leak and overlap stand at ``ov``
    (a 3/2 valve's block, or the 5/3 valve's entries: o + CY_PATHS)."""
    fill, vent = path_fractions(u, p[ov + V32_LEAK], p[ov + V32_OVERLAP])
    c = p[ov + V32_C]
    return c * fill, c * vent


@njit(cache=True)
def spool_conductances(u, p, o):  # pragma: no cover - compiled
    """The 5/3 valve's paths' conductances at spool position u: (supply → A, A → exhaust,
    supply → B, B → exhaust); B's at −u are A's swapped, so A's alone are evaluated."""
    fill_a, vent_a = path_conductances(u, p, o + CY_PATHS)
    return fill_a, vent_a, vent_a, fill_a


@njit(cache=True)
def chamber_flows(fill_a, vent_a, fill_b, vent_b, p_sup, pa, pb, p,
                  o):  # pragma: no cover - compiled
    """Net mass flows into A and B, each through its own paths of conductances (c_fill,
    c_vent) at supply pressure p_sup, and their slopes (ṁ_a, ∂ṁ_a/∂p_a, ṁ_b,
    ∂ṁ_b/∂p_b)."""
    b, m, r_lam, temperature = p[o + CY_B], p[o + CY_MEXP], p[o + CY_RLIN], p[o + CY_T]
    p_exh = p[o + CY_PATM]
    flow_a = chamber_inflow(pa, p_sup, p_exh, fill_a, vent_a, b, m, r_lam, temperature)
    flow_b = chamber_inflow(pb, p_sup, p_exh, fill_b, vent_b, b, m, r_lam, temperature)
    return flow_a[0], flow_a[1], flow_b[0], flow_b[1]


@njit(cache=True)
def cylinder_rates(x, v, pa, pb, fill_a, vent_a, fill_b, vent_b, p_sup, f_fric, f_load, p,
                   o):  # pragma: no cover - compiled
    """(dv/dt, dp_a/dt, dp_b/dt), each chamber fed through its own paths of conductances
    (c_fill, c_vent) (``chamber_flows``)."""
    mdot_a, _, mdot_b, _ = chamber_flows(fill_a, vent_a, fill_b, vent_b, p_sup, pa, pb, p, o)
    vol_a, vol_b = chamber_volumes(x, p, o)
    n, rt = p[o + CY_N], p[o + CY_R] * p[o + CY_T]
    f_press, f_stop, _, _ = piston_force(x, v, pa, pb, p, o)
    return ((f_press - f_fric - f_load + f_stop) / p[o + CY_M],
            chamber_pressure_rate(pa, vol_a, p[o + CY_AA] * v, mdot_a, n, rt),
            chamber_pressure_rate(pb, vol_b, -p[o + CY_AB] * v, mdot_b, n, rt))


@njit(cache=True)
def rest_pressures(fill_a, vent_a, fill_b, vent_b, p_sup, p, o):  # pragma: no cover
    """(p_a, p_b) at which each chamber's flows through its own paths of conductances
    (c_fill, c_vent) balance."""
    b, m, r_lam, temperature = p[o + CY_B], p[o + CY_MEXP], p[o + CY_RLIN], p[o + CY_T]
    p_exh = p[o + CY_PATM]
    return (rest_pressure(p_sup, p_exh, fill_a, vent_a, b, m, r_lam, temperature),
            rest_pressure(p_sup, p_exh, fill_b, vent_b, b, m, r_lam, temperature))


@njit(cache=True)
def path_params(row, pressure, volume, vol_rate, u, p_sup, held, p, o, ov,
                g):  # pragma: no cover - compiled
    """g[row, ·] = ∂ṗ/∂θ of one chamber fed through its paths (at ``ov``) at command u:
    their C, leak and overlap, and the cylinder block's flow entries p_supply (only where
    ``held``), p_atm, iso_b, iso_m, r_lin, R, T, n_poly (the volume's are the caller's)."""
    overlap = p[ov + V32_OVERLAP]
    u_fill, u_vent = path_fractions(u, p[ov + V32_LEAK], overlap)
    spool = min(max(u, -1.0), 1.0)
    _, e_fill = path_opening_slopes(spool, overlap)
    _, e_vent = path_opening_slopes(-spool, overlap)
    flow_params(row, pressure, volume, vol_rate, u_fill, u_vent, e_fill, e_vent,
                p[ov + V32_C], p_sup, held, p, o, g, ov + V32_C, ov + V32_LEAK,
                ov + V32_OVERLAP)


@njit(cache=True)
def cylinder_params(x, v, pa, pb, ua, ub, p_sup, held, net, p, o, oa, ob, g, row_v, row_a,
                    row_b):  # pragma: no cover - compiled
    """The cylinder block's and the paths' columns of ∂f/∂θ: the velocity row (dv/dt =
    net/m) and both chambers' rows (``g`` zeroed by the caller), each chamber fed through
    its own paths at its command, at supply pressure p_sup (``held``: the parameter
    p_supply's)."""
    m_mass = p[o + CY_M]
    p_atm = p[o + CY_PATM]
    area_a, area_b = p[o + CY_AA], p[o + CY_AB]
    dks, dcs, dxmax = stop_force_params(x, v, p[o + CY_KSTOP], p[o + CY_CSTOP],
                                        p[o + CY_XMAX])
    g[row_v, o + CY_M] = -net / (m_mass * m_mass)
    g[row_v, o + CY_AA] = (pa - p_atm) / m_mass
    g[row_v, o + CY_AB] = (p_atm - pb) / m_mass
    g[row_v, o + CY_PATM] = (area_b - area_a) / m_mass
    g[row_v, o + CY_KSTOP] = dks / m_mass
    g[row_v, o + CY_CSTOP] = dcs / m_mass
    g[row_v, o + CY_XMAX] = dxmax / m_mass
    vol_a, vol_b = chamber_volumes(x, p, o)
    n = p[o + CY_N]
    path_params(row_a, pa, vol_a, area_a * v, ua, p_sup, held, p, o, oa, g)
    path_params(row_b, pb, vol_b, -area_b * v, ub, p_sup, held, p, o, ob, g)
    fill_a, vent_a = path_conductances(ua, p, oa)
    fill_b, vent_b = path_conductances(ub, p, ob)
    mdot_a, _, mdot_b, _ = chamber_flows(fill_a, vent_a, fill_b, vent_b, p_sup, pa, pb, p, o)
    rt = p[o + CY_R] * p[o + CY_T]
    rate_a = chamber_pressure_rate(pa, vol_a, area_a * v, mdot_a, n, rt)
    rate_b = chamber_pressure_rate(pb, vol_b, -area_b * v, mdot_b, n, rt)
    g[row_a, o + CY_VDA] = -rate_a / vol_a
    g[row_a, o + CY_AA] = -rate_a / vol_a * x - n / vol_a * pa * v
    g[row_b, o + CY_VDB] = -rate_b / vol_b
    g[row_b, o + CY_AB] = -rate_b / vol_b * (p[o + CY_XMAX] - x) + n / vol_b * pb * v
    g[row_b, o + CY_XMAX] = -rate_b / vol_b * area_b


@njit(cache=True, inline="always")
def valve_command(t, ts, sig, ptr, ch):  # pragma: no cover - compiled
    """A 3/2 valve's command on channel ``ch`` (an empty channel reads 0: closed)."""
    return channel_eval(sig, ptr, ch, t, ts)[0]


# ------------------------------------------------------------------ the spool: direct or lagged
#: the lagged spool's block and its local state; the direct spool has neither
LAG_BLOCK = Block.of("spool_tau")
LG_TAU = LAG_BLOCK.index("spool_tau")
DIRECT_SPOOL_STATE = -1
LAGGED_SPOOL_STATE = 0


@njit(cache=True, inline="always")
def spool_target(t, ts, sig, ptr):  # pragma: no cover - compiled
    """The spool command clipped to the spool's travel [−1, 1]."""
    return min(max(spool_command(t, ts, sig, ptr), -1.0), 1.0)


@njit(cache=True, inline="always")
def direct_position(t, ts, y, s, p, o, sig, ptr):  # pragma: no cover - compiled
    """The spool follows its command at once."""
    return spool_target(t, ts, sig, ptr)


@njit(cache=True, inline="always")
def lagged_position(t, ts, y, s, p, o, sig, ptr):  # pragma: no cover - compiled
    """The spool's position is its state."""
    return y[s + LAGGED_SPOOL_STATE]


@njit(cache=True, inline="always")
def direct_rates(t, ts, y, s, p, o, sig, ptr, dydt):  # pragma: no cover - compiled
    pass


@njit(cache=True, inline="always")
def lagged_rates(t, ts, y, s, p, o, sig, ptr, dydt):  # pragma: no cover - compiled
    """du/dt = (u_command − u)/τ."""
    dydt[s + LAGGED_SPOOL_STATE] = (spool_target(t, ts, sig, ptr)
                                    - y[s + LAGGED_SPOOL_STATE]) / p[o + LG_TAU]


@njit(cache=True)
def direct_partials(p, o, jac, s):  # pragma: no cover - compiled
    pass


@njit(cache=True)
def lagged_partials(p, o, jac, s):  # pragma: no cover - compiled
    jac[s + LAGGED_SPOOL_STATE, s + LAGGED_SPOOL_STATE] = -1.0 / p[o + LG_TAU]


@njit(cache=True)
def direct_params(t, ts, y, s, p, o, sig, ptr, g):  # pragma: no cover - compiled
    pass


@njit(cache=True)
def lagged_params(t, ts, y, s, p, o, sig, ptr, g):  # pragma: no cover - compiled
    tau = p[o + LG_TAU]
    g[s + LAGGED_SPOOL_STATE, o + LG_TAU] = -(spool_target(t, ts, sig, ptr)
                                              - y[s + LAGGED_SPOOL_STATE]) / (tau * tau)


@njit(cache=True)
def direct_start(t, ts, p, o, sig, ptr, y0, s):  # pragma: no cover - compiled
    pass


@njit(cache=True)
def lagged_start(t, ts, p, o, sig, ptr, y0, s):  # pragma: no cover - compiled
    """At rest on the initial command."""
    y0[s + LAGGED_SPOOL_STATE] = spool_target(t, ts, sig, ptr)


@njit(cache=True)
def direct_project(y, s):  # pragma: no cover - compiled
    pass


@njit(cache=True)
def lagged_project(y, s):  # pragma: no cover - compiled
    """The spool stays within its travel (the exact lag of a clipped command does)."""
    y[s + LAGGED_SPOOL_STATE] = min(max(y[s + LAGGED_SPOOL_STATE], -1.0), 1.0)


@njit(cache=True)
def direct_scales(out, s):  # pragma: no cover - compiled
    pass


@njit(cache=True)
def lagged_scales(out, s):  # pragma: no cover - compiled
    out[s + LAGGED_SPOOL_STATE] = 1.0


# ------------------------------------------------------- the spool: second-order dynamics
#: the second-order spool's block and its local states (position, velocity)
SECOND_ORDER_BLOCK = Block.of("spool_omega", "spool_zeta")
SO_OMEGA = SECOND_ORDER_BLOCK.index("spool_omega")
SO_ZETA = SECOND_ORDER_BLOCK.index("spool_zeta")
SECOND_SPOOL_STATE = 0
SECOND_SPOOL_SPEED = 1


@njit(cache=True, inline="always")
def second_position(t, ts, y, s, p, o, sig, ptr):  # pragma: no cover - compiled
    """The spool's position is its first state (the flows clip it to ±1)."""
    return y[s + SECOND_SPOOL_STATE]


@njit(cache=True, inline="always")
def second_rates(t, ts, y, s, p, o, sig, ptr, dydt):  # pragma: no cover - compiled
    """du/dt = w, dw/dt = ω²·(u_command − u) − 2·ζ·ω·w."""
    omega = p[o + SO_OMEGA]
    speed = y[s + SECOND_SPOOL_SPEED]
    dydt[s + SECOND_SPOOL_STATE] = speed
    dydt[s + SECOND_SPOOL_SPEED] = (omega * omega * (spool_target(t, ts, sig, ptr)
                                                     - y[s + SECOND_SPOOL_STATE])
                                    - 2.0 * p[o + SO_ZETA] * omega * speed)


@njit(cache=True)
def second_partials(p, o, jac, s):  # pragma: no cover - compiled
    omega = p[o + SO_OMEGA]
    jac[s + SECOND_SPOOL_STATE, s + SECOND_SPOOL_SPEED] = 1.0
    jac[s + SECOND_SPOOL_SPEED, s + SECOND_SPOOL_STATE] = -omega * omega
    jac[s + SECOND_SPOOL_SPEED, s + SECOND_SPOOL_SPEED] = -2.0 * p[o + SO_ZETA] * omega


@njit(cache=True)
def second_params(t, ts, y, s, p, o, sig, ptr, g):  # pragma: no cover - compiled
    omega, speed = p[o + SO_OMEGA], y[s + SECOND_SPOOL_SPEED]
    error = spool_target(t, ts, sig, ptr) - y[s + SECOND_SPOOL_STATE]
    g[s + SECOND_SPOOL_SPEED, o + SO_OMEGA] = 2.0 * omega * error - 2.0 * p[o + SO_ZETA] * speed
    g[s + SECOND_SPOOL_SPEED, o + SO_ZETA] = -2.0 * omega * speed


@njit(cache=True)
def second_start(t, ts, p, o, sig, ptr, y0, s):  # pragma: no cover - compiled
    """At rest on the initial command."""
    y0[s + SECOND_SPOOL_STATE] = spool_target(t, ts, sig, ptr)
    y0[s + SECOND_SPOOL_SPEED] = 0.0


@njit(cache=True)
def second_project(y, s):  # pragma: no cover - compiled
    """Nothing: an underdamped spool may pass ±1 for a while (the flows clip it there);
    clipping the state would break its dynamics."""


@njit(cache=True)
def second_scales(out, s):  # pragma: no cover - compiled
    out[s + SECOND_SPOOL_STATE] = 1.0
    out[s + SECOND_SPOOL_SPEED] = 1.0


_SPOOL_FUNCTIONS = ("position", "rates", "partials", "params", "start", "project", "scales")
#: the spool's dynamics by the order of its lag: (kind, block, states, label)
_SPOOL_KINDS = {
    0: ("direct", Block(), (), "ideal spool"),
    1: ("lagged", LAG_BLOCK, (StateSpec("spool_position", "1"),), "spool lag"),
    2: ("second", SECOND_ORDER_BLOCK, (StateSpec("spool_position", "1"),
                                       StateSpec("spool_velocity", "1/s")),
        "second-order spool"),
}


SPOOL_LAG_CHOICES = ("False or 0 (an ideal spool), True or 1 (a first-order lag, spool_tau) "
                     "or 2 (a second-order spool, spool_omega and spool_zeta)")


def spool_part(order: int) -> Part:
    """The 5/3 valve's spool: following its command at once (order 0), with a first-order
    lag ``spool_tau`` (1, a state) or as a second-order system of natural frequency
    ``spool_omega`` and damping ``spool_zeta`` (2, two states)."""
    kind, block, states, label = _SPOOL_KINDS[int(order)]
    return Part(role="valve", block=block, states=states,
                functions={f"spool_{name}": f"{__name__}:{kind}_{name}"
                           for name in _SPOOL_FUNCTIONS},
                constants={"SPOOL_STATE": f"{__name__}:{kind.upper()}_SPOOL_STATE"},
                label=f"5/3 valve, {label}", key=f"spool_{kind}")


# ------------------------------------------- the chambers' heat transfer (HeatTransfer())
#: the block of chambers with a temperature state, and their local states (T_a, T_b); the
#: polytropic chambers have neither
THERMAL_BLOCK = Block.of("heat_transfer_coefficient")
TH_H = THERMAL_BLOCK.index("heat_transfer_coefficient")
POLYTROPIC_THERMAL_STATE = -1
HEAT_THERMAL_STATE = 0


@njit(cache=True)
def node_inflow(p_node, t_node, pressure, temp, b, m, r_lam):  # pragma: no cover
    """ISO 6358 flow per unit conductance from a node (supply, exhaust) into a chamber at
    (pressure, temp), at the upstream side's temperature, with what it carries, T_up·q:
    (q, T_up·q, ∂q/∂p, ∂(T_up·q)/∂p, ∂q/∂T, ∂(T_up·q)/∂T), p and T the chamber's."""
    if p_node >= pressure:  # into the chamber at the node's temperature
        q, _, dq_dp = iso_flow(p_node, pressure, b, m, r_lam, t_node)
        return q, t_node * q, dq_dp, t_node * dq_dp, 0.0, 0.0
    q, _, dq_dp = iso_flow(p_node, pressure, b, m, r_lam, temp)  # out at the chamber's
    dq_dt = -0.5 * q / temp
    return q, temp * q, dq_dp, temp * dq_dp, dq_dt, q + temp * dq_dt


@njit(cache=True)
def thermal_chamber(pressure, temp, volume, vol_rate, fill, vent, area, perimeter, h, p_sup,
                    p, o):  # pragma: no cover - compiled
    """One chamber's energy equation: (dp/dt, dT/dt, ṁ) and their partials in p, T, V,
    dV/dt; and per unit conductance of its supply and exhaust paths the mass inflows and
    T_up·q (for the spool's slope). ``fill``, ``vent`` are the paths' fractions of C,
    ``p_sup`` the supply pressure."""
    c, gamma, r_gas = p[o + CY_C], p[o + CY_GAMMA], p[o + CY_R]
    b, m, r_lam, t_wall = p[o + CY_B], p[o + CY_MEXP], p[o + CY_RLIN], p[o + CY_T]
    q_s, e_s, qs_p, es_p, qs_t, es_t = node_inflow(p_sup, t_wall, pressure, temp, b, m,
                                                   r_lam)
    q_e, e_e, qe_p, ee_p, qe_t, ee_t = node_inflow(p[o + CY_PATM], t_wall, pressure, temp,
                                                   b, m, r_lam)
    k_s, k_e = c * fill, c * vent
    mdot = k_s * q_s + k_e * q_e
    energy = k_s * e_s + k_e * e_e  # Σ T_up·q into the chamber
    wall = 2.0 * area + perimeter * volume / area
    heat = h * wall * (t_wall - temp)
    g1 = gamma - 1.0
    n_p = gamma * r_gas * energy - gamma * pressure * vol_rate + g1 * heat
    n_t = gamma * r_gas * energy - g1 * pressure * vol_rate + g1 * heat - r_gas * temp * mdot
    dp = n_p / volume
    kt = temp / (pressure * volume)
    dt = kt * n_t
    m_p, m_t = k_s * qs_p + k_e * qe_p, k_s * qs_t + k_e * qe_t
    e_p, e_t = k_s * es_p + k_e * ee_p, k_s * es_t + k_e * ee_t
    heat_v = h * perimeter / area * (t_wall - temp)
    heat_t = -h * wall
    dp_p = (gamma * r_gas * e_p - gamma * vol_rate) / volume
    dp_t = (gamma * r_gas * e_t + g1 * heat_t) / volume
    dp_v = (g1 * heat_v - dp) / volume
    dp_vr = -gamma * pressure / volume
    dt_p = kt * (gamma * r_gas * e_p - g1 * vol_rate - r_gas * temp * m_p) - dt / pressure
    dt_t = dt / temp + kt * (gamma * r_gas * e_t + g1 * heat_t - r_gas * mdot
                             - r_gas * temp * m_t)
    dt_v = kt * g1 * heat_v - dt / volume
    dt_vr = -kt * g1 * pressure
    return (dp, dt, mdot, dp_p, dp_t, dp_v, dp_vr, dt_p, dt_t, dt_v, dt_vr, q_s, e_s, q_e,
            e_e)


@njit(cache=True)
def thermal_pair(x, v, pa, pb, ta, tb, u, p_sup, p, o, h):  # pragma: no cover - compiled
    """Both chambers' ``thermal_chamber`` at piston (x, v), spool position u and supply
    pressure p_sup; the chambers' wetted perimeters are the bore's (A) and the bore's and
    the rod's (B)."""
    fill_a, vent_a, fill_b, vent_b = spool_fractions(u, p[o + CY_LEAK], p[o + CY_OVERLAP])
    vol_a, vol_b = chamber_volumes(x, p, o)
    area_a, area_b = p[o + CY_AA], p[o + CY_AB]
    bore, rod = p[o + CY_BORE], p[o + CY_ROD]
    return (thermal_chamber(pa, ta, vol_a, area_a * v, fill_a, vent_a, area_a,
                            math.pi * bore, h, p_sup, p, o),
            thermal_chamber(pb, tb, vol_b, -area_b * v, fill_b, vent_b, area_b,
                            math.pi * (bore + rod), h, p_sup, p, o))


@njit(cache=True)
def polytropic_rates(x, v, pa, pb, y, s, u, p_sup, p, o, oh, dydt, row_a,
                     row_b):  # pragma: no cover - compiled
    pass


@njit(cache=True)
def heat_rates(x, v, pa, pb, y, s, u, p_sup, p, o, oh, dydt, row_a,
               row_b):  # pragma: no cover - compiled
    """The chambers' pressure rates from their energy equations (replacing the polytropic
    ones in rows ``row_a``, ``row_b``) and their temperature rates."""
    ra, rb = thermal_pair(x, v, pa, pb, y[s], y[s + 1], u, p_sup, p, o, p[oh + TH_H])
    dydt[row_a], dydt[row_b] = ra[0], rb[0]
    dydt[s], dydt[s + 1] = ra[1], rb[1]


@njit(cache=True)
def polytropic_flows(x, pa, pb, y, s, u, p_sup, p, o, oh, out, i_a,
                     i_b):  # pragma: no cover - compiled
    pass


@njit(cache=True)
def heat_flows(x, pa, pb, y, s, u, p_sup, p, o, oh, out, i_a,
               i_b):  # pragma: no cover - compiled
    """The net mass flows into A and B (outflows at the chambers' temperatures) into
    out[i_a], out[i_b]."""
    ra, rb = thermal_pair(x, 0.0, pa, pb, y[s], y[s + 1], u, p_sup, p, o, p[oh + TH_H])
    out[i_a], out[i_b] = ra[2], rb[2]


@njit(cache=True)
def polytropic_partials(x, v, pa, pb, y, s, u, p_sup, p, o, oh, jac, row_a, row_b,
                        col_u):  # pragma: no cover - compiled
    pass


@njit(cache=True)
def heat_chamber_partials(rates, row_p, row_t, d_vol, d_fill, d_vent, volume, pressure,
                          temp, p, o, jac, col_u):  # pragma: no cover - compiled
    """One chamber's pressure and temperature rows of ∂f/∂y (x in column 0, v in 1) from
    ``thermal_chamber``'s partials; the spool's column when it is a state (col_u ≥ 0)."""
    jac[row_p, 0] = rates[5] * d_vol
    jac[row_p, 1] = rates[6] * d_vol
    jac[row_p, row_p] = rates[3]
    jac[row_p, row_t] = rates[4]
    jac[row_t, 0] = rates[9] * d_vol
    jac[row_t, 1] = rates[10] * d_vol
    jac[row_t, row_p] = rates[7]
    jac[row_t, row_t] = rates[8]
    if col_u >= 0:
        c, gamma, r_gas = p[o + CY_C], p[o + CY_GAMMA], p[o + CY_R]
        m_u = c * (d_fill * rates[11] + d_vent * rates[13])
        e_u = c * (d_fill * rates[12] + d_vent * rates[14])
        jac[row_p, col_u] = gamma * r_gas * e_u / volume
        jac[row_t, col_u] = temp / (pressure * volume) * (gamma * r_gas * e_u
                                                          - r_gas * temp * m_u)


@njit(cache=True)
def heat_partials(x, v, pa, pb, y, s, u, p_sup, p, o, oh, jac, row_a, row_b,
                  col_u):  # pragma: no cover - compiled
    """The pressure rows (replacing the polytropic ones) and the temperature rows of ∂f/∂y
    in x, v, p, T and the spool's position (column ``col_u`` when it is a state)."""
    ra, rb = thermal_pair(x, v, pa, pb, y[s], y[s + 1], u, p_sup, p, o, p[oh + TH_H])
    d_ext, d_ret, _, _ = spool_fraction_slopes(u, p[o + CY_OVERLAP])
    vol_a, vol_b = chamber_volumes(x, p, o)
    heat_chamber_partials(ra, row_a, s, p[o + CY_AA], d_ext, d_ret, vol_a, pa, y[s], p, o,
                          jac, col_u)
    heat_chamber_partials(rb, row_b, s + 1, -p[o + CY_AB], d_ret, d_ext, vol_b, pb,
                          y[s + 1], p, o, jac, col_u)


@njit(cache=True)
def node_inflow_params(p_node, t_node, pressure, temp, b, m, r_lam):  # pragma: no cover
    """Partials of ``node_inflow``'s (q, T_up·q) in the node's pressure and temperature and
    in b, m, r_lam: (q_pn, e_pn, q_tn, e_tn, q_b, e_b, q_m, e_m, q_lam, e_lam)."""
    inflow = p_node >= pressure
    t_up = t_node if inflow else temp
    q, dq_dpn, _ = iso_flow(p_node, pressure, b, m, r_lam, t_up)
    q_b, q_m, q_lam, _ = iso_flow_params(p_node, pressure, b, m, r_lam, t_up)
    q_tn = -0.5 * q / t_node if inflow else 0.0
    e_tn = 0.5 * q if inflow else 0.0
    return (dq_dpn, t_up * dq_dpn, q_tn, e_tn, q_b, t_up * q_b, q_m, t_up * q_m, q_lam,
            t_up * q_lam)


@njit(cache=True)
def flow_column(g, row_p, row_t, column, m_th, e_th, q_th, volume, kt, k_p, k_t,
                g1):  # pragma: no cover - compiled
    """A chamber's pressure and temperature entries of column ``column`` of ∂f/∂θ from
    the parameter's partials of ṁ, E = Σ T_up·q and Q̇ (k_p = γ·R, k_t = R·T_c,
    g1 = γ − 1, kt = T_c/(p·V))."""
    g[row_p, column] = (k_p * e_th + g1 * q_th) / volume
    g[row_t, column] = kt * (k_p * e_th + g1 * q_th - k_t * m_th)


@njit(cache=True)
def heat_chamber_params(g, row_p, row_t, pressure, temp, volume, vol_rate, area, perimeter,
                        fill, vent, e_fill, e_vent, geometry, p_sup, held, p, o, oh,
                        h):  # pragma: no cover - compiled
    """One chamber's pressure and temperature rows of ∂f/∂θ (the pressure row's cylinder
    entries rewritten); ``e_fill``, ``e_vent`` are the paths' slopes in the overlap,
    ``geometry`` (columns of its area, dead volume and stroke (−1: none), ∂V/∂area,
    ∂(dV/dt)/∂area, ∂P/∂D_bore, ∂P/∂d_rod), ``p_sup`` the supply pressure (``held``: the
    parameter p_supply's, whose column is written only then)."""
    rates = thermal_chamber(pressure, temp, volume, vol_rate, fill, vent, area, perimeter, h,
                            p_sup, p, o)
    mdot = rates[2]
    q_s, e_s, q_e, e_e = rates[11], rates[12], rates[13], rates[14]
    c, gamma, r_gas = p[o + CY_C], p[o + CY_GAMMA], p[o + CY_R]
    b, m, r_lam, t_wall = p[o + CY_B], p[o + CY_MEXP], p[o + CY_RLIN], p[o + CY_T]
    g1, kt = gamma - 1.0, temp / (pressure * volume)
    k_s, k_e = c * fill, c * vent
    energy = k_s * e_s + k_e * e_e
    wall = 2.0 * area + perimeter * volume / area
    heat = h * wall * (t_wall - temp)
    sup = node_inflow_params(p_sup, t_wall, pressure, temp, b, m, r_lam)
    exh = node_inflow_params(p[o + CY_PATM], t_wall, pressure, temp, b, m, r_lam)
    for k in range(CYLINDER_SIZE):
        g[row_p, o + k] = 0.0
    # the flow entries: ∂ṁ/∂θ, ∂E/∂θ, ∂Q̇/∂θ of each
    k_p, k_t = gamma * r_gas, r_gas * temp
    flow_column(g, row_p, row_t, o + CY_C, fill * q_s + vent * q_e, fill * e_s + vent * e_e,
                0.0, volume, kt, k_p, k_t, g1)
    flow_column(g, row_p, row_t, o + CY_LEAK, c * (q_s + q_e), c * (e_s + e_e), 0.0, volume,
                kt, k_p, k_t, g1)
    flow_column(g, row_p, row_t, o + CY_OVERLAP, c * (e_fill * q_s + e_vent * q_e),
                c * (e_fill * e_s + e_vent * e_e), 0.0, volume, kt, k_p, k_t, g1)
    if held:
        flow_column(g, row_p, row_t, o + CY_PSUP, k_s * sup[0], k_s * sup[1], 0.0, volume,
                    kt, k_p, k_t, g1)
    flow_column(g, row_p, row_t, o + CY_PATM, k_e * exh[0], k_e * exh[1], 0.0, volume, kt,
                k_p, k_t, g1)
    flow_column(g, row_p, row_t, o + CY_T, k_s * sup[2] + k_e * exh[2],
                k_s * sup[3] + k_e * exh[3], h * wall, volume, kt, k_p, k_t, g1)
    flow_column(g, row_p, row_t, o + CY_B, k_s * sup[4] + k_e * exh[4],
                k_s * sup[5] + k_e * exh[5], 0.0, volume, kt, k_p, k_t, g1)
    flow_column(g, row_p, row_t, o + CY_MEXP, k_s * sup[6] + k_e * exh[6],
                k_s * sup[7] + k_e * exh[7], 0.0, volume, kt, k_p, k_t, g1)
    flow_column(g, row_p, row_t, o + CY_RLIN, k_s * sup[8] + k_e * exh[8],
                k_s * sup[9] + k_e * exh[9], 0.0, volume, kt, k_p, k_t, g1)
    g[row_p, o + CY_GAMMA] = (r_gas * energy - pressure * vol_rate + heat) / volume
    g[row_t, o + CY_GAMMA] = kt * (r_gas * energy - pressure * vol_rate + heat)
    g[row_p, o + CY_R] = gamma * energy / volume
    g[row_t, o + CY_R] = kt * (gamma * energy - temp * mdot)
    g[row_p, oh + TH_H] = g1 * wall * (t_wall - temp) / volume
    g[row_t, oh + TH_H] = kt * g1 * wall * (t_wall - temp)
    # geometry: through V, dV/dt and the wall area's own area and perimeter
    heat_area = h * (2.0 - perimeter * volume / (area * area)) * (t_wall - temp)
    heat_perimeter = h * volume / area * (t_wall - temp)
    col_area, col_dead, col_xmax, dvol_area, dvol_rate_area, d_bore, d_rod = geometry
    g[row_p, o + col_area] = (rates[5] * dvol_area + rates[6] * dvol_rate_area
                              + g1 * heat_area / volume)
    g[row_t, o + col_area] = (rates[9] * dvol_area + rates[10] * dvol_rate_area
                              + kt * g1 * heat_area)
    g[row_p, o + col_dead] = rates[5]
    g[row_t, o + col_dead] = rates[9]
    if col_xmax >= 0:  # chamber B: V = chamber_b.V_dead + A_b·(x_max − x)
        g[row_p, o + col_xmax] = rates[5] * area
        g[row_t, o + col_xmax] = rates[9] * area
    g[row_p, o + CY_BORE] = g1 * heat_perimeter * d_bore / volume
    g[row_t, o + CY_BORE] = kt * g1 * heat_perimeter * d_bore
    g[row_p, o + CY_ROD] = g1 * heat_perimeter * d_rod / volume
    g[row_t, o + CY_ROD] = kt * g1 * heat_perimeter * d_rod


@njit(cache=True)
def polytropic_params(x, v, pa, pb, y, s, u, p_sup, held, p, o, oh, g, row_a,
                      row_b):  # pragma: no cover - compiled
    pass


@njit(cache=True)
def heat_params(x, v, pa, pb, y, s, u, p_sup, held, p, o, oh, g, row_a,
                row_b):  # pragma: no cover - compiled
    """The chambers' pressure rows of ∂f/∂θ (replacing the polytropic ones) and their
    temperature rows, the heat transfer coefficient's column included."""
    fill_a, vent_a, fill_b, vent_b = spool_fractions(u, p[o + CY_LEAK], p[o + CY_OVERLAP])
    _, _, e_extend, e_retract = spool_fraction_slopes(u, p[o + CY_OVERLAP])
    vol_a, vol_b = chamber_volumes(x, p, o)
    area_a, area_b = p[o + CY_AA], p[o + CY_AB]
    bore, rod, h = p[o + CY_BORE], p[o + CY_ROD], p[oh + TH_H]
    heat_chamber_params(g, row_a, s, pa, y[s], vol_a, area_a * v, area_a, math.pi * bore,
                        fill_a, vent_a, e_extend, e_retract,
                        (CY_AA, CY_VDA, -1, x, v, math.pi, 0.0), p_sup, held, p, o, oh, h)
    heat_chamber_params(g, row_b, s + 1, pb, y[s + 1], vol_b, -area_b * v, area_b,
                        math.pi * (bore + rod), fill_b, vent_b, e_retract, e_extend,
                        (CY_AB, CY_VDB, CY_XMAX, p[o + CY_XMAX] - x, -v, math.pi, math.pi),
                        p_sup, held, p, o, oh, h)


@njit(cache=True)
def polytropic_start(p, o, y0, s):  # pragma: no cover - compiled
    pass


@njit(cache=True)
def heat_start(p, o, y0, s):  # pragma: no cover - compiled
    """Both chambers at the walls' temperature."""
    y0[s] = y0[s + 1] = p[o + CY_T]


@njit(cache=True)
def polytropic_scales(p, o, out, s):  # pragma: no cover - compiled
    pass


@njit(cache=True)
def heat_scales(p, o, out, s):  # pragma: no cover - compiled
    out[s] = out[s + 1] = p[o + CY_T]


_THERMAL_FUNCTIONS = ("rates", "flows", "partials", "params", "start", "scales")


def thermal_part(chamber: ChamberLaw) -> Part:
    """The chambers' temperatures: none for a polytropic law, two states and the heat
    transfer coefficient with ``HeatTransfer()``."""
    heat = chamber.temperature_state
    kind = "heat" if heat else "polytropic"
    return Part(role="thermal", block=THERMAL_BLOCK if heat else Block(),
                states=(StateSpec("temperature_a", "K"), StateSpec("temperature_b", "K"))
                if heat else (),
                functions={f"thermal_{name}": f"{__name__}:{kind}_{name}"
                           for name in _THERMAL_FUNCTIONS},
                constants={"THERMAL_STATE": f"{__name__}:{kind.upper()}_THERMAL_STATE"},
                label="chambers with heat transfer" if heat else "polytropic chambers",
                key=f"chambers_{kind}")


#: the 5/3 valve's input: the spool command u in [-1, 1]
SPOOL_INPUT = InputChannel(
    "spool", "1", -1.0, 1.0, record_signals=("spool",),
    description="spool command of the 5/3 valve (-1 supply to B, 0 centred, 1 supply to A: "
                "extends)",
    label="spool command", rule="a 5/3 valve's command must stay within [{low:g}, {high:g}] "
                                "(1 extends, -1 retracts, 0 closes the centre)")


#: the two 3/2 valves' commands (Cylinder(valves="two-3/2")): each on the channel its
#: valve declares (``valve32_part``), u in [-1, 1]: 1 fills the chamber from the supply,
#: -1 vents it to the exhaust, 0 closes it
def _valve_command_input(chamber: str) -> InputChannel:
    name = f"command_{chamber.lower()}"
    return InputChannel(
        name, "1", -1.0, 1.0, record_signals=(name,), channel=name,
        description=f"command of chamber {chamber}'s 3/2 valve (1 supply to {chamber}, 0 "
                    f"closed, -1 {chamber} to exhaust)",
        label=f"3/2 valve command {name}",
        rule="a 3/2 valve's command must stay within [{low:g}, {high:g}] (1 fills its "
             "chamber from the supply, -1 vents it, 0 closes it)")


COMMAND_A_INPUT = _valve_command_input("A")
COMMAND_B_INPUT = _valve_command_input("B")

#: how the cylinder is fed: one 5/3 valve (the spool command) or a 3/2 valve per chamber
FIVE_THREE = "5/3"
TWO_THREE_TWO = "two-3/2"
VALVES_CHOICES = (FIVE_THREE, TWO_THREE_TWO)

#: the drive of two mirrored 3/2 valves (``Cylinder(valves="two-3/2", mirrored=True)``):
#: one command u in [-1, 1] on the drive channel, u_a = u and u_b = -u, as a pair of 3/2
#: valves replaces a 5/3 valve; its name is the spool command's (an experiment and a
#: position controller drive it as they drive the 5/3 valve's spool); a record drives it
#: by its ``command_a`` (what its runs write: valve A's command is u) or a ``spool``
MIRRORED_INPUT = replace(
    SPOOL_INPUT, record_signals=("command_a", "spool"),
    description="command u of the mirrored 3/2 valves (valve A's command u, valve B's -u: 1 "
                "extends, -1 retracts, 0 closes both)",
    label="mirrored 3/2 valves' command")


def valve32_part(instance: str, command: InputChannel | None, label: str) -> Part:
    """One chamber's 3/2 valve, placed under ``instance`` (valve_a, valve_b), reading its
    command on the channel of ``command`` (None: the drive channel, mirrored valves)."""
    return Part(role="valve", instance=instance, block=VALVE32_BLOCK, label=label,
                channels=() if command is None else (command.channel,))


#: the external load force on the rod, against extension: an input beside the spool
#: command, on the load-against-time channel the template reads; a record's ``load``
#: drives it (a cylinder's run writes its load under that name). 1 MN bounds what a
#: pneumatic cylinder meets (a 320 mm bore at 16 bar pushes 130 kN).
LOAD_INPUT = InputChannel(
    "load", "N", -1e6, 1e6, record_signals=("load",), channel="load_t",
    description="external force on the rod, against extension",
    label="load force", rule="a load force on a pneumatic cylinder must stay within "
                             "[{low:g}, {high:g}] N (is it in N?)")


#: the channel of the supply pressure: the cylinder's own, after the fixed ones
#: (``core.channels``), read by the template as ``CH_SUPPLY``
SUPPLY_CHANNEL = "supply"

#: the 5/3 valve's supply pressure [Pa absolute]: an input on the cylinder's own channel;
#: where no experiment drives it, the parameter p_supply holds it (a record's ``supply``
#: column drives it). Its range starts at the cylinder's p_atm (``Cylinder.inputs``):
#: below the atmosphere the supply would draw air out of the chambers.
SUPPLY_INPUT = InputChannel(
    "supply", "Pa", 1e5, MAX_ABSOLUTE_PRESSURE, record_signals=("supply",),
    channel=SUPPLY_CHANNEL, description="supply pressure of the 5/3 valve (absolute)",
    label="supply pressure", rule="a 5/3 valve's supply pressure must stay within "
                                  "[{low:g}, {high:g}] Pa absolute (from the atmosphere "
                                  "p_atm up; in Pa: 6 bar is 6e5)",
    shown_in=("Pa", 1.0))


#: the cylinder's derived signals (its template's ``outputs``) and their units: the forces,
#: the load, its valve's command (the 5/3 valve's spool u; two 3/2 valves': command_a and
#: command_b) and the chambers' net mass flows
SPOOL_OUTPUT_NAMES = ("friction", "pressure_force", "stop_force", "load", "spool",
                      "mass_flow_a", "mass_flow_b")
SPOOL_OUTPUT_UNITS = ("N", "N", "N", "N", "1", "kg/s", "kg/s")
VALVES_OUTPUT_NAMES = (*SPOOL_OUTPUT_NAMES[:4], "command_a", "command_b",
                       *SPOOL_OUTPUT_NAMES[5:])
VALVES_OUTPUT_UNITS = (*SPOOL_OUTPUT_UNITS[:4], "1", "1", *SPOOL_OUTPUT_UNITS[5:])


@dataclass(frozen=True, eq=False)
class Cylinder(DeclaredInputs):
    """A double-acting cylinder (bore ``D_bore``, rod ``d_rod``, stroke ``x_max``) with a
    friction law on its piston, driven through a closed-centre 5/3 proportional valve by
    a spool command u ∈ [−1, 1] (u > 0 extends). ``chamber`` is the gas law of both
    chambers (``HeatTransfer()``: their energy equations, temperatures as states);
    ``load`` an external force F_load(t) [N] against extension (None, the default: the
    input ``load``, which an experiment drives by name, zero where it does not);
    ``spool_lag`` the order of the spool's dynamics: 0 (or False, the default) follows the
    command at once, 1 (or True) with the time constant ``spool_tau`` (a state), 2 as a
    second-order system (``spool_omega``, ``spool_zeta``; two states). ``valves``: "5/3"
    (the default) or "two-3/2": a proportional 3/2 valve per chamber instead (instances
    ``valve_a``, ``valve_b`` of one kind, parameters ``valve_a.C`` ...), driven by the
    inputs ``command_a`` and ``command_b`` in [−1, 1] (1 fills the chamber from the
    supply, −1 vents it, 0 closes it); its valves follow their commands at once into
    polytropic chambers (each chamber's flow through its own valve's paths, one
    template for both). ``mirrored`` (with
    two 3/2 valves only): one command u drives both, u_a = u and u_b = −u (how a pair of
    3/2 valves replaces a 5/3 valve), its input the spool command's (``spool``), so that
    a closed loop and ``linearise`` act on it as on the 5/3 valve. ``friction``: one law
    on the piston (parameters ``Fc`` ...), or ``{"piston": law, "rod": law}``: two laws
    whose forces add, each an instance of the kind friction with its own states and
    parameters (``friction_piston.Fc``, ``friction_rod.sigma0``: ``placed_laws``)."""

    params: ParameterSet
    friction: FrictionModel | Mapping[str, FrictionModel] = field(default_factory=LuGre)
    chamber: ChamberLaw = field(default_factory=Isothermal)
    load: Signal | None = None
    spool_lag: bool | int = 0
    valves: str = FIVE_THREE
    mirrored: bool = False

    if TYPE_CHECKING:  # the constructor takes a set's name or path too (loaded in it)
        def __init__(self, params: ParameterSetLike,
                     friction: FrictionModel | Mapping[str, FrictionModel] = ...,
                     chamber: ChamberLaw = ..., load: Signal | None = ...,
                     spool_lag: bool | int = ..., valves: str = ...,
                     mirrored: bool = ...) -> None: ...

    def __post_init__(self):
        from ..checks import as_instance, check_type
        from ..errors import ArgumentError
        from ..parameters.files import as_parameter_set

        set_ = object.__setattr__
        set_(self, "params", as_parameter_set(self.params, "Cylinder"))
        examples = ("pa.LuGre(), pa.Dahl(), pa.BoucWen(), pa.CoulombViscous() or "
                    "pa.StribeckMap()")
        if isinstance(self.friction, Mapping):  # laws placed on the piston and the rod
            set_(self, "friction", placed_friction(self.friction, examples))
        else:
            set_(self, "friction", as_instance("friction", self.friction, FrictionModel,
                                               where="Cylinder", examples=examples))
        set_(self, "chamber", as_instance(
            "chamber", self.chamber, ChamberLaw, where="Cylinder",
            examples="pa.Isothermal(), pa.Adiabatic(), pa.Polytropic(exponent) or "
                     "pneumact.models.HeatTransfer()"))
        if self.load is not None:
            check_type("load", self.load, Signal, where="Cylinder",
                       what="a Signal (e.g. pa.experiments.Step(...)) or None")
        check_type("spool_lag", self.spool_lag, int, where="Cylinder", what=SPOOL_LAG_CHOICES)
        if self.spool_lag not in _SPOOL_KINDS:
            raise ArgumentError(f"Cylinder: spool_lag = {self.spool_lag!r}: must be "
                                f"{SPOOL_LAG_CHOICES}")
        if self.valves not in VALVES_CHOICES:
            raise ArgumentError(f"Cylinder: valves = {self.valves!r}: must be "
                                f"{FIVE_THREE!r} (one 5/3 valve, the spool command) or "
                                f"{TWO_THREE_TWO!r} (a 3/2 valve per chamber, command_a and "
                                "command_b)")
        if self.two_valves and (self.spool_lag or self.chamber.temperature_state):
            raise ArgumentError(
                f"Cylinder: valves = {self.valves!r} with spool_lag = {self.spool_lag!r} and "
                f"chamber = {type(self.chamber).__name__}: the 3/2 valves follow their "
                "commands at once and their chambers are polytropic (spool_lag=0 and "
                "Isothermal, Adiabatic or Polytropic); a spool's lag and HeatTransfer() "
                "are the 5/3 valve's")
        check_type("mirrored", self.mirrored, bool, where="Cylinder", what="True or False")
        if self.mirrored and not self.two_valves:
            raise ArgumentError(f"Cylinder: mirrored = True with valves = {self.valves!r}: "
                                "mirrored drives two 3/2 valves by one command (u_a = u, "
                                f"u_b = -u); give valves={TWO_THREE_TWO!r}")
        self.params.require(self.required, "Cylinder")

    @property
    def two_valves(self) -> bool:
        """Whether a 3/2 valve feeds each chamber (``valves="two-3/2"``)."""
        return self.valves == TWO_THREE_TWO

    #: the kernel template, one for both valve arrangements (``kernel_constants`` tells
    #: them apart)
    template: ClassVar[str] = "pneumact.models.cylinder_template"

    @property
    def output_names(self) -> tuple[str, ...]:
        """Its derived signals: the 5/3 valve's spool, or the two 3/2 valves' commands."""
        return VALVES_OUTPUT_NAMES if self.two_valves else SPOOL_OUTPUT_NAMES

    @property
    def output_units(self) -> tuple[str, ...]:
        return VALVES_OUTPUT_UNITS if self.two_valves else SPOOL_OUTPUT_UNITS

    @property
    def friction_laws(self) -> dict[str, FrictionModel]:
        """Its friction laws by instance: {"friction_piston": ..., "friction_rod": ...}
        where laws share the rod (``friction={...}``), else {"friction": its one law},
        whose parameters are unprefixed (``Fc``)."""
        if isinstance(self.friction, FrictionModel):
            return {"friction": self.friction}
        return {f"friction_{place}": law for place, law in self.friction.items()}

    @property
    def placed_laws(self) -> bool:
        """Whether several friction laws share the rod (placed as instances)."""
        return not isinstance(self.friction, FrictionModel)

    def steady_friction(self, v) -> np.ndarray:
        """The total friction in steady sliding at velocities ``v`` [N]: the sum of its
        laws' steady forces, each at its own parameters (numpy, no simulation)."""
        import numpy as np

        from ..core.component import instance_entry

        forces = []
        for instance, law in self.friction_laws.items():
            params = self.params if not self.placed_laws else {
                name: self.params[instance_entry(instance, name)]
                for name in law.block.parameters}
            forces.append(law.steady_force(v, params))
        return np.sum(forces, axis=0)

    @property
    def sensitivity_refusal(self) -> str | None:
        """Why forward sensitivities are refused: a friction law's reason, if any."""
        return next((law.sensitivity_refusal for law in self.friction_laws.values()
                     if law.sensitivity_refusal is not None), None)

    @property
    def spanned_roles(self) -> tuple[str, ...]:
        """Laws placed on the piston and the rod are read as one friction law's slice
        and block (``Assembly.role_span``): FRICTION_LO, FRICTION_HI, S_FRICTION."""
        return ("friction",) if self.placed_laws else ()

    def kernel_children(self) -> tuple:
        """Each placed law's own slice functions, a kernel of its template and functions,
        bound under its place (``piston_friction_rates`` ...: ``placed_laws``)."""
        if isinstance(self.friction, FrictionModel):
            return ()
        from ..core.codegen import Child, KernelSpec

        return tuple(Child(f"{place}_", KernelSpec(
            f"friction_{law.law}", (), tuple(law.functions().items()), (),
            components=(law.template,))) for place, law in self.friction.items())

    # -- the model protocol (``simulation.Model``) -----------------------------------------
    def inputs(self) -> tuple[InputChannel, ...]:
        """Its 5/3 valve's spool command u in [-1, 1] (``SPOOL_INPUT``), then its load
        force (``LOAD_INPUT``) unless the cylinder holds one (``load=``), then its supply
        pressure (``SUPPLY_INPUT``, from its p_atm up); found once (every run asks)."""
        found = self.__dict__.get("_inputs")
        if found is None:
            supply = replace(SUPPLY_INPUT, low=float(self.params["p_atm"]))
            load = () if self.load is not None else (LOAD_INPUT,)
            commands = ((MIRRORED_INPUT,) if self.mirrored else
                        (COMMAND_A_INPUT, COMMAND_B_INPUT) if self.two_valves
                        else (SPOOL_INPUT,))
            found = (*commands, *load, supply)
            object.__setattr__(self, "_inputs", found)
        return found

    def declared_input(self, name: str, who: str) -> InputChannel:
        """Its input named ``name``; the load of a cylinder that holds one is refused
        saying so (it is no input then)."""
        if name == LOAD_INPUT.name and self.load is not None:
            from ..errors import ExperimentError

            raise ExperimentError(f"{who} drives {name!r}, but this Cylinder holds its load "
                                  f"(load = {self.load!r}): drop load= to drive the input "
                                  f"{LOAD_INPUT.describe()}")
        return super().declared_input(name, who)

    @property
    def input_signals(self) -> tuple[str, ...]:
        return self.drive_input.record_signals

    def driven_by(self, signal: str) -> Cylinder:
        """This cylinder, when ``signal`` is its drive (the spool command, or valve A's
        command with two 3/2 valves)."""
        from ..errors import DataError

        if signal not in self.drive_input.record_signals:
            what = ("valve A's command" if self.two_valves and not self.mirrored
                    else "spool command")
            raise DataError(f"a Cylinder is driven by a record's {what}, not its {signal}")
        return self

    @property
    def plant_kind(self) -> str:
        return self.drive_input.name

    @property
    def drive_label(self) -> str:
        if self.mirrored:
            return "two mirrored 3/2 valves"
        return "two 3/2 valves" if self.two_valves else "5/3 valve"

    #: the sensors of its measured signals, by signal (``models.sensors``)
    sensor_names: ClassVar[Mapping[str, SensorNames]] = CYLINDER_SENSORS

    #: what ``Result.summary()`` computes of its runs: the piston's motion (a step)
    summary_kind: ClassVar[str] = "motion"

    #: two chambers: a controller may feed back the pressure difference the piston
    #: feels, ``pressure_feedback`` of its template ((p_a − p_atm) − (p_b − p_atm)·A_b/A_a)
    pressure_feedback: ClassVar[bool] = True

    def kernel_constants(self) -> dict[str, object]:
        """Whether a 3/2 valve feeds each chamber (``TWO_VALVES``: the template's chambers
        then read their valves' blocks and commands); with two 3/2 valves the sign of
        valve B's command (-1 mirrored: both read the drive channel, u_b = -u)."""
        if not self.two_valves:
            return {"TWO_VALVES": False}
        if self.mirrored:
            return {"TWO_VALVES": True, "CH_COMMAND_A": CH_DRIVE, "CH_COMMAND_B": CH_DRIVE,
                    "COMMAND_B_SIGN": -1.0}
        return {"TWO_VALVES": True, "COMMAND_B_SIGN": 1.0}

    @property
    def stroke(self) -> float | None:
        """x_max [m]: positions beyond it are impossible."""
        return float(self.params["x_max"])

    def breakpoints(self, bp, channels, t_start: float, t_end: float):
        """The experiment's breakpoints (a load's corners are added by the simulation)."""
        return bp

    @property
    def required(self) -> tuple[str, ...]:
        return required_parameters(self.parts())

    def parts(self) -> tuple[Part, ...]:
        cylinder = Part(
            role="cylinder", block=CYLINDER_BLOCK,
            states=(StateSpec("position", "m"), StateSpec("velocity", "m/s"),
                    StateSpec("pressure_a", "Pa"), StateSpec("pressure_b", "Pa")),
            settings=self.chamber.settings(), label="double-acting cylinder",
            channels=(SUPPLY_CHANNEL,))
        chambers = (chamber_part("chamber_a", "cap-side chamber A"),
                    chamber_part("chamber_b", "rod-side chamber B"))
        if self.two_valves:
            cylinder = replace(cylinder, block=VALVES_CYLINDER_BLOCK, settings={
                **cylinder.settings, **dict.fromkeys(FIVE_THREE_ENTRIES, 0.0)})
            command_a, command_b = ((None, None) if self.mirrored
                                    else (COMMAND_A_INPUT, COMMAND_B_INPUT))
            # their spools follow the commands at once: the direct spool's functions fill
            # the template's spool places (its position unread), as the polytropic
            # chambers' fill its thermal ones
            return (cylinder, *chambers, *self._friction_parts(),
                    valve32_part("valve_a", command_a, "3/2 valve of chamber A"),
                    valve32_part("valve_b", command_b, "3/2 valve of chamber B"),
                    replace(spool_part(0), label="", key="valves_3_2"),
                    thermal_part(self.chamber))
        return (cylinder, *chambers, *self._friction_parts(), spool_part(self.spool_lag),
                thermal_part(self.chamber))

    def _friction_parts(self) -> tuple[Part, ...]:
        """Its one law's part, or the placed laws' (``friction_place_parts``)."""
        if isinstance(self.friction, FrictionModel):
            return (self.friction.part(),)
        return friction_place_parts(self.friction)

    def channels(self, drive: Signal, drives: Mapping[str, Signal] | None = None
                 ) -> list[Signal | None]:
        """The spool command ``drive`` and the inputs ``drives`` names (its load, its
        supply pressure) on their channels; the load it holds, or none, where no
        experiment drives it; the supply's channel empty where none drives it (the kernel
        then reads p_supply). With two 3/2 valves ``drive`` is command_a; command_b's
        channel, where no experiment drives it, is empty: read as 0, valve B closed."""
        load = self.load if self.load is not None else Constant(0.0)
        return in_order({LOAD_INPUT.channel: load, **self.routed(drive, drives)},
                        self.channel_names)

    # -- the FMU exporter's protocol (``models.fmu_interface``) ---------------------------
    def fmu_form(self) -> Cylinder:
        """This cylinder as its FMU runs it (its load channel is there already; a load
        against time is refused: in the FMU it is the input)."""
        refuse_load_against_time("cylinder", self.load)
        return self

    def fmu_interface(self) -> FmuInterface:
        """The spool command u in [-1, 1] (starting centred), the external force (nominal:
        the supply's force on the piston, (p_supply - p_atm)·A_a), the supply pressure
        ``supply`` [Pa absolute] (starting at p_supply, from p_atm up), no end-stop check
        (``stop_check.c.j2`` is the diaphragm's: a preload and a spring) and the Euler
        step its stops allow resting under that force."""
        p = self.params
        push = (float(p["p_supply"]) - float(p["p_atm"])) * QUARTER_PI * float(p["D_bore"]) ** 2
        if self.two_valves and not self.mirrored:  # each valve's command, on its channel:
            # command_a the drive (the model fills its channel), command_b by name
            # (named valve_a_command, valve_b_command: command_a, command_b are outputs)
            commands: tuple[FmuInput, ...] = (
                replace(declared_fmu_input("valve_a_command", COMMAND_A_INPUT, 0.0),
                        declared=""),
                declared_fmu_input("valve_b_command", COMMAND_B_INPUT, 0.0))
        else:  # the spool command (mirrored 3/2 valves: u, u_a = u and u_b = -u)
            drive = self.drive_input
            commands = (drive_input("spool_command", drive.unit, drive.description, 0.0, 1.0,
                                    drive.low, drive.high),)
        step = explicit_step(float(p["m"]), 0.0, push, float(p["k_stop"]), float(p["c_stop"]))
        declared = next(i for i in self.inputs() if i.name == SUPPLY_INPUT.name)
        supply = declared_fmu_input(SUPPLY_INPUT.name, declared, float(p["p_supply"]),
                                    pressure=True)
        return FmuInterface((*commands, force_input(push), supply), None, step)

    def describe(self) -> str:
        valves = f", valves={self.valves!r}" if self.two_valves else ""
        valves += ", mirrored=True" if self.mirrored else ""
        friction = (self.friction if isinstance(self.friction, FrictionModel)
                    else dict(self.friction))
        return (f"Cylinder(friction={friction!r}, "
                f"chamber={type(self.chamber).__name__}, spool_lag={self.spool_lag}"
                f"{valves})")

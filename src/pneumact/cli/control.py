"""``pneumact control step|profile|hunting``: closed-loop position control runs.

Each writes signals.csv (SI), metrics.csv, loop.png and report.html into ``--out`` and
prints the metrics. Gains are SI, per metre of position error, in the plant input's
units (N for the rig, Pa for a pressure regulator, 1 for a command valve); positions
on the command line are in mm.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import StrEnum
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer
from rich.table import Table

from pneumact.checks import check_out_dir, check_range
from pneumact.cli.common import (
    CYLINDER_SET,
    Friction,
    FrictionOption,
    ParamsOption,
    PlantLoadStepOption,
    RtolOption,
    SchedulerOption,
    WorkersOption,
    check_valves,
    executor_of,
    load_input_of,
    load_quietly,
    load_step_of,
    out_console,
    refuse_load_step,
    run_with_progress,
    the_call,
    use_agg,
    user_errors,
)
from pneumact.errors import ParameterError

if TYPE_CHECKING:
    from pneumact.core.signals import Signal
    from pneumact.models import Actuator, Cylinder, FrictionRig
    from pneumact.models.controllers import Compensation

#: Exit code of a tuning that ran but whose gains do not meet --spec on the asked share
#: of the samples (the nominal plant alone without --uncertainty): the files are written
#: and the feasibility line says what they hold
EXIT_SPECS_NOT_MET = 3

control_app = typer.Typer(help="Closed-loop position control: step, profile, hunting, tune, "
                               "compare.",
                          no_args_is_help=True)


class Plant(StrEnum):
    regulator = "regulator"
    command = "command"
    source = "source"
    rig = "rig"
    cylinder = "cylinder"


class Regime(StrEnum):
    sliding = "sliding"
    presliding = "presliding"


class Structure(StrEnum):
    pid = "pid"
    cascade = "cascade"


#: starting gains per plant (kp [input/m], ki [input/(m·s)]): a 4 → 8 mm step of the
#: vgt-paper actuator settles (2 %) in 0.55 s without overshoot behind the regulator, in
#: 0.32 s with 11 % overshoot behind the command valve; the rig's are Canudas et al.'s
DEFAULT_GAINS = {"regulator": (5e6, 5e7), "source": (5e6, 5e7), "command": (200.0, 2000.0),
                 "rig": (3.0, 4.0), "cylinder": (60.0, 300.0)}
#: the regulator's set-point range [Pa abs] below p_atm when no limits are given
REGULATOR_MIN_PRESSURE = 10e3

PlantOption = Annotated[Plant, typer.Option(
    help="regulator / command / source: the vgt actuator behind that valve (the input is "
         "the pressure set-point, the valve command or the chamber pressure); rig: a mass "
         "with friction and a force actuator; cylinder: the double-acting cylinder behind "
         "its 5/3 valve or two 3/2 valves (--valves; the spool command, --params default "
         "iso15552-32).")]
PlantValvesOption = Annotated[str, typer.Option(
    "--valves", help="--plant cylinder: 5/3 (one 5/3 valve, its spool command) or two-3/2 "
                     "(a proportional 3/2 valve per chamber, both driven by the one command "
                     "mirrored: valve A's u, valve B's -u).")]
ControllerOption = Annotated[Structure, typer.Option(
    "--controller", help="pid, or cascade (outer P on position --kx, inner PI on velocity "
                         "--kv, --ki).")]
KpOption = Annotated[float | None, typer.Option(help="Proportional gain (plant default).")]
KiOption = Annotated[float | None, typer.Option(help="Integral gain (plant default).")]
KdOption = Annotated[float, typer.Option(help="Derivative gain.")]
DerivativeOption = Annotated[str, typer.Option(
    help="Derivative on: measurement, error, velocity (measured v), none.")]
FilterOption = Annotated[float, typer.Option(help="Derivative filter time constant [s].")]
KxOption = Annotated[float, typer.Option(help="Cascade: outer position gain [1/s].")]
KvOption = Annotated[float, typer.Option(help="Cascade: inner velocity gain.")]
UMinOption = Annotated[float | None, typer.Option(help="Lower output limit (input units).")]
UMaxOption = Annotated[float | None, typer.Option(help="Upper output limit (input units).")]
AntiWindupOption = Annotated[str, typer.Option(
    help="back-calculation, clamping or none.")]
TrackingOption = Annotated[float | None, typer.Option(
    help="Back-calculation tracking time [s] (default sqrt(Ti*Td) or Ti).")]
SampleOption = Annotated[float | None, typer.Option(
    help="Sample time [s] of a digital controller with zero-order hold (default: "
         "continuous).")]
VelocityEstimateOption = Annotated[str, typer.Option(
    help="Sampled: measured velocity, or difference of sampled positions.")]
CoulombOption = Annotated[float | None, typer.Option(
    "--coulomb-ff", help="Coulomb friction feed-forward on the set-point velocity [N].")]
DitherOption = Annotated[str | None, typer.Option(
    help="Dither 'AMPLITUDE,FREQUENCY' (controller units, Hz).")]
ObserverOption = Annotated[bool, typer.Option(
    "--observer", help="LuGre observer-based compensation (Canudas et al. 1995) with the "
                       "parameter set's LuGre values.")]
ObserverGainOption = Annotated[float, typer.Option(help="Observer gain k.")]
OutOption = Annotated[Path, typer.Option(help="Output directory.")]


@dataclass(frozen=True)
class ControllerOptions:
    structure: Structure
    kp: float | None
    ki: float | None
    kd: float
    derivative: str
    filter_time: float
    kx: float
    kv: float
    u_min: float | None
    u_max: float | None
    anti_windup: str
    tracking_time: float | None
    sample_time: float | None
    velocity_estimate: str
    coulomb_ff: float | None
    dither: str | None
    observer: bool
    observer_gain: float


def _limits(plant: Plant, params, options: ControllerOptions) -> tuple[float, float]:
    if plant in (Plant.regulator, Plant.source):  # a rig's set has no p_atm
        natural = (REGULATOR_MIN_PRESSURE, float(params["p_atm"]))
        for flag, value in (("--u-min", options.u_min), ("--u-max", options.u_max)):
            if value is not None and math.isfinite(value) and 0.0 < value < 1e3:
                raise ParameterError(
                    f"{flag} = {value:g} Pa: the limits are absolute pressures in Pa (the "
                    f"plant works from {natural[0]:g} to {natural[1]:g} Pa); {value:g} looks "
                    f"like kPa: {flag} {value * 1e3:g}")
    else:
        natural = {"command": (0.0, 1.0), "rig": (-math.inf, math.inf),
                   "cylinder": (-1.0, 1.0)}[plant.value]
    return (natural[0] if options.u_min is None else options.u_min,
            natural[1] if options.u_max is None else options.u_max)


def _compensation(options: ControllerOptions, params) -> tuple:
    from pneumact.control import Dither, LuGreObserver, StaticCompensation

    terms: list[Compensation] = []
    if options.coulomb_ff is not None:
        terms.append(StaticCompensation(options.coulomb_ff))
    if options.dither:
        parts = [p for p in options.dither.split(",") if p.strip()]
        try:
            amplitude, frequency = (float(p) for p in parts)
        except ValueError:
            raise ParameterError(f"--dither = {options.dither!r}; give AMPLITUDE,FREQUENCY "
                                 "(two numbers, controller units and Hz)") from None
        terms.append(Dither(amplitude, frequency))
    if options.observer:
        terms.append(LuGreObserver.from_parameters(params, gain=options.observer_gain))
    return tuple(terms)


def build_controller(plant: Plant, params, options: ControllerOptions):
    """The controller the options describe."""
    from pneumact.control import PID, Cascade

    kp0, ki0 = DEFAULT_GAINS[plant.value]
    u_min, u_max = _limits(plant, params, options)
    common: dict[str, Any] = dict(u_min=u_min, u_max=u_max, anti_windup=options.anti_windup,
                  tracking_time=options.tracking_time, sample_time=options.sample_time,
                  velocity_estimate=options.velocity_estimate,
                  compensation=_compensation(options, params))
    if options.structure is Structure.cascade:
        return Cascade(kx=options.kx, kv=options.kv,
                       ki=0.0 if options.ki is None else options.ki, **common)
    return PID(kp=kp0 if options.kp is None else options.kp,
               ki=ki0 if options.ki is None else options.ki, kd=options.kd,
               derivative=options.derivative, filter_time=options.filter_time, **common)


def plant_params(plant: Plant, params_name: str):
    """The parameter set of --params (the cylinder's iso15552-32 in place of the
    actuator's default set with --plant cylinder)."""
    if plant is Plant.cylinder and params_name == "vgt-paper":
        params_name = CYLINDER_SET
    return load_quietly(params_name)


#: the cylinder's default valving (``Cylinder.valves``, --valves)
CYLINDER_VALVES = "5/3"


def check_plant_valves(plant: Plant, valves: str) -> None:
    """--valves one of the cylinder's valvings, and given (other than 5/3) only with
    --plant cylinder."""
    if valves == CYLINDER_VALVES:
        return
    if plant is not Plant.cylinder:
        raise ParameterError(f"--valves {valves} is the cylinder's valving (--plant "
                             f"cylinder); --plant {plant.value} has no cylinder: drop "
                             "--valves")
    check_valves(valves)


def build_plant(plant: Plant, params, friction: str, load: Signal | None = None,
                valves: str = CYLINDER_VALVES) -> FrictionRig | Actuator | Cylinder:
    """The plant --plant names: the rig, the cylinder (behind its 5/3 valve, or two 3/2
    valves driven mirrored by the one command: ``Cylinder(valves="two-3/2",
    mirrored=True)``) or the actuator behind its valve; ``load``: the cylinder's or the
    actuator's external load (``Cylinder.load``, ``Actuator.load``, --load-step)."""
    from pneumact.models import VALVES, Actuator, Cylinder, FrictionRig, friction_models

    check_plant_valves(plant, valves)
    law = friction_models()[str(friction)]()
    if plant is Plant.rig:
        return FrictionRig(params, law, drive="force")
    if plant is Plant.cylinder:
        return Cylinder(params, law, load=load, valves=valves,
                        mirrored=valves != CYLINDER_VALVES)
    return Actuator(params, law, valve=VALVES[plant.value](), load=load)


def build_loop(plant: Plant, params_name: str, friction: str, options: ControllerOptions,
               start: float, gains: Path | None = None, load: Signal | None = None,
               valves: str = CYLINDER_VALVES):
    """(parameter set, ClosedLoop) holding the plant at ``start`` [m] at t = 0; the
    controller of a ``gains`` file (``control tune``) if given; ``load``: the plant's
    external load (--load-step); ``valves``: the cylinder's valving (``build_plant``)."""
    from pneumact.control import ClosedLoop

    params = plant_params(plant, params_name)
    model = build_plant(plant, params, friction, load, valves)
    if gains is not None:
        from pneumact.control import load_gains

        unit = ClosedLoop(model, build_controller(plant, params, options)).command_unit
        controller = load_gains(gains, command_unit=unit)
    else:
        controller = build_controller(plant, params, options)
    loop = ClosedLoop(model, controller)
    bias = loop.holding_input(start)
    return params, ClosedLoop(model, controller, bias=bias)


def _load_step(plant: Plant, text: str | None, experiment) -> Signal | None:
    """The plant's load of --load-step FORCE,TIME within the run of ``experiment``
    (``common.load_step_of``, within the range of the plant's load input: the cylinder's
    or the actuator's); refused for the rig, which has none."""
    from pneumact.models import Actuator, Cylinder

    if text is None:
        return None
    if plant is Plant.rig:
        refuse_load_step(text, "--plant cylinder, regulator, command or source")
    kind = Cylinder if plant is Plant.cylinder else Actuator
    return load_step_of(text, experiment, load_input=load_input_of(kind))


def _check_setpoints(plant: Plant, params_name: str, **positions_mm: float) -> None:
    """Set-points [mm] within the actuator's stroke (before the loop is built)."""
    if plant is Plant.rig:
        return
    params = plant_params(plant, params_name)
    x_max = params["x_max"] * 1e3
    for label, value in positions_mm.items():
        check_range(label, value, 0.0, x_max, unit="mm",
                    hint=f"the stroke of '{params.name}' is 0 to x_max = {x_max:g} mm")


#: a measured profile may pass an end of the stroke by its sensor's noise: by this many
#: standard deviations of it (estimated from the profile), and at least END_TOLERANCE [m]
NOISE_SIGMAS = 5.0
END_TOLERANCE = 10e-6


def _within_stroke(plant: Plant, params_name: str, label: str, positions):
    """A profile's positions [m], those past an end of the stroke by no more than the
    noise of a measurement (``NOISE_SIGMAS`` σ, at least ``END_TOLERANCE``) put on that
    end, with a note; farther ones are left for ``_check_setpoints`` to refuse."""
    import numpy as np

    from pneumact.cli.common import err_console

    if plant is Plant.rig or len(positions) < 4:
        return positions
    x_max = plant_params(plant, params_name)["x_max"]
    # white noise of σ gives second differences of standard deviation σ·√6
    sigma = 1.4826 * float(np.median(np.abs(np.diff(positions, 2)))) / np.sqrt(6.0)
    tolerance = max(END_TOLERANCE, NOISE_SIGMAS * sigma)
    inside = np.clip(positions, 0.0, x_max)
    moved = np.abs(inside - positions)
    if not 0.0 < moved.max() <= tolerance:
        return positions
    err_console.print(f"note: {label}: {np.count_nonzero(moved)} set-point(s) up to "
                      f"{moved.max() * 1e6:.3g} µm past an end of the stroke (within the "
                      f"measurement's noise, {tolerance * 1e6:.3g} µm) put on that end",
                      soft_wrap=True)
    return inside


def _run_and_write(ctx, loop, experiment, out: Path, rtol: float, title: str,
                   tracking: bool = False, start: float | None = None) -> None:
    """Run the loop and write its study; ``start`` [m]: the piston placed there at t = 0
    (a cylinder rests on a stop wherever its chambers balance; an actuator's rest under
    the loop's holding input is the start already: None)."""
    import pneumact as pa
    from pneumact.control.study import run_loop
    from pneumact.simulation.simulate import check_drive

    check_drive(loop, experiment)  # before the progress display
    study = run_with_progress(lambda report: run_loop(
        loop, experiment, solver=pa.Rodas4(rtol=rtol), progress=report, title=title,
        tracking=tracking, y0=None if start is None else {"position": start}))
    use_agg()
    written = study.write(out, call=the_call(ctx))
    _print_metrics(study.to_pandas("metrics"))
    for path in written:
        out_console.print(f"wrote {path}")


def _print_metrics(frame) -> None:
    from pneumact.cli.common import fmt
    from pneumact.io.display import display_frame

    table = Table(title="closed loop")
    for column in ("metric", "value", "unit"):
        table.add_column(column, justify="right" if column == "value" else "left")
    for _, row in display_frame(frame).iterrows():
        value = row["value"]
        text = str(value) if isinstance(value, bool) else fmt(float(value), 4)
        table.add_row(str(row["metric"]), text, str(row["unit"]))
    out_console.print(table)


def _options(ctx: typer.Context) -> ControllerOptions:
    """The controller options of ``step`` and ``profile``, read from the parsed command
    (both declare the same options)."""
    from dataclasses import fields

    given = {"structure": ctx.params["controller"]}
    given.update({f.name: ctx.params[f.name] for f in fields(ControllerOptions)
                  if f.name != "structure"})
    _refuse_unused(ctx, given["structure"], given)
    return ControllerOptions(**given)


GainsFileOption = Annotated[Path | None, typer.Option(
    help="A gains file written by 'pneumact control tune' (gains.toml): its "
                    "controller replaces the gain and controller options.")]
#: the options a gains file replaces
CONTROLLER_WORDS = ("controller", "kp", "ki", "kd", "derivative", "filter_time", "kx", "kv",
                    "u_min", "u_max", "anti_windup", "tracking_time", "sample_time",
                    "velocity_estimate")


def _refuse_with_gains(ctx: typer.Context, gains: Path | None) -> None:
    if gains is None:
        return
    given = [f"--{n.replace('_', '-')}" for n in CONTROLLER_WORDS
             if (src := ctx.get_parameter_source(n)) is not None and src.name != "DEFAULT"]
    if given:
        raise ParameterError(f"{', '.join(given)}: the gains file {gains} gives the "
                             "controller; leave them out or leave out --gains-file")
    if not gains.is_file():
        raise ParameterError(f"--gains-file {gains}: no such file")


#: options that only one controller structure reads
PID_ONLY = ("kp", "kd", "derivative", "filter_time")
CASCADE_ONLY = ("kx", "kv")


def _refuse_unused(ctx: typer.Context, structure: Structure, given: dict) -> None:
    """Options given on the command line that the chosen controller would ignore."""
    def on_command_line(name: str) -> bool:
        source = ctx.get_parameter_source(name)
        return source is not None and source.name != "DEFAULT"

    flag = {name: "--" + name.replace("_", "-") for name in given}
    ignored = PID_ONLY if structure is Structure.cascade else CASCADE_ONLY
    unused = [flag[n] for n in ignored if on_command_line(n)]
    if unused:
        raise ParameterError(f"{', '.join(unused)}: not read by --controller "
                             f"{structure.value}")
    if on_command_line("observer_gain") and not given["observer"]:
        raise ParameterError("--observer-gain is the gain of the LuGre observer: give "
                             "--observer too")
    if on_command_line("tracking_time") and given["anti_windup"] != "back-calculation":
        raise ParameterError(f"--tracking-time belongs to back-calculation anti-windup, not "
                             f"--anti-windup {given['anti_windup']}")


@control_app.command("step")
def step_command(
    ctx: typer.Context,
    start: Annotated[float, typer.Option(help="Initial position and set-point [mm].")] = 4.0,
    stop: Annotated[float, typer.Option(help="Set-point after the step [mm].")] = 8.0,
    t_step: Annotated[float, typer.Option(help="Time of the step [s].")] = 0.1,
    t_end: Annotated[float, typer.Option(help="Duration [s].")] = 1.0,
    plant: PlantOption = Plant.regulator,
    valves: PlantValvesOption = CYLINDER_VALVES,
    params: ParamsOption = "vgt-paper",
    friction: FrictionOption = Friction.lugre,
    controller: ControllerOption = Structure.pid,
    kp: KpOption = None, ki: KiOption = None, kd: KdOption = 0.0,
    derivative: DerivativeOption = "measurement", filter_time: FilterOption = 1e-3,
    kx: KxOption = 50.0, kv: KvOption = 1e4,
    u_min: UMinOption = None, u_max: UMaxOption = None,
    anti_windup: AntiWindupOption = "back-calculation", tracking_time: TrackingOption = None,
    sample_time: SampleOption = None, velocity_estimate: VelocityEstimateOption = "measured",
    coulomb_ff: CoulombOption = None, dither: DitherOption = None,
    observer: ObserverOption = False, observer_gain: ObserverGainOption = 0.0,
    rtol: RtolOption = 1e-6,
    gains_file: GainsFileOption = None,
    load_step: PlantLoadStepOption = None,
    out: OutOption = Path("pneumact-control-step"),
) -> None:
    """A position set-point step: rise and settling time, overshoot, steady-state
    error, stick phases and control effort; with --load-step, the plant (the cylinder's
    rod, the actuator's diaphragm) loaded by a force step (--start = --stop: the load
    alone, its rejection)."""
    with user_errors():
        from pneumact.experiments import SetpointStep

        out = check_out_dir("--out", out)
        options = _options(ctx)
        _refuse_with_gains(ctx, gains_file)
        if start == stop and load_step is None:
            raise ParameterError(f"--start = --stop = {start:g} mm: there is no step to "
                                 "follow; give two different positions (or a --load-step "
                                 "to reject)")
        experiment = SetpointStep(start * 1e-3, stop * 1e-3, t_step, t_end)
        load = _load_step(plant, load_step, experiment)
        _check_setpoints(plant, params, **{"--start": start, "--stop": stop})
        _, loop = build_loop(plant, params, friction, options, start * 1e-3, gains_file,
                             load, valves)
        _run_and_write(ctx, loop, experiment, out, rtol,
                       f"Position step {start:g} → {stop:g} mm ({plant.value})",
                       start=start * 1e-3 if plant is Plant.cylinder else None)


@control_app.command("profile")
def profile_command(
    ctx: typer.Context,
    profile: Annotated[Path, typer.Argument(
        help="CSV with 'time [s]' and a position column ('reference' or 'position', unit "
             "in the header, e.g. 'position [mm]').", exists=False)],
    column: Annotated[str | None, typer.Option(
        help="The set-point column (default: reference, else position).")] = None,
    plant: PlantOption = Plant.regulator,
    valves: PlantValvesOption = CYLINDER_VALVES,
    params: ParamsOption = "vgt-paper",
    friction: FrictionOption = Friction.lugre,
    controller: ControllerOption = Structure.pid,
    kp: KpOption = None, ki: KiOption = None, kd: KdOption = 0.0,
    derivative: DerivativeOption = "measurement", filter_time: FilterOption = 1e-3,
    kx: KxOption = 50.0, kv: KvOption = 1e4,
    u_min: UMinOption = None, u_max: UMaxOption = None,
    anti_windup: AntiWindupOption = "back-calculation", tracking_time: TrackingOption = None,
    sample_time: SampleOption = None, velocity_estimate: VelocityEstimateOption = "measured",
    coulomb_ff: CoulombOption = None, dither: DitherOption = None,
    observer: ObserverOption = False, observer_gain: ObserverGainOption = 0.0,
    rtol: RtolOption = 1e-6,
    load_step: PlantLoadStepOption = None,
    out: OutOption = Path("pneumact-control-profile"),
) -> None:
    """Follow a measured or designed position profile (piecewise linear between its
    samples); with --load-step, the plant (the cylinder's rod, the actuator's diaphragm)
    loaded by a force step on the way."""
    with user_errors():
        import numpy as np

        from pneumact.errors import DataError
        from pneumact.experiments import SetpointProfile
        from pneumact.io import read_record

        record = read_record(profile)
        name = column or next((c for c in ("reference", "position") if c in record), None)
        if name is None or name not in record:
            raise DataError(f"{profile}: no set-point column {column or 'reference/position'}"
                            f"; columns: {', '.join(record.signals)}")
        if record.units.get(name) != "m":
            raise DataError(f"{profile}: column '{name}' has unit "
                            f"'{record.units.get(name)}'; give it a length unit in the "
                            f"header, e.g. '{name} [mm]'")
        out = check_out_dir("--out", out)
        positions = _within_stroke(plant, params, profile.name, record[name])
        experiment = SetpointProfile(record.time, positions, name=profile.name)
        load = _load_step(plant, load_step, experiment)
        _check_setpoints(plant, params, **{
            f"{profile.name}: lowest set-point": float(np.min(positions)) * 1e3,
            f"{profile.name}: highest set-point": float(np.max(positions)) * 1e3})
        options = _options(ctx)
        _, loop = build_loop(plant, params, friction, options, float(positions[0]),
                             load=load, valves=valves)
        _run_and_write(ctx, loop, experiment, out, rtol,
                       f"Position profile {profile.name} ({plant.value})", tracking=True,
                       start=float(positions[0]) if plant is Plant.cylinder else None)


@control_app.command("hunting")
def hunting_command(
    ctx: typer.Context,
    kp: Annotated[float, typer.Option(help="Kp [N/m].")] = 3.0,
    ki: Annotated[float, typer.Option(help="Ki [N/(m·s)].")] = 4.0,
    kv: Annotated[float, typer.Option(help="Kv [N·s/m] (on the measured velocity).")] = 6.0,
    position_setpoint: Annotated[float, typer.Option(
        "--position-setpoint", help="Set-point xd [m].")] = 1.0,
    t_end: Annotated[float, typer.Option(help="Duration [s].")] = 100.0,
    params: ParamsOption = "canudas1995",
    sample_time: SampleOption = None,
    rtol: RtolOption = 1e-6,
    out: OutOption = Path("pneumact-hunting"),
) -> None:
    """Canudas de Wit et al. (1995): a unit mass with LuGre friction under
    u = −Kv·v − Kp·(x − xd) − Ki·∫(x − xd) dt hunts around the set-point."""
    with user_errors():
        from pneumact.control.study import canudas_hunting

        out = check_out_dir("--out", out)
        loop, experiment = canudas_hunting(load_quietly(params), kp=kp, ki=ki, kv=kv,
                                           position_setpoint=position_setpoint, t_end=t_end,
                                           sample_time=sample_time)
        _run_and_write(ctx, loop, experiment, out, rtol,
                       "Hunting (Canudas de Wit et al. 1995)")


@control_app.command("tune")
def tune_command(
    ctx: typer.Context,
    spec: Annotated[str, typer.Option(
        help="Specifications, comma-separated: settling=0.3 (s), rise=…, overshoot=5% "
             "(of the step), error=20um (steady state), no-hunting, effort=…, "
             "variation=…, band=2%, fraction=95% (of the uncertainty samples).")
    ] = "settling=0.3,overshoot=5%,error=20um,no-hunting",
    plant: PlantOption = Plant.regulator,
    valves: PlantValvesOption = CYLINDER_VALVES,
    params: ParamsOption = "vgt-paper",
    friction: FrictionOption = Friction.lugre,
    kp: KpOption = None, ki: KiOption = None,
    kd: Annotated[float, typer.Option(help="Starting derivative gain (0: a PID tunes kd "
                                           "from Td = 2 ms).")] = 0.0,
    filter_time: FilterOption = 1e-3,
    u_min: UMinOption = None, u_max: UMaxOption = None,
    sample_time: SampleOption = None,
    gains: Annotated[str | None, typer.Option(
        help="The gains to tune, comma-separated, e.g. kp,ki,kd (default: kp, ki, and kd "
             "when --kd is given).")] = None,
    at: Annotated[float | None, typer.Option(
        help="Position the moves start from [mm] (default mid-stroke).")] = None,
    uncertainty: Annotated[Path | None, typer.Option(
        help="CSV of plant parameter samples (one column per parameter, SI): the design "
             "must hold over them.")] = None,
    gain_spread: Annotated[float, typer.Option(
        help="Search box: each gain's start ×/÷ this.")] = 30.0,
    n_global: Annotated[int, typer.Option(help="Gain vectors of the global search.")] = 64,
    max_evaluations: Annotated[int, typer.Option(
        help="Evaluations of each local search.")] = 40,
    rounds: Annotated[int, typer.Option(help="Robust rounds (samples added).")] = 2,
    margin: Annotated[float, typer.Option(
        help="Aim at limits this fraction tighter.")] = 0.05,
    seed: Annotated[int, typer.Option(help="Seed of the global search.")] = 0,
    workers: WorkersOption = None, scheduler: SchedulerOption = None,
    out: OutOption = Path("pneumact-control-tune"),
) -> None:
    """Tune the controller's gains on the nonlinear loop to meet --spec on four
    reference moves (a small step, steps up and down across break-away, a ramp), over
    the --uncertainty samples; write gains.toml (for 'control step --gains-file'), the
    metrics, their spread, the figure and a report."""
    with user_errors():
        import pandas as pd

        from pneumact.control import Specs, default_moves, tune
        from pneumact.errors import DataError

        out = check_out_dir("--out", out)
        specs = Specs.parse(spec)
        names = None if gains is None else [n.strip() for n in gains.split(",")
                                            if n.strip()]
        executor = executor_of(workers, scheduler)
        samples = None
        if uncertainty is not None:
            try:
                samples = pd.read_csv(uncertainty)
            except (OSError, ValueError) as exc:
                raise DataError(f"--uncertainty {uncertainty}: cannot read it as a CSV "
                                f"({exc})") from None
        options = ControllerOptions(Structure.pid, kp, ki, kd, "measurement", filter_time,
                                    50.0, 1e4, u_min, u_max, "back-calculation", None,
                                    sample_time, "measured", None, None, False, 0.0)
        if at is not None:
            _check_setpoints(plant, params, **{"--at": at})
        start = None if at is None else at * 1e-3
        _, loop = build_loop(plant, params, friction, options,
                             start if start is not None else _mid(plant, params),
                             valves=valves)
        moves = default_moves(loop, specs, start)
        result = run_with_progress(lambda report: tune(
            loop, specs, moves=moves, gains=names, uncertainty=samples, spread=gain_spread,
            n_global=n_global, max_evaluations=max_evaluations, rounds=rounds,
            margin=margin, seed=seed, executor=executor, progress=report))
        use_agg()
        written = result.write(out, call=the_call(ctx))
        _print_gains(result)
        out_console.print(result.feasibility())
        for path in written:
            out_console.print(f"wrote {path}")
    if not result.meets_specs:  # written, said, and told by the exit code too
        raise typer.Exit(EXIT_SPECS_NOT_MET)


@control_app.command("compare")
def compare_command(
    ctx: typer.Context,
    spec: Annotated[str, typer.Option(
        help="Specifications, as for 'control tune' (settling, overshoot, error, "
             "no-hunting, band).")] = "settling=0.3,overshoot=5%,error=20um,no-hunting",
    plant: PlantOption = Plant.regulator,
    valves: PlantValvesOption = CYLINDER_VALVES,
    params: ParamsOption = "vgt-paper",
    friction: FrictionOption = Friction.lugre,
    u_min: UMinOption = None, u_max: UMaxOption = None,
    at: Annotated[float | None, typer.Option(
        help="Operating point and the moves' start [mm] (default mid-stroke).")] = None,
    regime: Annotated[Regime, typer.Option(
        help="The linearisation: sliding (at the speed of a 20 %-of-stroke move within "
             "the settling spec) or presliding.")] = Regime.sliding,
    velocity: Annotated[float | None, typer.Option(
        help="Sliding: the speed of the linearisation [mm/s] (default 20 % of the stroke "
             "over the settling spec).")] = None,
    tuned: Annotated[Path | None, typer.Option(
        help="A gains file (from 'control tune') to run beside the linear designs.")] = None,
    out: OutOption = Path("pneumact-control-compare"),
) -> None:
    """Design a PID on the linearised plant with python-control, then run it on the
    nonlinear loop as it is and with static, dither and LuGre-observer friction
    compensation (and the --tuned gains): which design meets --spec on the reference
    moves and what breaks (hunts, sticks short, creeps, overshoots); write the tables,
    the responses, the Bode plot, linear_gains.toml and a report."""
    with user_errors():
        from pneumact.control import Specs

        out = check_out_dir("--out", out)
        specs = Specs.parse(spec)
        if at is not None:
            _check_setpoints(plant, params, **{"--at": at})
        start = _mid(plant, params) if at is None else at * 1e-3
        options = ControllerOptions(Structure.pid, None, None, 0.0, "measurement", 1e-3,
                                    50.0, 1e4, u_min, u_max, "back-calculation", None, None,
                                    "measured", None, None, False, 0.0)
        _, loop = build_loop(plant, params, friction, options, start, valves=valves)
        if velocity is not None:
            check_range("--velocity", velocity, 0.0, unit="mm/s", low_open=True)
        speed = None if velocity is None else velocity * 1e-3
        extra = None
        if tuned is not None:
            from pneumact.control import load_gains

            extra = (f"tuned ({tuned.name})", load_gains(tuned))
        comparison = run_with_progress(lambda report: _compare(
            loop, specs, start, regime.value, speed, extra))
        use_agg()
        written = comparison.write(out, call=the_call(ctx))
        _print_comparison(comparison)
        for path in written:
            out_console.print(f"wrote {path}")


def _compare(loop, specs, start: float, regime: str, velocity: float | None, tuned):
    """The linear PID with each friction compensation, and ``tuned`` (name, controller)
    if given, on the nonlinear loop."""
    from pneumact.control import compare_designs, friction_designs, linear_design

    linear = linear_design(loop, specs, at=start, regime=regime, velocity=velocity)
    designs = dict(friction_designs(linear))
    if tuned is not None:
        designs[tuned[0]] = tuned[1]
    return compare_designs(loop, specs, designs, at=start, linear=linear)


def _print_comparison(comparison) -> None:
    table = Table(title=f"on the nonlinear loop: {comparison.specs.describe()}")
    for column in ("design", "moves met", "what broke"):
        table.add_column(column)
    for _, row in comparison.summary().iterrows():
        table.add_row(str(row["design"]), f"{row['moves met']} of {row['moves']}",
                      str(row["what broke"]))
    out_console.print(table)


def _mid(plant: Plant, params_name: str) -> float:
    return 0.0 if plant is Plant.rig else 0.5 * float(plant_params(plant, params_name)["x_max"])


def _print_gains(result) -> None:
    from pneumact.cli.common import fmt

    table = Table(title=f"tuned: specs met on {100 * result.met:.0f} % of "
                        f"{len(result.samples)} samples")
    for column in ("gain", "value", "unit", "datasheet value", "datasheet unit"):
        table.add_column(column)
    for _, row in result.gains_table().iterrows():
        table.add_row(str(row["gain"]), fmt(float(row["value"]), 4), str(row["unit"]),
                      fmt(float(row["datasheet value"]), 4), str(row["datasheet unit"]))
    out_console.print(table)

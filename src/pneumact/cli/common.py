"""What every command shares: consoles, one-line errors, atomic multi-file output,
progress display, and the options that build a model and its experiment.

``simulate``, ``simulate-batch`` (and the commands that come after them) take the same
``--params --valve --friction --decaying-damping --elements --chamber --exponent --t-end --low
--input-csv --rtol`` options,
defined once here (``ModelOptions``) and turned into library objects by one function
(``build_model``, ``build_experiment``). Nothing here imports numpy, pandas or numba at
module level: a command pays for what it uses.
"""

from __future__ import annotations

import contextlib
import logging
import math
import os
import warnings
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from enum import StrEnum
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, cast

import typer
from rich.console import Console
from rich.text import Text

from pneumact.checks import check_int, check_names, check_range
from pneumact.errors import ArgumentError, ExperimentError, PassivityWarning, PneumactError
from pneumact.models.friction import GMS, LuGre
from pneumact.models.pneumatics import Polytropic
from pneumact.models.valves import PressureSource

#: Exit code of a user's mistake (bad option, bad file, invalid parameters); also that of
#: ``params check`` when the file is not valid.
EXIT_USER_ERROR = 2
EXIT_CHECK_FAILED = EXIT_USER_ERROR
#: Exit code of a failure that is pneumact's own (a bug): one line, no traceback unless
#: PNEUMACT_TRACEBACK=1.
EXIT_INTERNAL_ERROR = 1
#: Exit code after Ctrl-C (128 + SIGINT).
EXIT_INTERRUPTED = 130
#: Default experiment: the slow triangular cycle of the paper's Figs. 5-6, from the set's
#: p_atm down to this pressure [Pa abs] and back in this period [s] (or 0 → 1 → 0 for a
#: command valve).
DEFAULT_LOW_PRESSURE = 20e3
DEFAULT_PERIOD = 20.0
COMPILING = "compiling kernel (first use; cached afterwards)"
#: a progress bar's label until the first report: the runs are being prepared (a large
#: sample drawn, the kernel compiled on its first use: not only compiling)
STARTING = "preparing the runs (compiling the kernel on its first use)"
#: progress stages that are the whole run: a bar shows the command's label alone
WHOLE_RUN_STAGES = ("simulate", "batch", "fit", "validate")

out_console = Console(highlight=False)
err_console = Console(stderr=True, highlight=False)


class Valve(StrEnum):
    source = "source"
    command = "command"
    regulator = "regulator"
    iso6358 = "iso6358"


def command_driven(valve: Valve) -> bool:
    """Whether ``--valve`` names a valve its command u drives (command, iso6358)."""
    from pneumact.models import VALVES

    return VALVES[valve.value].drive == "command"


class Chamber(StrEnum):
    """The chamber laws (``pneumact.models``): Isothermal, Adiabatic, Polytropic, and the
    cylinder's HeatTransfer (its chambers' energy equations, temperatures as states)."""

    isothermal = "isothermal"
    adiabatic = "adiabatic"
    polytropic = "polytropic"
    heat_transfer = "heat-transfer"


def _friction_choices() -> type[StrEnum]:
    """The ``--friction`` choices: every law the friction module registers."""
    from pneumact.models.friction import friction_models

    members = {name.replace("-", "_"): name for name in friction_models()}
    return cast("type[StrEnum]", StrEnum("Friction", members))


if TYPE_CHECKING:
    from pneumact.progress import Progress as ProgressReport
    from pneumact.progress import ProgressCallback

    class Friction(StrEnum):
        """The choices as mypy sees them: built at run time from the registered laws, so
        only the one the commands name (their default) is declared."""

        lugre = "lugre"
else:
    Friction = _friction_choices()

ParamsOption = Annotated[str, typer.Option(
    "--params", help="Parameter set: a shipped name or a .toml file.")]
ValveOption = Annotated[Valve, typer.Option(
    help="source: prescribed pressure; command: valve command u in [0, 1]; regulator: "
         "pressure set-point; iso6358: the command valve with ISO 6358 flows (iso_C_res, "
         "iso_C_atm, iso_b, iso_m).")]
FrictionOption = Annotated[Friction, typer.Option(help="Friction model.")]
ChamberOption = Annotated[Chamber, typer.Option(
    help="Chamber gas law (behind a valve); heat-transfer: the cylinder's chambers with "
         "their energy equations and the wall's heat transfer (heat_transfer_coefficient).")]
ExponentOption = Annotated[float, typer.Option(
    help="Polytropic exponent n of --chamber polytropic, between 1 (isothermal) and γ.")]
DecayingDampingOption = Annotated[bool, typer.Option(
    "--decaying-damping", help="LuGre: σ1(v) = σ1·exp(−(v/vs)²) instead of a constant "
                               "σ1.")]
ElementsOption = Annotated[int | None, typer.Option(
    "--elements", help="GMS: the number of blocks (default 4; the set carries gms_k1.., "
                       "gms_nu1.. and gms_C).")]
TEndOption = Annotated[float | None, typer.Option(
    "--t-end", help="Duration [s]: the period of the default cycle (default 20), or where "
                    "to stop the input.")]
LowOption = Annotated[float | None, typer.Option(
    "--low", help="Lowest pressure of the default pressure cycle [kPa abs] (default 20; "
                  "not with --valve command, iso6358 or --input-csv).")]
InputOption = Annotated[Path | None, typer.Option(
    "--input-csv", help="CSV with time and an input signal (e.g. 'pressure [kPa]'); "
                        "--model cylinder: time, spool and optionally 'load [kN]' (other "
                        "columns ignored).")]
RtolOption = Annotated[float, typer.Option(help="Relative tolerance of the solver.")]
# the options of pneumact.options.Executor and Checkpoint (their defaults are the
# objects'), shared by every command that runs batches
SchedulerOption = Annotated[str | None, typer.Option(help="Dask scheduler address.")]
WorkersOption = Annotated[int | None, typer.Option(
    help="Local threads, >= 1 (default all cores).")]
ChunkSizeOption = Annotated[int | None, typer.Option(
    "--chunk-size", help="Runs per task (default: about four tasks per worker).")]
ResumeOption = Annotated[bool, typer.Option(
    "--resume", help="Continue the runs kept in the output directory after an interruption.")]
OverwriteOption = Annotated[bool, typer.Option(
    "--overwrite", help="Start the runs kept in the output directory again.")]

#: the defaults of the model options: the library's own
DEFAULT_VALVE = Valve(PressureSource.cli_name)
DEFAULT_FRICTION = Friction(LuGre.cli_name)
DEFAULT_DECAYING_DAMPING: bool = LuGre.decaying_damping
DEFAULT_EXPONENT: float = Polytropic.exponent


@dataclass(frozen=True)
class ModelOptions:
    """The model and experiment options of a command, as given."""

    params: str = "vgt-paper"
    valve: Valve = DEFAULT_VALVE
    friction: str = DEFAULT_FRICTION
    chamber: Chamber = Chamber.isothermal
    t_end: float | None = None
    low_kpa: float | None = None
    input_csv: Path | None = None
    rtol: float = 1e-6
    exponent: float = DEFAULT_EXPONENT
    decaying_damping: bool = DEFAULT_DECAYING_DAMPING
    elements: int | None = None
    spool_lag: int = 0
    load_step: str | None = None
    valves: str = "5/3"


def executor_of(workers: int | None, scheduler: str | None, chunk_size: int | None = None):
    """The ``Executor`` of --workers, --scheduler and --chunk-size (checked by it, the
    message naming the options)."""
    from pneumact.options import Executor

    for option, value in (("--workers", workers), ("--chunk-size", chunk_size)):
        if value is not None:
            check_int(option, value, minimum=1)
    if scheduler is not None:
        from pneumact.options import check_scheduler_address

        check_scheduler_address(scheduler, "--scheduler")
    return Executor(workers=workers, scheduler=scheduler, chunk_size=chunk_size)


def checkpoint_of(folder: Path, resume: bool, overwrite: bool):
    """The ``Checkpoint`` of --out, --resume and --overwrite."""
    from pneumact.options import Checkpoint

    if resume and overwrite:
        raise ArgumentError("--resume and --overwrite contradict each other: continue the "
                            "kept runs, or start them again; give one")
    return Checkpoint(folder, resume=resume, overwrite=overwrite)


def load_quietly(name: str):
    """A parameter set (its passivity warning belongs to ``params show/check`` and the
    reports: ``user_errors`` hides it from the other commands)."""
    import pneumact as pa

    return pa.load_params(name)


def check_model_options(options: ModelOptions) -> None:
    """Refuse options that would do nothing with the others given."""
    if options.chamber is not Chamber.isothermal and options.valve is Valve.source:
        raise ArgumentError(
            f"--chamber {options.chamber.value} has no effect with --valve source: the "
            "pressure is prescribed, so the chamber's gas law never enters; drop --chamber, "
            "or drive a valve (--valve command or regulator)")
    if options.exponent != DEFAULT_EXPONENT and options.chamber is not Chamber.polytropic:
        raise ArgumentError(f"--exponent {options.exponent:g} is the exponent of --chamber "
                            f"polytropic, not of --chamber {options.chamber.value}")
    if options.decaying_damping and str(options.friction) != LuGre.cli_name:
        raise ArgumentError(f"--decaying-damping is an option of --friction lugre, not of "
                            f"--friction {options.friction}")
    if options.low_kpa is not None:
        if options.input_csv is not None:
            raise ArgumentError("--low sets the default pressure cycle, which --input-csv "
                                "replaces; drop one of them")
        if command_driven(options.valve):
            raise ArgumentError("--low sets the lowest pressure of the default pressure "
                                f"cycle; with --valve {options.valve.value} the default "
                                "cycle is the command 0 -> 1 -> 0, which has no pressure "
                                "to set")
    if options.t_end is not None:
        check_range("--t-end", options.t_end, 0.0, unit="s", low_open=True)
    check_range("--rtol", options.rtol, 1e-14, 1.0, high_open=True)


#: where the cylinder runs on the command line (the hint of ``refuse_cylinder_set``)
CYLINDER_COMMANDS = ("--model cylinder (simulate, simulate-batch, fit, sensitivity, export "
                     "fmu) or --plant cylinder (control step, profile, tune, compare)")


def refuse_cylinder_set(params, what: str = "this command models the diaphragm actuator"):
    """A double-acting cylinder's set (a bore, no diaphragm) given where the diaphragm
    actuator is modelled: one line saying where the cylinder runs instead."""
    if "D_bore" in params and "A_d" not in params:
        raise ArgumentError(f"--params {params.name}: a double-acting cylinder's set (bore "
                            f"D_bore, no diaphragm area A_d); {what}: give a diaphragm's "
                            f"set (vgt-paper), or run the cylinder with {CYLINDER_COMMANDS}")


def build_model(options: ModelOptions, params=None):
    """(parameter set, Actuator) the options describe."""
    from pneumact.models import VALVES, Actuator

    if options.valves != ModelOptions.valves:
        raise ArgumentError(f"--valves {options.valves} is the cylinder's valving (--model "
                            "cylinder); the diaphragm actuator has its --valve: drop --valves")
    if options.spool_lag != 0:
        raise ArgumentError(f"--spool-lag {options.spool_lag} is the cylinder's 5/3 valve's "
                            "spool (--model cylinder); the diaphragm actuator's valves have "
                            "no spool: drop --spool-lag")
    check_model_options(options)
    params = load_quietly(options.params) if params is None else params
    refuse_cylinder_set(params)
    friction = friction_of(options)
    _check_friction_parameters(friction, params, options)
    return params, Actuator(params, friction=friction, valve=VALVES[options.valve.value](),
                            chamber=build_chamber(options.chamber, options.exponent))


class ModelKind(StrEnum):
    """The model kinds a command builds (--model)."""

    actuator = "actuator"
    cylinder = "cylinder"


ModelOption = Annotated[ModelKind, typer.Option(
    "--model", help="actuator: the diaphragm actuator behind --valve; cylinder: the "
                    "double-acting cylinder behind its 5/3 valve or two 3/2 valves "
                    "(--valves; --params default iso15552-32, a spool step from -1 to 0.5 "
                    "at 0.1 s).")]
ValvesOption = Annotated[str, typer.Option(
    "--valves", help="--model cylinder: 5/3 (one 5/3 valve, its spool command) or two-3/2 "
                     "(a proportional 3/2 valve per chamber, inputs command_a and command_b; "
                     "by default command_a steps from -1 to 0.5 at 0.1 s and command_b "
                     "mirrors it, from 1 to -0.5: the spool step's equivalent).")]
SpoolLagOption = Annotated[int, typer.Option(
    "--spool-lag", help="--model cylinder: the 5/3 valve's spool dynamics, 0 (it follows "
                        "its command), 1 (a first-order lag, spool_tau) or 2 (second "
                        "order, spool_omega and spool_zeta).")]


def build_model_of(kind: ModelKind, options: ModelOptions):
    """(parameter set, model, experiment) of --model: the actuator (``build_model``,
    ``build_experiment``) or the cylinder (``build_cylinder``, ``cylinder_experiment``)."""
    if kind is ModelKind.cylinder:
        params, model = build_cylinder(options)
        experiment = cylinder_experiment(options, params, model)
        return params, with_load_step(model, experiment, options), experiment
    params, model = build_model(options)
    experiment = build_experiment(options, params)
    return params, with_load_step(model, experiment, options), experiment


#: the parameter set of ``--model cylinder`` when --params keeps the actuator's default
CYLINDER_SET = "iso15552-32"
#: the default spool step's duration [s] (the spool steps at 0.1 s)
CYLINDER_T_END = 1.0
#: the default spool step: (before, after, t_step [s]); command_b mirrors it with two
#: 3/2 valves
SPOOL_STEP = (-1.0, 0.5, 0.1)


def build_cylinder(options: ModelOptions, params=None):
    """(parameter set, Cylinder) the options describe: --params (iso15552-32 in place of
    the actuator's default set), the friction and chamber laws; its own 5/3 valve."""
    from dataclasses import replace

    from pneumact.models import Cylinder

    if options.valve is not DEFAULT_VALVE:
        raise ArgumentError(f"--valve {options.valve.value} is the actuator's valve; --model "
                            "cylinder has its own 5/3 valve (a spool command u in [-1, 1]): "
                            "drop --valve")
    if options.low_kpa is not None:
        raise ArgumentError("--low is the actuator's pressure cycle; --model cylinder steps "
                            "its valve's spool: drop --low")
    check_model_options(replace(options, valve=Valve.command))  # a valve feeds its chambers
    name = CYLINDER_SET if options.params == ModelOptions.params else options.params
    params = load_quietly(name) if params is None else params
    friction = friction_of(options)
    _check_friction_parameters(friction, params, options)
    if options.spool_lag not in (0, 1, 2):
        raise ArgumentError(f"--spool-lag {options.spool_lag}: the spool's dynamics are of "
                            "order 0 (it follows its command), 1 (spool_tau) or 2 "
                            "(spool_omega, spool_zeta)")
    check_valves(options.valves)
    return params, Cylinder(params, friction=friction,
                            chamber=build_chamber(options.chamber, options.exponent, True),
                            spool_lag=options.spool_lag, valves=options.valves)


def check_valves(valves: str) -> None:
    """--valves one of the cylinder's valvings (``Cylinder``'s ``valves``)."""
    from pneumact.models.cylinder import VALVES_CHOICES

    if valves not in VALVES_CHOICES:
        raise ArgumentError(f"--valves {valves}: must be one of "
                            f"{', '.join(VALVES_CHOICES)} (one 5/3 valve, or a 3/2 valve "
                            "per chamber)")


def cylinder_experiment(options: ModelOptions, params, cylinder):
    """The input CSV (a spool column, or command_a and command_b with two 3/2 valves,
    optionally a load: the columns ``cylinder``'s inputs declare), or a spool step from -1
    to 0.5 at 0.1 s lasting --t-end (default 1 s); with two 3/2 valves its equivalent,
    command_a stepping so and command_b mirrored (from 1 to -0.5)."""
    import pneumact as pa

    if options.input_csv is not None:
        return build_experiment(options, params, cylinder)
    t_end = CYLINDER_T_END if options.t_end is None else options.t_end
    before, after, t_step = SPOOL_STEP
    step = pa.experiments.SpoolStep(before, after, t_step, t_end=t_end)
    if not cylinder.two_valves:
        return step
    return pa.Experiment(step.drive, "command_a", t_end, n_points=step.n_points,
                         name="SpoolStep (two 3/2 valves, mirrored)", drives={
                             "command_b": pa.experiments.Step(t_step, -before, -after)})


#: what --load-step does to each model, said once for both options' help
_LOAD_STEP_HELP = ("a load force stepping from 0 to FORCE [N] at TIME [s], given as FORCE,TIME "
                   "(e.g. 300,0.3), within +-1 MN: on the cylinder's rod, against extension "
                   "(FORCE > 0 pushes the rod in); on the diaphragm actuator, against larger "
                   "x as its spring is (FORCE > 0 moves its rest by -FORCE/k)")
LoadStepOption = Annotated[str | None, typer.Option(
    "--load-step", help=f"--model cylinder or actuator: {_LOAD_STEP_HELP}.")]
#: --load-step as the control commands word it (the plant's load, a disturbance)
PlantLoadStepOption = Annotated[str | None, typer.Option(
    "--load-step", help=f"--plant cylinder, regulator, command or source: {_LOAD_STEP_HELP}: "
                        "the loop's load-disturbance rejection.")]


def load_input_of(model):
    """The input channel a model declares (or would declare) for its load force: the
    cylinder's ``models.cylinder.LOAD_INPUT``, the diaphragm actuator's
    ``models.actuator.LOAD_INPUT`` (its range and rule the messages quote); ``model``: a
    model or its class."""
    from pneumact.models import Cylinder
    from pneumact.models.actuator import LOAD_INPUT as ACTUATOR_LOAD
    from pneumact.models.cylinder import LOAD_INPUT as CYLINDER_LOAD

    cylinder = model is Cylinder or isinstance(model, Cylinder)
    return CYLINDER_LOAD if cylinder else ACTUATOR_LOAD


def load_step_of(text: str, experiment, input_csv: Path | None = None, load_input=None):
    """The load step --load-step FORCE,TIME gives (``Cylinder.load``, ``Actuator.load``): a
    force [N] within the range of ``load_input`` (the model's load input, ``load_input_of``;
    default the cylinder's), from a time [s] within the run of ``experiment``, and no load
    column of ``input_csv`` (--input-csv) beside it."""
    from pneumact.core.signals import Step
    from pneumact.models.cylinder import LOAD_INPUT

    load_input = LOAD_INPUT if load_input is None else load_input
    parts = text.split(",")
    try:
        force, time = (float(part) for part in parts)
    except ValueError:
        raise ArgumentError(f"--load-step {text!r}: give FORCE,TIME, a force [N] and the time "
                            "[s] it steps on, e.g. 300,0.3") from None
    check_range("--load-step TIME", time, experiment.t_start, experiment.t_end, unit="s",
                low_open=True, high_open=True, hint="the load steps within the run")
    load_input.check(min(force, 0.0), max(force, 0.0), where=f"--load-step {text}")
    if load_input.name in experiment.drives:
        raise ArgumentError(f"--load-step {text} and the load column of --input-csv "
                            f"{input_csv} both drive the load; drop one")
    return Step(time, 0.0, force)


def refuse_load_step(text: str, plants: str) -> None:
    """--load-step given where no model with a load input runs: one line naming the
    options (``plants``) that run one."""
    raise ArgumentError(f"--load-step {text}: loads a cylinder's rod or a diaphragm "
                        f"actuator's diaphragm; give {plants}")


def with_load_step(model, experiment, options: ModelOptions):
    """``model`` (a Cylinder or an Actuator) loaded by --load-step (its ``load`` the step
    ``Step(TIME, 0, FORCE)``) where it is given, else as it is."""
    from dataclasses import replace

    if options.load_step is None:
        return model
    return replace(model, load=load_step_of(options.load_step, experiment,
                                            options.input_csv, load_input_of(model)))


def _check_friction_parameters(friction, params, options: ModelOptions) -> None:
    """A set without the law's own parameters (GMS's blocks) is refused naming the shipped
    sets that have them and everything the given set has."""
    import pneumact as pa
    from pneumact.parameters import catalogue

    missing = [name for name in friction.required
               if name not in params and catalogue()[name].default is None]
    if not missing:
        return
    needed = {*friction.required, *params}
    with warnings.catch_warnings():  # the shipped sets' own warnings are not the user's
        warnings.simplefilter("ignore")
        having = [name for name, _ in pa.available_params()
                  if needed <= set(load_quietly(name))]
    hint = f"; shipped sets that have them: {', '.join(having)} (--params)" if having else ""
    raise ArgumentError(f"--friction {options.friction}: parameter set {params.name!r} lacks "
                        f"{', '.join(missing)}{hint}; or add them to a copy of its .toml "
                        f"file (pneumact params show {params.name} lists its values)")


def friction_of(options: ModelOptions):
    """The friction law --friction, --decaying-damping and --elements name."""
    from pneumact.models import friction_models

    law = friction_models()[str(options.friction)]
    if options.elements is not None and law is not GMS:
        raise ArgumentError(f"--elements is an option of --friction gms, not of "
                            f"--friction {options.friction}")
    if options.decaying_damping:
        return law(decaying_damping=True)  # type: ignore[call-arg]
    if options.elements is not None:
        return law(n_elements=options.elements)  # type: ignore[call-arg]
    return law()


def build_chamber(chamber: Chamber, exponent: float = DEFAULT_EXPONENT,
                  cylinder: bool = False):
    """The chamber law --chamber (and --exponent) name; heat transfer for the cylinder's
    chambers only (``cylinder``)."""
    from pneumact.models import Adiabatic, HeatTransfer, Isothermal, Polytropic

    if chamber is Chamber.heat_transfer:
        if not cylinder:
            raise ArgumentError("--chamber heat-transfer: only the cylinder's chambers carry "
                                "a gas temperature (--model cylinder); the "
                                "diaphragm actuator's chamber is isothermal, adiabatic or "
                                "polytropic")
        return HeatTransfer()
    if chamber is Chamber.polytropic:
        return Polytropic(exponent)
    return Adiabatic() if chamber is Chamber.adiabatic else Isothermal()


def build_experiment(options: ModelOptions, params, model=None):
    """The experiment the options describe: the input CSV (its columns the ones ``model``'s
    inputs declare, where given), or the default slow cycle (pressure p_atm → low → p_atm,
    or command 0 → 1 → 0 for a command valve)."""
    import pneumact as pa

    if options.input_csv is not None:
        experiment = pa.experiments.from_csv(options.input_csv, p_atm=params["p_atm"],
                                             model=model)
        if options.t_end is not None:
            if options.t_end > experiment.t_end:
                raise ExperimentError(
                    f"--t-end = {options.t_end:g} s is beyond the input data, which ends at "
                    f"{experiment.t_end:g} s; give --t-end <= {experiment.t_end:g}")
            experiment = experiment.with_duration(options.t_end)
        return experiment
    period = DEFAULT_PERIOD if options.t_end is None else options.t_end
    if command_driven(options.valve):
        return pa.CommandCycle(0.0, 1.0, period=period)
    p_atm_kpa = params["p_atm"] * 1e-3
    low = DEFAULT_LOW_PRESSURE * 1e-3 if options.low_kpa is None else options.low_kpa
    looks_pa = math.isfinite(low) and 0.0 < low * 1e-3 < p_atm_kpa <= low
    hint = (f"{low:g} looks like Pa; the option is in kPa: --low {low * 1e-3:g}" if looks_pa
            else f"absolute, below the set's p_atm = {p_atm_kpa:g} kPa")
    check_range("--low", low, 0.0, p_atm_kpa, unit="kPa", low_open=True, high_open=True,
                hint=hint)
    return pa.PressureCycle(high=params["p_atm"], low=low * 1e3, period=period)


# --------------------------------------------------------------------------- plumbing
def plain_message(message: str) -> str:
    """A message as a person reads it: numpy's reprs of numbers (``np.float64(nan)``,
    ``np.int64(3)``) written as the numbers."""
    import re

    return re.sub(r"np\.(?:float|int|uint|bool|complex)_?\d*\(([^()]*)\)", r"\1", message)


def print_error(message: str, prefix: str = "error") -> None:
    err_console.print(Text(f"{prefix}: {plain_message(message)}", style="red"),
                      soft_wrap=True)


def _print_warning(message: warnings.WarningMessage) -> None:
    text = plain_message(f"warning: {message.category.__name__}: {message.message}")
    err_console.print(Text(text, style="yellow"), soft_wrap=True)


def _flush_warnings(caught: list[warnings.WarningMessage]) -> None:
    seen = set()
    for message in caught:
        key = (message.category, str(message.message))
        if key not in seen and not issubclass(message.category, DeprecationWarning):
            seen.add(key)
            _print_warning(message)
    caught.clear()


#: what a Ctrl-C keeps, said in the "stopped" line of a command that resumes nothing
KEPT_AS_IT_WAS = ("nothing new was written; an output folder from an earlier run is kept "
                  "as it was")
#: ... and of one whose finished runs are kept (a batch, a global sensitivity study)
KEPT_FOR_RESUME = ("the runs finished so far are kept: run the same command with --resume "
                   "to continue")


@contextlib.contextmanager
def user_errors(code: int = EXIT_USER_ERROR, *, passivity: bool = False,
                kept: str = KEPT_AS_IT_WAS) -> Iterator[None]:
    """Warnings -> yellow lines (the passivity of a set only with ``passivity``: that is
    for ``params show/check``); a pneumact error or a bad path -> one red line, exit
    ``code``; Ctrl-C -> one line saying what is ``kept``, exit 130; anything else is
    pneumact's own failure: one line saying so, exit 1 (the traceback with
    PNEUMACT_TRACEBACK=1)."""
    passthrough = (typer.Exit, typer.Abort, typer.TyperException)

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        if not passivity:
            warnings.simplefilter("ignore", PassivityWarning)
        try:
            yield
        except passthrough:  # typer's own exits and usage errors
            raise
        except PneumactError as exc:
            _flush_warnings(caught)
            print_error(exc.for_cli())
            raise typer.Exit(code) from None
        except OSError as exc:  # missing input file, output directory not writable, ...
            _flush_warnings(caught)
            print_error(str(exc))
            raise typer.Exit(code) from None
        except MemoryError as exc:
            _flush_warnings(caught)
            print_error(f"not enough memory ({str(exc) or 'the run is too large'}); keep fewer "
                        "output points or a shorter run")
            raise typer.Exit(code) from None
        except KeyboardInterrupt:
            _flush_warnings(caught)
            print_error(f"interrupted; {kept}", prefix="stopped")
            raise typer.Exit(EXIT_INTERRUPTED) from None
        except Exception as exc:
            _flush_warnings(caught)
            if os.environ.get("PNEUMACT_TRACEBACK"):
                raise
            text = exc.args[0] if isinstance(exc, KeyError) and exc.args else exc  # no quotes
            print_error(f"{type(exc).__name__}: {text} (this is a bug in pneumact, not a "
                        "mistake of yours: please report it with the command; "
                        "PNEUMACT_TRACEBACK=1 shows where it happened)",
                        prefix="internal error")
            raise typer.Exit(EXIT_INTERNAL_ERROR) from None
    _flush_warnings(caught)


def use_agg() -> None:
    """Render off-screen: the CLI only writes PNG files."""
    import matplotlib

    matplotlib.use("Agg")


def write_outputs(out_dir: Path, writers: dict[str, Callable[[Path], Any]]) -> list[Path]:
    """All files or none: see ``pneumact.io.tables.write_files``."""
    from pneumact.io.tables import write_files

    return write_files(out_dir, writers)


def figure_writer(make):
    """``pneumact.plotting.figure_writer``, imported only when a command writes a figure
    (numpy and matplotlib stay out of the command line's start-up)."""
    from pneumact.plotting import figure_writer as writer

    return writer(make)


@contextlib.contextmanager
def progress_display(label: str = "", *, counts: bool = False, transient: bool = True,
                     bar_per_stage: bool = True) -> Iterator[ProgressCallback]:
    """The one adapter from ``pneumact.progress.Progress`` reports to rich progress bars:
    yields a ``progress`` callback for any public function. A spinner says the kernel is
    compiling until the first report; then one bar per stage (``label: stage``), done of
    total, or (``bar_per_stage=False``, for stages that are parts of one whole: the
    sections of a reproduction) one bar that names the current stage. ``counts``: the
    bar counts items (a batch's sets: ``done/total``, the failed ones and the rate of
    this session; reused chunks do not count) instead of a percentage.
    """
    import time

    from rich.progress import (
        BarColumn,
        MofNCompleteColumn,
        Progress,
        SpinnerColumn,
        TaskProgressColumn,
        TextColumn,
        TimeElapsedColumn,
    )

    columns: list[Any] = [SpinnerColumn(), TextColumn("{task.description}"), BarColumn()]
    if counts:
        columns += [MofNCompleteColumn(), TextColumn("failed {task.fields[failed]}"),
                    TextColumn("{task.fields[rate]} sims/s"), TimeElapsedColumn(),
                    TextColumn("left {task.fields[left]}")]
    else:
        columns += [TaskProgressColumn(), TimeElapsedColumn()]
    started = time.perf_counter()
    with Progress(*columns, console=err_console, transient=transient) as bar:
        waiting = bar.add_task(STARTING, total=None, failed=0, rate="-", left="-:--:--")
        tasks: dict[str, Any] = {}
        first: dict[str, float] = {}
        estimated: set[str] = set()
        first_chunk: dict[str, tuple[float, float]] = {}

        def update(report: ProgressReport) -> None:
            task = tasks.get(report.stage if bar_per_stage else "")
            if task is None:
                task = waiting if not tasks else bar.add_task("", total=None, failed=0,
                                                               rate="-", left="-:--:--")
                tasks[report.stage if bar_per_stage else ""] = task
            first.setdefault(report.stage, report.done)
            now = time.perf_counter()
            elapsed = now - started
            rate = (report.done - first[report.stage]) / elapsed if elapsed > 0 else 0.0
            # the steady rate: from the first finished chunk on (compiling excluded)
            if report.stage not in first_chunk and report.done > first[report.stage]:
                first_chunk[report.stage] = (now, report.done)
            since, done_then = first_chunk.get(report.stage, (now, report.done))
            steady = ((report.done - done_then) / (now - since)
                      if now - since >= STEADY_WINDOW_S else 0.0)
            shown = (report.stage if not label else label
                     if report.stage in WHOLE_RUN_STAGES else f"{label}: {report.stage}")
            # the time left at the rate measured in this session (reused chunks and a
            # burst of finished chunks do not count as speed)
            left = remaining_time(report.total - report.done, steady if steady > 0 else rate)
            if (steady > 0 and report.total > 1 and report.done < report.total
                    and report.stage not in estimated):  # sets, starts, points: not runs
                estimated.add(report.stage)
                logging.getLogger("pneumact.estimates").info(
                    "%s: %d of %d left; at the rate after the first (%.3g/s) about %s",
                    shown, report.total - report.done, report.total, steady, left)
            bar.update(task, description=shown, completed=report.done, total=report.total,
                       failed=report.failed, rate=f"{rate:.0f}", left=left)

        yield update


def run_with_progress(run: Callable[[ProgressCallback], Any], what: str = "simulating") -> Any:
    """Call ``run(progress)`` under ``progress_display(what)``."""
    with progress_display(what) as progress:
        return run(progress)


def batch_progress(label: str = "batch") -> contextlib.AbstractContextManager[ProgressCallback]:
    """``progress_display`` for the batch engine: counts sets, failed sets and the rate."""
    return progress_display(label, counts=True, transient=False)


def fit_with_progress(run: Callable[[ProgressCallback], Any]) -> Any:
    """Run a fit under ``progress_display("fitting")``: a bar per stage that reports
    (the fit, multistart starts, profile points)."""
    return run_with_progress(run, "fitting")


def the_call(ctx) -> str:
    """The command being run (``ctx``: its ``typer.Context``), as a line that can be
    pasted back: its path and every argument and option that differs from its default
    (from the parsed context, so it is right under a test runner too)."""
    import shlex

    words = ctx.command_path.split()
    for param in ctx.command.params:
        value = ctx.params.get(param.name)
        values = value if isinstance(value, list | tuple) else [value]
        if param.param_type_name == "argument":
            words += [str(v) for v in values]
        elif value not in (None, param.default, False) and value != []:
            flag = max(param.opts, key=len)
            if value is True:
                words.append(flag)
                continue
            for item in values:
                words += [flag, str(getattr(item, "value", item))]
    return " ".join(shlex.quote(w) for w in words)


def fmt(value: float | None, digits: int = 4) -> str:
    return "n/a" if value is None or not math.isfinite(value) else f"{value:.{digits}g}"


def names(text: str | None, option: str = "") -> list[str] | None:
    """A comma-separated list option as names (None if not given); a name given twice,
    or an option given as an empty list, is refused."""
    if text is None:
        return None
    items = [n.strip() for n in text.split(",") if n.strip()]
    if option:
        if not items:
            raise ArgumentError(f"{option} = {text!r}: give one or more names separated by "
                                "commas")
        check_names(option, items)
    return items


def shown_path(path: Path, stage: Path, out: Path) -> Path:
    """Where a file written into ``stage`` ends up once the run is swapped into ``out``."""
    try:
        return out / Path(path).relative_to(stage)
    except ValueError:
        return Path(path)


def given_options(ctx: typer.Context, *params: str) -> list[str]:
    """The options among ``params`` (parameter names) given on the command line, as the
    user typed them (``--f-scale``), in the order asked."""
    flags = []
    for name in params:
        source = ctx.get_parameter_source(name)
        if source is not None and source.name != "DEFAULT":
            flags.append("--" + name.replace("_", "-"))
    return flags


def refuse_unused(ctx: typer.Context, params: tuple[str, ...] | str, why: str,
                  fix: str = "leave it out") -> None:
    """Refuse the options among ``params`` given on the command line where they would do
    nothing (``why``: "with the linear loss"), one message naming them."""
    flags = given_options(ctx, *((params,) if isinstance(params, str) else params))
    if flags:
        verb = "does" if len(flags) == 1 else "do"
        raise ArgumentError(f"{', '.join(flags)} {verb} nothing {why}; {fix}")



class _NoteHandler(logging.Handler):
    """Prints the estimates big work logs before it starts (``pneumact.estimates``:
    memory, time) as ``note:`` lines on stderr, as they come."""

    def emit(self, record: logging.LogRecord) -> None:
        err_console.print(Text(f"note: {plain_message(record.getMessage())}",
                               style="yellow"), soft_wrap=True)


def show_estimates() -> None:
    """Let the estimates before big work reach the terminal (once per process)."""
    logger = logging.getLogger("pneumact.estimates")
    logger.setLevel(logging.INFO)
    if not any(isinstance(h, _NoteHandler) for h in logger.handlers):
        logger.addHandler(_NoteHandler())
        logger.propagate = False


#: seconds after the first finished chunk before its rate counts (the threads' first
#: chunks finish together: a burst, not a rate)
STEADY_WINDOW_S = 2.0


def remaining_time(left: float, rate: float) -> str:
    """``left`` items at ``rate`` per second as h:mm:ss ("-:--:--" without a rate)."""
    if not rate > 0 or not math.isfinite(left / rate):
        return "-:--:--"
    seconds = round(max(left, 0.0) / rate)
    return f"{seconds // 3600}:{seconds % 3600 // 60:02d}:{seconds % 60:02d}"

"""``pneumact export fmu``: the actuator (or ``--model cylinder``) as an FMI 2.0 or 3.0
FMU (Model Exchange, Co-Simulation or both)."""

from __future__ import annotations

from enum import StrEnum
from pathlib import Path
from typing import Annotated

import typer
from rich.table import Table

from pneumact.checks import check_out_dir, check_path
from pneumact.cli.common import (
    DEFAULT_DECAYING_DAMPING,
    DEFAULT_EXPONENT,
    DEFAULT_FRICTION,
    DEFAULT_VALVE,
    Chamber,
    ChamberOption,
    DecayingDampingOption,
    ElementsOption,
    ExponentOption,
    FrictionOption,
    ModelKind,
    ModelOption,
    ModelOptions,
    ParamsOption,
    SpoolLagOption,
    ValveOption,
    ValvesOption,
    build_model_of,
    out_console,
    user_errors,
)

export_app = typer.Typer(help="Export the actuator to the tools it goes into (FMI).",
                         no_args_is_help=True)

DEFAULT_NAME = "actuator.fmu"


class FmuKind(StrEnum):
    """The FMI interfaces of the FMU."""

    me = "me"
    cs = "cs"
    both = "both"


@export_app.command("fmu")
def export_fmu_command(
    params: ParamsOption = "vgt-paper",
    model: ModelOption = ModelKind.actuator,
    spool_lag: SpoolLagOption = 0,
    valves: ValvesOption = "5/3",
    valve: ValveOption = DEFAULT_VALVE,
    friction: FrictionOption = DEFAULT_FRICTION,
    decaying_damping: DecayingDampingOption = DEFAULT_DECAYING_DAMPING,
    elements: ElementsOption = None,
    chamber: ChamberOption = Chamber.isothermal,
    exponent: ExponentOption = DEFAULT_EXPONENT,
    out: Annotated[Path, typer.Option(
        help="The FMU file (…/name.fmu; its stem is the model identifier), or a folder to "
             f"write {DEFAULT_NAME} into (cylinder.fmu with --model cylinder, also in place "
             "of the default).")] = Path(DEFAULT_NAME),
    binary: Annotated[bool, typer.Option(
        "--binary/--no-binary",
        help="Build this platform's binary with the C compiler (the C sources are always "
             "inside).")] = True,
    compiler: Annotated[str | None, typer.Option(
        help="The C compiler to build the binary with (default: $CC, else cc, gcc, "
             "clang).")] = None,
    kind: Annotated[FmuKind, typer.Option(
        help="me: Model Exchange (the importer's solver integrates); cs: Co-Simulation (the "
             "FMU steps itself with pneumact's RODAS4, inputs held over each step); both.",
        case_sensitive=False)] = FmuKind.me,
    fmi: Annotated[int, typer.Option(
        min=2, max=3, help="The FMI version: 2 (2.0) or 3 (3.0).")] = 2,
) -> None:
    """Export the actuator (or --model cylinder) as an FMI 2.0 or 3.0 FMU (Simulink,
    Dymola, OpenModelica, GT-SUITE, FMPy), Model Exchange, Co-Simulation or both: inputs,
    every parameter, states and outputs."""
    with user_errors():
        from pneumact.export import export_fmu

        name = f"{model.value}.fmu"
        target = check_path("--out", Path(name) if out == Path(DEFAULT_NAME) else out)
        if target.suffix != ".fmu":  # a folder (refused at once if it is a file)
            target = check_out_dir("--out", target) / name
        options = ModelOptions(params=params, valve=valve, friction=friction, chamber=chamber,
                               exponent=exponent, decaying_damping=decaying_damping,
                               elements=elements, spool_lag=spool_lag, valves=valves)
        _, built, _ = build_model_of(model, options)
        fmu = export_fmu(built, target, binary=binary, compiler=compiler,
                         kind=FmuKind(kind).value, fmi=fmi)
        _print_summary(fmu)


def _print_summary(fmu) -> None:
    table = Table(title=f"pneumact export fmu: {fmu.identifier} ({fmu.kind}, FMI {fmu.fmi})",
                  show_header=True)
    table.add_column("causality")
    table.add_column("variables")
    for causality in ("input", "parameter", "output"):
        table.add_row(causality, ", ".join(fmu.names(causality)))
    table.add_row("event indicators", f"{fmu.event_indicators} (end stops"
                  + (f", {fmu.mode_switches} friction modes)" if fmu.mode_switches else ")"))
    table.add_row("binary", f"{fmu.platform} ({fmu.compiler})" if fmu.platform
                  else "none (sources only)")
    out_console.print(table)
    out_console.print(f"wrote {fmu.path}")

"""``pneumact validate RECORDS... --out DIR``: the model against measured records.

Each record drives the model the way it was made (``--input auto``, the default: its
logged set-point through the regulator, else its pressure as a pressure source, else
its command through the valve); ``--input model`` keeps the model's ``--valve``. With
``--train`` records and ``--free`` parameters, fits on the training records first and
validates on both sets, with the metrics side by side. Every record gets a verdict that
combines fit % with the loop measures and the residuals.
"""

from __future__ import annotations

from enum import StrEnum
from pathlib import Path
from typing import Annotated

import typer
from rich.table import Table
from rich.text import Text

from pneumact.checks import check_out_dir
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
    ModelOptions,
    ParamsOption,
    RtolOption,
    ValveOption,
    build_model,
    err_console,
    fit_with_progress,
    fmt,
    names,
    out_console,
    refuse_unused,
    the_call,
    use_agg,
    user_errors,
)
from pneumact.cli.identify import RecordsArgument
from pneumact.errors import ParameterError
from pneumact.models.inputs import DEFAULT_INPUT as DEFAULT_INPUT_NAME
from pneumact.models.inputs import INPUTS

#: The ``--input`` choices: how a record's input is chosen (auto, model, or a signal).
Input = StrEnum("Input", {name: name for name in INPUTS})  # type: ignore[misc]
DEFAULT_INPUT = Input(DEFAULT_INPUT_NAME)

VERDICT_STYLE = {"adequate": "green", "adequate, residuals not white": "yellow",
                 "inadequate": "red"}


def validate_command(
    ctx: typer.Context,
    records: RecordsArgument,
    params: ParamsOption = "vgt-paper",
    valve: ValveOption = DEFAULT_VALVE,
    input: Annotated[Input, typer.Option(
        help="auto: each record drives the valve it was made with (set-point: regulator, "
             "else pressure: source, else command: command); model: the --valve for all "
             "records; or the record signal that drives them.")] = DEFAULT_INPUT,
    friction: FrictionOption = DEFAULT_FRICTION,
    decaying_damping: DecayingDampingOption = DEFAULT_DECAYING_DAMPING,
    elements: ElementsOption = None,
    chamber: ChamberOption = Chamber.isothermal,
    exponent: ExponentOption = DEFAULT_EXPONENT,
    signals: Annotated[str, typer.Option(help="Measured signals to compare.")] = "position",
    train: Annotated[list[Path] | None, typer.Option(
        help="Training records (repeat the option): fit --free on them first.")] = None,
    free: Annotated[str | None, typer.Option(
        help="Parameters to fit on the --train records.")] = None,
    smooth_input: Annotated[bool, typer.Option(
        "--smooth-input", help="Rebuild a noisy measured input as piecewise linear.")] = False,
    rtol: RtolOption = 1e-6,
    out: Annotated[Path, typer.Option(help="Output directory.")] = Path("pneumact-validation"),
) -> None:
    """Validate the model against measured records: metrics, loop measures, residuals,
    plots and a self-contained HTML report."""
    with user_errors():
        import pneumact as pa
        from pneumact.io import read_records
        from pneumact.validation import train_test, validate

        out = check_out_dir("--out", out)
        wanted = tuple(names(signals, "--signals") or ("position",))
        free_names = names(free, "--free")
        drive = str(input)
        if drive not in ("auto", "model"):
            refuse_unused(ctx, "valve", f"with --input {drive} (the records' {drive} chooses "
                          "the valve)", "leave it out, or give --input model to drive every "
                          "record through --valve")
        parameter_set, model = build_model(ModelOptions(
            params=params, valve=valve, friction=friction, chamber=chamber, rtol=rtol,
            exponent=exponent, decaying_damping=decaying_damping,
                               elements=elements))
        test = read_records(records, p_atm=parameter_set["p_atm"])
        solver = pa.Rodas4(rtol=rtol)
        use_agg()
        if bool(train) != bool(free):
            raise ParameterError("--train and --free go together: the parameters to fit "
                                 "and the records to fit them on")
        if train:
            training = read_records(train, p_atm=parameter_set["p_atm"])
            result = fit_with_progress(lambda report: train_test(
                model, training, test, free_names or [], signals=wanted, input=drive,
                smooth_input=smooth_input, solver=solver, progress=report))
            written = result.write(out, call=the_call(ctx))
            _print_metrics(result.metrics())
            _print_verdicts(result.test.verdicts())
        else:
            with err_console.status("simulating the records"):
                validation = validate(model, test, signals=wanted, solver=solver,
                                      smooth_input=smooth_input, input=drive)
            written = validation.write(out, call=the_call(ctx), parameters=parameter_set)
            _print_metrics(validation.metrics())
            _print_verdicts(validation.verdicts())
        for path in written:
            out_console.print(f"wrote {path}")


def _print_verdicts(frame) -> None:
    for _, row in frame.iterrows():
        style = VERDICT_STYLE.get(row["verdict"], "white")
        line = Text(f"{row['record']} (driven by its {row['input']}, {row['valve']}): ")
        line.append(row["verdict"], style=style)
        line.append(f": {row['reasons']}")
        out_console.print(line, soft_wrap=True)


def _print_metrics(frame) -> None:
    """The metrics per signal, in display units with the unit in each header."""
    from pneumact.validation.metrics import metrics_for_reading

    for signal, shown in metrics_for_reading(frame).items():
        table = Table(title=f"validation: {signal}")
        columns = [c for c in shown.columns if c not in ("n", "verdict")]
        for column in columns:
            table.add_column(column, justify="left" if column in ("set", "record")
                             else "right")
        for _, row in shown.iterrows():
            table.add_row(*(str(row[c]) if c in ("set", "record") else fmt(row[c], 4)
                            for c in columns))
        out_console.print(table)

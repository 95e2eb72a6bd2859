"""``pneumact compare``: which friction law do the records support?"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from pneumact.cli.common import (
    DEFAULT_EXPONENT,
    DEFAULT_VALVE,
    Chamber,
    ChamberOption,
    ExponentOption,
    ModelOptions,
    ParamsOption,
    SchedulerOption,
    ValveOption,
    WorkersOption,
    build_model,
    executor_of,
    names,
    out_console,
    progress_display,
    the_call,
    use_agg,
    user_errors,
)
from pneumact.cli.identify import DataFormat
from pneumact.errors import ArgumentError
from pneumact.options import Optimizer

RecordsArgument = Annotated[list[Path], typer.Argument(
    help="Record files (CSV with 'name [unit]' headers, Parquet, or --format emps/tudelft "
         "files) or folders of them.")]


#: what a data set's records are fitted on, by format: (signal, also free); the signal gets
#: a sensor offset per record (a load cell's, a drive's current offset) and the measured
#: position, noisy, is rebuilt piecewise linear before it drives the rig
RIG_FORMATS = {"emps": ("friction", ()), "tudelft": ("friction", ())}
#: Hz: the low-pass before the EMPS position is differentiated for M·a (1 kHz samples)
EMPS_CUTOFF = 50.0


def _read(paths: list[Path], data_format: DataFormat, p_atm: float):
    from pneumact.io import read_records
    from pneumact.io.datasets import read_emps, read_tudelft_cylinder
    if data_format is DataFormat.auto and all(p.suffix.lower() == ".mat" for p in paths):
        data_format = DataFormat.emps
    if data_format is DataFormat.emps:
        # the drive's force carries M·a: the friction is force − M·a − offset, with M and
        # the offset of the inverse model identified on the first record
        from pneumact.identification import inverse_friction

        raw = [read_emps(path) for path in paths]
        inverse = inverse_friction(raw[0], cutoff=EMPS_CUTOFF)
        return [inverse.friction_of(rec) for rec in raw], data_format
    if data_format is DataFormat.tudelft:
        return [read_tudelft_cylinder(p) for p in paths], data_format
    return read_records(paths, p_atm=p_atm), DataFormat.record


def compare_command(
    ctx: typer.Context,
    records: RecordsArgument,
    laws: Annotated[str, typer.Option(
        help="Comma-separated laws as --friction names them, gms:N for N blocks.")] = (
        "lugre,gms:4,elasto-plastic,dahl,stribeck"),
    holdout: Annotated[str | None, typer.Option(
        help="Comma-separated indices of the held-out records (default: the last; one "
             "record: its last third).")] = None,
    data_format: Annotated[DataFormat, typer.Option(
        "--format", help="auto (.mat: EMPS), record (an actuator's CSV/Parquet), emps or "
                         "tudelft (a rig driven by the measured position).")] = (
        DataFormat.auto),
    signals: Annotated[str | None, typer.Option(
        help="Measured signals to fit and score (default: position; a data set's force).")
    ] = None,
    params: ParamsOption = "vgt-paper",
    valve: ValveOption = DEFAULT_VALVE,
    chamber: ChamberOption = Chamber.isothermal,
    exponent: ExponentOption = DEFAULT_EXPONENT,
    multistart: Annotated[str, typer.Option(
        help="Extra starts per law, or 'auto' (4 for a law of more than 6 parameters).")
    ] = "auto",
    jacobian: Annotated[str, typer.Option(
        help="The fits' Jacobian: sensitivities (a kernel of its own per law, compiled once), "
             "2-point or 3-point (differences).")] = "sensitivities",
    workers: WorkersOption = None,
    scheduler: SchedulerOption = None,
    out: Annotated[Path, typer.Option(help="Output directory.")] = Path("pneumact-compare"),
) -> None:
    """Fit each friction law on training records, score it on held-out ones, recommend."""
    with user_errors():
        from pneumact.checks import check_int, check_out_dir
        from pneumact.validation.compare import (
            compare_friction_models,
            friction_rig_for,
        )

        out = check_out_dir("--out", out)
        law_names = names(laws, "--laws") or []
        if multistart != "auto":
            try:
                starts: int | str = check_int("--multistart", int(multistart), minimum=0)
            except ValueError:
                raise ArgumentError(f"--multistart = {multistart!r}; give a number of "
                                    "starts (>= 0) or 'auto'") from None
        else:
            starts = "auto"
        held = None
        if holdout is not None:
            try:
                held = [int(i) for i in names(holdout, "--holdout") or []]
            except ValueError:
                raise ArgumentError(f"--holdout = {holdout!r}; give record indices, "
                                    "e.g. 1 or 0,2") from None
        parameter_set, actuator = build_model(ModelOptions(
            params=params, valve=valve, chamber=chamber, exponent=exponent))
        recs, data_format = _read(list(records), data_format, parameter_set["p_atm"])
        also: tuple[str, ...] = ()
        offsets: list[str] = []
        smooth = None
        if data_format.value in RIG_FORMATS:
            signal, also = RIG_FORMATS[data_format.value]
            model = friction_rig_for(recs, signal)
            chosen = names(signals, "--signals") or [signal]
            offsets, smooth = [signal], True
        else:
            model = actuator
            chosen = names(signals, "--signals") or ["position"]
        with progress_display("comparing laws", counts=True) as report:
            result = compare_friction_models(
                model, recs, law_names, holdout=held, signals=chosen, also=also,
                offsets=offsets, smooth_input=smooth, multistart=starts,
                optimizer=Optimizer(jacobian=jacobian),
                executor=executor_of(workers, scheduler), progress=report)
        use_agg()
        written = result.write(out, call=the_call(ctx))
        out_console.print(_table(result.to_pandas()))
        out_console.print(result.recommendation)
        for path in written:
            out_console.print(f"wrote {path}")


def _table(frame):
    """The comparison as a rich table: each law's held-out fit, z against the best, ΔBIC
    and verdict (a failed law with its reason)."""
    from rich.table import Table

    table = Table(title="friction laws, best held-out prediction first")
    for column in ("law", "parameters", "held-out fit %", "z vs best", "ΔBIC", "verdict"):
        table.add_column(column, justify="left" if column in ("law", "verdict") else "right")
    for _, row in frame.iterrows():
        if row["verdict"] == "failed":
            table.add_row(row["law"], "", "", "", "", f"failed: {str(row['error'])[:80]}")
            continue
        table.add_row(row["law"], f"{int(row['parameters'])}", f"{row['held_out_fit_%']:.1f}",
                      f"{row['z_vs_best']:+.2f}", f"{row['delta_bic']:.4g}", row["verdict"])
    return table

"""``pneumact simulate-batch PARAMS.csv --out DIR``: ``simulate_batch`` from the command
line.

Reads the parameter table (CSV or Parquet; header cells ``name`` or ``name [unit]``,
values converted to SI), builds the model (``--model``: the actuator or the cylinder) and
experiment from the same options as ``simulate``, runs the batch with a progress bar and
writes ``DIR/results.parquet``,
``DIR/summary.csv`` (and ``DIR/signals.parquet`` with ``--signals``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from pneumact.checks import check_out_dir
from pneumact.cli.common import (
    DEFAULT_DECAYING_DAMPING,
    DEFAULT_EXPONENT,
    DEFAULT_FRICTION,
    DEFAULT_VALVE,
    KEPT_FOR_RESUME,
    Chamber,
    ChamberOption,
    ChunkSizeOption,
    DecayingDampingOption,
    ElementsOption,
    ExponentOption,
    FrictionOption,
    InputOption,
    LoadStepOption,
    LowOption,
    ModelKind,
    ModelOption,
    ModelOptions,
    OverwriteOption,
    ParamsOption,
    ResumeOption,
    RtolOption,
    SchedulerOption,
    SpoolLagOption,
    TEndOption,
    ValveOption,
    ValvesOption,
    WorkersOption,
    batch_progress,
    build_model_of,
    checkpoint_of,
    err_console,
    executor_of,
    names,
    user_errors,
)
from pneumact.errors import DataError
from pneumact.options import Checkpoint, Executor


def read_parameter_table(path: Path):
    """The parameter table of ``path`` in SI (columns with a unit are converted)."""
    import numpy as np
    import pandas as pd

    from pneumact.io.tables import read_table
    from pneumact.parameters import catalogue, parse_value

    specs = catalogue()
    frame, units = read_table(path)
    for name in frame.columns:
        if name not in specs:
            from pneumact.parameters.validation import unknown_name

            raise DataError(f"{path}: column {unknown_name(name, '')}")
    table = pd.DataFrame(index=frame.index)
    for name in frame.columns:
        values = pd.to_numeric(frame[name], errors="coerce")
        bad = values.isna() & frame[name].astype(str).str.strip().ne("")
        if bad.any():
            row = int(np.flatnonzero(bad.to_numpy())[0])
            raise DataError(f"{path}: column '{name}' row {row + 1} = {frame[name].iloc[row]!r}"
                            ": must be a number")
        unit = units.get(name)
        if unit and name in specs and unit != specs[name].unit:
            si_unit = specs[name].unit
            zero = parse_value(name, f"0 {unit}", si_unit)
            one = parse_value(name, f"1 {unit}", si_unit)
            if zero == 0.0:
                values = values * one
            else:  # an offset unit (degC): convert value by value
                values = values.map(lambda v, u=unit, n=name, si=si_unit:
                                    parse_value(n, f"{v!r} {u}", si))
        table[name] = values.astype(float)
    return table


def simulate_batch(
    params_csv: Annotated[Path, typer.Argument(help="table of parameter sets: one column "
                                                     "per parameter, one row per set")],
    out: Annotated[Path, typer.Option("--out", help="output directory (resumable)")],
    params: ParamsOption = "vgt-paper",
    model: ModelOption = ModelKind.actuator,
    spool_lag: SpoolLagOption = 0,
    valves: ValvesOption = "5/3",
    load_step: LoadStepOption = None,
    valve: ValveOption = DEFAULT_VALVE,
    friction: FrictionOption = DEFAULT_FRICTION,
    decaying_damping: DecayingDampingOption = DEFAULT_DECAYING_DAMPING,
    elements: ElementsOption = None,
    chamber: ChamberOption = Chamber.isothermal,
    exponent: ExponentOption = DEFAULT_EXPONENT,
    t_end: TEndOption = None,
    low: LowOption = None,
    input_csv: InputOption = None,
    rtol: RtolOption = 1e-6,
    features: Annotated[str | None, typer.Option(help="comma-separated feature names")]
    = None,
    signals: Annotated[str | None, typer.Option(help="comma-separated signal names")] = None,
    scheduler: SchedulerOption = Executor.scheduler,
    workers: WorkersOption = Executor.workers,
    chunk_size: ChunkSizeOption = Executor.chunk_size,
    resume: ResumeOption = Checkpoint.resume,
    overwrite: OverwriteOption = Checkpoint.overwrite,
) -> None:
    """Simulate every parameter set of PARAMS_CSV (the actuator, or --model cylinder);
    write Parquet and a CSV summary."""
    with user_errors(kept=KEPT_FOR_RESUME):
        import pneumact as pa

        executor = executor_of(workers, scheduler, chunk_size)
        checkpoint = checkpoint_of(check_out_dir("--out", out), resume, overwrite)
        table = read_parameter_table(params_csv)
        options = ModelOptions(params=params, valve=valve, friction=friction, chamber=chamber,
                               t_end=t_end, low_kpa=low, input_csv=input_csv, rtol=rtol,
                               exponent=exponent, decaying_damping=decaying_damping,
                               elements=elements, spool_lag=spool_lag, valves=valves,
                               load_step=load_step)
        _, built, experiment = build_model_of(model, options)
        with batch_progress() as progress:
            result = pa.simulate_batch(built, experiment, table,
                                       features=names(features, "--features"),
                                       signals=names(signals, "--signals"),
                                       solver=pa.Rodas4(rtol=rtol), executor=executor,
                                       checkpoint=checkpoint, progress=progress)
    stats = result.stats
    err_console.print(
        f"{stats['n_sets']} sets, {stats['failed']} failed, {stats['computed']} computed "
        f"({stats['reused_chunks']} chunks reused) in {stats['wall_time_s']:.1f} s "
        f"({stats['sims_per_s']:.0f} sims/s); results in {out}/results.parquet and "
        f"{out}/summary.csv")

"""``pneumact batch PARAMS.csv --out DIR``: the batch engine from the command line.

A thin layer over ``simulate_batch``: reads the parameter table (CSV or Parquet; header
cells ``name`` or ``name [unit]``, values converted to SI), builds the actuator from a
base parameter set and a valve, runs the batch with a progress bar and writes
``DIR/results.parquet``, ``DIR/summary.csv`` (and ``DIR/signals.parquet`` with
``--signals``). Register it on a typer app with ``app.command("batch")(batch_command)``.
"""

from __future__ import annotations

import time
import warnings
from pathlib import Path
from typing import Annotated

import numpy as np
import pandas as pd
import typer

from .errors import DataError, PassivityWarning, PneumactError

VALVES = ("source", "command", "regulator")


def read_parameter_table(path: Path) -> pd.DataFrame:
    """The parameter table of ``path`` in SI (columns with a unit are converted)."""
    from .io import read_table
    from .parameters import SPECS
    from .parameters.loader import parse_value

    frame, units = read_table(path)
    table = pd.DataFrame(index=frame.index)
    for name in frame.columns:
        values = pd.to_numeric(frame[name], errors="coerce")
        bad = values.isna() & frame[name].astype(str).str.strip().ne("")
        if bad.any():
            row = int(np.flatnonzero(bad.to_numpy())[0])
            raise DataError(f"{path}: column '{name}' row {row + 1} = {frame[name].iloc[row]!r}"
                            ": must be a number")
        unit = units.get(name)
        if unit and name in SPECS and unit != SPECS[name].unit:
            zero = parse_value(name, f"0 {unit}")
            one = parse_value(name, f"1 {unit}")
            if zero == 0.0:
                values = values * one
            else:  # an offset unit (degC): convert value by value
                values = values.map(lambda v, u=unit, n=name: parse_value(n, f"{v!r} {u}"))
        table[name] = values.astype(float)
    return table


def _experiment(valve: str, t_end: float | None):
    from .experiments import CommandCycle, PressureCycle

    period = 20.0 if t_end is None else float(t_end)
    if valve == "command":
        return CommandCycle(0.0, 1.0, period=period)
    return PressureCycle(high=100e3, low=20e3, period=period)


def _model(base: str, valve: str):
    from .models import Actuator, CommandValve, PressureRegulator, PressureSource
    from .parameters import load_params

    if valve not in VALVES:
        raise PneumactError(f"--valve {valve!r}: allowed: {', '.join(VALVES)}")
    valve_obj = {"source": PressureSource, "command": CommandValve,
                 "regulator": PressureRegulator}[valve]()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PassivityWarning)
        params = load_params(base)
    return Actuator(params, valve=valve_obj)


def _names(text: str | None) -> list[str] | None:
    if text is None:
        return None
    return [n.strip() for n in text.split(",") if n.strip()]


def batch_command(
    params_csv: Annotated[Path, typer.Argument(help="table of parameter sets: one column "
                                                     "per parameter, one row per set")],
    out: Annotated[Path, typer.Option("--out", help="output directory (resumable)")],
    base: Annotated[str, typer.Option(help="base parameter set: name or TOML file")]
    = "vgt-paper",
    valve: Annotated[str, typer.Option(help="source | command | regulator")] = "source",
    features: Annotated[str | None, typer.Option(help="comma-separated feature names")]
    = None,
    signals: Annotated[str | None, typer.Option(help="comma-separated signal names")] = None,
    scheduler: Annotated[str | None, typer.Option(help="Dask scheduler address")] = None,
    resume: Annotated[bool, typer.Option("--resume", help="continue a batch in --out")]
    = False,
    t_end: Annotated[float | None, typer.Option("--t-end", help="cycle period [s]")] = None,
    workers: Annotated[int | None, typer.Option(help="local threads (default all cores)")]
    = None,
) -> None:
    """Simulate every parameter set of PARAMS_CSV; write Parquet and a CSV summary."""
    from rich.console import Console
    from rich.progress import (
        BarColumn,
        MofNCompleteColumn,
        Progress,
        TextColumn,
        TimeElapsedColumn,
        TimeRemainingColumn,
    )

    from .batch import simulate_batch

    console = Console(stderr=True)
    try:
        table = read_parameter_table(params_csv)
        model = _model(base, valve)
        experiment = _experiment(valve, t_end)
        started = time.perf_counter()
        with Progress(TextColumn("[bold]batch"), BarColumn(), MofNCompleteColumn(),
                      TextColumn("failed {task.fields[failed]}"),
                      TextColumn("{task.fields[rate]} sims/s"),
                      TimeElapsedColumn(), TextColumn("left"), TimeRemainingColumn(),
                      console=console) as bar:
            task = bar.add_task("batch", total=len(table), failed=0, rate="-")
            first: list[int] = []

            def progress(done: int, failed: int, total: int) -> None:
                if not first:
                    first.append(done)  # chunks reused from disk do not count in the rate
                elapsed = time.perf_counter() - started
                rate = (done - first[0]) / elapsed if elapsed > 0 else 0.0
                bar.update(task, completed=done, total=total, failed=failed,
                           rate=f"{rate:.0f}")

            with warnings.catch_warnings():
                warnings.simplefilter("ignore", PassivityWarning)
                result = simulate_batch(model, experiment, table, features=_names(features),
                                        signals=_names(signals), scheduler=scheduler,
                                        out_dir=out, resume=resume, workers=workers,
                                        progress=progress)
    except PneumactError as exc:
        console.print(f"[red]error: {exc}[/red]", soft_wrap=True, highlight=False)
        raise typer.Exit(2) from None
    stats = result.stats
    console.print(
        f"{stats['n_sets']} sets, {stats['failed']} failed, {stats['computed']} computed "
        f"({stats['reused_chunks']} chunks reused) in {stats['wall_time_s']:.1f} s "
        f"({stats['sims_per_s']:.0f} sims/s); results in {out}/results.parquet and "
        f"{out}/summary.csv", highlight=False)

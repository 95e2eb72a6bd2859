"""The ``pneumact`` command line: a thin layer over the public API.

    pneumact simulate                         # vgt-paper, slow pressure cycle -> pneumact-out/
    pneumact simulate --valve command --t-end 10 --out run1
    pneumact simulate --input measured_pressure.csv
    pneumact friction-test stick-slip --t-end 5
    pneumact params list | show NAME|FILE | check FILE

Options map onto exactly the objects of the library (parameter set, friction model,
valve, experiment, solver); no physics lives here. Output files are written only after
a successful run, atomically, and together (no CSV without its plot). A user's mistake
prints one red line ``error: ...`` on stderr and exits with code 2.
"""

from __future__ import annotations

import contextlib
import math
import re
import shutil
import tempfile
import warnings
from collections.abc import Callable, Iterator
from enum import StrEnum
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.console import Console
from rich.table import Table
from rich.text import Text

from pneumact import __version__
from pneumact.batch_cli import batch_command
from pneumact.errors import PneumactError

#: Exit code of a user's mistake (bad option, bad file, invalid parameters).
EXIT_USER_ERROR = 2
#: Exit code of ``params check`` when the file is not valid.
EXIT_CHECK_FAILED = 1

#: Default experiment of ``simulate``: lowest pressure [Pa abs] and period [s] of the
#: slow triangular cycle starting and ending at the set's p_atm (paper Figs. 5-6).
DEFAULT_LOW_PRESSURE = 20e3
DEFAULT_PERIOD = 20.0
COMPILING = "compiling kernel (first use; cached afterwards)"
_NAME_UNIT = re.compile(r"^\s*(?P<name>.*?)\s*\[(?P<unit>[^\[\]]*)\]\s*$")

app = typer.Typer(
    name="pneumact",
    help="Pneumatic diaphragm actuators with LuGre friction: simulate, test, inspect.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)
params_app = typer.Typer(help="List, show and check parameter sets.", no_args_is_help=True)
app.add_typer(params_app, name="params")

out_console = Console(highlight=False)
err_console = Console(stderr=True, highlight=False)


class FrictionChoice(StrEnum):
    lugre = "lugre"
    dahl = "dahl"
    bouc_wen = "bouc-wen"
    coulomb = "coulomb"
    stribeck = "stribeck"


class ValveChoice(StrEnum):
    source = "source"
    command = "command"
    regulator = "regulator"


class FrictionTestKind(StrEnum):
    steady_state = "steady-state"
    presliding = "presliding"
    frictional_lag = "frictional-lag"
    break_away = "break-away"
    stick_slip = "stick-slip"


def _friction_model(choice: FrictionChoice):
    import pneumact as pa

    return {
        FrictionChoice.lugre: pa.LuGre,
        FrictionChoice.dahl: pa.Dahl,
        FrictionChoice.bouc_wen: pa.BoucWen,
        FrictionChoice.coulomb: pa.CoulombViscous,
        FrictionChoice.stribeck: pa.StribeckMap,
    }[choice]()


# --------------------------------------------------------------------------- plumbing


def _print_error(message: str) -> None:
    err_console.print(Text(f"error: {message}", style="red"), soft_wrap=True)


def _print_warning(message: warnings.WarningMessage) -> None:
    text = f"warning: {message.category.__name__}: {message.message}"
    err_console.print(Text(text, style="yellow"), soft_wrap=True)


@contextlib.contextmanager
def _user_errors(code: int = EXIT_USER_ERROR) -> Iterator[None]:
    """Warnings -> yellow lines; a pneumact error or a bad path -> one red line, exit."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            yield
        except PneumactError as exc:
            _flush_warnings(caught)
            _print_error(str(exc))
            raise typer.Exit(code) from None
        except OSError as exc:  # missing input file, output directory not writable, ...
            _flush_warnings(caught)
            _print_error(str(exc))
            raise typer.Exit(code) from None
    _flush_warnings(caught)


def _flush_warnings(caught: list[warnings.WarningMessage]) -> None:
    seen = set()
    for message in caught:
        key = (message.category, str(message.message))
        if key not in seen and not issubclass(message.category, DeprecationWarning):
            seen.add(key)
            _print_warning(message)
    caught.clear()


def _use_agg() -> None:
    """Render off-screen: the CLI only writes PNG files."""
    import matplotlib

    matplotlib.use("Agg")


def _write_outputs(out_dir: Path, writers: dict[str, Callable[[Path], Any]]) -> list[Path]:
    """Write every file into a private staging directory first, then move each into
    ``out_dir`` atomically; on any failure, remove what was already moved (and the
    directory if this call created it), so no partial set of outputs is left."""
    from pneumact.io import atomic_write

    created_dir = not out_dir.exists()
    staging = Path(tempfile.mkdtemp(prefix="pneumact-"))
    written: list[Path] = []
    try:
        for name, write in writers.items():
            write(staging / name)
        for name in writers:
            target = out_dir / name
            with atomic_write(target) as tmp:
                shutil.copyfile(staging / name, tmp)
            written.append(target)
    except BaseException:
        for path in written:
            path.unlink(missing_ok=True)
        if created_dir:
            with contextlib.suppress(OSError):
                out_dir.rmdir()
        raise
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    return written


def _run_with_progress(run: Callable[[Callable[[float], None] | None], Any],
                       what: str = "simulating") -> Any:
    """Call ``run(progress)`` under a rich progress bar; a spinner says the kernel is
    compiling until the first progress report arrives."""
    from rich.progress import (
        BarColumn,
        Progress,
        SpinnerColumn,
        TaskProgressColumn,
        TextColumn,
        TimeElapsedColumn,
    )

    columns = (SpinnerColumn(), TextColumn("{task.description}"), BarColumn(),
               TaskProgressColumn(), TimeElapsedColumn())
    with Progress(*columns, console=err_console, transient=True) as bar:
        task = bar.add_task(COMPILING, total=None)

        def report(fraction: float) -> None:
            bar.update(task, description=what, total=1.0, completed=fraction)

        return run(report)


def _fmt(value: float, digits: int = 4) -> str:
    return "n/a" if value is None or not math.isfinite(value) else f"{value:.{digits}g}"


# --------------------------------------------------------------------------- top level


def _version(value: bool) -> None:
    if value:
        out_console.print(f"pneumact {__version__}")
        raise typer.Exit()


@app.callback()
def main(
    version: Annotated[bool, typer.Option("--version", callback=_version, is_eager=True,
                                          help="Print the version and exit.")] = False,
) -> None:
    """Pneumatic diaphragm actuators with LuGre friction."""


# --------------------------------------------------------------------------- simulate


def _simulate_experiment(valve: ValveChoice, input_csv: Path | None, t_end: float | None,
                         params):
    """The experiment the options describe (a cycle, or the input CSV)."""
    import pneumact as pa
    from pneumact.errors import ExperimentError

    if input_csv is not None:
        experiment = pa.experiments.from_csv(input_csv)
        if t_end is not None:
            if t_end > experiment.t_end:
                raise ExperimentError(
                    f"--t-end = {t_end:g} s is beyond the input data, which ends at "
                    f"{experiment.t_end:g} s; give --t-end <= {experiment.t_end:g}"
                )
            experiment = experiment.with_duration(t_end)
        return experiment
    period = DEFAULT_PERIOD if t_end is None else t_end
    if not (math.isfinite(period) and period > 0):
        raise ExperimentError(f"--t-end = {period:g} s; must be a duration > 0")
    if valve is ValveChoice.command:
        return pa.CommandCycle(0.0, 1.0, period=period)
    return pa.PressureCycle(high=params["p_atm"], low=DEFAULT_LOW_PRESSURE, period=period)


@app.command()
def simulate(
    params: Annotated[str, typer.Option(help="Parameter set: a shipped name or a .toml file.")
                      ] = "vgt-paper",
    out: Annotated[Path, typer.Option(help="Output directory (simulation.csv, "
                                           "hysteresis.png).")] = Path("pneumact-out"),
    input_csv: Annotated[Path | None, typer.Option(
        "--input", help="CSV with time and an input signal (e.g. 'pressure [kPa]').")] = None,
    valve: Annotated[ValveChoice, typer.Option(
        help="source: prescribed pressure; command: valve command u in [0, 1]; "
             "regulator: pressure set-point.")] = ValveChoice.source,
    t_end: Annotated[float | None, typer.Option(
        help="Duration [s]: the period of the default cycle, or where to stop the input.")
    ] = None,
    rtol: Annotated[float, typer.Option(help="Relative tolerance of the solver.")] = 1e-6,
    friction: Annotated[FrictionChoice, typer.Option(help="Friction model.")
                        ] = FrictionChoice.lugre,
) -> None:
    """Simulate the actuator; write simulation.csv (SI) and hysteresis.png."""
    with _user_errors():
        import pneumact as pa
        from pneumact.plotting import plot_hysteresis, save_figure
        from pneumact.simulation.simulate import check_drive

        _use_agg()
        parameter_set = pa.load_params(params)
        valve_model = {ValveChoice.source: pa.PressureSource,
                       ValveChoice.command: pa.CommandValve,
                       ValveChoice.regulator: pa.PressureRegulator}[valve]()
        actuator = pa.Actuator(parameter_set, friction=_friction_model(friction),
                               valve=valve_model)
        experiment = _simulate_experiment(valve, input_csv, t_end, parameter_set)
        solver = pa.Rodas4(rtol=rtol)
        check_drive(actuator, experiment)  # a clear error before any progress display
        result = _run_with_progress(
            lambda report: pa.simulate(actuator, experiment, solver, progress=report))
        summary = result.summary()

        import matplotlib.pyplot as plt

        ax = plot_hysteresis(result, label=f"{parameter_set.name}, {friction.value}")
        try:
            written = _write_outputs(out, {
                "simulation.csv": result.save,
                "hysteresis.png": lambda path: save_figure(ax.figure, path),
            })
        finally:
            plt.close(ax.figure)
        _print_simulation_summary(summary, result, parameter_set["p_atm"], written)


def _print_simulation_summary(summary: dict[str, float], result, p_atm: float,
                              written: list[Path]) -> None:
    table = Table(title="pneumact simulate", show_header=True)
    table.add_column("quantity")
    table.add_column("value", justify="right")
    table.add_column("unit")
    start = summary["breakaway_pressure"]
    rows = [
        ("stroke", _fmt(summary["stroke"] * 1e3), "mm"),
        ("loop width (pressure)", _fmt(summary["loop_width_pressure"] * 1e-3), "kPa"),
        ("loop width (position)", _fmt(summary["loop_width_position"] * 1e3), "mm"),
        ("motion starts at", _fmt(start * 1e-3), "kPa abs"),
        ("motion starts at", _fmt((p_atm - start) * 1e-3), "kPa of vacuum"),
        ("solver steps", str(result.meta.get("steps", "n/a")), ""),
        ("wall time", _fmt(result.meta.get("wall_time_s", float("nan")), 3), "s"),
    ]
    for row in rows:
        table.add_row(*row)
    out_console.print(table)
    for path in written:
        out_console.print(f"wrote {path}")


# --------------------------------------------------------------------------- friction test


@app.command("friction-test")
def friction_test(
    kind: Annotated[FrictionTestKind, typer.Argument(help="Which classic experiment.")],
    params: Annotated[str, typer.Option(help="Parameter set: a shipped name or a .toml file.")
                      ] = "canudas1995",
    out: Annotated[Path, typer.Option(help="Output directory (friction_test.csv, "
                                           "friction_test_curve.csv, friction_test.png).")
                   ] = Path("pneumact-out"),
    t_end: Annotated[float | None, typer.Option(help="Duration [s] (default: the test's own).")
                     ] = None,
    friction: Annotated[FrictionChoice, typer.Option(help="Friction model.")
                        ] = FrictionChoice.lugre,
) -> None:
    """Run a classic friction experiment on the friction rig; write CSV and PNG."""
    with _user_errors():
        import pneumact as pa
        from pneumact.plotting import plot_friction_test, save_figure

        try:
            from pneumact.experiments.friction import run_friction_test
        except ImportError as exc:
            raise PneumactError(
                f"friction tests are not available in this installation ({exc})"
            ) from None
        _use_agg()
        parameter_set = pa.load_params(params)
        model = _friction_model(friction)
        with err_console.status(f"running the {kind.value} test ({COMPILING})"):
            test = run_friction_test(kind.value, parameter_set, friction=model, t_end=t_end)
        import matplotlib.pyplot as plt

        fig = plot_friction_test(test, kind.value)
        writers: dict[str, Callable[[Path], Any]] = {"friction_test.csv": test.result.save}
        if getattr(test, "table", None) is not None:
            writers["friction_test_curve.csv"] = lambda path: _save_table(test.table, path)
        writers["friction_test.png"] = lambda path: save_figure(fig, path)
        try:
            written = _write_outputs(out, writers)
        finally:
            plt.close(fig)
        result = test.result
        table = Table(title=f"pneumact friction-test {kind.value}")
        table.add_column("quantity")
        table.add_column("value", justify="right")
        table.add_row("friction model", model.name)
        table.add_row("drive", str(getattr(test, "drive_quantity", "")))
        table.add_row("duration [s]", _fmt(float(result.time[-1] - result.time[0])))
        table.add_row("samples", str(len(result.time)))
        table.add_row("solver steps", str(result.meta.get("steps", "n/a")))
        table.add_row("wall time [s]", _fmt(result.meta.get("wall_time_s", float("nan")), 3))
        out_console.print(table)
        for path in written:
            out_console.print(f"wrote {path}")


def _save_table(frame, path: Path) -> None:
    """Write a derived curve whose columns are named ``name [unit]`` (SI)."""
    from pneumact.io import write_table

    names, units = [], {}
    for column in map(str, frame.columns):
        match = _NAME_UNIT.match(column)
        name = match["name"] if match else column
        names.append(name)
        if match:
            units[name] = match["unit"]
    renamed = frame.set_axis(names, axis=1)
    renamed.attrs = {}
    write_table(renamed, path, units)


# --------------------------------------------------------------------------- params


@params_app.command("list")
def params_list() -> None:
    """List the parameter sets shipped with pneumact."""
    with _user_errors():
        import pneumact as pa

        table = Table(title="shipped parameter sets")
        table.add_column("name", style="bold")
        table.add_column("description")
        for name, description in pa.available_params():
            table.add_row(name, description)
        out_console.print(table)


@params_app.command("show")
def params_show(
    name: Annotated[str, typer.Argument(help="A shipped set name or a .toml file.")],
) -> None:
    """Show every parameter: value as given, in SI, source and meaning."""
    with _user_errors():
        import pneumact as pa

        parameter_set = pa.load_params(name)
        frame = parameter_set.to_frame()
        table = Table(title=f"{parameter_set.name}: {parameter_set.description}")
        for column in ("name", "given", "SI value", "source", "description"):
            table.add_column(column, overflow="fold")
        for row in frame.itertuples(index=False):
            si = f"{row.value:.6g} {row.unit}".rstrip()
            table.add_row(row.name, row.given or "", si, row.source, row.description)
        out_console.print(table)


@params_app.command("check")
def params_check(
    file: Annotated[str, typer.Argument(help="A .toml parameter file (or a shipped name).")],
) -> None:
    """Load and validate a parameter file: prints OK or the error (exit code 1)."""
    with _user_errors(code=EXIT_CHECK_FAILED):
        import pneumact as pa

        parameter_set = pa.load_params(file)
        out_console.print(Text(f"OK: {parameter_set.name} ({len(parameter_set)} parameters "
                               "given)", style="green"))


app.command("batch")(batch_command)


if __name__ == "__main__":
    app()

"""What every command shares: consoles, one-line errors, atomic multi-file output,
progress display, and the options that build a model and its experiment.

``simulate``, ``batch`` (and the commands that come after them) take the same
``--params --valve --friction --chamber --t-end --low --high --input --rtol`` options,
defined once here (``ModelOptions``) and turned into library objects by one function
(``build_model``, ``build_experiment``). Nothing here imports numpy, pandas or numba at
module level: a command pays for what it uses.
"""

from __future__ import annotations

import contextlib
import math
import warnings
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from enum import StrEnum
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.console import Console
from rich.text import Text

from pneumact.errors import ExperimentError, PneumactError

#: Exit code of a user's mistake (bad option, bad file, invalid parameters).
EXIT_USER_ERROR = 2
#: Exit code of ``params check`` when the file is not valid.
EXIT_CHECK_FAILED = 1
#: Default experiment: the slow triangular cycle of the paper's Figs. 5-6, from the set's
#: p_atm down to this pressure [Pa abs] and back in this period [s] (or 0 → 1 → 0 for a
#: command valve).
DEFAULT_LOW_PRESSURE = 20e3
DEFAULT_PERIOD = 20.0
COMPILING = "compiling kernel (first use; cached afterwards)"

out_console = Console(highlight=False)
err_console = Console(stderr=True, highlight=False)


class Valve(StrEnum):
    source = "source"
    command = "command"
    regulator = "regulator"


class Chamber(StrEnum):
    isothermal = "isothermal"
    adiabatic = "adiabatic"


def _friction_choices() -> type[StrEnum]:
    """The ``--friction`` choices: every law the friction module registers."""
    from pneumact.models.friction import friction_models

    return StrEnum("Friction", {name.replace("-", "_"): name for name in friction_models()})


Friction = _friction_choices()

ParamsOption = Annotated[str, typer.Option(
    "--params", help="Parameter set: a shipped name or a .toml file.")]
ValveOption = Annotated[Valve, typer.Option(
    help="source: prescribed pressure; command: valve command u in [0, 1]; regulator: "
         "pressure set-point.")]
FrictionOption = Annotated[Friction, typer.Option(help="Friction model.")]
ChamberOption = Annotated[Chamber, typer.Option(help="Chamber gas law (behind a valve).")]
TEndOption = Annotated[float | None, typer.Option(
    "--t-end", help="Duration [s]: the period of the default cycle, or where to stop the "
                    "input.")]
LowOption = Annotated[float, typer.Option(
    "--low", help="Lowest pressure of the default cycle [kPa abs].")]
InputOption = Annotated[Path | None, typer.Option(
    "--input", help="CSV with time and an input signal (e.g. 'pressure [kPa]').")]
RtolOption = Annotated[float, typer.Option(help="Relative tolerance of the solver.")]
# the batch engine's options, shared by every command that runs batches
SchedulerOption = Annotated[str | None, typer.Option(help="Dask scheduler address.")]
WorkersOption = Annotated[int | None, typer.Option(help="Local threads (default all cores).")]
ResumeOption = Annotated[bool, typer.Option(
    "--resume", help="Continue the runs kept in the output directory after an interruption.")]
OverwriteOption = Annotated[bool, typer.Option(
    "--overwrite", help="Start the runs kept in the output directory again.")]


@dataclass(frozen=True)
class ModelOptions:
    """The model and experiment options of a command, as given."""

    params: str = "vgt-paper"
    valve: Valve = Valve.source
    friction: str = "lugre"
    chamber: Chamber = Chamber.isothermal
    t_end: float | None = None
    low_kpa: float = DEFAULT_LOW_PRESSURE * 1e-3
    input_csv: Path | None = None
    rtol: float = 1e-6


def load_quietly(name: str):
    """A parameter set; a passivity warning is shown once by ``user_errors``."""
    import pneumact as pa

    return pa.load_params(name)


def build_model(options: ModelOptions, params=None):
    """(parameter set, Actuator) the options describe."""
    from pneumact.models import (
        VALVES,
        Actuator,
        Adiabatic,
        Isothermal,
        friction_models,
    )

    params = load_quietly(options.params) if params is None else params
    friction = friction_models()[str(options.friction)]()
    chamber = Adiabatic() if options.chamber is Chamber.adiabatic else Isothermal()
    return params, Actuator(params, friction=friction, valve=VALVES[options.valve.value](),
                            chamber=chamber)


def build_experiment(options: ModelOptions, params):
    """The experiment the options describe: the input CSV, or the default slow cycle
    (pressure p_atm → low → p_atm, or command 0 → 1 → 0 for a command valve)."""
    import pneumact as pa

    if options.input_csv is not None:
        experiment = pa.experiments.from_csv(options.input_csv, p_atm=params["p_atm"])
        if options.t_end is not None:
            if options.t_end > experiment.t_end:
                raise ExperimentError(
                    f"--t-end = {options.t_end:g} s is beyond the input data, which ends at "
                    f"{experiment.t_end:g} s; give --t-end <= {experiment.t_end:g}")
            experiment = experiment.with_duration(options.t_end)
        return experiment
    period = DEFAULT_PERIOD if options.t_end is None else options.t_end
    if not (math.isfinite(period) and period > 0):
        raise ExperimentError(f"--t-end = {period:g} s; must be a duration > 0")
    if options.valve is Valve.command:
        return pa.CommandCycle(0.0, 1.0, period=period)
    return pa.PressureCycle(high=params["p_atm"], low=options.low_kpa * 1e3, period=period)


# --------------------------------------------------------------------------- plumbing
def print_error(message: str) -> None:
    err_console.print(Text(f"error: {message}", style="red"), soft_wrap=True)


def _print_warning(message: warnings.WarningMessage) -> None:
    text = f"warning: {message.category.__name__}: {message.message}"
    err_console.print(Text(text, style="yellow"), soft_wrap=True)


def _flush_warnings(caught: list[warnings.WarningMessage]) -> None:
    seen = set()
    for message in caught:
        key = (message.category, str(message.message))
        if key not in seen and not issubclass(message.category, DeprecationWarning):
            seen.add(key)
            _print_warning(message)
    caught.clear()


@contextlib.contextmanager
def user_errors(code: int = EXIT_USER_ERROR) -> Iterator[None]:
    """Warnings -> yellow lines; a pneumact error or a bad path -> one red line, exit."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            yield
        except PneumactError as exc:
            _flush_warnings(caught)
            print_error(str(exc))
            raise typer.Exit(code) from None
        except OSError as exc:  # missing input file, output directory not writable, ...
            _flush_warnings(caught)
            print_error(str(exc))
            raise typer.Exit(code) from None
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


def run_with_progress(run: Callable[[Callable[[float], None] | None], Any],
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


@contextlib.contextmanager
def batch_progress(label: str = "batch") -> Iterator[Callable[[int, int, int], None]]:
    """A rich progress bar for the batch engine: yields ``progress(done, failed, total)``
    (sets done and failed, and the rate of this session: reused chunks do not count)."""
    import time

    from rich.progress import (
        BarColumn,
        MofNCompleteColumn,
        Progress,
        TextColumn,
        TimeElapsedColumn,
        TimeRemainingColumn,
    )

    started = time.perf_counter()
    with Progress(TextColumn(f"[bold]{label}"), BarColumn(), MofNCompleteColumn(),
                  TextColumn("failed {task.fields[failed]}"),
                  TextColumn("{task.fields[rate]} sims/s"),
                  TimeElapsedColumn(), TextColumn("left"), TimeRemainingColumn(),
                  console=err_console) as bar:
        task = bar.add_task(label, total=None, failed=0, rate="-")
        first: list[int] = []

        def progress(done: int, failed: int, total: int) -> None:
            if not first:
                first.append(done)
            elapsed = time.perf_counter() - started
            rate = (done - first[0]) / elapsed if elapsed > 0 else 0.0
            bar.update(task, completed=done, total=total, failed=failed, rate=f"{rate:.0f}")

        yield progress


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


def fit_with_progress(run):
    """Run a fit under a progress display: a spinner while fitting, a bar per stage that
    reports progress (multistart starts, profile points)."""
    from rich.progress import BarColumn, Progress, SpinnerColumn, TextColumn, TimeElapsedColumn

    with Progress(SpinnerColumn(), TextColumn("{task.description}"), BarColumn(),
                  TimeElapsedColumn(), console=err_console, transient=True) as bar:
        tasks = {"fit": bar.add_task("fitting", total=None)}

        def report(label: str, fraction: float) -> None:
            if label not in tasks:
                tasks[label] = bar.add_task(label, total=1.0)
            bar.update(tasks[label], completed=fraction)

        return run(report)


def fmt(value: float | None, digits: int = 4) -> str:
    return "n/a" if value is None or not math.isfinite(value) else f"{value:.{digits}g}"


def names(text: str | None) -> list[str] | None:
    """A comma-separated list option as names (None if not given)."""
    if text is None:
        return None
    return [n.strip() for n in text.split(",") if n.strip()]

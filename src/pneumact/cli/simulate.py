"""``pneumact simulate``: one run of the actuator (CSV, hysteresis plot and a summary) or of
the double-acting cylinder (CSV, step response plot and a summary)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import numpy as np
import typer
from rich.table import Table

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
    InputOption,
    LoadStepOption,
    LowOption,
    ModelKind,
    ModelOption,
    ModelOptions,
    ParamsOption,
    RtolOption,
    SpoolLagOption,
    TEndOption,
    ValveOption,
    ValvesOption,
    build_experiment,
    build_model,
    build_model_of,
    fmt,
    out_console,
    run_with_progress,
    use_agg,
    user_errors,
    with_load_step,
    write_outputs,
)


def simulate(
    params: ParamsOption = "vgt-paper",
    model: ModelOption = ModelKind.actuator,
    spool_lag: SpoolLagOption = 0,
    valves: ValvesOption = "5/3",
    out: Annotated[Path, typer.Option(help="Output directory (simulation.csv, "
                                           "hysteresis.png).")] = Path("pneumact-out"),
    input_csv: InputOption = None,
    valve: ValveOption = DEFAULT_VALVE,
    friction: FrictionOption = DEFAULT_FRICTION,
    decaying_damping: DecayingDampingOption = DEFAULT_DECAYING_DAMPING,
    elements: ElementsOption = None,
    chamber: ChamberOption = Chamber.isothermal,
    exponent: ExponentOption = DEFAULT_EXPONENT,
    t_end: TEndOption = None,
    low: LowOption = None,
    rtol: RtolOption = 1e-6,
    load_step: LoadStepOption = None,
) -> None:
    """Simulate the actuator (write simulation.csv in SI and hysteresis.png) or the
    cylinder (simulation.csv and response.png); with --load-step, either loaded by a force
    step (``Actuator.load``, ``Cylinder.load``)."""
    with user_errors():
        import pneumact as pa
        from pneumact.simulation.simulate import check_drive_while_building

        out = check_out_dir("--out", out)
        options = ModelOptions(params=params, valve=valve, friction=friction, chamber=chamber,
                               t_end=t_end, low_kpa=low, input_csv=input_csv, rtol=rtol,
                               exponent=exponent, decaying_damping=decaying_damping,
                               elements=elements, spool_lag=spool_lag, valves=valves,
                               load_step=load_step)
        if model is ModelKind.cylinder:
            _simulate_cylinder(options, out)
            return
        parameter_set, actuator = build_model(options)
        experiment = build_experiment(options, parameter_set)
        actuator = with_load_step(actuator, experiment, options)
        solver = pa.Rodas4(rtol=rtol)
        # a clear error before any progress display; the kernel's compiler runs meanwhile
        check_drive_while_building(actuator, experiment)
        result = run_with_progress(
            lambda report: pa.simulate(actuator, experiment, solver, progress=report))
        summary = result.summary()
        use_agg()

        from pneumact.plotting import off_screen, plot_hysteresis

        with off_screen():  # written, never shown: no pyplot
            figure = plot_hysteresis(result, label=f"{parameter_set.name}, {friction}")
        written = _write_run(out, result, figure, "hysteresis.png")
        _print_summary(summary, result, parameter_set["p_atm"], written)


def _motion_rows(result) -> list[tuple[str, str, str]]:
    """How the run slides: stick-slip (it stops and jumps) or steadily, with the
    velocity's range over 20-80 % of the stroke."""
    from pneumact.analysis import sliding_motion

    if "velocity" not in result.signals:
        return []
    motion = sliding_motion(result["position"], result["velocity"])
    if not np.isfinite(motion.max_speed):
        return []
    how = (f"stick-slip ({motion.stops} stops)" if motion.stick_slip else
           "steady sliding")
    slowest = "0" if motion.min_speed < 1e-3 * motion.max_speed else \
        fmt(motion.min_speed * 1e3)
    return [("motion (20-80 % of stroke)", how, ""),
            ("speed range (20-80 % of stroke)", f"{slowest}–{fmt(motion.max_speed * 1e3)}",
             "mm/s")]


def _print_summary(summary: dict[str, float], result, p_atm: float, written) -> None:
    table = Table(title="pneumact simulate", show_header=True)
    table.add_column("quantity")
    table.add_column("value", justify="right")
    table.add_column("unit")
    start = summary["breakaway_pressure"]
    rows = [
        ("stroke", fmt(summary["stroke"] * 1e3), "mm"),
        ("loop width (pressure)", fmt(summary["loop_width_pressure"] * 1e-3), "kPa"),
        ("loop width (position)", fmt(summary["loop_width_position"] * 1e3), "mm"),
        ("break-away (sliding line at rest)", fmt(start * 1e-3), "kPa abs"),
        ("break-away (sliding line at rest)", fmt((p_atm - start) * 1e-3), "kPa of vacuum"),
        ("sliding speed (20-80 % of stroke)", fmt(summary["sliding_speed"] * 1e3), "mm/s"),
        *_motion_rows(result),
        ("solver steps", str(result.meta.get("steps", "n/a")), ""),
        ("wall time", fmt(result.meta.get("wall_time_s", float("nan")), 3), "s"),
    ]
    for row in rows:
        table.add_row(*row)
    out_console.print(table)
    for path in written:
        out_console.print(f"wrote {path}")


def _simulate_cylinder(options: ModelOptions, out: Path) -> None:
    """One run of the cylinder: simulation.csv, response.png and its summary; with
    --load-step, its rod loaded by that step (``Cylinder.load``)."""
    import pneumact as pa
    from pneumact.simulation.simulate import check_drive_while_building

    parameter_set, cylinder, experiment = build_model_of(ModelKind.cylinder, options)
    check_drive_while_building(cylinder, experiment)
    result = run_with_progress(lambda report: pa.simulate(
        cylinder, experiment, pa.Rodas4(rtol=options.rtol), progress=report))
    use_agg()

    from pneumact.plotting import off_screen, plot_time_series

    with off_screen():  # written, never shown: no pyplot
        commands = ["command_a", "command_b"] if cylinder.two_valves else ["spool"]
        figure = plot_time_series(result, [*commands, "position", "velocity", "pressure_a",
                                           "pressure_b"])
    written = _write_run(out, result, figure, "response.png")
    _print_cylinder_summary(result, float(parameter_set["x_max"]), written)


def _print_cylinder_summary(result, stroke: float, written) -> None:
    """Travel, top speeds, when 95 % of the stroke is first reached, the end pressures."""
    table = Table(title="pneumact simulate --model cylinder", show_header=True)
    table.add_column("quantity")
    table.add_column("value", justify="right")
    table.add_column("unit")
    position, velocity = result["position"], result["velocity"]
    reached = result.time[position >= 0.95 * stroke]
    rows = [
        ("travel", f"{fmt(position.min() * 1e3)} to {fmt(position.max() * 1e3)}", "mm"),
        ("top speed out / in", f"{fmt(velocity.max())} / {fmt(-velocity.min())}", "m/s"),
        ("95 % of the stroke first at", fmt(reached[0]) if reached.size else "never", "s"),
        ("p_a, p_b at the end", f"{fmt(result['pressure_a'][-1] * 1e-3)}, "
                                f"{fmt(result['pressure_b'][-1] * 1e-3)}", "kPa abs"),
        ("solver steps", str(result.meta.get("steps", "n/a")), ""),
    ]
    for row in rows:
        table.add_row(*row)
    out_console.print(table)
    for path in written:
        out_console.print(f"wrote {path}")


def _write_run(out, result, figure, png: str):
    """The run's CSV and ``figure`` as ``png`` into ``out`` (all or nothing); the figure
    closed whatever happens."""
    from pneumact.plotting import close_figure, save_figure

    try:
        return write_outputs(out, {"simulation.csv": result.save,
                                   png: lambda path: save_figure(figure, path)})
    finally:
        close_figure(figure)

"""``pneumact campaign``, ``pneumact identify paper|friction`` and ``pneumact fit``."""

from __future__ import annotations

import functools
from enum import StrEnum
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer
from rich.markup import escape
from rich.table import Table
from rich.text import Text

from pneumact.checks import check_int, check_out_dir, check_positive, check_range, check_seed
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
    SchedulerOption,
    SpoolLagOption,
    ValveOption,
    ValvesOption,
    WorkersOption,
    build_chamber,
    build_model_of,
    err_console,
    executor_of,
    figure_writer,
    fit_with_progress,
    fmt,
    load_quietly,
    names,
    out_console,
    progress_display,
    refuse_cylinder_set,
    refuse_unused,
    the_call,
    use_agg,
    user_errors,
    write_outputs,
)
from pneumact.errors import DataError, ParameterError
from pneumact.options import LOSSES, Executor, Multistart, Optimizer, Profile

if TYPE_CHECKING:
    from pneumact.identification.campaign import CampaignPlan

identify_app = typer.Typer(help="Identify parameters from measured records.",
                           no_args_is_help=True)

RecordsArgument = Annotated[list[Path], typer.Argument(
    help="Record files (CSV with 'name [unit]' headers, or Parquet) or folders of them.")]


def _estimates_table(title: str, table) -> Table:
    out = Table(title=title)
    for column in ("parameter", "value", "std. error", "95 % interval", "unit"):
        out.add_column(column, justify="left" if column in ("parameter", "unit") else "right")
    for name, row in table.iterrows():
        out.add_row(str(name), fmt(row["value"], 6), fmt(row["stderr"], 3),
                    f"{fmt(row['ci95_low'], 5)} .. {fmt(row['ci95_high'], 5)}",
                    str(row.get("unit", "")))
    return out


#: The losses of ``fit``: scipy least_squares' (robust ones damp outliers).
Loss = StrEnum("Loss", {name: name for name in LOSSES})  # type: ignore[misc]
DEFAULT_LOSS = Loss(Optimizer.loss)


def _status(what: str):
    return err_console.status(what, spinner="dots")


# --------------------------------------------------------------------------- campaign
#: Exit code of an identification that ran but could not identify every parameter (the
#: report says why; identified.toml is written only with --partial).
EXIT_NOT_IDENTIFIED = 3


def _write_breakpoints(designed: CampaignPlan, test: str, path: Path) -> None:
    designed.breakpoints(test).to_csv(path, index=False)


def _plan_table(plan) -> Table:
    """The plan as a technician reads it, whole in 80 columns: every header with its
    unit (two lines), no vertical rules, names never cut."""
    from rich import box
    from rich.markup import escape

    frame = plan.to_pandas()
    table = Table(title=f"bench plan for {plan.prior.name} (prior within ±"
                        f"{100 * plan.spread:.0f} %; pressures absolute)",
                  box=box.SIMPLE_HEAD, pad_edge=False)
    # the kind is the test's name (sweep, ramp_..., presliding): in plan.csv, not here
    columns = {"valve": "driven by", "lowest [kPa abs]": "lowest\n[kPa]",
               "ramp rate [kPa/s]": "rate\n[kPa/s]",
               "expected speed [mm/s]": "speed\n[mm/s]", "duration [s]": "duration\n[s]",
               "sample rate [Hz]": "sampling\n[Hz]"}
    table.add_column("test", no_wrap=True)
    for column, label in columns.items():
        table.add_column(escape(label), justify="left" if column == "valve" else "right",
                         no_wrap=True)
    for name, row in frame.iterrows():
        table.add_row(str(name), *(_plan_cell(row[c]) for c in columns))
    return table


def _plan_cell(value) -> str:
    if not isinstance(value, float):
        return str(value)
    if value != value:  # NaN: not set for this test
        return "–"
    return f"{value:.0f}" if value >= 100 else fmt(value, 3)


def campaign(
    ctx: typer.Context,
    params: ParamsOption = "vgt-paper",
    out: Annotated[Path, typer.Option(help="Output directory for the records.")] = Path(
        "pneumact-campaign"),
    plan: Annotated[bool, typer.Option(
        "--plan", help="Only design the tests: print and write the plan (plan.csv and one "
                       "set-point CSV per test) for a real bench, simulate nothing.")] = False,
    spread: Annotated[float, typer.Option(
        help="How far off the spring and friction values of --params may be [%].")] = 50.0,
    seed: Annotated[int, typer.Option(help="Seed of the measurement noise (>= 0).")] = 0,
    pressure_noise: Annotated[float, typer.Option(
        "--pressure-noise", help="Pressure sensor noise, standard deviation [kPa].")] = 0.02,
    position_noise: Annotated[float, typer.Option(
        "--position-noise", help="Position sensor noise, standard deviation [µm].")] = 1.0,
    resolution: Annotated[float, typer.Option(
        help="Position sensor resolution [µm] (0: none).")] = 1.0,
    round_number: Annotated[int, typer.Option(
        "--round", help="Which round of tests this is: from 2 on, every test's name ends "
                        "in _round<N>, so that the records of both rounds can be identified "
                        "together (design it from the first round's identified.toml).")] = 1,
    simulate: Annotated[Path | None, typer.Option(
        "--simulate", help="Run the plan written to this folder by --plan (designed from "
                           "another set: a prior) on --params (the truth) instead of "
                           "designing one.")] = None,
) -> None:
    """Design a bench campaign (sweep, ramps, presliding) for an actuator known roughly as
    --params, and simulate it as CSV records; with --plan, write the plan only (plan.csv
    and the set-point of each test) for a real bench; with --simulate PLAN, run a plan
    designed earlier (from a prior) on --params."""
    with user_errors():
        from pneumact.identification import Noise, design_campaign, synthetic_campaign
        from pneumact.identification.campaign import read_plan

        if plan:
            refuse_unused(ctx, ("seed", "pressure_noise", "position_noise", "resolution"),
                          "with --plan (it only designs the tests, nothing is simulated)",
                          "leave them out, or simulate the plan with --simulate")
        check_seed("--seed", seed)
        check_range("--spread", spread, 0.0, 100.0, unit="%", high_open=True)
        for label, value in (("--pressure-noise", pressure_noise),
                             ("--position-noise", position_noise),
                             ("--resolution", resolution)):
            check_positive(label, value, strict=False)
        out = check_out_dir("--out", out)
        parameter_set = load_quietly(params)
        refuse_cylinder_set(parameter_set, "the paper's identification is the diaphragm's")
        if simulate is not None:
            if plan:
                raise ParameterError("--simulate runs a written plan, --plan writes one: "
                                     "give one of them")
            _simulate_plan(read_plan(simulate), parameter_set, out, seed,
                           Noise(pressure_noise * 1e3, position_noise * 1e-6,
                                 resolution * 1e-6), simulate)
            return
        if round_number < 1:
            raise ParameterError(f"--round = {round_number}; allowed: 1 (the first round) "
                                 "or more")
        suffix = f"_round{round_number}" if round_number > 1 else ""
        designed = design_campaign(parameter_set, spread=spread / 100, suffix=suffix)
        if plan:  # the tests, for a real bench
            writers = {"plan.csv": lambda p: designed.to_pandas().to_csv(p)}
            for test in designed.tests:
                writers[f"setpoint_{test.name}.csv"] = functools.partial(
                    _write_breakpoints, designed, test.name)
        else:  # the tests simulated: a folder of records, nothing else
            noise = Noise(pressure_noise * 1e3, position_noise * 1e-6, resolution * 1e-6)
            with _status("simulating the bench campaign"):
                records = synthetic_campaign(parameter_set, designed.tests, noise=noise,
                                             seed=seed)
            units = _record_units()
            writers = {f"{r.source}.csv": functools.partial(r.save, units=units)
                       for r in records}
        written = write_outputs(out, writers)
        out_console.print(_plan_table(designed))
        for name, purpose in designed.purposes.items():
            out_console.print(f"  {name}: {purpose}", soft_wrap=True)
        for note in designed.notes:
            err_console.print(f"note: {note}", style="yellow", soft_wrap=True)
        what = "the plan" if plan else f"{len(designed.tests)} simulated records"
        out_console.print(f"wrote {what} ({len(written)} files) to {out}")


def _record_units() -> dict[str, str]:
    """The units a simulated record's columns are written in (kPa, mm: a bench's)."""
    from pneumact.io.records import PRESSURE_SIGNAL

    return {PRESSURE_SIGNAL: "kPa", "position": "mm", "setpoint": "kPa"}


def _simulate_plan(tests, parameter_set, out: Path, seed: int, noise, source: Path) -> None:
    """Simulate a written plan's ``tests`` on ``parameter_set`` and write the records."""
    from pneumact.identification import synthetic_campaign

    with _status(f"simulating the plan of {source} on {parameter_set.name}"):
        records = synthetic_campaign(parameter_set, tests, noise=noise, seed=seed)
    units = _record_units()
    written = write_outputs(out, {f"{r.source}.csv": functools.partial(r.save, units=units)
                                  for r in records})
    out_console.print(f"ran the plan of {source} ({len(tests)} tests) on "
                      f"{parameter_set.name}: wrote {len(written)} records to {out}")


# --------------------------------------------------------------------------- identify
def _verdict_table(result) -> Table:
    table = Table(title="identification: " + result.headline())
    estimates = result.to_pandas()
    rounds = "round" in estimates.columns  # combined rounds: where each value comes from
    for column in ("parameter", "value", "95 % interval", "unit",
                   *(["round"] if rounds else []), "verdict", "reason"):
        table.add_column(column, overflow="fold")
    for name, row in estimates.iterrows():
        style = {"identified": "green", "poorly identified": "yellow"}.get(row["verdict"],
                                                                            "red")
        table.add_row(str(name), fmt(row["value"], 6),
                      f"{fmt(row['ci95_low'], 5)} .. {fmt(row['ci95_high'], 5)}",
                      str(row["unit"]), *([str(row["round"])] if rounds else []),
                      Text(row["verdict"], style=style), escape(str(row["reason"])))
    return table


@identify_app.command("paper")
def identify_paper_command(
    ctx: typer.Context,
    records: RecordsArgument,
    params: ParamsOption = "vgt-paper",
    out: Annotated[Path, typer.Option(help="Output directory.")] = Path("pneumact-identify"),
    chamber: ChamberOption = Chamber.isothermal,
    spread: Annotated[float, typer.Option(
        help="How far off the spring and friction values of --params may be [%].")] = 50.0,
    sliding_speed: Annotated[float | None, typer.Option(
        "--sliding-speed", help="Fix the speed [mm/s] above which eq. 13 applies (v >> vs) "
                                "instead of deriving it from vs; it is then only "
                                "checked.")] = None,
    fit_delta: Annotated[bool, typer.Option(
        "--fit-delta", help="Also fit the Stribeck exponent delta.")] = False,
    staged_only: Annotated[bool, typer.Option(
        "--staged-only", help="Stop after the paper's four stages (fast; their intervals "
                              "are conditional on the earlier stages).")] = False,
    partial: Annotated[bool, typer.Option(
        "--partial", hidden=True, help="No longer needed: identified.toml always holds "
                                       "the identified values, the others at the "
                                       "prior's, marked.")] = False,
    seed: Annotated[int, typer.Option(help="Seed of the input-noise replicates.")] = 0,
    workers: WorkersOption = Executor.workers,
    previous: Annotated[Path | None, typer.Option(
        "--previous", help="The folder an earlier round's `identify paper --out` wrote: "
                           "its results and these records' are combined per parameter "
                           "(the weighted mean where both rounds agree, refused where they "
                           "disagree, else the round that has an interval), each value "
                           "saying its round.")] = None,
) -> None:
    """Identify the actuator from bench records named sweep*, ramp* and presliding*: the
    paper's staged procedure (section III.2), then a joint refinement of every spring and
    friction parameter, intervals that include the noise on the measured inputs, and a
    verdict per parameter. Exits 3 when a parameter is not identified; identified.toml
    holds the identified values and the prior's for the others, each marked. A folder
    with a sweep and no ramp is a signature (see ``pneumact identify signature``). With
    --previous, the result is this round's combined with the earlier round's."""
    with user_errors():
        from pneumact.identification import identify_paper
        from pneumact.io import read_records
        from pneumact.io.records import PRESSURE_SIGNAL

        if sliding_speed is not None:
            check_positive("--sliding-speed", sliding_speed)
        check_range("--spread", spread, 0.0, 100.0, unit="%", high_open=True)
        check_seed("--seed", seed)
        executor = executor_of(workers, None)
        out = check_out_dir("--out", out)
        earlier = None if previous is None else _previous_round(previous, out)
        parameter_set = load_quietly(params)
        refuse_cylinder_set(parameter_set, "the paper's identification is the diaphragm's")
        recs = read_records(records, required=(PRESSURE_SIGNAL, "position"),
                            p_atm=parameter_set["p_atm"])
        with progress_display("identifying", bar_per_stage=False) as progress:
            result = identify_paper(
                recs, parameter_set, fit_delta=fit_delta, prior_spread=spread / 100,
                sliding_speed=None if sliding_speed is None else sliding_speed * 1e-3,
                chamber=build_chamber(chamber), refine=not staged_only, seed=seed,
                executor=executor, progress=progress)
        if partial:
            err_console.print("note: --partial is no longer needed: identified.toml always "
                              "holds the identified values, the others at the prior's, "
                              "marked", style="yellow", soft_wrap=True)
        if earlier is not None:
            from pneumact.identification import combine_rounds

            out_console.print("this round: " + result.headline())
            result = combine_rounds(earlier, result)
        _finish_identification(result, out, the_call(ctx))


def _previous_round(previous: Path, out: Path):
    """The earlier round ``--previous`` names, read before the long work starts."""
    from pneumact.identification.combine import read_round

    if previous.resolve() == out.resolve():
        raise ParameterError(f"--previous = {previous} is also --out: writing would replace "
                             "the round it combines with; give another --out")
    return read_round(previous)


def _finish_identification(result, out: Path, call: str) -> None:
    """Write an identification's files, print its verdicts, findings and, for a
    signature, the valve engineer's numbers; exit 3 unless what the records can tell
    is identified."""
    from pneumact.identification import SignatureIdentification

    use_agg()
    written = write_outputs(out, result.writers(call=call))
    out_console.print(_verdict_table(result))
    signature = isinstance(result, SignatureIdentification)
    if signature:
        out_console.print(_valve_table(result.valve))
    for finding in result.diagnostics:
        style = {"error": "red", "warning": "yellow"}.get(finding.severity, "")
        err_console.print(Text(finding.line(), style=style), soft_wrap=True)
    for path in written:
        out_console.print(f"wrote {path}")
    done = result.signature_ok if signature else result.ok
    if not result.ok:
        err_console.print(Text(
            ("a signature tells F0, k and Fc; " if signature else "") + "not every "
            "parameter is identified: identified.toml holds the identified ones and the "
            "prior's values for the others, each marked in its source", style="yellow"
            if done else "red"), soft_wrap=True)
    if not done:
        raise typer.Exit(EXIT_NOT_IDENTIFIED)


def _valve_table(valve) -> Table:
    table = Table(title="the valve engineer's numbers (95 % intervals)")
    for column in ("quantity", "value", "meaning"):
        table.add_column(column, overflow="fold")
    for name, row in valve.iterrows():
        table.add_row(str(name), str(row["display"]), escape(str(row["meaning"])))
    return table


@identify_app.command("signature")
def identify_signature_command(
    ctx: typer.Context,
    records: RecordsArgument,
    params: ParamsOption = "vgt-paper",
    out: Annotated[Path, typer.Option(help="Output directory.")] = Path("pneumact-identify"),
    spread: Annotated[float, typer.Option(
        help="How far off the spring and friction values of --params may be [%].")] = 50.0,
) -> None:
    """Identify what one slow pressure sweep up and down (a valve signature) tells: F0, k
    and Fc (sigma2 where the speed varies), the bench set, spring rate, friction band and
    dead band with intervals; the other parameters are named with the test that would
    tell each. Exits 3 when F0, k or Fc is not identified."""
    with user_errors():
        from pneumact.identification import identify_signature
        from pneumact.io import read_records
        from pneumact.io.records import PRESSURE_SIGNAL

        check_range("--spread", spread, 0.0, 100.0, unit="%", high_open=True)
        out = check_out_dir("--out", out)
        parameter_set = load_quietly(params)
        refuse_cylinder_set(parameter_set, "the paper's identification is the diaphragm's")
        recs = read_records(records, required=(PRESSURE_SIGNAL, "position"),
                            p_atm=parameter_set["p_atm"])
        result = identify_signature(recs, parameter_set, prior_spread=spread / 100)
        _finish_identification(result, out, the_call(ctx))


class DataFormat(StrEnum):
    auto = "auto"
    record = "record"
    emps = "emps"
    tudelft = "tudelft"


class FrictionLaw(StrEnum):
    coulomb_viscous = "coulomb-viscous"
    stribeck = "stribeck"


def _read_any(path: Path, data_format: DataFormat):
    from pneumact.io import read_record
    from pneumact.io.datasets import read_emps, read_tudelft_cylinder

    if data_format is DataFormat.emps or (data_format is DataFormat.auto and
                                          path.suffix.lower() == ".mat"):
        return read_emps(path)
    if data_format is DataFormat.tudelft:
        return read_tudelft_cylinder(path)
    return read_record(path)


@identify_app.command("friction")
def identify_friction_command(
    ctx: typer.Context,
    record: Annotated[Path, typer.Argument(help="Record with position and force.")],
    friction: Annotated[FrictionLaw, typer.Option(
        help="Friction law of the inverse model.")] = FrictionLaw.coulomb_viscous,
    data_format: Annotated[DataFormat, typer.Option(
        "--format", help="auto (.mat: EMPS), record (CSV/Parquet), emps, tudelft.")] = (
        DataFormat.auto),
    force: Annotated[str | None, typer.Option(
        help="Signal holding the force: 'force' (with inertia) or 'friction'.")] = None,
    mass: Annotated[bool, typer.Option(help="Estimate the moving mass (F = M·a + F_f).")] = True,
    asymmetric: Annotated[bool, typer.Option(help="Coulomb and viscous per direction.")] = (
        False),
    cutoff: Annotated[float | None, typer.Option(
        help="Zero-phase low-pass cut-off [Hz] before differentiation.")] = None,
    decimate: Annotated[int, typer.Option(help="Keep every n-th sample after filtering.")] = 1,
    validate: Annotated[Path | None, typer.Option(
        help="A second record: report the relative force error there.")] = None,
    out: Annotated[Path, typer.Option(help="Output directory.")] = Path("pneumact-friction"),
) -> None:
    """Friction from measured motion and force (inverse model, linear/nonlinear least
    squares)."""
    with user_errors():
        from pneumact.identification import inverse_friction

        out = check_out_dir("--out", out)
        if cutoff is not None:
            check_positive("--cutoff", cutoff)
        rec = _read_any(record, data_format)
        force_name = force or ("friction" if "friction" in rec and not mass else "force")
        if data_format is DataFormat.tudelft and force is None:
            force_name, mass = "friction", False
        if decimate < 1:
            raise ParameterError(f"--decimate = {decimate}; must be >= 1")
        result = inverse_friction(rec, friction.value, force=force_name, mass=mass,
                                  asymmetric=asymmetric, cutoff=cutoff, decimate=decimate)
        other = [_read_any(validate, data_format)] if validate else []
        checked = result.validate(other[0]) if other else None
        use_agg()
        from pneumact.io.report import Report
        from pneumact.validation import validate_friction

        validation = validate_friction(result, other)

        def report(path: Path) -> None:
            page = Report(f"{friction.value} friction identified on {record.name}",
                          call=the_call(ctx))
            page.table(table, "Estimates with standard errors and 95 % intervals (SI)")
            page.figure(result.plot(), "Inverse model on the identification record")
            page.table(validation.metrics(), "Force error per record", index=False)
            if other:
                page.figure(validation.plot(), "Measured and predicted force")
            page.write(path)

        table = result.to_pandas()
        summary = {"relative_force_error": result.relative_force_error,
                   "condition_number": result.condition_number}
        if checked is not None:
            summary["relative_force_error_validation"] = checked
        written = write_outputs(out, {
            "friction.csv": lambda p: table.to_csv(p),
            "summary.csv": lambda p: _series_csv(summary, p),
            "friction.png": figure_writer(result.plot),
            "metrics.csv": lambda p: validation.metrics().to_csv(p, index=False),
            "report.html": report,
        })
        out_console.print(_estimates_table(f"{friction.value} friction from {record.name}",
                                           table))
        out_console.print(f"relative force error {100 * result.relative_force_error:.2f} %, "
                          f"condition number {result.condition_number:.3g}")
        if checked is not None and validate is not None:
            out_console.print(f"relative force error on {validate.name}: {100 * checked:.2f} %")
        for path in written:
            out_console.print(f"wrote {path}")


def _series_csv(values: dict, path) -> None:
    import pandas as pd

    pd.Series(values, name="value").rename_axis("quantity").to_csv(path)


# --------------------------------------------------------------------------- fit
def fit_command(
    ctx: typer.Context,
    records: RecordsArgument,
    free: Annotated[str, typer.Option(help="Comma-separated parameters to fit.")],
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
    per_record: Annotated[str | None, typer.Option(
        "--per-record", help="Free parameters with one value per record.")] = None,
    signals: Annotated[str, typer.Option(help="Measured signals to match.")] = "position",
    offsets: Annotated[str | None, typer.Option(
        help="Signals with a free sensor offset per record.")] = None,
    window: Annotated[str | None, typer.Option(
        help="'t0,t1' [s]: match only this time span.")] = None,
    multistart: Annotated[int, typer.Option(
        help="Extra space-filling starts (>= 0).")] = Multistart.starts,
    seed: Annotated[int, typer.Option(
        help="Seed of the multistart points (>= 0).")] = Multistart.seed,
    profile: Annotated[str | None, typer.Option(
        help="Parameters whose profile likelihood to compute.")] = None,
    points: Annotated[int, typer.Option(
        help="Profile: most steps on each side of the optimum (>= 3).")] = Profile.points,
    loss: Annotated[Loss, typer.Option(
        help="linear, or a robust loss: soft_l1, huber, cauchy, arctan.")] = DEFAULT_LOSS,
    f_scale: Annotated[float, typer.Option(
        "--f-scale", help="Residual scale of a robust loss.")] = Optimizer.f_scale,
    workers: WorkersOption = Executor.workers,
    scheduler: SchedulerOption = Executor.scheduler,
    rtol: Annotated[float, typer.Option(help="Relative tolerance of the solver.")] = 1e-6,
    out: Annotated[Path, typer.Option(help="Output directory.")] = Path("pneumact-fit"),
) -> None:
    """Fit parameters of the actuator (or --model cylinder, its records driven by a
    spool command) to measured records (forward-sensitivity Jacobian)."""
    with user_errors():
        import pneumact as pa
        from pneumact.identification import fit
        from pneumact.io import read_records

        out = check_out_dir("--out", out)
        check_int("--multistart", multistart, minimum=0)
        check_seed("--seed", seed)
        check_int("--points", points, minimum=3)
        check_positive("--f-scale", f_scale)
        if loss.value == "linear":
            refuse_unused(ctx, "f_scale", "with the linear loss (it scales a robust loss)",
                          "give --loss soft_l1, huber, cauchy or arctan, or leave it out")
        if multistart == 0:
            refuse_unused(ctx, "seed", "without --multistart (it seeds the extra starts)",
                          "give --multistart N, or leave it out")
        if profile is None:
            refuse_unused(ctx, "points", "without --profile (it sizes the profiles)",
                          "give --profile NAMES, or leave it out")
        executor = executor_of(workers, scheduler)
        free_names = names(free, "--free")
        span = None
        if window is not None:
            try:
                span = tuple(float(x) for x in window.split(","))
            except ValueError:
                span = ()
            if len(span) != 2:
                raise DataError(f"--window = {window!r}; give 't0,t1' in seconds")
            from pneumact.identification.arguments import check_window

            check_window(span, where="--window")
        parameter_set, built, _ = build_model_of(model, ModelOptions(
            params=params, valve=valve, friction=friction, chamber=chamber, rtol=rtol,
            exponent=exponent, decaying_damping=decaying_damping, elements=elements,
            spool_lag=spool_lag, valves=valves))
        recs = read_records(records, p_atm=parameter_set["p_atm"])
        result = fit_with_progress(lambda report: fit(
            built, recs, free_names, per_record=names(per_record, "--per-record") or (),
            signals=names(signals, "--signals") or ("position",),
            offsets=names(offsets, "--offsets") or (), window=span,
            multistart=Multistart(multistart, seed),
            profile=Profile(names(profile, "--profile") or (), points),
            optimizer=Optimizer(loss=loss.value, f_scale=f_scale), executor=executor,
            solver=pa.Rodas4(rtol=rtol), progress=report))
        use_agg()
        writers = result.writers(the_call(ctx))
        written = write_outputs(out, writers)
        out_console.print(_estimates_table("fitted parameters", result.to_pandas()))
        from pneumact.io.display import display_value

        for _, row in result.statistics.iterrows():
            rms, unit = display_value(row["rms"], row["unit"])
            out_console.print(f"{Path(row['record']).name} {row['signal']}: fit "
                              f"{row['fit_percent']:.2f} %, RMS {rms:.4g} {unit}")
        for name, prof in result.profiles.items():
            out_console.print(f"profile of {name}: {prof.verdict}")
        out_console.print(f"{result.simulations} simulations in {result.wall_time:.2f} s")
        for path in written:
            out_console.print(f"wrote {path}")

"""``pneumact sensitivity oat|sobol|morris|src|fast``: sensitivity studies of the actuator."""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum
from pathlib import Path
from typing import Annotated

import typer
from rich.table import Table

from pneumact.checks import check_int, check_out_dir, check_seed
from pneumact.cli.common import (
    Chamber,
    ChamberOption,
    Friction,
    FrictionOption,
    ModelOptions,
    OverwriteOption,
    ParamsOption,
    ResumeOption,
    SchedulerOption,
    TEndOption,
    Valve,
    ValveOption,
    WorkersOption,
    batch_progress,
    build_experiment,
    build_model,
    check_batch_flags,
    check_workers,
    err_console,
    figure_writer,
    fmt,
    names,
    out_console,
    shown_path,
    the_call,
    use_agg,
    user_errors,
    write_outputs,
)
from pneumact.errors import ArgumentError, ParameterError


class Method(StrEnum):
    oat = "oat"
    sobol = "sobol"
    morris = "morris"
    src = "src"
    fast = "fast"


def _variations(text: str | None) -> dict[str, str] | None:
    """'sigma0=50%,Fs=16%' -> {"sigma0": "50%", "Fs": "16%"}."""
    if text is None:
        return None
    out = {}
    for item in names(text) or []:
        name, sep, amount = item.partition("=")
        if not sep or not amount.strip():
            raise ParameterError(f"--vary item {item!r}; write name=N% (e.g. sigma0=50%)")
        out[name.strip()] = amount.strip()
    return out


def sensitivity(
    ctx: typer.Context,
    method: Annotated[Method, typer.Argument(help="oat (paper eq. 15), sobol, morris, src "
                                                  "(eq. 14) or fast (RBD-FAST).")],
    params: ParamsOption = "vgt-paper",
    valve: ValveOption = Valve.command,
    friction: FrictionOption = Friction.lugre,
    chamber: ChamberOption = Chamber.isothermal,
    t_end: TEndOption = None,
    vary: Annotated[str | None, typer.Option(
        help="name=N% list; default: the paper's amounts (oat), else ±20 % of sigma0, "
             "sigma1, sigma2, vs and ±10 % of Fc, Fs (so that Fs >= Fc in every run).")] = None,
    features: Annotated[str, typer.Option(help="Features to analyse.")] = (
        "loop_width_pressure,breakaway_pressure"),
    signals: Annotated[str | None, typer.Option(
        help="Signals to analyse along time (e.g. position): indices against time and along "
             "the loop, and local normalised sensitivities.")] = None,
    times: Annotated[int, typer.Option(help="Points of the time grid of --signals.")] = 41,
    n: Annotated[int | None, typer.Option("--n", help=(
        "Base sample size: sobol a power of two >= 8 (default 256), src >= 2·(k + 1) for k "
        "parameters, fast >= 40, or trajectories (morris, >= 2); not for oat."),
        show_default=False)] = None,
    second_order: Annotated[bool, typer.Option("--second-order",
                                               help="Sobol second-order indices.")] = False,
    convergence: Annotated[bool, typer.Option(
        "--convergence", help="Sobol: indices and CI widths at n/16, n/8, ... n from the "
                              "same sample.")] = False,
    seed: Annotated[int, typer.Option(help="Seed of the sample (>= 0).")] = 0,
    scheduler: SchedulerOption = None,
    workers: WorkersOption = None,
    resume: ResumeOption = False,
    overwrite: OverwriteOption = False,
    out: Annotated[Path, typer.Option(help="Output directory.")] = Path("pneumact-sensitivity"),
) -> None:
    """Sensitivity of the actuator's features (and signals) to its parameters, on the
    batch engine. The runs of the global methods are kept in OUT/runs (resumable)."""
    with user_errors():
        import numpy as np

        check_batch_flags(resume, overwrite, scheduler)
        check_workers(workers)
        check_seed("--seed", seed)
        check_int("--times", times, minimum=2)
        out = check_out_dir("--out", out)
        _check_method_options(method, n, second_order, convergence,
                              resume=resume, overwrite=overwrite,
                              scheduler=scheduler is not None, workers=workers is not None)
        options = ModelOptions(params, valve, friction, chamber, t_end)
        parameter_set, actuator = build_model(options)
        experiment = build_experiment(options, parameter_set)
        feature_names = names(features, "--features") or []
        signal_names = names(signals, "--signals") or []
        from pneumact.simulation.batch import check_outputs

        check_outputs(actuator, experiment, feature_names, signal_names, cli=True)
        use_agg()
        study = Study(method, actuator, experiment, parameter_set, vary,
                      DEFAULT_N if n is None else n, second_order, seed,
                      dict(scheduler=scheduler, workers=workers, resume=resume,
                           overwrite=overwrite))
        try:
            factors = study.problem().names
        except ParameterError as exc:
            raise ParameterError(f"--vary: {exc.message}") from None
        if method is not Method.oat:
            check_sample_size(method, study.n, len(factors))
        from pneumact.io.tables import staged_folder

        with staged_folder(out, resumable=method is not Method.oat, resume=resume,
                           overwrite=overwrite) as stage:
            writers = study.features(feature_names, stage, convergence)
            grid = np.linspace(experiment.t_start, experiment.t_end, times)
            for signal in signal_names:
                writers.update(study.signal(signal, grid, stage))
            writers["report.html"] = _report_writer(study, the_call(ctx), list(writers))
            written = write_outputs(stage, writers)
        for path in written:
            out_console.print(f"wrote {shown_path(path, stage, out)}")


#: default --n of the sample-based methods
DEFAULT_N = 256


def _check_method_options(method: Method, n, second_order: bool, convergence: bool,
                          **batch: bool) -> None:
    """Refuse the options the method would ignore."""
    if method is Method.oat:
        given = [f"--{name}" for name, on in {"n": n is not None, **batch}.items() if on]
        given += ["--second-order"] if second_order else []
        if given:
            raise ArgumentError(f"{', '.join(given)}: not for oat, which varies one "
                                "parameter at a time, without a sample or kept runs")
    for flag, on in (("--convergence", convergence), ("--second-order", second_order)):
        if on and method is not Method.sobol:
            raise ArgumentError(f"{flag} is for sobol, not {method.value}")
    if convergence and second_order:
        raise ArgumentError("--convergence follows first and total indices; run "
                            "--second-order separately")


def check_sample_size(method: Method, n: int, k: int) -> None:
    """--n checked against what the method needs, before any run."""
    from pneumact.sensitivity import methods

    option = "--n"
    if method is Method.sobol:
        methods.check_sobol_n(n, where="", name=option)
    elif method is Method.morris:
        check_int(option, n, minimum=methods.MIN_MORRIS_TRAJECTORIES)
    elif method is Method.src:
        methods.check_src_n(n, k, where="", name=option)
    else:
        check_int(option, n, minimum=methods.MIN_RBD_FAST_N)


@dataclass
class Study:
    """One sensitivity command: the method, the model and the batch options, and the
    writers of what each analysis produced."""

    method: Method
    model: object
    experiment: object
    parameter_set: object
    vary: str | None
    n: int
    second_order: bool
    seed: int
    batch: dict

    def problem(self):
        from pneumact import sensitivity as sa

        return sa.Problem.around(self.parameter_set, _variations(self.vary) or sa.DEFAULT_RANGES)

    def _run(self, evaluate, convergence: bool = False):
        from pneumact import sensitivity as sa

        problem, n, seed = self.problem(), self.n, self.seed
        if convergence:
            return sa.sobol_convergence(problem, evaluate, n_max=n, n_min=max(1, n // 16),
                                        seed=seed, target_width=None)
        run = {Method.sobol: lambda: sa.sobol(problem, evaluate, n, self.second_order, seed),
               Method.morris: lambda: sa.morris(problem, evaluate, n, seed=seed),
               Method.src: lambda: sa.src(problem, evaluate, n, seed),
               Method.fast: lambda: sa.rbd_fast(problem, evaluate, n, seed)}[self.method]
        return run(), None

    def features(self, feature_names: list[str], out: Path, convergence: bool) -> dict:
        """Writers of the feature study (oat: Figs. 3 and 5 and the change table)."""
        from pneumact import sensitivity as sa

        if self.method is Method.oat:
            with err_console.status("oat: simulating"):
                study = sa.one_at_a_time(self.model, self.experiment, _variations(self.vary),
                                         features=feature_names)
            curves = sa.friction_velocity(self.parameter_set, _variations(self.vary))
            _print_oat(study, feature_names)
            return {"runs.csv": lambda p: study.runs.to_csv(p, index=False),
                    "loops.png": figure_writer(study.plot_loops),
                    "friction_velocity.png": figure_writer(curves.plot)}
        problem = self.problem()
        with batch_progress(f"{self.method.value}: features") as progress:
            evaluate = sa.model_outputs(self.model, self.experiment, problem, feature_names,
                                        out_dir=out / "runs", progress=progress, **self.batch)
            study, table = self._run(evaluate, convergence)
        writers = {"indices.csv": lambda p: study.indices.to_csv(p, index=False),
                   "sample.csv": lambda p: study.sample.to_csv(p, index=False),
                   "outputs.csv": lambda p: study.outputs.to_csv(p, index=False)}
        for feature in feature_names:
            writers[f"indices_{feature}.png"] = figure_writer(lambda f=feature: study.plot(f))
            _print_indices(study, feature)
        if table is not None:
            writers["convergence.csv"] = lambda p: table.to_csv(p, index=False)
            for feature in feature_names:
                writers[f"convergence_{feature}.png"] = figure_writer(
                    lambda f=feature: sa.plot_convergence(table, f))
        return writers

    def signal(self, signal: str, grid, out: Path) -> dict:
        """Writers of the signal's indices along time and along the loop, and of its
        local normalised sensitivities."""
        import pneumact as pa
        from pneumact import sensitivity as sa

        problem = self.problem()
        with err_console.status(f"local sensitivities of {signal}"):
            local = sa.local_along_time(self.model, self.experiment, problem.names, signal,
                                        grid)
            nominal = pa.simulate(self.model, self.experiment, t_eval=grid)
        pressure_kpa = nominal["pressure"] * 1e-3
        writers = {f"local_{signal}.csv": lambda p: local.to_csv(p),
                   f"local_{signal}.png": figure_writer(lambda: sa.plot_along_time(local))}
        if self.method is Method.oat:
            return writers
        with batch_progress(f"{self.method.value}: {signal}") as progress:
            evaluate = sa.model_signal(self.model, self.experiment, problem, signal, grid,
                                       out_dir=out / f"runs-{signal}", progress=progress,
                                       **self.batch)
            study, _ = self._run(evaluate)
        curves = sa.along_time(study)
        writers.update({
            f"indices_{signal}.csv": lambda p: study.indices.to_csv(p, index=False),
            f"along_time_{signal}.png": figure_writer(lambda: sa.plot_along_time(study)),
            f"along_loop_{signal}.png": figure_writer(
                lambda: sa.plot_along_loop(curves, pressure_kpa, "chamber pressure [kPa]"))})
        return writers


def _report_writer(study: Study, call: str, names: list[str]):
    """report.html: the CSV tables and PNG figures of ``names``, read back from beside it
    (``write_outputs`` stages every file before the report), in one page."""

    def write(path: Path) -> None:
        import pandas as pd

        from pneumact.io.report import Report

        report = Report(f"Sensitivity study: {study.method.value}", call=call,
                        parameters=study.parameter_set)
        for name in names:
            staged = path.parent / name
            if name.endswith(".csv") and name not in ("sample.csv", "outputs.csv"):
                report.heading(name.removesuffix(".csv"))
                report.table(pd.read_csv(staged).head(400), name, index=False)
            elif name.endswith(".png"):
                report.image(staged.read_bytes(), name.removesuffix(".png"))
        report.write(path)

    return write


def _print_oat(study, features) -> None:
    for feature in features:
        ranking = study.ranking(feature)
        table = Table(title=f"one at a time: largest change of {feature}")
        table.add_column("parameter")
        table.add_column("|Δ|", justify="right")
        for name, value in ranking.items():
            table.add_row(name, fmt(value, 4))
        out_console.print(table)


def _print_indices(study, feature: str) -> None:
    frame = study.table(feature)
    table = Table(title=f"{study.method}: {feature}")
    table.add_column("parameter")
    for column in frame.columns:
        table.add_column(column, justify="right")
    for name, row in frame.iterrows():
        table.add_row(name, *(fmt(v, 3) for v in row))
    out_console.print(table)

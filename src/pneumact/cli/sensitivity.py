"""``pneumact sensitivity oat|sobol|morris|src|fast``: sensitivity studies of the actuator."""

from __future__ import annotations

from enum import StrEnum
from pathlib import Path
from typing import Annotated

import typer
from rich.table import Table

from pneumact.cli.common import (
    Chamber,
    ChamberOption,
    Friction,
    FrictionOption,
    ModelOptions,
    ParamsOption,
    TEndOption,
    Valve,
    ValveOption,
    build_experiment,
    build_model,
    err_console,
    figure_writer,
    fmt,
    names,
    out_console,
    use_agg,
    user_errors,
    write_outputs,
)
from pneumact.errors import ParameterError

#: Ranges of the global methods unless --vary: Fc and Fs at ±10 % so that no run has
#: Fs < Fc (vgt-paper: Fc ≤ 2.86 N < 2.88 N ≤ Fs).
DEFAULT_GLOBAL = {"sigma0": "20%", "sigma1": "20%", "sigma2": "20%", "vs": "20%",
                  "Fc": "10%", "Fs": "10%"}


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
    n: Annotated[int, typer.Option("--n", help="Base sample size (sobol, src, fast) or "
                                               "trajectories (morris).")] = 256,
    second_order: Annotated[bool, typer.Option("--second-order",
                                               help="Sobol second-order indices.")] = False,
    seed: Annotated[int, typer.Option(help="Seed of the sample.")] = 0,
    scheduler: Annotated[str | None, typer.Option(help="Dask scheduler address.")] = None,
    out: Annotated[Path, typer.Option(help="Output directory.")] = Path("pneumact-sensitivity"),
) -> None:
    """Sensitivity of the actuator's features to its parameters, on the batch engine."""
    with user_errors():
        from pneumact import sensitivity as sa

        options = ModelOptions(params, valve, friction, chamber, t_end)
        parameter_set, actuator = build_model(options)
        experiment = build_experiment(options, parameter_set)
        feature_names = names(features) or []
        if n < 1:
            raise ParameterError(f"--n = {n}; must be >= 1")
        use_agg()
        with err_console.status(f"{method.value}: simulating"):
            if method is Method.oat:
                study = sa.one_at_a_time(actuator, experiment, _variations(vary),
                                         features=feature_names)
            else:
                variations = _variations(vary) or DEFAULT_GLOBAL
                problem = sa.Problem.around(parameter_set, variations)
                evaluate = sa.model_outputs(actuator, experiment, problem, feature_names,
                                            scheduler=scheduler)
                run = {Method.sobol: lambda: sa.sobol(problem, evaluate, n, second_order,
                                                      seed),
                       Method.morris: lambda: sa.morris(problem, evaluate, n, seed=seed),
                       Method.src: lambda: sa.src(problem, evaluate, n, seed),
                       Method.fast: lambda: sa.rbd_fast(problem, evaluate, n, seed)}[method]
                study = run()
        if method is Method.oat:
            curves = sa.friction_velocity(parameter_set, _variations(vary))
            writers = {"runs.csv": lambda p: study.runs.to_csv(p, index=False),
                       "loops.png": figure_writer(study.plot_loops),
                       "friction_velocity.png": figure_writer(curves.plot)}
            _print_oat(study, feature_names)
        else:
            writers = {"indices.csv": lambda p: study.indices.to_csv(p, index=False),
                       "sample.csv": lambda p: study.sample.to_csv(p, index=False),
                       "outputs.csv": lambda p: study.outputs.to_csv(p, index=False)}
            for feature in feature_names:
                writers[f"indices_{feature}.png"] = figure_writer(
                    lambda f=feature: study.plot(f))
                _print_indices(study, feature)
        for path in write_outputs(out, writers):
            out_console.print(f"wrote {path}")


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

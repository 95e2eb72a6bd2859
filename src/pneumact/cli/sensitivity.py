"""``pneumact sensitivity oat|sobol|morris|src|rbd_fast``: sensitivity studies of the actuator
(or ``--model cylinder``), at one operating condition or across several (``--conditions``,
the actuator's)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from enum import StrEnum
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer
from rich.table import Table

from pneumact.checks import check_int, check_out_dir, check_seed
from pneumact.cli.common import (
    DEFAULT_DECAYING_DAMPING,
    DEFAULT_EXPONENT,
    DEFAULT_FRICTION,
    DEFAULT_VALVE,
    KEPT_AS_IT_WAS,
    KEPT_FOR_RESUME,
    Chamber,
    ChamberOption,
    ChunkSizeOption,
    DecayingDampingOption,
    ElementsOption,
    ExponentOption,
    FrictionOption,
    LoadStepOption,
    ModelKind,
    ModelOption,
    ModelOptions,
    OverwriteOption,
    ParamsOption,
    ResumeOption,
    SchedulerOption,
    SpoolLagOption,
    TEndOption,
    Valve,
    ValveOption,
    ValvesOption,
    WorkersOption,
    batch_progress,
    build_model_of,
    checkpoint_of,
    err_console,
    executor_of,
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
from pneumact.models.actuator import CHAMBER_PRESSURE
from pneumact.models.friction import FrictionModel
from pneumact.options import Checkpoint, Executor

if TYPE_CHECKING:
    from pneumact.experiments.actuator import Experiment
    from pneumact.models.actuator import Actuator
    from pneumact.models.cylinder import Cylinder
    from pneumact.parameters.parameter_set import ParameterSet


#: --features when not given, by the model's ``summary_kind``: the actuator's loop, the
#: cylinder's move (its step reaches the end stop: the travel is the stroke whatever the
#: parameters, the top speed is not)
DEFAULT_FEATURES = {"hysteresis": "loop_width_pressure,breakaway_pressure",
                    "motion": "top_speed_out"}


class Method(StrEnum):
    oat = "oat"
    sobol = "sobol"
    morris = "morris"
    src = "src"
    rbd_fast = "rbd_fast"


def _variations(text: str | None) -> dict[str, str] | None:
    """'sigma0=50%,Fs=16%' -> {"sigma0": "50%", "Fs": "16%"}."""
    if text is None:
        return None
    out = {}
    for item in names(text) or []:
        name, sep, amount = item.partition("=")
        if not sep or not amount.strip():
            raise ParameterError(f"--variations item {item!r}; write name=N% (e.g. sigma0=50%)")
        out[name.strip()] = amount.strip()
    return out


ConditionsOption = Annotated[list[str] | None, typer.Option(
    "--conditions",
    help="Run the study at each operating condition: AXIS=V1,V2,... with AXIS period (s, "
         "or with a unit: 2min), speed (sliding speed with a unit: 2vs, 1.5mm/s; the "
         "period is found), amplitude (fraction of the full cycle) or valve (source, "
         "command, regulator). Repeat for more axes: every combination is run. Indices are "
         "written and plotted against the sliding speed in units of vs.")]


def sensitivity(
    ctx: typer.Context,
    method: Annotated[Method, typer.Argument(help="oat (paper eq. 15), sobol, morris, src "
                                                  "(eq. 14) or rbd_fast.")],
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
    variations: Annotated[str | None, typer.Option(
        help="name=N% list; default: the paper's amounts (oat), else ±20 % of sigma0, "
             "sigma1, sigma2, vs and ±10 % of Fc, Fs (so that Fs >= Fc in every run).")] = None,
    features: Annotated[str | None, typer.Option(
        help="Features to analyse (default: loop_width_pressure,breakaway_pressure of the "
             "actuator, top_speed_out of the cylinder).")] = None,
    signals: Annotated[str | None, typer.Option(
        help="Signals to analyse along time (e.g. position): indices against time and along "
             "the loop, and local normalised sensitivities.")] = None,
    times: Annotated[int, typer.Option(help="Points of the time grid of --signals.")] = 41,
    n: Annotated[int | None, typer.Option("--n", help=(
        "Base sample size: sobol a power of two >= 8, src >= 2·(k + 1) for k parameters, "
        "rbd_fast >= 40, or trajectories (morris, >= 2); not for oat. Default: the API's "
        "(sobol 1024, src 500, rbd_fast 1000, morris 20; 256 with --conditions)."),
        show_default=False)] = None,
    second_order: Annotated[bool, typer.Option("--second-order",
                                               help="Sobol second-order indices.")] = False,
    convergence: Annotated[bool, typer.Option(
        "--convergence", help="Sobol: indices and CI widths at n/16, n/8, ... n from the "
                              "same sample.")] = False,
    seed: Annotated[int, typer.Option(help="Seed of the sample (>= 0).")] = 0,
    conditions: ConditionsOption = None,
    scheduler: SchedulerOption = Executor.scheduler,
    workers: WorkersOption = Executor.workers,
    chunk_size: ChunkSizeOption = Executor.chunk_size,
    resume: ResumeOption = Checkpoint.resume,
    overwrite: OverwriteOption = Checkpoint.overwrite,
    out: Annotated[Path, typer.Option(help="Output directory.")] = Path("pneumact-sensitivity"),
) -> None:
    """Sensitivity of the actuator's (or the cylinder's) features and signals to its
    parameters, on the batch engine. The runs of the global methods are kept in OUT/runs
    (resumable)."""
    with user_errors(kept=KEPT_AS_IT_WAS if method is Method.oat else KEPT_FOR_RESUME):
        import numpy as np

        executor = executor_of(workers, scheduler, chunk_size)
        check_seed("--seed", seed)
        check_int("--times", times, minimum=2)
        out = checkpoint_of(check_out_dir("--out", out), resume, overwrite).path
        _check_method_options(method, n, second_order, convergence,
                              resume=resume, overwrite=overwrite,
                              scheduler=scheduler is not None, workers=workers is not None,
                              chunk_size=chunk_size is not None)
        options = ModelOptions(params=params, valve=valve, friction=friction, chamber=chamber,
                               t_end=t_end, exponent=exponent,
                               decaying_damping=decaying_damping,
                               elements=elements, spool_lag=spool_lag, valves=valves,
                               load_step=load_step)
        parameter_set, actuator, experiment = build_model_of(model, options)
        if conditions and model is ModelKind.cylinder:
            raise ArgumentError("--conditions varies the actuator's pressure cycle (period, "
                                "amplitude, valve); --model cylinder steps its spool: drop "
                                "--conditions")
        if conditions and load_step is not None:
            raise ArgumentError(f"--load-step {load_step} with --conditions: the conditions "
                                "vary the pressure cycle (its period among them) under a "
                                "load stepping at one fixed time; drop one of them")
        if features is None:
            features = DEFAULT_FEATURES[actuator.summary_kind]
        feature_names = names(features, "--features") or []
        signal_names = names(signals, "--signals") or []
        from pneumact.simulation.batch import check_outputs

        check_outputs(actuator, experiment, feature_names, signal_names, cli=True)
        if conditions and (signal_names or convergence):
            raise ParameterError("--conditions runs the feature study at each condition; "
                                 "run --signals and --convergence without it")
        use_agg()
        study = Study(method, actuator, experiment, parameter_set, variations,
                      api_sample_size(method, bool(conditions)) if n is None else n,
                      second_order, seed, executor,
                      resume)
        try:
            factors = study.problem().names
        except ParameterError as exc:
            raise ParameterError(f"--variations: {exc.message}") from None
        if method is not Method.oat:
            check_sample_size(method, study.n, len(factors))
        if signal_names:  # the largest allocation, estimated before any run
            from pneumact.simulation import assemble
            from pneumact.simulation.memory import check_memory, simulate_bytes

            assembly = assemble(actuator)
            check_memory(simulate_bytes(times, len(assembly.states),
                                        len(assembly.output_names), len(factors)),
                         f"--signals on --times {times} points (sensitivities to "
                         f"{len(factors)} parameters)")
        from pneumact.io.tables import staged_folder

        with staged_folder(out, resumable=method is not Method.oat, resume=resume,
                           overwrite=overwrite) as stage:
            if conditions:
                chosen = parse_conditions(conditions, actuator, valve, t_end)
                writers = study.across(chosen, feature_names, stage)
            else:
                writers = study.features(feature_names, stage, convergence)
            grid = np.linspace(experiment.t_start, experiment.t_end, times)
            for signal in signal_names:
                writers.update(study.signal(signal, grid, stage))
            writers["report.html"] = _report_writer(study, the_call(ctx), list(writers))
            written = write_outputs(stage, writers)
        for path in written:
            out_console.print(f"wrote {shown_path(path, stage, out)}")


def api_sample_size(method: Method, across: bool) -> int:
    """--n when not given: the API's default sample size of the method (of
    ``across_conditions`` across conditions; morris: its trajectories)."""
    import inspect

    from pneumact import sensitivity as sa

    function: Callable[..., object]
    if across:
        function, name = sa.across_conditions, "n"
    elif method is Method.morris:
        function, name = sa.morris, "trajectories"
    elif method is Method.oat:
        return 0
    else:
        function, name = getattr(sa, method.value), "n"
    return int(inspect.signature(function).parameters[name].default)


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
    """One sensitivity command: the method, the model, where the runs go (``executor``;
    kept resumable beside the outputs, continued with ``resume``), and the writers of
    what each analysis produced."""

    method: Method
    model: Actuator | Cylinder
    experiment: Experiment
    parameter_set: ParameterSet
    variations: str | None
    n: int
    second_order: bool
    seed: int
    executor: Executor
    resume: bool = False

    def checkpoint(self, folder: Path) -> Checkpoint:
        """Where a study's runs are kept (inside the staged output folder, which the
        --overwrite of the command already emptied)."""
        return Checkpoint(folder, resume=self.resume)

    def problem(self):
        from pneumact import sensitivity as sa

        return sa.Problem.around(self.parameter_set,
                                 _variations(self.variations) or sa.DEFAULT_RANGES)

    def _run(self, evaluate, convergence: bool = False):
        from pneumact import sensitivity as sa

        problem, n, seed = self.problem(), self.n, self.seed
        if convergence:
            return sa.sobol_convergence(problem, evaluate, n_max=n, n_min=max(1, n // 16),
                                        seed=seed, target_width=None)
        run = {Method.sobol: lambda: sa.sobol(problem, evaluate, n, self.second_order, seed),
               Method.morris: lambda: sa.morris(problem, evaluate, n, seed=seed),
               Method.src: lambda: sa.src(problem, evaluate, n, seed),
               Method.rbd_fast: lambda: sa.rbd_fast(problem, evaluate, n, seed)}[self.method]
        return run(), None

    def features(self, feature_names: list[str], out: Path, convergence: bool) -> dict:
        """Writers of the feature study (oat: Figs. 3 and 5 and the change table)."""
        from pneumact import sensitivity as sa

        if self.method is Method.oat:
            with err_console.status("oat: simulating"):
                study = sa.one_at_a_time(self.model, self.experiment, _variations(self.variations),
                                         features=feature_names, executor=self.executor)
            _print_oat(study, feature_names)
            writers = {"runs.csv": lambda p: study.runs.to_csv(p, index=False),
                       "loops.png": figure_writer(  # zoomed into an actuator's loops
                           lambda: study.plot_loops(zoom=CHAMBER_PRESSURE in study.signals))}
            # Fig. 3 of the varied parameters of the friction law (not the valve's, ...)
            friction = self.model.friction  # one law (the command line places no two)
            law = set(friction.required) if isinstance(friction, FrictionModel) else set()
            on_law = {name: amount for name, amount in
                      (_variations(self.variations) or sa.PAPER_VARIATIONS).items()
                      if name in law}
            if on_law:
                curves = sa.friction_velocity(self.parameter_set, on_law)
                writers["friction_velocity.png"] = figure_writer(curves.plot)
            return writers
        problem = self.problem()
        with batch_progress(f"{self.method.value}: features") as progress:
            evaluate = sa.model_outputs(self.model, self.experiment, problem, feature_names,
                                        checkpoint=self.checkpoint(out / "runs"),
                                        progress=progress, executor=self.executor)
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

    def across(self, chosen: list, feature_names: list[str], out: Path) -> dict:
        """Writers of the feature study at each condition: the conditions, the indices
        against them and one plot per feature (index against v/vs)."""
        from pneumact import sensitivity as sa

        variations = _variations(self.variations)
        with batch_progress(f"{self.method.value}: {len(chosen)} conditions") as progress:
            study = sa.across_conditions(
                self.model, chosen, self.method.value, variations=variations,
                features=feature_names, n=self.n, seed=self.seed,
                second_order=self.second_order, checkpoint=self.checkpoint(out / "runs"),
                progress=None if self.method is Method.oat else progress,
                executor=self.executor)
        for feature in feature_names:
            _print_across(study, feature)
        writers = {"conditions.csv": lambda p: study.conditions.to_csv(p, index=False),
                   "indices.csv": lambda p: study.indices.to_csv(p, index=False)}
        for feature in feature_names:
            writers[f"indices_{feature}_by_speed.png"] = figure_writer(
                lambda f=feature: study.plot(f))
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
        pressure_kpa = (nominal[CHAMBER_PRESSURE] * 1e-3 if CHAMBER_PRESSURE in nominal
                        else None)
        writers = {f"local_{signal}.csv": lambda p: local.to_csv(p),
                   f"local_{signal}.png": figure_writer(lambda: sa.plot_along_time(local))}
        if self.method is Method.oat:
            return writers
        with batch_progress(f"{self.method.value}: {signal}") as progress:
            evaluate = sa.model_signal(self.model, self.experiment, problem, signal, grid,
                                       checkpoint=self.checkpoint(out / f"runs-{signal}"),
                                       progress=progress, executor=self.executor)
            study, _ = self._run(evaluate)
        curves = sa.along_time(study)
        writers.update({
            f"indices_{signal}.csv": lambda p: study.indices.to_csv(p, index=False),
            f"along_time_{signal}.png": figure_writer(lambda: sa.plot_along_time(study))})
        if pressure_kpa is not None:  # an actuator's loop (a cylinder has two chambers)
            writers[f"along_loop_{signal}.png"] = figure_writer(
                lambda: sa.plot_along_loop(curves, pressure_kpa, "chamber pressure [kPa]"))
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


def _print_across(study, feature: str) -> None:
    frame = study.index(feature)
    speeds = study.conditions.set_index("condition")["speed_vs"]
    key = study.default_index
    table = Table(title=f"{study.method}: {key} of {feature} by condition")
    table.add_column("condition")
    table.add_column("v/vs", justify="right")
    for column in frame.columns:
        table.add_column(column, justify="right")
    for label, row in frame.iterrows():
        table.add_row(label, fmt(speeds[label], 3), *(fmt(v, 3) for v in row))
    out_console.print(table)


def parse_conditions(items: list[str], model, valve: Valve, t_end: float | None) -> list:
    """The conditions of ``--conditions AXIS=V1,V2 ...`` (every combination of the axes;
    axes not given: the command's --valve, the period --t-end or 20 s, amplitude 1)."""
    from pneumact import sensitivity as sa

    axes: dict[str, list] = {}
    for item in items:
        axis, sep, values = item.partition("=")
        axis = axis.strip()
        listed = names(values)
        if not sep or axis not in CONDITION_AXES or not listed:
            raise ParameterError(f"--conditions {item!r}; write AXIS=V1,V2,... with AXIS one "
                                 f"of {', '.join(CONDITION_AXES)} (e.g. period=20,80,320)")
        if axis in axes:
            raise ParameterError(f"--conditions: the axis {axis} is given twice")
        axes[axis] = [CONDITION_AXES[axis](v, model) for v in listed]
    if "period" in axes and "speed" in axes:
        raise ParameterError("--conditions: give either periods or sliding speeds, not both")
    if t_end is not None and ("period" in axes or "speed" in axes):
        raise ParameterError("--t-end and --conditions period/speed both set the cycle; give "
                             "the periods in --conditions only")
    valves = axes.get("valve", [valve.value])
    amplitudes = axes.get("amplitude", [1.0])
    if "speed" not in axes:
        return sa.conditions(axes.get("period", [t_end or 20.0]), amplitudes, valves)
    return [c for v in valves for a in amplitudes
            for c in sa.at_speeds(model, axes["speed"], amplitude=a, valve=v)]


def _period(text: str, model) -> float:
    from pneumact.io.quantities import parse_value

    value = parse_value("--conditions period", text if not _bare(text) else f"{text} s", "s")
    if not value > 0:
        raise ParameterError(f"--conditions period={text}; must be a duration > 0")
    return value


def _speed(text: str, model) -> float:
    """A sliding speed [m/s]: '2vs' (times the set's Stribeck velocity) or with a unit."""
    from pneumact.io.quantities import parse_value

    compact = text.replace(" ", "")
    if compact.endswith("vs"):
        factor = compact.removesuffix("vs") or "1"
        try:
            value = float(factor) * float(model.params["vs"])
        except ValueError:
            raise ParameterError(f"--conditions speed={text}; write a multiple of vs such as "
                                 "2vs") from None
    elif _bare(text):
        raise ParameterError(f"--conditions speed={text} has no unit; write e.g. {text}vs or "
                             f"{text}mm/s")
    else:
        value = parse_value("--conditions speed", text, "m/s")
    if not value > 0:
        raise ParameterError(f"--conditions speed={text}; must be > 0")
    return value


def _amplitude(text: str, model) -> float:
    try:
        value = float(text)
    except ValueError:
        raise ParameterError(f"--conditions amplitude={text}; give a fraction of the full "
                             "cycle in (0, 1]") from None
    return value


def _valve(text: str, model) -> str:
    if text not in {v.value for v in Valve}:
        raise ParameterError(f"--conditions valve={text}; allowed: "
                             f"{', '.join(v.value for v in Valve)}")
    return text


def _bare(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


CONDITION_AXES = {"period": _period, "speed": _speed, "amplitude": _amplitude,
                  "valve": _valve}


def _print_indices(study, feature: str) -> None:
    frame = study.to_pandas(output=feature)
    table = Table(title=f"{study.method}: {feature}")
    table.add_column("parameter")
    for column in frame.columns:
        table.add_column(column, justify="right")
    for name, row in frame.iterrows():
        table.add_row(name, *(fmt(v, 3) for v in row))
    out_console.print(table)

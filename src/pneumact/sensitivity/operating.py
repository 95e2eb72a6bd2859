"""Sensitivity across operating conditions: which parameters matter depends on how the
actuator is driven, so a study is run at each of several conditions and its indices are
returned as a function of them.

A ``Condition`` is the default slow triangular cycle (pressure p_atm → 20 kPa abs → p_atm
behind a pressure source or the regulator, command 0 → 1 → 0 behind the command valve)
with a ``period``, an ``amplitude`` (fraction of that full cycle) and a ``valve``. Each
condition is also described by the sliding speed it produces, measured on its nominal run
(``analysis.sliding_speed``: the mean speed over 20–80 % of the stroke) and given in units
of the Stribeck velocity vs: LuGre friction changes character around v ≈ vs, so v/vs is
the axis on which the indices are read. ``at_speeds`` finds the periods that give wanted
sliding speeds.

``across_conditions`` runs one study per condition (one at a time, Sobol, Morris, SRC or
RBD-FAST, on the batch engine) and gathers the indices in one long table
(``ConditionStudy.indices``); ``ConditionStudy.plot`` draws an index against v/vs;
``where`` turns a margin measured at each condition into the ranges of v/vs where it is
positive, with the boundaries interpolated between conditions.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import os
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from ..errors import ParameterError
from ..io.report import ResultVocabulary
from ..progress import Progress, ProgressCallback, notify

if TYPE_CHECKING:
    from matplotlib.figure import Figure
from ..options import Checkpoint, Executor
from ..plotting import tight_layout

__all__ = ["CONDITION_COLUMNS", "FULL_CYCLE_LOW_PRESSURE", "METHODS", "VALVE_NAMES",
           "Condition", "ConditionStudy", "across_conditions", "at_speeds", "conditions",
           "where"]

#: The lowest pressure [Pa abs] of the full pressure cycle (amplitude 1).
FULL_CYCLE_LOW_PRESSURE = 20e3
#: Valves a condition can name (as on the command line).
VALVE_NAMES = ("source", "command", "regulator")
#: Study methods ``across_conditions`` runs.
METHODS = ("oat", "sobol", "morris", "src", "rbd_fast")
#: Columns of ``ConditionStudy.conditions`` that describe a condition.
CONDITION_COLUMNS = ("condition", "valve", "period", "amplitude", "sliding_speed",
                     "speed_vs")
#: Index plotted by default per method.
DEFAULT_INDEX = {"oat": "relative_change", "sobol": "ST", "morris": "mu_star",
                 "src": "SRC2", "rbd_fast": "S1"}
#: ``at_speeds``: iterations of the period search and the accepted relative speed error.
SPEED_ITERATIONS = 8
SPEED_RTOL = 0.02


@dataclass(frozen=True)
class Condition:
    """One operating condition: the default triangular cycle of ``period`` [s] through
    ``valve`` (source, command or regulator), reaching ``amplitude`` (0 < a ≤ 1) of the
    full cycle: down to p_atm − a·(p_atm − 20 kPa), or a command up to a."""

    period: float = 20.0
    amplitude: float = 1.0
    valve: str = "command"

    def __post_init__(self):
        if not (math.isfinite(self.period) and self.period > 0):
            raise ParameterError(f"condition: period = {self.period!r} s; must be a duration "
                                 "> 0")
        if not (math.isfinite(self.amplitude) and 0 < self.amplitude <= 1):
            raise ParameterError(f"condition: amplitude = {self.amplitude!r}; must be a "
                                 "fraction of the full cycle in (0, 1]")
        if self.valve not in VALVE_NAMES:
            raise ParameterError(f"condition: valve = {self.valve!r}; allowed: "
                                 f"{', '.join(VALVE_NAMES)}")

    @property
    def label(self) -> str:
        text = f"{self.valve}, {self.period:g} s"
        return text if self.amplitude == 1 else f"{text}, amplitude {self.amplitude:g}"

    def model(self, base):
        """``base`` (an ``Actuator``) behind this condition's valve; its own valve object
        is kept when it is of that kind (custom area maps survive)."""
        from ..models import VALVES

        kind = VALVES[self.valve]
        if type(base.valve) is kind:
            return base
        return dataclasses.replace(base, valve=kind())

    def experiment(self, params):
        """The cycle of this condition for a parameter set (its p_atm)."""
        from ..experiments import CommandCycle, PressureCycle

        if self.valve == "command":
            return CommandCycle(0.0, self.amplitude, period=self.period)
        high = float(params["p_atm"])
        return PressureCycle(high, high - self.amplitude * (high - FULL_CYCLE_LOW_PRESSURE),
                             period=self.period)


def conditions(periods: Sequence[float] = (20.0,), amplitudes: Sequence[float] = (1.0,),
               valves: Sequence[str] = ("command",)) -> list[Condition]:
    """Every combination of ``periods`` [s], ``amplitudes`` and ``valves``."""
    return [Condition(float(p), float(a), str(v)) for v in valves for a in amplitudes
            for p in periods]


def nominal_features(model, condition: Condition, solver=None) -> dict[str, float]:
    """The hysteresis features of ``model`` run under ``condition`` (SI)."""
    from ..simulation import simulate

    run = simulate(condition.model(model), condition.experiment(model.params), solver)
    return run.summary()


def at_speeds(model, speeds: Sequence[float], *, amplitude: float = 1.0,
              valve: str = "command", solver=None) -> list[Condition]:
    """Conditions whose nominal run slides at each of ``speeds`` [m/s] (within 2 %):
    the period is found by a secant-like search on the measured sliding speed, which is
    close to inversely proportional to the period."""
    out = []
    for target in speeds:
        if not (math.isfinite(target) and target > 0):
            raise ParameterError(f"at_speeds: speed = {target!r} m/s; must be > 0")
        condition = Condition(20.0, amplitude, valve)
        for _ in range(SPEED_ITERATIONS):
            speed = nominal_features(model, condition, solver)["sliding_speed"]
            if not np.isfinite(speed):
                raise ParameterError(f"at_speeds: {condition.label} gives no loop to measure "
                                     "a sliding speed on; choose a larger amplitude")
            if abs(speed / target - 1) <= SPEED_RTOL:
                break
            condition = dataclasses.replace(condition,
                                            period=condition.period * speed / target)
        else:
            raise ParameterError(
                f"at_speeds: {1e3 * target:g} mm/s is not reached behind the {valve} "
                f"valve (the {condition.period:.3g} s cycle slides at {1e3 * speed:.3g} "
                "mm/s); the valve's flow limits how fast the diaphragm can slide")
        out.append(condition)
    return out


# --------------------------------------------------------------------------- the study
@dataclass(eq=False)
class ConditionStudy(ResultVocabulary):
    """Indices at each condition. ``conditions``: one row per condition (valve, period,
    amplitude, measured sliding speed and v/vs, nominal features); ``indices``: the long
    table of every study (condition columns, output, parameter, the method's indices);
    ``results``: the study object of each condition.

    ``to_pandas()``: the indices (``"conditions"``: the conditions); ``plot(output)``: an
    index against v/vs (default the first output); ``write(folder)``: both tables, the
    figure of every output and report.html."""

    report_title = "Sensitivity across operating conditions"
    figure_name = "indices_by_speed"

    def tables(self) -> dict[str, pd.DataFrame]:
        return {"indices": self.indices, "conditions": self.conditions}

    @property
    def output_names(self) -> list[str]:
        return list(dict.fromkeys(self.indices["output"]))

    def figures(self) -> dict[str, Callable[[], Figure]]:
        return {f"indices_{output}_by_speed": functools.partial(self.plot, output)
                for output in self.output_names}

    method: str
    conditions: pd.DataFrame
    indices: pd.DataFrame
    results: list = field(default_factory=list)

    @property
    def default_index(self) -> str:
        """The index ``index``, ``ranking`` and ``plot`` use unless told (per method)."""
        return DEFAULT_INDEX[self.method]

    def index(self, output: str, index: str | None = None) -> pd.DataFrame:
        """One index of ``output``: a row per condition (by label), a column per parameter."""
        key = self._key(index)
        sub = self.indices[self.indices["output"] == output]
        if sub.empty:
            raise ParameterError(f"no output {output!r} in this study; it has "
                                 f"{', '.join(dict.fromkeys(self.indices['output']))}")
        table = sub.pivot(index="condition", columns="parameter", values=key)
        order = list(self.conditions["condition"])
        return table.loc[[c for c in order if c in table.index]]

    def ranking(self, output: str, index: str | None = None) -> pd.DataFrame:
        """Per condition, the parameters from most to least influential on ``output``."""
        table = self.index(output, index).abs()
        ranked = table.apply(lambda row: list(row.sort_values(ascending=False).index),
                             axis=1, result_type="expand")
        ranked.columns = [f"rank {i + 1}" for i in range(ranked.shape[1])]
        speeds = self.conditions.set_index("condition")["speed_vs"]
        return ranked.assign(speed_vs=speeds.loc[ranked.index].to_numpy())

    def plot(self, output: str | None = None, index: str | None = None) -> Figure:
        """The index of ``output`` (default: the first) against v/vs (log axis), a line
        per parameter and a panel per valve and amplitude, with the confidence band where
        there is one."""
        from ..plotting import label_log_axis, panel_grid

        output = output or self.output_names[0]
        key = self._key(index)
        groups = list(self.conditions.groupby(["valve", "amplitude"], sort=False))
        fig, panels = panel_grid(len(groups), width=5.2, height=3.8, columns=3)
        sub = self.indices[self.indices["output"] == output]
        for (ax,), ((valve, amplitude), rows) in zip(panels, groups, strict=True):
            part = sub[sub["condition"].isin(rows["condition"])]
            for name, line in part.groupby("parameter", sort=False):
                line = line.sort_values("speed_vs")
                ax.plot(line["speed_vs"], line[key], "o-", ms=3, lw=1.2, label=name)
                if f"{key}_conf" in line:
                    ax.fill_between(line["speed_vs"], line[key] - line[f"{key}_conf"],
                                    line[key] + line[f"{key}_conf"], alpha=0.15)
            ax.set_xscale("log")
            label_log_axis(ax)
            ax.axvline(1.0, color="k", lw=0.6, ls=":")
            ax.set_xlabel("sliding speed v / vs (nominal run)")
            ax.set_ylabel(f"{key} of {output}")
            amp = "" if amplitude == 1 else f", amplitude {amplitude:g}"
            ax.set_title(f"{self.method}: {valve} valve{amp}", fontsize=9)
            ax.grid(True, which="both", alpha=0.3)
        panels[0][0].legend(fontsize=7)
        tight_layout(fig)
        return fig

    def _key(self, index: str | None) -> str:
        key = index or DEFAULT_INDEX[self.method]
        if key not in self.indices.columns:
            allowed = [c for c in self.indices.columns
                       if c not in (*CONDITION_COLUMNS, "output", "parameter")]
            raise ParameterError(f"index {key!r}; this {self.method} study has "
                                 f"{', '.join(allowed)}")
        return key


def across_conditions(model, conditions: Sequence[Condition], method: str = "sobol", *,
                      variations: Mapping[str, object] | None = None,
                      features: Sequence[str] = ("loop_width_pressure", "breakaway_pressure"),
                      n: int = 256, seed: int = 0, second_order: bool = False,
                      checkpoint: Checkpoint | str | os.PathLike | None = None,
                      progress: ProgressCallback | None = None,
                      solver=None, executor: Executor | int | str | None = None
                      ) -> ConditionStudy:
    """Run the ``method`` study (oat, sobol, morris, src or rbd_fast) of ``model`` (an
    ``Actuator``: its parameters, friction and chamber) at each condition.

    ``variations``: the paper's amounts for oat, ``DEFAULT_RANGES`` otherwise; ``n``: base
    sample (sobol, src, rbd_fast) or trajectories (morris). ``checkpoint``: a
    ``Checkpoint`` (or a folder): each condition's runs are kept in
    ``<folder>/<condition>`` (resumable, see ``model_outputs``). ``progress``: called
    with a ``pneumact.progress.Progress`` (stage "across conditions", the sets done of
    all conditions' sets). ``executor``: where the runs go (an ``Executor``, or a
    number of threads).
    """
    if method not in METHODS:
        raise ParameterError(f"across_conditions: method = {method!r}; allowed: "
                             f"{', '.join(METHODS)}")
    checkpoint = Checkpoint.of(checkpoint, "across_conditions")
    executor = Executor.of(executor, "across_conditions")
    conditions = list(conditions)
    if not conditions:
        raise ParameterError("across_conditions: give at least one condition")
    labels = [c.label for c in conditions]
    if len(set(labels)) != len(labels):
        raise ParameterError(f"across_conditions: conditions repeat: {', '.join(labels)}")
    rows, frames, results = [], [], []
    for i, condition in enumerate(conditions):
        row = _describe(model, condition, solver)
        relay = _relay(progress, i, len(conditions))
        where_runs = None if checkpoint is None else checkpoint.within(_folder(condition))
        result, table = _study(model, condition, method, variations, list(features), n,
                               seed, second_order, where_runs, relay, solver, executor)
        rows.append(row)
        frames.append(table.assign(**{k: row[k] for k in CONDITION_COLUMNS}))
        results.append(result)
    indices = pd.concat(frames, ignore_index=True)
    front = [*CONDITION_COLUMNS, "output", "parameter"]
    indices = indices[front + [c for c in indices.columns if c not in front]]
    return ConditionStudy(method, pd.DataFrame(rows), indices, results)


def _describe(model, condition: Condition, solver) -> dict:
    summary = nominal_features(model, condition, solver)
    speed = summary["sliding_speed"]
    vs = float(model.params["vs"]) if "vs" in model.params else math.nan
    return {"condition": condition.label, "valve": condition.valve,
            "period": condition.period, "amplitude": condition.amplitude,
            "sliding_speed": speed, "speed_vs": speed / vs,
            **{f"nominal_{k}": v for k, v in summary.items()}}


def _folder(condition: Condition) -> str:
    return f"{condition.valve}-{condition.period:g}s-a{condition.amplitude:g}"


def _relay(progress: ProgressCallback | None, i: int, count: int
           ) -> ProgressCallback | None:
    """A batch progress callback of condition ``i`` that reports over all conditions."""
    if progress is None:
        return None

    def relay(batch: Progress) -> None:
        notify(progress, "across conditions", i * batch.total + batch.done, count * batch.total,
               batch.failed)

    return relay


def _study(model, condition, method, variations, features, n, seed, second_order, checkpoint,
           progress, solver, executor) -> tuple[object, pd.DataFrame]:
    """(study object, its long index table: output, parameter, indices) at one condition."""
    from . import methods
    from .oat import PAPER_VARIATIONS, one_at_a_time
    from .problem import DEFAULT_RANGES, Problem

    actuator = condition.model(model)
    experiment = condition.experiment(model.params)
    if method == "oat":
        oat = one_at_a_time(actuator, experiment, variations or PAPER_VARIATIONS,
                            features=features, executor=executor, solver=solver)
        return oat, oat_indices(oat)
    problem = Problem.around(model.params, variations or DEFAULT_RANGES)
    evaluate = methods.model_outputs(actuator, experiment, problem, features,
                                     checkpoint=checkpoint, progress=progress,
                                     solver=solver, executor=executor)
    run = {"sobol": lambda: methods.sobol(problem, evaluate, n, second_order, seed),
           "morris": lambda: methods.morris(problem, evaluate, n, seed=seed),
           "src": lambda: methods.src(problem, evaluate, n, seed),
           "rbd_fast": lambda: methods.rbd_fast(problem, evaluate, n, seed)}[method]
    study = run()
    return study, study.indices


def oat_indices(study) -> pd.DataFrame:
    """The one-at-a-time study as indices: per feature and parameter, the change of the
    feature at the low and the high value, the largest |change| and that relative to the
    nominal value."""
    runs = study.runs
    nominal = runs.iloc[0]
    rows = []
    for feature in study.features:
        for name, sub in runs[runs["parameter"] != "nominal"].groupby("parameter", sort=False):
            deltas = sub[f"delta_{feature}"].to_numpy(float)
            changes = sub["change_%"].to_numpy(float)
            largest = float(np.nanmax(np.abs(deltas)))
            rows.append({"output": feature, "parameter": name,
                         "change_low": float(deltas[np.argmin(changes)]),
                         "change_high": float(deltas[np.argmax(changes)]),
                         "max_abs_change": largest,
                         "relative_change": largest / abs(float(nominal[feature]))})
    return pd.DataFrame(rows)


# --------------------------------------------------------------------------- ranges
def where(x: Sequence[float], margin: Sequence[float]) -> pd.DataFrame:
    """The ranges of ``x`` (e.g. v/vs, increasing after sorting) where ``margin`` ≥ 0:
    one row per range with its first and last condition (``x_from``, ``x_to``) and the
    boundaries (``lower``, ``upper``) interpolated linearly in log x between the last
    condition where it holds and the first where it does not (NaN at the ends of the
    studied range: no boundary was found there)."""
    order = np.argsort(np.asarray(x, dtype=float))
    xs = np.asarray(x, dtype=float)[order]
    ms = np.asarray(margin, dtype=float)[order]
    holds = ms >= 0
    rows = []
    i = 0
    while i < xs.size:
        if not holds[i]:
            i += 1
            continue
        j = i
        while j + 1 < xs.size and holds[j + 1]:
            j += 1
        lower = _crossing(xs[i - 1], xs[i], ms[i - 1], ms[i]) if i > 0 else np.nan
        upper = _crossing(xs[j], xs[j + 1], ms[j], ms[j + 1]) if j + 1 < xs.size else np.nan
        rows.append({"x_from": xs[i], "x_to": xs[j], "lower": lower, "upper": upper})
        i = j + 1
    return pd.DataFrame(rows, columns=["x_from", "x_to", "lower", "upper"])


def _crossing(x0: float, x1: float, m0: float, m1: float) -> float:
    """Where the margin crosses zero between two conditions (linear in log x)."""
    if not (np.isfinite(m0) and np.isfinite(m1)) or m0 == m1:
        return float(np.sqrt(x0 * x1))
    fraction = m0 / (m0 - m1)
    return float(np.exp(np.log(x0) + fraction * (np.log(x1) - np.log(x0))))

"""Validation of a model against measured records (the paper's Fig. 6, for any record).

``validate`` drives the model the way each record was made: by the input the record
carries (a logged regulator set-point first, else the measured pressure as a pressure
source, else the valve command; ``input=`` chooses otherwise), simulates on the record's
own time grid and compares the measured outputs: error metrics per record and over all
records, the hysteresis-loop measures of model and measurement, the residuals (over time,
against pressure, their autocorrelation), and a verdict per record that combines fit %
with the loop measures and the residuals' whiteness (``verdicts``). ``train_test`` fits
on some records and validates on others, with both sets of metrics side by side.
"""

from __future__ import annotations

import functools
import os
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from ..errors import ArgumentError, DataError
from ..io.records import PRESSURE_SIGNAL, Record
from ..io.report import NotebookDisplay
from ..models import VALVES
from ..models.actuator import CHAMBER_PRESSURE
from ..models.inputs import DEFAULT_INPUT, INPUT_SIGNALS, INPUTS
from ..progress import ProgressCallback, check_progress, notify
from .loops import compare_loops, loop_measures, reversals
from .metrics import METRIC_NAMES, autocorrelation, error_metrics
from .verdicts import Criteria, record_verdict, worst_verdict

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from ..identification.fit import FitResult
    from ..simulation.result import Result
    from ..simulation.simulate import Model

__all__ = ["INPUTS", "RecordValidation", "TrainTest", "Validation", "drive_for", "train_test",
           "validate"]

ALL_RECORDS = "all records"


def _can_drive(record: Record) -> str:
    carried = [s for s in dict.fromkeys(INPUT_SIGNALS.values()) if s in record]
    if not carried:
        return "it carries none of setpoint, pressure, command, so it can drive no valve"
    valves = [f"{VALVES[c].__name__} (--valve {c})" for c, s in INPUT_SIGNALS.items()
              if s in carried]
    return f"it carries {', '.join(carried)}, so it can drive {' or '.join(valves)}"


def drive_for(model: Model, record: Record, input: str = DEFAULT_INPUT) -> tuple[Model, str]:
    """(the model driven the way ``record`` was made, the record signal that drives it),
    as ``input`` says (see ``INPUTS``): an actuator goes behind the valve the chosen
    signal drives; a model with one input (a rig, a closed loop) is driven by it."""
    if input not in INPUTS:
        raise DataError(f"input = {input!r}; allowed: {', '.join(INPUTS)}")
    own = model.input_signal
    if input == "model" or len(model.input_signals) == 1:
        if own not in record:
            what = "the model" if len(model.input_signals) == 1 else (
                f"the model's {model.drive_label}")
            raise DataError(f"{record.source}: {what} is driven by a record's {own}, "
                            f"which this record lacks; {_can_drive(record)} (input='auto' "
                            "or --valve auto picks it)")
        return model, own
    if input == "auto":
        carried = [s for s in model.input_signals if s in record]
        if not carried:
            raise DataError(f"{record.source}: {_can_drive(record)}; the record has: time, "
                            f"{', '.join(record.signals) or '(nothing)'}")
        signal = carried[0]
    else:
        signal = input
        if signal not in record:
            raise DataError(f"{record.source}: input = {signal!r}, which this record lacks; "
                            f"{_can_drive(record)}")
    return model.driven_by(signal), signal


def _write_bytes(data: bytes, path: Path) -> None:
    Path(path).write_bytes(data)


@dataclass(eq=False)
class RecordValidation(NotebookDisplay):
    """One record against the model's prediction of it: ``metrics()`` and
    ``to_pandas()`` (tables), ``plot()`` (a Figure) and ``write(folder)`` as those of a
    ``Validation`` of this record alone."""

    name: str
    record: Record
    simulated: Result
    signals: tuple[str, ...]
    input: str = ""
    valve: str = ""
    #: signals asked for but not compared: the record's input drives the model with
    #: them, so the model would only repeat them (a fit of 100 % that says nothing)
    dropped: tuple[str, ...] = ()

    def measured(self, signal: str) -> np.ndarray:
        return self.record[signal]

    def predicted(self, signal: str) -> np.ndarray:
        return np.asarray(self.simulated[signal], dtype=float)

    def residual(self, signal: str) -> np.ndarray:
        """Measured − predicted, on the record's time grid."""
        return self.measured(signal) - self.predicted(signal)

    def notebook_table(self) -> pd.DataFrame:
        """The metrics, for a notebook's display."""
        return self.metrics()

    def metrics(self) -> pd.DataFrame:
        """Per signal: RMS, max, NRMSE, fit %, R², n (``validation.metrics``)."""
        return pd.DataFrame(
            [{"record": self.name, "signal": s,
              **error_metrics(self.measured(s), self.predicted(s), f"{self.name}: {s}")}
             for s in self.signals], columns=["record", "signal", *METRIC_NAMES])

    def alone(self) -> Validation:
        """A ``Validation`` of this record alone."""
        return Validation([self], self.signals, label=self.name)

    def to_pandas(self, name: str | None = None) -> pd.DataFrame:
        """Long table: time, signal, measured, model, residual (see
        ``Validation.to_pandas``)."""
        return self.alone().to_pandas(name)

    def plot(self) -> Figure:
        return self.alone().plot()

    def write(self, out_dir: str | os.PathLike, *, call: str = "") -> list[Path]:
        """The files of ``Validation.write`` for this record alone."""
        return self.alone().write(out_dir, call=call, title=f"Validation on {self.name}")

    @property
    def has_loop(self) -> bool:
        return PRESSURE_SIGNAL in self.record and "position" in self.record

    def loops(self) -> pd.DataFrame | None:
        """Loop measures of measurement and model (None without pressure and position)."""
        if not self.has_loop:
            return None
        t = self.record.time
        measured = loop_measures(t, self.record[PRESSURE_SIGNAL], self.record["position"])
        model = loop_measures(t, self.predicted(CHAMBER_PRESSURE), self.predicted("position"))
        return compare_loops(measured, model)

    def reversals(self) -> pd.DataFrame | None:
        """Reversal points of measurement and model, side by side (matched in order)."""
        if not self.has_loop:
            return None
        t = self.record.time
        measured = reversals(t, self.record[PRESSURE_SIGNAL], self.record["position"])
        model = reversals(t, self.predicted(CHAMBER_PRESSURE), self.predicted("position"))
        n = min(len(measured), len(model))
        out = measured.iloc[:n].add_prefix("measured_").reset_index(drop=True)
        for column in (PRESSURE_SIGNAL, "position"):
            out[f"model_{column}"] = model[column].to_numpy()[:n]
            out[f"{column}_difference"] = out[f"model_{column}"] - out[f"measured_{column}"]
        return out


@dataclass(eq=False)
class Validation(NotebookDisplay):
    """Validation of one model on a set of records; ``label`` names the set (e.g. test).

    ``to_pandas()``: the time series, long (``"metrics"``, ``"verdicts"``, ``"loops"``:
    the others); ``plot()``: the loops (the time series without a loop); ``write(folder)``:
    every table, every figure and report.html."""

    records: list[RecordValidation]
    signals: tuple[str, ...]
    values: dict[str, float] = field(default_factory=dict)
    label: str = "validation"
    criteria: Criteria = field(default_factory=Criteria)

    def notebook_table(self) -> pd.DataFrame:
        """The metrics, for a notebook's display."""
        return self.metrics()

    def metrics(self) -> pd.DataFrame:
        """Per record and signal, plus all records pooled: RMS, max, NRMSE, fit %, R², n,
        and the record's verdict (``verdicts()``; pooled: the worst)."""
        verdicts = self.verdicts().set_index("record")["verdict"]
        rows = []
        for rv in self.records:
            for row in rv.metrics().to_dict("records"):
                rows.append({**row, "verdict": verdicts[rv.name]})
        for signal in self.signals:
            compared = [rv for rv in self.records if signal in rv.signals]
            if not compared:
                continue
            measured = np.concatenate([rv.measured(signal) for rv in compared])
            predicted = np.concatenate([rv.predicted(signal) for rv in compared])
            rows.append({"record": ALL_RECORDS, "signal": signal,
                         **error_metrics(measured, predicted, f"{ALL_RECORDS}: {signal}"),
                         "verdict": worst_verdict(verdicts)})
        return pd.DataFrame(rows, columns=["record", "signal", *METRIC_NAMES, "verdict"])

    def verdicts(self) -> pd.DataFrame:
        """Per record: the input and valve that drove it, the verdict (adequate,
        adequate with non-white residuals, inadequate), the reasons, and the value of
        every check (fit %, loop measure errors, share of residual lags outside the
        white-noise band); see ``validation.verdicts``."""
        return pd.DataFrame([record_verdict(rv, self.criteria) for rv in self.records])

    def loops(self) -> pd.DataFrame:
        """Loop measures of every record with a loop (record, measure, unit, measured,
        model, difference, relative)."""
        frames = [frame.assign(record=rv.name) for rv in self.records
                  if (frame := rv.loops()) is not None]
        if not frames:
            return pd.DataFrame(columns=["record", "measure", "unit", "measured", "model",
                                         "difference", "relative"])
        out = pd.concat(frames, ignore_index=True)
        return out[["record", *[c for c in out.columns if c != "record"]]]

    def reversals(self) -> pd.DataFrame:
        frames = [frame.assign(record=rv.name) for rv in self.records
                  if (frame := rv.reversals()) is not None]
        return pd.concat(frames, ignore_index=True) if frames else pd.DataFrame()

    def residual_autocorrelation(self, max_lag: int | None = None) -> pd.DataFrame:
        """Autocorrelation of each record's residual (lag, acf, band) per signal."""
        rows = []
        for rv in self.records:
            for signal in rv.signals:
                acf, band = autocorrelation(rv.residual(signal), max_lag)
                rows.append(pd.DataFrame({"record": rv.name, "signal": signal,
                                          "lag": np.arange(acf.size), "acf": acf,
                                          "band": band}))
        return pd.concat(rows, ignore_index=True)

    def to_pandas(self, name: str | None = None) -> pd.DataFrame:
        """Long table: record, time, signal, measured, model, residual (SI); ``name``:
        "metrics", "verdicts" or "loops" for those tables."""
        others = {"metrics": self.metrics, "verdicts": self.verdicts, "loops": self.loops}
        if name is not None:
            if name not in others:
                raise ArgumentError(f"to_pandas: name = {name!r}; allowed: "
                                    f"{', '.join(others)}")
            return others[name]()
        frames = []
        for rv in self.records:
            for s in rv.signals:
                frames.append(pd.DataFrame({"record": rv.name, "time": rv.record.time,
                                            "signal": s, "measured": rv.measured(s),
                                            "model": rv.predicted(s),
                                            "residual": rv.residual(s)}))
        return pd.concat(frames, ignore_index=True)

    # ----------------------------------------------------------------------- plots
    def plot(self) -> Figure:
        """The loops (``plot_loops``) when a record has pressure and position, else the
        time series (``plot_time``)."""
        if any(rv.has_loop for rv in self.records):
            return self.plot_loops()
        return self.plot_time()

    def plot_loops(self):
        """Measured and predicted pressure–position loops per record (the paper's Fig. 6)."""
        from .plots import plot_loops

        return plot_loops(self)

    def plot_time(self):
        """Measured and predicted signals against time, with the residuals."""
        from .plots import plot_time

        return plot_time(self)

    def plot_residuals(self):
        """Residuals against pressure and their autocorrelation with the white-noise band."""
        from .plots import plot_residuals

        return plot_residuals(self)

    # ----------------------------------------------------------------------- output
    def figure_pngs(self) -> dict[str, bytes]:
        """The figures as PNG, rendered once for both the files and the report: time,
        residuals, and loops when a record has pressure and position; each a figure per
        page of records beyond ``PANELS_PER_PAGE`` (``loops``, ``loops-2``, ...)."""
        from ..io.report import figure_png
        from ..plotting import PNG_DPI, page_name, record_pages
        from .plots import plot_loops, plot_residuals, plot_time

        looped = [rv for rv in self.records if rv.has_loop]
        makes = [("time", plot_time, self.records), ("residuals", plot_residuals,
                                                     self.records)]
        if looped:
            makes.append(("loops", plot_loops, looped))
        return {page_name(name, k): figure_png(make(self, page), dpi=PNG_DPI)
                for name, make, records in makes
                for k, page in enumerate(record_pages(records), start=1)}

    def add_to(self, report, title: str | None = None,
               figures: dict[str, bytes] | None = None) -> None:
        """This validation's tables and figures (``figure_pngs()`` unless given) as
        sections of a ``Report``."""
        from .plots import add_to_report

        add_to_report(self, report, title, self.figure_pngs() if figures is None else figures)

    def writers(self, prefix: str = "", figures: dict[str, bytes] | None = None
                ) -> dict[str, Callable[[Path], object]]:
        """Files of this validation: metrics, loops and the time series (CSV), figures."""
        figures = self.figure_pngs() if figures is None else figures
        writers: dict[str, Callable[[Path], object]] = {
            f"{prefix}metrics.csv": lambda p: self.metrics().to_csv(p, index=False),
            f"{prefix}loops.csv": lambda p: self.loops().to_csv(p, index=False),
            f"{prefix}timeseries.csv": lambda p: self.to_pandas().to_csv(p, index=False)}
        for name, png in figures.items():
            writers[f"{prefix}{name}.png"] = functools.partial(_write_bytes, png)
        return writers

    def write(self, out_dir: str | os.PathLike, *, call: str = "", parameters=None,
              title: str = "Validation") -> list[Path]:
        """All files and ``report.html``, all or nothing."""
        from ..io.report import Report
        from ..io.tables import write_files

        figures = self.figure_pngs()
        report = Report(title, call=call, parameters=parameters)
        self.add_to(report, figures=figures)
        writers = self.writers(figures=figures)
        writers["report.html"] = report.write
        return write_files(out_dir, writers)


def validate(model, records: Record | Sequence[Record], *,
             signals: Sequence[str] = ("position",), values: Mapping[str, float] | None = None,
             solver=None, smooth_input: bool = False, label: str = "validation",
             input: str = DEFAULT_INPUT, criteria: Criteria | None = None,
             progress: ProgressCallback | None = None) -> Validation:
    """Simulate ``model`` (with parameter ``values`` if given) under each record's
    measured input and compare ``signals`` with the measurement.

    ``input``: ``auto`` drives each record the way it was made (its set-point through the
    regulator, else its pressure as a pressure source, else its command through the
    valve; the model's valve is kept when it is that kind), ``model`` keeps the model's
    valve, or name the signal (``INPUTS``). ``criteria``: the thresholds of the verdicts.
    ``progress`` is called with a ``pneumact.progress.Progress`` (stage "validate",
    records done of all).
    """
    from ..checks import check_names
    from ..identification import experiment_for
    from ..io.records import as_records
    from ..simulation import simulate
    from ..simulation.simulate import check_model, model_stroke

    check_model(model, "validate")
    check_progress(progress, "validate")
    records = as_records(records, "validate")
    signals = tuple(check_names("signals", signals, where="validate", what="signal name",
                                allow_empty=False))
    stroke = model_stroke(model)
    if stroke is not None:
        for record in records:
            record.check_within_stroke(stroke, "validate")
    out = []
    for i, record in enumerate(records):
        record.require(signals, "validation")
        driven, signal = drive_for(model, record, input)
        name = os.path.basename(record.source) or f"record {i + 1}"
        compared = tuple(s for s in signals if s != signal)
        if not compared:
            raise DataError(f"validate: {name} drives the model with its {signal}, the "
                            f"only signal asked (signals={list(signals)}): the model would "
                            "repeat its input; compare another signal (e.g. position)")
        experiment = experiment_for(driven, record, smooth_input)
        simulated = simulate(driven, experiment, solver, t_eval=record.time,
                             values=dict(values or {}))
        out.append(RecordValidation(name, record, simulated, compared, signal,
                                    driven.drive_label, tuple(s for s in signals
                                                              if s not in compared)))
        notify(progress, "validate", i + 1, len(records))
    return Validation(out, signals, dict(values or {}), label, criteria or Criteria())


@dataclass(eq=False)
class TrainTest(NotebookDisplay):
    """A fit on training records and its validation on those and on test records.

    ``to_pandas()``: training and test metrics (``metrics()``; ``"summary"``: pooled,
    side by side); ``plot()``: the test records' loops or time series; ``write(folder)``:
    both validations, the estimates and report.html."""

    fit: FitResult
    train: Validation
    test: Validation

    def notebook_table(self) -> pd.DataFrame:
        """The metrics, for a notebook's display."""
        return self.metrics()

    def metrics(self) -> pd.DataFrame:
        """Training and test metrics in one table (``set`` column): over-fitting shows as
        a test fit % well below the training one."""
        return pd.concat([self.train.metrics().assign(set="training"),
                          self.test.metrics().assign(set="test")], ignore_index=True)

    def to_pandas(self, name: str | None = None) -> pd.DataFrame:
        """``metrics()`` (``name`` None or "metrics"), or "summary"."""
        if name not in (None, "metrics", "summary"):
            raise ArgumentError(f"to_pandas: name = {name!r}; allowed: metrics, summary")
        return self.summary() if name == "summary" else self.metrics()

    def plot(self) -> Figure:
        """The test validation's figure (``Validation.plot``)."""
        return self.test.plot()

    def summary(self) -> pd.DataFrame:
        """Pooled metrics of each set side by side, one row per signal."""
        table = self.metrics()
        pooled = table[table["record"] == ALL_RECORDS]
        return pooled.pivot(index="signal", columns="set",
                            values=["rms", "fit_percent", "r2"])

    def write(self, out_dir: str | os.PathLike, *, call: str = "") -> list[Path]:
        from ..io.report import Report
        from ..io.tables import write_files

        parameters = self.fit.report_parameters()
        report = Report("Identification and validation on held-out records", call=call,
                        parameters=parameters)
        report.heading("Fitted parameters")
        report.table(self.fit.to_pandas(), "Estimates with standard errors (training records)")
        report.heading("Training against test")
        from .metrics import metrics_for_reading

        for signal, shown in metrics_for_reading(self.metrics()).items():
            report.table(shown, f"Error metrics of the {signal}, per record and pooled",
                         index=False)
        train_figures, test_figures = self.train.figure_pngs(), self.test.figure_pngs()
        self.train.add_to(report, "Training records", train_figures)
        self.test.add_to(report, "Test records", test_figures)
        writers = {**self.train.writers("train_", train_figures),
                   **self.test.writers("test_", test_figures),
                   "metrics.csv": lambda p: self.metrics().to_csv(p, index=False),
                   "estimates.csv": lambda p: self.fit.to_pandas().to_csv(p),
                   "report.html": report.write}
        return write_files(out_dir, writers)


def _refuse_trained_tests(train: Sequence[Record], test: Sequence[Record]) -> None:
    """A test record that is also a training record (the same data) tests nothing."""
    for k, record in enumerate(test):
        for trained in train:
            if (record.time.shape == trained.time.shape
                    and np.array_equal(record.time, trained.time)
                    and set(record.signals) == set(trained.signals)
                    and all(np.array_equal(record.signals[n], trained.signals[n])
                            for n in record.signals)):
                raise DataError(
                    f"train_test: test record {k + 1} ({record.source or 'record'}) is also "
                    f"a training record ({trained.source or 'record'}): a model validated "
                    "on the data it was fitted to is not tested; hold out a record the fit "
                    "does not see")


def train_test(model, train: Sequence[Record], test: Sequence[Record], free: Sequence[str],
               *, signals: Sequence[str] = ("position",), input: str = DEFAULT_INPUT,
               **fit_options) -> TrainTest:
    """Fit ``free`` parameters on ``train`` (``identification.fit`` options), then
    validate the fitted model on both sets. With ``input='auto'`` the fit drives the
    model by the first input every training record carries (setpoint, pressure, command)
    and each test record by its own (see ``validate``)."""
    from ..identification import fit

    train, test = list(train), list(test)
    if not train or not test:
        raise DataError("train_test: give at least one training and one test record")
    _refuse_trained_tests(train, test)
    chosen = input
    if input == "auto":
        shared = [s for s in INPUT_SIGNALS.values() if all(s in r for r in train)]
        if not shared:
            raise DataError("train_test: the training records share no input signal "
                            "(setpoint, pressure or command); fit records made the same way")
        chosen = shared[0]
    model, _ = drive_for(model, train[0], chosen)
    smooth = fit_options.get("smooth_input", False)
    result = fit(model, train, free, signals=signals, **fit_options)
    values = {k: v for k, v in result.values.items() if "[" not in k}
    return TrainTest(result,
                     validate(model, train, signals=signals, values=values, label="training",
                              input="model", smooth_input=smooth),
                     validate(model, test, signals=signals, values=values, label="test",
                              input=input, smooth_input=smooth))

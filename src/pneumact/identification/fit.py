"""Fitting any parameters of a model to one or several measured records.

``fit(model, records, free=[...])`` simulates each record under its own measured input
(pressure, command or set-point) and minimises the weighted output error of the
measured signals (position by default) with scipy ``least_squares``. The Jacobian comes
from forward sensitivities (one simulation per record and iteration, whatever the
number of parameters) unless ``jacobian="2-point"`` asks for finite differences.

Parameters are shared by all records unless listed in ``per_record`` (then each record
has its own value, labelled ``name[i]``); positive parameters are fitted in log scale by
default; bounds default to the catalogue's range, or a factor of 100 either side.
Standard errors and correlations come from the Gauss-Newton covariance at the optimum;
``multistart`` runs space-filling starts in parallel and ``profile`` computes profile
likelihoods with a verdict on identifiability.
"""

from __future__ import annotations

import copy
import functools
import math
import os
import threading
import time as _time
from collections import OrderedDict
from collections.abc import Callable, Mapping, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd
from scipy.optimize import least_squares

from ..errors import DataError, ParameterError, PneumactError, SolverError
from ..io.records import Record
from ..io.report import ResultVocabulary
from ..models.sensors import (
    DEFAULT_SENSORS,
    Sensors,
    first_order_lag,
    is_sensor_parameter,
    lag_derivative,
    sensor_names,
)
from ..options import Bounds, Executor, Multistart, Offsets, Optimizer, Profile, Weights
from ..plotting import tight_layout
from ..progress import ProgressCallback, notify, stop_threads
from .arguments import check_fit_arguments, check_window, fit_records
from .estimates import Estimates, covariance_from_jacobian

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from ..io.report import Report
    from ..simulation.simulate import Model

__all__ = ["FitResult", "ProfileLikelihood", "fit"]

#: the sensor lags a fit of the single-chamber actuator can free, and the signal each
#: delays (a model that places its own sensors: ``sensor_lags``)
SENSOR_LAGS = {names.lag: signal for signal, names in DEFAULT_SENSORS.items()}


def sensor_lags(models: Sequence) -> dict[str, str]:
    """The sensor lags a fit of ``models`` can free (``position_lag``,
    ``sensor_pressure_a.lag``), and the signal each delays."""
    return {names.lag: signal for model in models
            for signal, names in sensor_names(model).items()}

CHI2_95 = 3.841458820694124  # χ²(1) 95 % quantile: the profile-likelihood threshold


@dataclass(frozen=True)
class _Column:
    label: str  # "sigma0", "F0[1]" or "offset_position[0]"
    name: str  # a model parameter, or the signal of an offset
    record: int | None  # None: shared by all records
    offset: bool = False  # an additive sensor offset of signal ``name``, not a parameter
    lag: bool = False  # the first-order lag of signal ``name``'s sensor (``label``)

    @property
    def parameter(self) -> bool:
        """A parameter of the model (not a sensor's offset or lag)."""
        return not (self.offset or self.lag)


class _Problem:
    """The residual vector and its Jacobian as functions of the free parameters."""

    def __init__(self, models, records, columns, log, signals, weights, solver, jacobian,
                 base_values, windows, smooth_input=True, record_weights=None):
        self.models, self.records, self.columns = list(models), list(records), list(columns)
        self.log = np.asarray(log, dtype=bool)
        self.signals, self.weights, self.solver = tuple(signals), dict(weights), solver
        self.record_weights = (np.ones(len(self.records)) if record_weights is None
                               else np.asarray(record_weights, dtype=float))
        #: threads that simulate the records of one evaluation (1 inside a multistart,
        #: whose starts run on threads of their own)
        self.workers = 1
        self.jacobian = jacobian
        #: the relative step of a difference Jacobian: √rtol balances the solver's noise
        #: (rtol/step) against the truncation error (step); unused with sensitivities
        self.diff_step = math.sqrt(max(getattr(solver, "rtol", 1e-6), 1e-14))
        self.base = dict(base_values)
        #: the parameters each record's model reads (a joint fit mixes valves)
        self.model_parameters = [_parameter_names(m) for m in self.models]
        #: the sensors each record's model states (lags held unless fitted)
        self.sensors = [Sensors.of(m) for m in self.models]
        self.smooth_input = smooth_input
        self.experiments = [experiment_for(m, r, smooth_input)
                            for m, r in zip(self.models, self.records, strict=True)]
        self.masks = []
        for r, window in zip(self.records, windows, strict=True):
            lo, hi = window if window is not None else (-np.inf, np.inf)
            mask = (r.time >= lo) & (r.time <= hi)
            if mask.sum() < 2:
                raise DataError(f"fit: window {window} s leaves {mask.sum()} samples of "
                                f"{r.source} ({r.time[0]:.6g}..{r.time[-1]:.6g} s)")
            self.masks.append(mask)
        self.simulations = 0
        self._cache: dict[bytes, tuple[np.ndarray, np.ndarray | None, list]] = {}
        #: the last evaluation with a Jacobian (the optimizer's last accepted point, where
        #: ``fit`` evaluates again), kept when the cache is cleared
        self._kept: tuple[bytes, tuple] | None = None
        self._last_trial: bytes | None = None  # see ``new_optimizer_run``
        self._accepting = True

    def __getstate__(self) -> dict:
        """Pickled (for Dask) without the cache of simulated results."""
        return {**self.__dict__, "_cache": {}, "_kept": None}

    # -- parameter spaces
    def theta(self, phi: np.ndarray) -> np.ndarray:
        out = np.array(phi, dtype=float)
        out[self.log] = np.exp(out[self.log])
        return out

    def phi(self, theta: np.ndarray) -> np.ndarray:
        out = np.array(theta, dtype=float)
        out[self.log] = np.log(out[self.log])
        return out

    def weight(self, i: int, signal: str) -> float:
        """Weight of record ``i``'s residuals of ``signal``."""
        return self.weights[signal] * self.record_weights[i]

    def values_for(self, theta: np.ndarray, i: int) -> dict[str, float]:
        """Parameter values of record ``i``'s model at ``theta``."""
        own = self.model_parameters[i]
        values = {n: v for n, v in self.base.items() if n in own}
        for col, value in zip(self.columns, theta, strict=True):
            if col.parameter and col.record in (None, i) and col.name in own:
                values[col.name] = float(value)
        return values

    def free_names(self, i: int) -> list[str]:
        """The free parameters record ``i``'s model reads, in column order."""
        own = self.model_parameters[i]
        return [c.name for c in self.columns
                if c.parameter and c.record in (None, i) and c.name in own]

    def offset_of(self, theta: np.ndarray, i: int, signal: str) -> float:
        return sum(float(v) for c, v in zip(self.columns, theta, strict=True)
                   if c.offset and c.record == i and c.name == signal)

    def lag_of(self, theta: np.ndarray, i: int, signal: str) -> float:
        """The lag [s] of ``signal``'s sensor for record ``i``: fitted, or as stated."""
        for c, v in zip(self.columns, theta, strict=True):
            if c.lag and c.name == signal:
                return max(float(v), 0.0)
        return self.sensors[i].lag(signal)

    def measured(self, theta: np.ndarray, i: int, signal: str, values: np.ndarray
                 ) -> np.ndarray:
        """``values`` of ``signal`` (samples at record ``i``'s times, along the first
        axis) seen through its sensor's lag."""
        return first_order_lag(self.records[i].time, values, self.lag_of(theta, i, signal))

    # -- evaluation
    def evaluate(self, theta: np.ndarray, with_jacobian: bool):
        """(weighted residuals, Jacobian in θ-space or None, simulated Results); the
        records run on ``workers`` threads (the compiled integrators release the GIL)."""
        key = theta.tobytes()
        cached = self._cache.get(key)
        if cached is None and self._kept is not None and self._kept[0] == key:
            cached = self._kept[1]
        if cached is not None and (cached[1] is not None or not with_jacobian):
            return cached
        runs = map_on_threads(self.workers, lambda i: self._run(theta, i, with_jacobian),
                    range(len(self.records)))
        rows, blocks, results = [], [], []
        for i, (result, sens) in enumerate(runs):
            self.simulations += 1
            results.append(result)
            mask = self.masks[i]
            rows.append(np.concatenate([
                self.weight(i, s) * (self.measured(theta, i, s, result[s])
                                     + self.offset_of(theta, i, s) - self.records[i][s])[mask]
                for s in self.signals]))
            if with_jacobian:
                blocks.append(self._block(theta, i, result, sens, mask))
        out = (np.concatenate(rows), np.vstack(blocks) if with_jacobian else None, results)
        if len(self._cache) > 8:
            self._cache.clear()
        self._cache[key] = out
        if with_jacobian:
            self._kept = (key, out)
        return out

    def _run(self, theta: np.ndarray, i: int, with_jacobian: bool):
        """(Result, SensitivityResult or None) of record ``i`` at ``theta``."""
        from ..simulation import simulate, simulate_sensitivities
        from .memo import sensitivities

        model, record, experiment = self.models[i], self.records[i], self.experiments[i]
        values = self.values_for(theta, i)
        names = self.free_names(i)
        try:
            if with_jacobian and names and self.smooth_input:
                sens = sensitivities(model, experiment, rebuilt_input(model, record),
                                     record.time, names, self.solver, values)
                return sens.result, sens
            if with_jacobian and names:
                sens = simulate_sensitivities(model, experiment, names, self.solver,
                                              t_eval=record.time, values=values)
                return sens.result, sens
            return simulate(model, experiment, self.solver, t_eval=record.time,
                            values=values), None
        except SolverError as exc:
            shown = ", ".join(f"{c.label}={v:.6g}" for c, v in zip(self.columns, theta,
                                                                   strict=True))
            raise SolverError(f"fit: the simulation of {record.source} failed at {shown}: "
                              f"{exc}") from exc

    def _block(self, theta, i, result, sens, mask) -> np.ndarray:
        """Rows of record ``i`` in the Jacobian (θ-space): the forward sensitivities seen
        through the sensors' lags (a linear filter), an offset's ones, and a lag's
        derivative of the filter."""
        n = int(mask.sum())
        block = np.zeros((n * len(self.signals), len(self.columns)))
        own = self.model_parameters[i]
        seen = {s: self.measured(theta, i, s, sens[s]) for s in self.signals} \
            if sens is not None else {}
        k = 0
        for j, col in enumerate(self.columns):
            if col.record not in (None, i) or (col.parameter and col.name not in own):
                continue
            if col.offset or col.lag:
                if col.name not in self.signals:
                    continue
                q = self.signals.index(col.name)
                block[q * n:(q + 1) * n, j] = self.weight(i, col.name) * (
                    1.0 if col.offset else lag_derivative(
                        self.records[i].time, result[col.name],
                        self.lag_of(theta, i, col.name))[mask])
                continue
            block[:, j] = np.concatenate([self.weight(i, s) * seen[s][mask, k]
                                          for s in self.signals])
            k += 1
        return block

    def new_optimizer_run(self) -> None:
        """Forget the last optimizer's trial points: ``residuals`` keeps the last one not
        yet followed by its Jacobian, and whether the optimizer accepted the one before."""
        self._last_trial = None
        self._accepting = True

    def residuals(self, phi: np.ndarray) -> np.ndarray:
        """The residuals at ``phi``, with the forward sensitivities in the same runs while
        the optimizer accepts its trial points, plain after it rejected one: the
        Jacobian of an accepted point comes free, a rejected point (4 in 10 of the
        joint fit's on drawn actuators, mostly near convergence) never needs it, and
        sensitivities of 8 parameters cost 3-5 plain runs."""
        key = phi.tobytes()
        if self._last_trial is not None and self._last_trial != key:
            self._accepting = False  # the last trial point was left without a Jacobian
        self._last_trial = key
        return self.evaluate(self.theta(phi), self.jacobian == "sensitivities"
                             and self._accepting)[0]

    def jac(self, phi: np.ndarray) -> np.ndarray:
        if phi.tobytes() == self._last_trial:
            self._accepting = True
        self._last_trial = None
        theta = self.theta(phi)
        jac = self.evaluate(theta, True)[1]
        return jac * np.where(self.log, theta, 1.0)[None, :]


#: content of a measured input (``memo.content_key`` of its times and values) -> (knot
#: times, knot values): a record and its crops (a windowed fit's) share their rebuilt
#: input, which costs 0.4 s on a presliding test; the least recently used are forgotten
_REBUILT_INPUTS: OrderedDict[bytes, tuple[np.ndarray, np.ndarray]] = OrderedDict()
_REBUILT_LOCK = threading.Lock()
#: Rebuilt inputs remembered at most (knots only: a few kB each).
REBUILT_ENTRIES = 256


def experiment_for(model, record: Record, smooth: bool = False):
    """The record's measured input as the model's experiment, and each other input the
    model declares whose record signal the record carries (a cylinder's ``load``) as
    measured; with ``smooth`` the drive rebuilt piecewise linear
    (``identification.inputs``), which also leaves the integrator far fewer breakpoints
    than one per sample. Either way a jump between two samples (a spool step) stays a
    jump, at the first sample that shows it: a line across the interval would move it."""
    from ..core.signals import PiecewiseLinear
    from ..experiments import from_record, from_samples
    from .inputs import input_jumps, sampled_input

    drive = model.drive_input  # the declared input the record's signal drives
    others = recorded_inputs(model, record)
    signals = (drive.record_signal, *others.values())
    if not smooth and (drive.record_signal not in record or not any(
            input_jumps(record[s]).size for s in signals)):
        return from_record(record, drive.name, signal=drive.record_signal, drives=others)
    if not smooth:  # the samples as they are, a step kept as a step (``sampled_input``)
        drives = {name: PiecewiseLinear(*sampled_input(record.time, record[signal]))
                  for name, signal in others.items()}
        return from_samples(*sampled_input(record.time, record[drive.record_signal]),
                            drive.name, name=os.path.basename(record.source) or "record",
                            n_points=record.time.size, drives=drives)
    knots_t, knots_v = rebuilt_input(model, record)
    drives = {name: PiecewiseLinear(*rebuilt_signal(record, signal))
              for name, signal in others.items()}
    return from_samples(knots_t, knots_v, drive.name,
                        name=os.path.basename(record.source) or "record",
                        n_points=record.time.size, drives=drives)


def recorded_inputs(model, record: Record) -> dict[str, str]:
    """Input name -> record signal of each input of ``model`` beside its drive whose
    record signal ``record`` carries."""
    return {channel.name: channel.record_signal for channel in model.inputs()[1:]
            if channel.record_signal in record}


def rebuilt_input(model, record: Record) -> tuple[np.ndarray, np.ndarray]:
    """(knot times, knot values) of the record's measured input as rebuilt piecewise
    linear (``identification.inputs``) to drive ``model``; computed once per content
    (of its times and values: the same input cropped to the same samples is the same)."""
    return rebuilt_signal(record, model.input_signal)


def rebuilt_signal(record: Record, signal: str) -> tuple[np.ndarray, np.ndarray]:
    """(knot times, knot values) of the record's ``signal`` rebuilt piecewise linear,
    once per content (``rebuilt_input``)."""
    from .inputs import piecewise_linear_input
    from .memo import content_key

    values = record[signal]
    key = content_key(record.time, values)
    with _REBUILT_LOCK:
        found = _REBUILT_INPUTS.get(key)
        if found is not None:
            _REBUILT_INPUTS.move_to_end(key)
            return found
    knots = piecewise_linear_input(record.time, values)
    with _REBUILT_LOCK:
        _REBUILT_INPUTS[key] = knots
        while len(_REBUILT_INPUTS) > REBUILT_ENTRIES:
            _REBUILT_INPUTS.popitem(last=False)
    return knots


def forget_rebuilt_inputs() -> None:
    """Forget every rebuilt input (``rebuilt_input``): a benchmark's timed run pays for
    rebuilding, as a user's first fit of new records does."""
    with _REBUILT_LOCK:
        _REBUILT_INPUTS.clear()


def input_signal(model: Model) -> str:
    """The record signal that drives ``model``: its declared drive's (a regulator's
    set-point, a pressure, a command, a rig's drive)."""
    return model.input_signal


def _models_per_record(model, n: int) -> list:
    """One model per record: ``model`` for all, or a sequence of ``n`` models."""
    if isinstance(model, Sequence) and not isinstance(model, str):
        models = list(model)
        if len(models) != n:
            raise ParameterError(f"fit: {len(models)} models for {n} records; give one "
                                 "model, or one per record")
        return models
    return [model] * n


def _windows_per_record(window, n: int) -> list:
    """One (t0, t1) window or None per record, from one window for all or a sequence."""
    if window is None:
        return [None] * n
    if len(window) == 2 and all(isinstance(w, int | float | np.floating) for w in window):
        return [tuple(map(float, window))] * n
    windows = list(window)
    if len(windows) != n:
        raise ParameterError(f"fit: {len(windows)} windows for {n} records; give one "
                             "(t0, t1) window, or one per record (None for all of it)")
    return [None if w is None else tuple(map(float, w)) for w in windows]


def _parameter_names(model) -> frozenset[str]:
    from ..core.assembly import assemble

    return frozenset(assemble(model).parameter_names)


# --------------------------------------------------------------------------- results
@dataclass(eq=False)
class ProfileLikelihood:
    """Profile likelihood of one parameter: Δ = N·ln(SSR/SSR_min) against its value."""

    name: str
    grid: np.ndarray
    delta: np.ndarray
    estimate: float
    threshold: float = CHI2_95

    @property
    def interval(self) -> tuple[float, float]:
        """Where Δ crosses the 95 % threshold on each side (nan: no crossing in bounds)."""
        out = []
        for side in (self.grid < self.estimate, self.grid > self.estimate):
            g, d = self.grid[side], self.delta[side]
            above = np.flatnonzero(d > self.threshold)
            if above.size == 0:
                out.append(np.nan)
                continue
            j = above[-1] if g.size and g[0] < self.estimate else above[0]
            k = j + 1 if g[0] < self.estimate else j - 1
            if 0 <= k < g.size:
                out.append(float(np.interp(self.threshold, sorted([d[j], d[k]]),
                                           [g[j], g[k]] if d[j] < d[k] else [g[k], g[j]])))
            else:
                out.append(float(g[j]))
        return out[0], out[1]

    @property
    def verdict(self) -> str:
        low = bool(np.any(self.delta[self.grid < self.estimate] > self.threshold))
        high = bool(np.any(self.delta[self.grid > self.estimate] > self.threshold))
        if low and high:
            return "identifiable"
        if low or high:
            return "practically non-identifiable"
        return "structurally non-identifiable"


@dataclass(eq=False)
class FitResult(ResultVocabulary):
    """Estimates with standard errors, fit statistics, the simulations at the optimum.

    ``to_pandas()``: the estimates (``"statistics"``, ``"correlation"``, ``"starts"``:
    the others); ``plot()``: measured and fitted signals with residuals; ``write(folder)``:
    the tables, the figures, fitted.toml (when every estimate is shared) and report.html.
    """

    report_title = "Parameter fit"
    figure_name = "fit"

    estimates: Estimates
    records: list[Record]
    simulated: list
    statistics: pd.DataFrame
    residuals: np.ndarray
    cost: float
    aic: float
    success: bool
    message: str
    iterations: int
    simulations: int
    wall_time: float
    signals: tuple[str, ...]
    jacobian: np.ndarray
    starts: pd.DataFrame = field(default_factory=pd.DataFrame)
    profiles: dict[str, ProfileLikelihood] = field(default_factory=dict)
    base_values: dict[str, float] = field(default_factory=dict)
    model: Model | None = None
    window: tuple[float, float] | None = None
    weights: dict[str, float] = field(default_factory=dict)
    #: the model of each record (one model for all, unless a joint fit mixes valves)
    models: list = field(default_factory=list)
    #: the (t0, t1) window of each record's residuals (None: all of it)
    windows: list = field(default_factory=list)
    #: the search bounds (low, high) of each estimate
    bounds: tuple[np.ndarray, np.ndarray] = (np.empty(0), np.empty(0))
    #: the weight of each record's residuals (times the signal's ``weights``)
    record_weights: np.ndarray = field(default_factory=lambda: np.ones(0))
    #: per record, the lag [s] of each fitted signal's sensor (fitted or as stated)
    sensor_lags: list = field(default_factory=list)

    def weight(self, i: int, signal: str) -> float:
        """Weight of record ``i``'s residuals of ``signal`` in the fit."""
        extra = self.record_weights[i] if len(self.record_weights) else 1.0
        return self.weights[signal] * extra

    def fitted(self, i: int, signal: str) -> np.ndarray:
        """The model's ``signal`` for record ``i`` as fitted: simulated, plus the
        record's sensor offset if one was fitted."""
        offset = sum(float(v) for n, v in self.values.items()
                     if n == f"offset_{signal}[{i}]")
        lag = self.sensor_lags[i].get(signal, 0.0) if self.sensor_lags else 0.0
        return first_order_lag(self.records[i].time, self.simulated[i][signal],
                               lag) + offset

    def masks(self) -> list[np.ndarray]:
        """Per record, the samples whose residuals the fit used (its window)."""
        return [np.ones(r.time.size, bool) if w is None else
                (r.time >= w[0]) & (r.time <= w[1])
                for r, w in zip(self.records, self.windows, strict=True)]

    @property
    def values(self) -> dict[str, float]:
        return self.estimates.as_dict()

    @property
    def correlation(self) -> pd.DataFrame:
        names = list(self.estimates.names)
        return pd.DataFrame(self.estimates.correlation, index=names, columns=names)

    def tables(self) -> dict[str, pd.DataFrame]:
        tables = {"estimates": self.estimates.to_pandas(), "statistics": self.statistics,
                  "correlation": self.correlation}
        if len(self.starts) > 1:
            tables["starts"] = self.starts
        return tables

    def to_pandas(self, name: str | None = None) -> pd.DataFrame:
        """The estimates with standard errors, 95 % intervals and verdicts (SI); ``name``:
        "statistics", "correlation" or "starts" (a multistart fit)."""
        return self.estimates.to_pandas() if name is None else super().to_pandas(name)

    def plot(self) -> Figure:
        """Measured and fitted signals per record, with residuals (``plot_fit``)."""
        return self.plot_fit()

    def parameters(self, name: str = "fitted"):
        """The model's parameter set with the shared estimates, each value's source
        saying it was fitted (per-record values are not one set's: see ``values``)."""
        from ..parameters import ParameterSet
        from ..parameters.parameter_set import ParameterInfo, number_text

        if self.model is None:
            raise ParameterError("FitResult.parameters: the result has no model")
        params = self.model.params
        values, info = dict(params.values), dict(params.info)
        for j, label in enumerate(self.estimates.names):
            if "[" in label:
                continue
            values[label] = float(self.estimates.values[j])
            info[label] = ParameterInfo(
                number_text(label, values[label]), "fitted",
                f"± {self.estimates.stderr[j]:.3g} (standard error); records: "
                + ", ".join(os.path.basename(r.source) for r in self.records))
        return ParameterSet(values, name=name, provenance=params.provenance, info=info,
                            description=f"fitted from {len(self.records)} record(s)")

    def shared(self) -> bool:
        """Whether every estimate is one value for all records (then it makes a
        parameter set)."""
        return all("[" not in n for n in self.estimates.names)

    def report_parameters(self):
        return self.parameters() if self.shared() and self.model is not None else None

    def report(self, call: str = "", png: bytes | dict[str, bytes] | None = None) -> Report:
        """Estimates, statistics, correlation and the fit figures as an HTML ``Report``
        (not yet written; ``png``: the fit figure, or its pages by name, if already
        drawn)."""
        from ..io.report import Report

        report = Report(self.report_title, call=call, parameters=self.report_parameters())
        report.text(f"{len(self.records)} record(s), signals {', '.join(self.signals)}; "
                    f"{self.iterations} iterations, {self.simulations} simulations, "
                    f"{self.wall_time:.1f} s; {self.message}")
        report.table(self.to_pandas(), "Estimates with standard errors and 95 % intervals "
                                       "(SI)")
        report.table(self.statistics, "Fit statistics per record and signal", index=False)
        report.table(self.correlation, "Correlation of the estimates")
        pages = [png] if isinstance(png, bytes) else list((png or self.fit_pngs()).values())
        for k, page in enumerate(pages, start=1):
            report.image(page, "Measured and fitted signals, residuals" + (
                f" (page {k} of {len(pages)})" if len(pages) > 1 else ""))
        if self.profiles:
            report.figure(self.plot_profiles(), "Profile likelihoods")
        return report

    def writers(self, call: str = "") -> dict[str, Callable[[Path], object]]:
        """The files of ``write``, by name: each a function writing to a path."""
        from ..io.report import table_writer
        from ..plotting import figure_writer

        pngs = self.fit_pngs()
        writers: dict[str, Callable[[Path], object]] = {
            f"{name}.csv": table_writer(frame) for name, frame in self.tables().items()}
        for name, png in pngs.items():
            writers[f"{name}.png"] = functools.partial(_write_png_bytes, png)
        if len(self.starts) > 1:
            writers["waterfall.png"] = figure_writer(self.plot_waterfall)
        if self.profiles:
            writers["profiles.png"] = figure_writer(self.plot_profiles)
        writers["report.html"] = self.report(call, pngs).write
        if self.model is not None and not any("[" in n and not n.startswith("offset_")
                                              for n in self.estimates.names):
            from ..parameters import write_params

            writers["fitted.toml"] = lambda p: write_params(self.parameters(), p)
        return writers

    def write(self, out_dir: str | os.PathLike[str], *, call: str = "") -> list[Path]:
        """estimates.csv, statistics.csv, correlation.csv (starts.csv), fit.png
        (waterfall.png, profiles.png), fitted.toml (no per-record parameter) and report.html:
        all or nothing."""
        from ..io.tables import write_files

        return write_files(out_dir, self.writers(call))

    def plot_fit(self, page: int = 0):
        """Measured and simulated signals per record, with residuals: every record
        (``page`` 0), or the ``page``-th page of ``PANELS_PER_PAGE`` records (from 1)."""
        from ..plotting import plot_measured_and_model, record_pages

        entries = [(os.path.basename(rec.source), rec.time, rec, sim, rec.units)
                   for rec, sim in zip(self.records, self.simulated, strict=True)]
        if page:
            entries = record_pages(entries)[page - 1]
        return plot_measured_and_model(entries, self.signals, "fitted model", self.window)

    @property
    def fit_pages(self) -> int:
        """Pages of ``plot_fit`` the files and the report hold (fit.png, fit-2.png, ...)."""
        from ..plotting import record_pages

        return len(record_pages(self.records))

    def fit_pngs(self) -> dict[str, bytes]:
        """``fit``, ``fit-2``, ...: each page of ``plot_fit`` as PNG."""
        from ..io.report import figure_png
        from ..plotting import page_name

        return {page_name("fit", k): figure_png(self.plot_fit(k))
                for k in range(1, self.fit_pages + 1)}

    def plot_waterfall(self):
        """Final cost of every start, sorted: a flat first step means a found optimum."""
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(6, 3.5))
        costs = np.sort(self.starts["cost"].to_numpy()) if len(self.starts) else [self.cost]
        ax.semilogy(np.arange(1, len(costs) + 1), costs, "o-")
        ax.set_xlabel("start (sorted by final cost)")
        ax.set_ylabel("final cost ½Σr²")
        ax.grid(True, alpha=0.3)
        return fig

    def plot_profiles(self):
        from ..plotting import label_log_axis, panel_grid

        fig, panels = panel_grid(len(self.profiles), width=4.2)
        for (ax,), prof in zip(panels, self.profiles.values(), strict=False):
            ax.plot(prof.grid, prof.delta, "o-")
            ax.axhline(prof.threshold, color="k", ls="--", lw=0.8, label="95 % threshold")
            ax.axvline(prof.estimate, color="C3", lw=0.8)
            ax.set_xlabel(prof.name)
            ax.set_ylabel("Δ = N·ln(SSR/SSR_min)")
            ax.set_title(prof.verdict, fontsize=9)
            ax.grid(True, alpha=0.3)
            if prof.grid.min() > 0 and prof.grid.max() / prof.grid.min() > 20:
                ax.set_xscale("log")
                label_log_axis(ax)
        tight_layout(fig)
        return fig


# --------------------------------------------------------------------------- fitting
def _columns(free: Sequence[str], per_record: Sequence[str], n_records: int,
             offsets: Sequence[str] = (), offset_records: Sequence[int] | None = None,
             lags: Mapping[str, str] = SENSOR_LAGS) -> list[_Column]:
    unknown = [n for n in per_record if n not in free]
    if unknown:
        raise ParameterError(f"fit: per_record names {unknown} are not among the free "
                             f"parameters {list(free)}")
    if per_record and n_records == 1:
        raise ParameterError(f"fit: per_record = {', '.join(per_record)} with one record: one "
                             "value per record is then the shared value; give several records, "
                             "or leave per_record out")
    cols = []
    for name in free:
        if name in lags:
            if name in per_record:
                raise ParameterError(f"fit: per_record = [{name!r}]: a sensor's lag is "
                                     "one for every record")
            cols.append(_Column(name, lags[name], None, lag=True))
        elif name in per_record:
            cols += [_Column(f"{name}[{i}]", name, i) for i in range(n_records)]
        else:
            cols.append(_Column(name, name, None))
    which = range(n_records) if offset_records is None else sorted(set(offset_records))
    bad = [i for i in which if not 0 <= i < n_records]
    if bad:
        raise ParameterError(f"fit: offsets records {bad} are not record indices "
                             f"(0..{n_records - 1})")
    for signal in offsets:
        cols += [_Column(f"offset_{signal}[{i}]", signal, i, offset=True) for i in which]
    return cols


def _bounds(columns, start, bounds, log):
    from ..parameters import catalogue

    specs = catalogue()
    lo, hi = np.empty(len(columns)), np.empty(len(columns))
    for j, col in enumerate(columns):
        if col.offset:
            lo[j], hi[j] = -np.inf, np.inf
            continue
        spec = specs[col.label if col.lag else col.name]
        given = (bounds or {}).get(col.label if col.lag else col.name)
        if given is not None:
            lo[j], hi[j] = map(float, given)
        else:
            lo[j] = spec.minimum if spec.minimum is not None else -np.inf
            hi[j] = spec.maximum if spec.maximum is not None else np.inf
            if log[j]:
                lo[j] = max(lo[j], start[j] / 100)
                hi[j] = min(hi[j], start[j] * 100)
        if log[j] and lo[j] <= 0:
            lo[j] = start[j] / 100 if given is None else lo[j]
        if not lo[j] < hi[j] or not lo[j] <= start[j] <= hi[j] or (log[j] and lo[j] <= 0):
            raise ParameterError(
                f"fit: bounds of {col.label} are ({lo[j]:.6g}, {hi[j]:.6g}) with start "
                f"{start[j]:.6g}; need low < high, the start inside"
                + (" and low > 0 (log scale)" if log[j] else ""))
    return lo, hi


def _statistics(records, simulated, signals, n_par, weighted_residuals):
    rows = []
    for rec, sim in zip(records, simulated, strict=True):
        for s in signals:
            e = sim[s] - rec[s]
            y = rec[s]
            nrmse = float(np.linalg.norm(e) / max(float(np.linalg.norm(y - y.mean())), 1e-300))
            rows.append({"record": os.path.basename(rec.source), "signal": s,
                         "unit": rec.units.get(s, ""),
                         "samples": e.size, "rms": float(np.sqrt(np.mean(e**2))),
                         "max_abs": float(np.max(np.abs(e))), "nrmse": nrmse,
                         "fit_percent": 100 * (1 - nrmse)})
    stats = pd.DataFrame(rows)
    n = weighted_residuals.size
    ssr = float(weighted_residuals @ weighted_residuals)
    aic = n * np.log(max(ssr, 1e-300) / n) + 2 * n_par
    return stats, aic


def _difference_jacobian(problem: _Problem, theta: np.ndarray) -> np.ndarray:
    """dr/dθ at the solution by central differences of relative step ``diff_step``, for
    the covariance of a fit whose model carries no forward sensitivities."""
    columns = []
    for j in range(theta.size):
        step = problem.diff_step * (abs(theta[j]) if theta[j] != 0.0 else 1.0)
        up, down = theta.copy(), theta.copy()
        up[j] += step
        down[j] -= step
        columns.append((problem.evaluate(up, False)[0] - problem.evaluate(down, False)[0])
                       / (2.0 * step))
    return np.column_stack(columns)


def _solve(problem: _Problem, phi0, lo, hi, optimizer: Optimizer):
    problem.new_optimizer_run()
    jac = problem.jac if problem.jacobian == "sensitivities" else problem.jacobian
    return least_squares(problem.residuals, phi0, jac=jac, bounds=(lo, hi),
                         loss=optimizer.loss, f_scale=optimizer.f_scale, x_scale="jac",
                         max_nfev=optimizer.max_nfev, method="trf",
                         diff_step=problem.diff_step)


def _starts(n, lo, hi, seed):
    from scipy.stats import qmc

    if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))):
        raise ParameterError("fit: multistart needs finite bounds for every free parameter")
    sample = qmc.LatinHypercube(d=lo.size, seed=seed).random(n)
    return lo + sample * (hi - lo)


def one_blas_thread(function: Callable) -> Callable:
    """Run ``function`` with numpy's BLAS on one thread. Identification runs threads of
    its own (records, replicates, and callers' pools) and calls BLAS on tall, narrow
    matrices, where BLAS threads only compete with those: the family validation test
    took 255 s with OpenBLAS left to its default and 120 s with this, on 2 cores."""

    @functools.wraps(function)
    def run(*args, **kwargs):
        _enter_one_blas_thread()
        try:
            return function(*args, **kwargs)
        finally:
            _leave_one_blas_thread()

    return run


#: the BLAS limit is process-wide: the first of concurrent callers sets it, the last
#: restores it (a limiter per call would restore it while another thread still runs)
_BLAS_LOCK = threading.Lock()
_BLAS_STATE: dict = {"depth": 0, "limiter": None}


def _enter_one_blas_thread() -> None:
    from threadpoolctl import threadpool_limits

    with _BLAS_LOCK:
        if _BLAS_STATE["depth"] == 0:
            _BLAS_STATE["limiter"] = threadpool_limits(limits=1, user_api="blas")
        _BLAS_STATE["depth"] += 1


def _leave_one_blas_thread() -> None:
    with _BLAS_LOCK:
        _BLAS_STATE["depth"] -= 1
        if _BLAS_STATE["depth"] == 0:
            _BLAS_STATE["limiter"].restore_original_limits()
            _BLAS_STATE["limiter"] = None


@one_blas_thread
def fit(model, records: Record | Sequence[Record], free: Sequence[str], *,
        per_record: Sequence[str] = (), start: Mapping[str, float] | None = None,
        bounds: Bounds | Mapping[str, tuple[float, float]] | None = None,
        signals: Sequence[str] = ("position",),
        weights: Weights | Mapping[str, float] | None = None,
        optimizer: Optimizer | str | None = None, solver=None,
        multistart: Multistart | int = 0,
        executor: Executor | int | str | None = None,
        profile: Profile | Sequence[str] = (),
        offsets: Offsets | Sequence[str] = (),
        window: tuple[float, float] | None = None, smooth_input: bool = True,
        covariance: str = "hac",
        progress: ProgressCallback | None = None) -> FitResult:
    """Fit ``free`` parameters of ``model`` to ``records`` (see the module docstring).

    ``model`` is one model for every record, or a sequence with one model per record
    (a joint fit of records made through different valves: the parameters are shared
    by name, and each record's model reads those it has).

    ``start`` gives starting values (default: the model's parameter set); ``bounds``
    the search space (``Bounds``: (low, high) per name, which are fitted in log scale;
    a dict of ranges is enough); ``weights`` (``Weights``) multiplies each signal's
    residuals (default 1/std of the measured signal) and each record's (default 1);
    ``optimizer`` (``Optimizer``, or a loss name such as "soft_l1" for outliers) says
    how least squares runs; ``multistart`` (``Multistart``, or a number of starts) adds
    Latin-hypercube starts inside the bounds, run on the ``executor``'s threads or Dask
    scheduler; ``profile`` (``Profile``, or parameter names) computes profile
    likelihoods. ``offsets`` (``Offsets``, or signal names) gets a free additive sensor
    offset per record; ``window`` = (t0, t1) restricts the residuals to that time
    span and ends each simulation at t1, or gives one such window (or None) per record;
    each simulation still starts at the record's start, because friction remembers the
    approach (started at rest at t0 instead, the presliding stage of the paper's
    procedure finds σ0 53 % low): crop a record whose actuator rests at t0 with
    ``record.crop(t0, t1)`` to simulate less. ``smooth_input`` rebuilds
    a noisy measured input as piecewise linear before it drives the model (see
    ``identification.inputs``: noise on the input dithers LuGre bristles and biases the
    estimates). ``covariance`` is "hac" (residuals correlated in time, the default) or
    "iid" (see ``estimates.covariance_from_jacobian``). ``progress`` is called with a
    ``pneumact.progress.Progress``: stage "fit" (started, done), then "multistart"
    (starts done of all) and "profile <name>" (points done).
    """
    records = fit_records(records)
    models = _models_per_record(model, len(records))
    windows = [check_window(w) for w in _windows_per_record(window, len(records))]
    # nothing after t1 is simulated; before t0 is (friction remembers the approach)
    records = [r if w is None else r.crop(None, w[1]) for r, w in zip(records, windows,
                                                                       strict=True)]
    bounds, weights = Bounds.of(bounds), Weights.of(weights)
    optimizer, multistart = Optimizer.of(optimizer), Multistart.of(multistart)
    executor, profile, offsets = Executor.of(executor, "fit"), Profile.of(profile), \
        Offsets.of(offsets)
    checked = check_fit_arguments(
        models[0], records, free, per_record=per_record, start=start, signals=signals,
        executor=executor, smooth_input=smooth_input, progress=progress, solver=solver)
    from ..simulation.simulate import check_model

    for other in dict.fromkeys(models[1:]):
        check_model(other, "fit")
    free, solver = checked["free"], checked["solver"]
    if covariance not in ("hac", "iid"):
        raise ParameterError(f"fit: covariance = {covariance!r}; allowed: hac, iid")
    signals = tuple(signals)
    for rec, own in zip(records, models, strict=True):
        rec.require([*signals, own.input_signal], "this fit")
    from ..core.assembly import assemble
    from ..simulation import Rodas4

    assemblies = [assemble(m) for m in dict.fromkeys(models)]
    base: dict[str, float] = {}
    for assembly in assemblies:
        base.update(assembly.values(assembly.pack()))
    freeable = sensor_lags(models)
    foreign = [n for n in free if is_sensor_parameter(n) and n not in freeable]
    if foreign:
        described = (models[0].describe() if hasattr(models[0], "describe")
                     else type(models[0]).__name__)
        raise ParameterError(f"fit: free = {foreign}: no sensor lag of {described}; its "
                             f"sensors' lags: {', '.join(freeable)} (an offset: "
                             "offsets=[signal])")
    lags = [n for n in free if n in freeable]
    stated = Sensors.of(models[0])
    base.update({n: stated.lag(freeable[n]) for n in lags})
    for names_, what in ((free, "fit"), (list(start or {}), "fit start")):
        unknown = [n for n in names_ if n not in base]
        if unknown:
            assemblies[0].check_parameters(unknown, what)
    bad = [s for s in offsets.signals if s not in signals]
    if bad:
        raise ParameterError(f"fit: offsets for {bad}, which are not fitted signals "
                             f"({', '.join(signals)})")
    bad = [n for n in lags if freeable[n] not in signals]
    if bad:
        raise ParameterError(f"fit: free = {bad}, the lag of a sensor whose signal is not "
                             f"fitted ({', '.join(signals)}); fit its signal too")
    columns = _columns(free, per_record, len(records), offsets.signals, offsets.records,
                       freeable)
    theta0 = np.array([0.0 if c.offset else float((start or {}).get(c.label, base[c.label]))
                       if c.lag else float((start or {}).get(c.name, base[c.name]))
                       for c in columns])
    names_log = bounds.log_names(free)
    log_mask = np.array([c.name in names_log and theta0[j] > 0
                         for j, c in enumerate(columns)])
    lo, hi = _bounds(columns, theta0, bounds.ranges, log_mask)
    given_weights = dict(weights.signals or {})
    stray = [s for s in given_weights if s not in signals]
    if stray:
        raise ParameterError(f"fit: weights for {', '.join(stray)}, which "
                             f"{'is' if len(stray) == 1 else 'are'} not fitted: the keys of"
                             f" weights must be among the fitted signals ({', '.join(signals)}); "
                             "fit more signals with signals=[...]")
    signal_weights = {}
    for s in signals:  # a fitted signal without a given weight: 1/std of its measurement
        if s in given_weights:
            signal_weights[s] = given_weights[s]
        else:
            y = np.concatenate([r[s] for r in records])
            signal_weights[s] = 1.0 / (np.std(y) or max(abs(np.mean(y)), 1.0))
    record_weights = weights.records
    if record_weights is not None and len(record_weights) != len(records):
        raise ParameterError(f"fit: weights.records = {list(record_weights)}; need one "
                             f"finite weight > 0 per record ({len(records)})")
    refusals = {m.sensitivity_refusal for m in models} - {None}
    if refusals and optimizer.jacobian == "sensitivities":
        raise ParameterError(
            f"fit: the model does not carry forward sensitivities ({'; '.join(refusals)}); "
            "give optimizer=Optimizer(jacobian=\"2-point\") to fit with finite differences")
    problem = _Problem(models, records, columns, log_mask, signals, signal_weights,
                       solver or Rodas4(rtol=1e-6), optimizer.jacobian, base, windows,
                       smooth_input, record_weights)
    problem.workers = 1 if multistart.starts else executor.threads
    plo, phi_ = problem.phi(lo), problem.phi(hi)
    tic = _time.perf_counter()
    notify(progress, "fit", 0, 1)
    starts = [problem.phi(theta0)]
    if multistart.starts:  # an offset has no bounds: each start begins it where the fit does
        offset = np.array([c.offset for c in columns])
        starts += [np.where(offset, starts[0], s) for s in _starts(
            multistart.starts, np.where(offset, 0.0, plo), np.where(offset, 1.0, phi_),
            multistart.seed)]
    solutions = _run_starts(problem, starts, plo, phi_, optimizer, executor, progress)
    best = min(solutions, key=lambda s: s.cost)
    notify(progress, "fit", 1, 1)
    theta = problem.theta(best.x)
    if problem.jacobian == "sensitivities":
        r, jac, simulated = problem.evaluate(theta, True)
    else:
        r, _, simulated = problem.evaluate(theta, False)
        jac = _difference_jacobian(problem, theta)
    groups = [int(m.sum()) for m in problem.masks for _ in signals]
    cov, dof = covariance_from_jacobian(jac, r, len(columns), groups=groups,
                                        correlated=covariance == "hac")
    from ..parameters import catalogue

    units = tuple(records[0].units.get(c.name, "") if c.offset else
                  catalogue()[c.label if c.lag else c.name].unit
                  for c in columns)
    est = Estimates(tuple(c.label for c in columns), theta, np.sqrt(np.diag(cov)), cov, dof,
                    units)
    stats, aic = _statistics(records, simulated, signals, len(columns), r)
    start_table = pd.DataFrame(
        [{"start": k, **{f"{c.label}_start": v for c, v in zip(columns, problem.theta(s0),
                                                            strict=True)},
          "cost": sol.cost, "converged": bool(sol.success), "nfev": sol.nfev}
         for k, (s0, sol) in enumerate(zip(starts, solutions, strict=True))])
    result = FitResult(est, records, simulated, stats, r, float(best.cost), float(aic),
                       bool(best.success), str(best.message), int(best.nfev),
                       problem.simulations, 0.0, signals, jac, start_table, {}, base,
                       models[0], next((w for w in windows if w is not None), None),
                       dict(signal_weights), models, windows, (lo, hi),
                       problem.record_weights.copy(),
                       [{s: problem.lag_of(theta, i, s) for s in signals}
                        for i in range(len(records))])
    for name in profile.names:
        result.profiles[name] = _profile(problem, result, name, plo, phi_, optimizer,
                                         profile.points, progress)
    result.simulations = problem.simulations
    result.wall_time = _time.perf_counter() - tic
    return result


def _run_starts(problem, starts, lo, hi, optimizer: Optimizer, executor: Executor, progress):
    if len(starts) == 1:
        return [_solve(problem, starts[0], lo, hi, optimizer)]
    options = (lo, hi, optimizer)
    if executor.scheduler is not None:
        from ..simulation.batch.engine import dask_client

        client, owned = dask_client(executor.scheduler)
        futures = []
        try:
            futures = client.map(_solve_copy, [problem] * len(starts), starts,
                                 [options] * len(starts), pure=False)
            done = client.gather(futures)
        except BaseException:  # Ctrl-C: the starts not begun on the workers are dropped
            client.cancel(futures)
            raise
        finally:
            if owned:
                client.close()
        problem.simulations += sum(sol.simulations for sol in done)
        return done
    if len(starts) > executor.threads and threading.current_thread() is \
            threading.main_thread():  # more than one round, not a fit inside other work
        _announce_multistart(problem, starts, executor.threads)
    done = []
    with stop_threads(ThreadPoolExecutor(max_workers=executor.threads)) as pool:
        futures = [pool.submit(_solve_copy, problem, s, options) for s in starts]
        for k, fut in enumerate(futures):
            done.append(fut.result())
            problem.simulations += done[-1].simulations
            notify(progress, "multistart", k + 1, len(futures))
    return done


#: evaluations of the records (each with its Jacobian) one start of a multistart
#: typically takes: the range of the estimate said before the first start has finished
EVALUATIONS_PER_START = (5, 50)
#: results a problem's cache holds at most (``_Problem.evaluate``: 9, and the last one
#: with a Jacobian), per thread's copy
CACHE_ENTRIES = 10


def _announce_multistart(problem: _Problem, starts: list, threads: int) -> None:
    """Time one evaluation of the records at the first start (a first chunk; the first
    call may compile, so the second is timed), then say the time the starts will take
    and check their memory (``check_memory``), before any start is committed."""
    from ..simulation.memory import ESTIMATES, check_memory

    own = _own_copy(problem)
    theta = problem.theta(starts[0])
    with_jacobian = problem.jacobian == "sensitivities"
    try:
        own.evaluate(theta, with_jacobian)
        own._cache.clear()
        tic = _time.perf_counter()
        residuals, jacobian, results = own.evaluate(theta, with_jacobian)
        seconds = _time.perf_counter() - tic
    except PneumactError:
        return  # the start is refused by the fit itself, with its message
    per_entry = residuals.nbytes + (0 if jacobian is None else jacobian.nbytes) + sum(
        values.nbytes for result in results for values in result.signals.values())
    needed = threads * CACHE_ENTRIES * per_entry + len(starts) * 64 * (residuals.size + 1)
    check_memory(needed, f"fit: {len(starts)} multistart starts on {threads} threads")
    rounds = len(starts) / threads
    low, high = (rounds * n * seconds for n in EVALUATIONS_PER_START)
    ESTIMATES.info("multistart: %d starts on %d threads; one evaluation of the records "
                   "takes %.2g s, a start %d to %d of them: about %s to %s; about %.3g MiB "
                   "of memory", len(starts), threads, seconds, *EVALUATIONS_PER_START,
                   _duration(low), _duration(high), needed / 1024**2)


def _duration(seconds: float) -> str:
    """``seconds`` as h:mm:ss."""
    whole = round(seconds)
    return f"{whole // 3600}:{whole % 3600 // 60:02d}:{whole % 60:02d}"


def _write_png_bytes(png: bytes, path: Path) -> None:
    """Write an already drawn PNG to ``path`` (a writer of ``write_files``)."""
    Path(path).write_bytes(png)


def _own_copy(problem: _Problem) -> _Problem:
    """A shallow copy with its own cache and counter (one per thread or start), whose
    records run one after the other."""
    own = copy.copy(problem)
    own._cache = {}
    own._kept = None
    own.new_optimizer_run()
    own.simulations = 0
    own.workers = 1
    return own


def map_on_threads(workers: int, fn, items):
    """``list(map(fn, items))``, on ``workers`` threads when more than one (the
    compiled integrators release the GIL)."""
    items = list(items)
    if workers <= 1 or len(items) <= 1:
        return [fn(item) for item in items]
    with stop_threads(ThreadPoolExecutor(max_workers=min(workers, len(items)))) as pool:
        return list(pool.map(fn, items))


def _solve_copy(problem, phi0, options):
    """One start on its own copy of the problem; returns the solution and its count of
    simulations (summed by the caller, so Dask workers report theirs too)."""
    own = _own_copy(problem)
    sol = _solve(own, phi0, *options)
    sol.simulations = own.simulations
    return sol


def _profile(problem, result, name, lo, hi, optimizer, n_points, progress) -> ProfileLikelihood:
    """Step out from the optimum on each side (steps doubling from one standard error)
    until Δ exceeds twice the 95 % threshold or the bound is reached, refitting the other
    parameters at each point from the previous one."""
    labels = [c.label for c in problem.columns]
    if name not in labels:
        raise ParameterError(f"fit: profile of {name!r}, which is not a free parameter "
                             f"({', '.join(labels)})")
    j = labels.index(name)
    phi_hat = problem.phi(result.estimates.values)
    se = result.estimates.stderr[j]
    se_phi = se / abs(result.estimates.values[j]) if problem.log[j] else se
    first = se_phi if np.isfinite(se_phi) and se_phi > 0 else 0.01 * max(abs(phi_hat[j]), 1)
    ssr_min = 2 * result.cost
    n = result.residuals.size
    keep = [k for k in range(len(labels)) if k != j]
    points = {float(phi_hat[j]): 0.0}
    count = 0
    for side, bound in ((-1, lo[j]), (1, hi[j])):
        x0 = phi_hat[keep]
        for k in range(n_points):
            target = phi_hat[j] + side * first * 2.0**k
            at_bound = side * (target - bound) >= 0
            target = bound if at_bound else target
            ssr, x0 = _refit(problem, j, target, keep, x0, lo, hi, optimizer)
            delta = max(n * np.log(max(ssr, 1e-300) / ssr_min), 0.0)
            points[float(target)] = delta
            count += 1
            notify(progress, f"profile {name}", min(count, 2 * n_points), 2 * n_points)
            if at_bound or delta > 2 * CHI2_95:
                break
    grid_phi = np.array(sorted(points))
    delta = np.array([points[g] for g in grid_phi])
    grid = np.exp(grid_phi) if problem.log[j] else grid_phi
    return ProfileLikelihood(name, grid, delta, float(result.estimates.values[j]))


def _refit(problem, j, phi_j, keep, x0, lo, hi, optimizer: Optimizer):
    """(SSR, optimum of the others) with parameter ``j`` held at ``phi_j``."""
    sub = _Fixed(problem, j, phi_j)
    if keep:
        jac = sub.jac if problem.jacobian == "sensitivities" else problem.jacobian
        sol = least_squares(sub.residuals, np.clip(x0, lo[keep], hi[keep]), jac=jac,
                            bounds=(lo[keep], hi[keep]), loss=optimizer.loss,
                            f_scale=optimizer.f_scale, x_scale="jac", method="trf",
                            diff_step=problem.diff_step)
        ssr, x = 2 * sol.cost, sol.x
    else:
        r = sub.residuals(np.empty(0))
        ssr, x = float(r @ r), x0
    problem.simulations += sub.inner.simulations
    return ssr, x


class _Fixed:
    """The problem with parameter ``j`` held at ``phi_j``: residuals over the others."""

    def __init__(self, problem, j, phi_j):
        self.inner = _own_copy(problem)
        self.j, self.phi_j = j, phi_j

    def _full(self, phi_rest):
        return np.insert(np.asarray(phi_rest, dtype=float), self.j, self.phi_j)

    def residuals(self, phi_rest):
        return self.inner.residuals(self._full(phi_rest))

    def jac(self, phi_rest):
        return np.delete(self.inner.jac(self._full(phi_rest)), self.j, axis=1)

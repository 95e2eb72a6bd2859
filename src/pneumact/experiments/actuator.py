"""Experiments on the actuator: what is applied (pressure, command or set-point) and for
how long. An experiment is data; the actuator's valve says what its signal means."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..checks import (
    check_absolute_pressure,
    check_choice,
    check_finite,
    check_int,
    check_positive,
    check_range,
    check_type,
)
from ..core.signals import PiecewiseLinear, Signal, Step, Triangle
from ..errors import DataError, ExperimentError
from ..models.cylinder import SPOOL_INPUT
from ..models.inputs import DECLARED_INPUTS, quantity_driven_by
from ..models.valves import COMMAND_INPUT, PRESSURE_INPUT

QUANTITIES = {channel.name: channel.unit for channel in DECLARED_INPUTS}


@dataclass(frozen=True, eq=False)
class Experiment:
    """A drive signal of a named quantity applied from ``t_start`` to ``t_end``.

    ``n_points`` output samples are written on a uniform grid unless ``t_eval`` is
    given to ``simulate``. ``quantity`` names the model's drive (its first declared
    input); ``drives`` drives its other inputs by name (input name -> signal: a
    cylinder's ``load``), each where its model declares it.
    """

    drive: Signal
    quantity: str
    t_end: float
    t_start: float = 0.0
    n_points: int = 2001
    name: str = "experiment"
    extra_breakpoints: tuple[float, ...] = field(default=())
    drives: Mapping[str, Signal] = field(default_factory=dict)

    def __post_init__(self):
        name = str(self.name)
        check_type("drive", self.drive, Signal, where=name,
                   what="a Signal (Ramp, Step, Triangle, Sine, PiecewiseLinear, ...)")
        check_choice("quantity", self.quantity, QUANTITIES, where=name, error=ExperimentError)
        object.__setattr__(self, "drives", self._checked_drives(name))
        t_start = check_finite("t_start", self.t_start, where=name, error=ExperimentError)
        if t_start < 0:
            raise ExperimentError(f"{name}: t_start = {t_start:g} s: must be >= 0 (a run "
                                  "starts at t = 0 or later; shift a record's time axis, "
                                  "e.g. time - time[0])")
        t_end = check_finite("t_end", self.t_end, where=name, error=ExperimentError)
        if not t_end > t_start:
            raise ExperimentError(f"{name}: t_end = {t_end:g} s: must be > t_start = "
                                  f"{t_start:g} s")
        check_int("n_points", self.n_points, minimum=2, where=name, error=ExperimentError)

    def _checked_drives(self, name: str) -> dict[str, Signal]:
        """``drives`` as a dict of known quantities other than ``quantity`` to Signals."""
        check_type("drives", self.drives, Mapping, where=name,
                   what="a dict of input name -> Signal, e.g. {'load': Step(0.5, 0.0, 100.0)}")
        for quantity, signal in self.drives.items():
            check_choice("drives", quantity, QUANTITIES, where=name, error=ExperimentError)
            if quantity == self.quantity:
                raise ExperimentError(f"{name}: drives = {{{quantity!r}: ...}}: {quantity!r} "
                                      "is the experiment's quantity, driven by drive; drives "
                                      "names the model's other inputs")
            check_type(f"drives[{quantity!r}]", signal, Signal, where=name,
                       what="a Signal (Ramp, Step, Triangle, Sine, PiecewiseLinear, ...)")
        return dict(self.drives)

    @property
    def unit(self) -> str:
        return QUANTITIES[self.quantity]

    @property
    def inputs(self) -> dict[str, Signal]:
        """Every input it drives by name, its quantity first."""
        return {self.quantity: self.drive, **self.drives}

    def breakpoints(self) -> np.ndarray:
        """Times the integrator must stop at, within [t_start, t_end] (found once: an
        experiment does not change; a copy each time)."""
        found = self.__dict__.get("_breakpoints")
        if found is None:
            found = self._find_breakpoints()
            object.__setattr__(self, "_breakpoints", found)
        return found.copy()

    def input_extremes(self) -> dict[str, tuple[float, float]]:
        """Input name -> (lowest, highest) value of its signal over the run
        (``Signal.extremes``), found once: every run checks its drive against the
        model's declared ranges, and a fit runs the same experiment hundreds of times."""
        found = self.__dict__.get("_input_extremes")
        if found is None:
            found = {name: signal.extremes(self.t_start, self.t_end)
                     for name, signal in self.inputs.items()}
            object.__setattr__(self, "_input_extremes", found)
        return dict(found)

    def _find_breakpoints(self) -> np.ndarray:
        bp = np.concatenate([*(signal.breakpoints() for signal in self.inputs.values()),
                             self.extra_breakpoints, [self.t_start, self.t_end]])
        bp = np.unique(bp)
        return bp[(bp >= self.t_start) & (bp <= self.t_end)]

    def output_times(self) -> np.ndarray:
        return np.linspace(self.t_start, self.t_end, int(self.n_points))

    def with_duration(self, t_end: float) -> Experiment:
        """The same input over another duration."""
        return Experiment(self.drive, self.quantity, t_end, self.t_start, self.n_points,
                          self.name, self.extra_breakpoints, self.drives)


def PressureCycle(high: float = 100e3, low: float = 20e3, period: float = 20.0,
                  cycles: int = 1, n_points: int = 4001) -> Experiment:
    """Slow triangular pressure cycle, ``high`` → ``low`` → ``high`` [Pa absolute]: the
    quasi-static hysteresis test of the paper's Figs. 5-6."""
    for label, value in (("high", high), ("low", low)):
        check_absolute_pressure(label, value, where="PressureCycle", error=ExperimentError)
    if not high > low:
        raise ExperimentError(f"PressureCycle: need low < high, got low = {low:g} Pa, "
                              f"high = {high:g} Pa")
    check_positive("period", period, unit="s", where="PressureCycle", error=ExperimentError)
    check_int("cycles", cycles, minimum=1, where="PressureCycle", error=ExperimentError)
    return Experiment(Triangle(high, low, period, cycles), PRESSURE_INPUT.name, period * cycles,
                      n_points=n_points, name="PressureCycle")


def CommandCycle(low: float = 0.0, high: float = 1.0, period: float = 20.0, cycles: int = 1,
                 n_points: int = 4001) -> Experiment:
    """Slow triangular valve command cycle ``low`` → ``high`` → ``low`` (u ∈ [0, 1])."""
    for label, value in (("low", low), ("high", high)):
        check_range(label, value, 0.0, 1.0, where="CommandCycle", error=ExperimentError,
                    hint="a valve command is a fraction: 0 vents the chamber, 1 opens it to "
                         "the reservoir")
    if not low < high:
        raise ExperimentError(f"CommandCycle: need low < high, got low = {low:g}, "
                              f"high = {high:g}")
    check_positive("period", period, unit="s", where="CommandCycle", error=ExperimentError)
    check_int("cycles", cycles, minimum=1, where="CommandCycle", error=ExperimentError)
    return Experiment(Triangle(low, high, period, cycles), COMMAND_INPUT.name, period * cycles,
                      n_points=n_points, name="CommandCycle")


def from_samples(time, values, quantity: str, name: str = "measured input",
                 n_points: int | None = None,
                 drives: Mapping[str, Signal] | None = None) -> Experiment:
    """A measured input (e.g. a recorded pressure), linear between samples; ``drives``
    the model's other inputs by name (``Experiment.drives``)."""
    time = np.asarray(time, dtype=float)
    sig = PiecewiseLinear(time, values)
    n = int(n_points) if n_points else int(min(max(time.size, 2), 20001))
    return Experiment(sig, quantity, float(time[-1]), float(time[0]), n, name,
                      drives=drives or {})


def from_record(record, quantity: str, n_points: int | None = None,
                signal: str | None = None, drives: Mapping[str, str] | None = None
                ) -> Experiment:
    """A measured record's ``signal`` (default: ``quantity``) as a simulation input of
    that ``quantity`` (pressure, command, ...), linear between samples; e.g. a
    regulator's ``setpoint`` signal drives its ``pressure`` input. ``drives`` (input name
    -> record signal) drives the model's other inputs with the record's signals, e.g.
    ``{"load": "load"}``."""
    signal = quantity if signal is None else signal
    drives = dict(drives or {})
    record.require([signal, *drives.values()], f"driving a simulation with its {signal}")
    others = {name: PiecewiseLinear(record.time, record.signals[column])
              for name, column in drives.items()}
    return from_samples(record.time, record.signals[signal], quantity,
                        name=Path(record.source).name or "record",
                        n_points=n_points or record.time.size, drives=others)


def from_csv(path: str | Path, p_atm: float | None = None, *, model=None) -> Experiment:
    """An input signal read from a CSV (``time [s]`` and one of pressure / command / ...);
    ``p_atm`` [Pa] turns a ``pressure_gauge`` column into absolute pressure. With a
    ``model``, its declared inputs decide the columns: its drive's is required, each other
    input's drives it by name where present (a cylinder: ``spool``, optionally ``load``);
    other columns are ignored (a record's outputs may sit beside its inputs)."""
    from ..io.records import read_record, read_signal_csv

    if model is not None:
        return _declared_from_record(read_record(path, p_atm=p_atm), model)
    name, time, values = read_signal_csv(path, p_atm=p_atm)
    quantity = quantity_driven_by(name)
    return from_samples(time, values, quantity, name=f"{Path(path).name}")


def _declared_from_record(record, model) -> Experiment:
    """The experiment a record's columns give ``model`` by its declared inputs (its drive
    first): the drive's record signal required, the others' optional."""
    inputs = model.inputs()
    drive, *others = inputs
    column = next((s for s in drive.record_signals if s in record.signals), None)
    if column is None:
        declared = ", ".join(f"{i.record_signal} [{i.unit}]" for i in inputs)
        have = ", ".join(["time", *record.signals])
        raise DataError(f"{record.source}: has no {drive.record_signal} column (columns: "
                        f"{have}); a {type(model).__name__}'s input file needs time and its drive "
                        f"{' or '.join(drive.record_signals)}, optionally the other "
                        f"inputs it declares (columns {declared})")
    drives = {i.name: PiecewiseLinear(record.time, record.signals[s])
              for i in others for s in i.record_signals[:1] if s in record.signals}
    return from_samples(record.time, record.signals[column], drive.name,
                        name=Path(record.source).name, drives=drives)


def SpoolStep(before: float = -1.0, after: float = 0.5, t_step: float = 0.1,
              t_end: float = 1.0, n_points: int = 2001) -> Experiment:
    """Step of a 5/3 valve's spool command from ``before`` to ``after`` at ``t_step`` [s]
    (u ∈ [−1, 1]; the default holds a cylinder retracted, then extends it at half
    opening): the cylinder's step response."""
    for label, value in (("before", before), ("after", after)):
        check_range(label, value, -1.0, 1.0, where="SpoolStep", error=ExperimentError,
                    hint="a 5/3 valve's spool command: 1 extends, -1 retracts, 0 closes")
    check_positive("t_step", t_step, unit="s", where="SpoolStep", error=ExperimentError)
    if not t_end > t_step:
        raise ExperimentError(f"SpoolStep: t_end = {t_end:g} s: must be > t_step = "
                              f"{t_step:g} s")
    check_int("n_points", n_points, minimum=2, where="SpoolStep", error=ExperimentError)
    return Experiment(Step(t_step, before, after), SPOOL_INPUT.name, t_end, n_points=n_points,
                      name="SpoolStep")
